//! Per-region hair types: roots follow the region map, and the growth pass grows each
//! region with its own shape, as the CPU mirror does.

use std::path::Path;

use glam::{Vec2, Vec3};
use pelage_reference::strands::{Level, grow_strands};
use pelage_scene::{HairParams, HairType, MapImage, Mesh, RegionParams, SceneFile, TextureMap};
use pelage_strands::{GrowStrands, MeshBuffers, StrandStage, sample_roots};

mod common;
use common::{gpu, grow_on_gpu, mirror_roots};

/// A region texture of three vertical bands over u: region 0, 1 and 2.
fn bands() -> TextureMap {
    let texels = (0..4 * 3).map(|i| [(i % 3) as u8, 0, 0, 255]).collect();
    TextureMap::from_image("bands", MapImage::new(3, 4, texels).unwrap())
}

/// Three regions of different hair types, lengths and colours over the creature.
fn three_regions(count: u32) -> HairParams {
    let mut p = HairParams::default();
    p.roots.count = count;
    p.roots.textures.region = Some(bands());
    p.growth.segments = 12;
    p.growth.length = 0.2;
    p.growth.regions = vec![
        RegionParams {
            hair_type: Some(HairType::Wavy {
                amplitude: 0.03,
                frequency: 5.0,
            }),
            length: Some(0.45),
            color: Some(Vec3::new(0.9, 0.7, 0.3)),
            ..Default::default()
        },
        RegionParams {
            hair_type: Some(HairType::Curly {
                radius: 0.02,
                pitch: 0.06,
            }),
            width: Some(0.006),
            ..Default::default()
        },
    ];
    p
}

#[test]
fn gpu_matches_cpu_mirror_with_three_regions_of_different_hair_types() {
    let gpu = gpu();
    let mesh = Mesh::creature();
    let buffers = MeshBuffers::upload(&gpu, &mesh).unwrap();
    let (lo, hi) = mesh.bounds();
    // The tolerance of grow.rs's mirror test.
    let tolerance = 1e-5 * (hi - lo).length();
    let params = three_regions(600);
    let mut strands = GrowStrands::new(&gpu, &mesh, &buffers, &params).unwrap();
    let roots = mirror_roots(strands.roots());
    // The same fur with every region straight (the roots keep their regions' lengths,
    // widths and colours): what the mirror grows when the regions' shapes are lost.
    let mut one_shape = params.clone();
    for region in &mut one_shape.growth.regions {
        region.hair_type = Some(HairType::Straight);
    }
    let per_region: Vec<usize> = (0..3)
        .map(|k| strands.roots().iter().filter(|r| r.region == k).count())
        .collect();
    println!("strands per region: {per_region:?}");
    assert!(per_region.iter().all(|&n| n > 50), "{per_region:?}");
    for t in [0.0, 0.37, 5.0] {
        let gpu_vertices = grow_on_gpu(&gpu, &mut strands, t);
        let cpu = grow_strands(&mesh, &roots, &params, t, Level::full(&params));
        assert_eq!(gpu_vertices.len(), cpu.len());
        let worst = gpu_vertices
            .iter()
            .zip(&cpu)
            .map(|(g, c)| (g.truncate() - c.truncate()).abs().max_element())
            .fold(0.0f32, f32::max);
        println!("three regions t={t}: max |GPU - CPU| = {worst:.2e} (tolerance {tolerance:.2e})");
        assert!(worst <= tolerance, "t={t}: GPU and CPU differ by {worst}");
        // The mirror with every strand in region 0 is another fur: the regions matter.
        let straight = grow_strands(&mesh, &roots, &one_shape, t, Level::full(&one_shape));
        let moved = straight
            .iter()
            .zip(&cpu)
            .map(|(s, c)| (s.truncate() - c.truncate()).length())
            .fold(0.0f32, f32::max);
        assert!(
            moved > 100.0 * tolerance,
            "regions change nothing ({moved})"
        );
    }
}

#[test]
fn set_color_keeps_each_region_its_colour() {
    let gpu = gpu();
    let mesh = Mesh::creature();
    let buffers = MeshBuffers::upload(&gpu, &mesh).unwrap();
    let params = three_regions(300);
    let mut strands = GrowStrands::new(&gpu, &mesh, &buffers, &params).unwrap();
    let before = strands.roots().to_vec();
    let new_color = Vec3::new(0.1, 0.2, 0.3);
    strands
        .set_color(&gpu.queue, new_color, params.growth.color_jitter)
        .unwrap();
    // The same as growing with the new base colour: region 1 keeps its own colour.
    let mut rebuilt = params.clone();
    rebuilt.growth.color = new_color;
    let expected = sample_roots(&mesh, &rebuilt.roots, &rebuilt.growth).unwrap();
    assert_eq!(strands.roots(), &expected[..]);
    for (b, a) in before.iter().zip(strands.roots()) {
        assert_eq!(b.color == a.color, b.region == 1, "region {}", b.region);
    }
}

/// The share of the surface each region of `map` covers on `mesh`: every triangle's
/// area split over a 21-point barycentric grid's texels.
fn region_area_shares(mesh: &Mesh, map: &MapImage, regions: usize) -> Vec<f64> {
    const N: usize = 20;
    let mut area = vec![0.0f64; regions];
    for (t, a) in mesh.triangle_areas().iter().enumerate() {
        let mut points = 0usize;
        let mut counts = vec![0usize; regions];
        for i in 0..=N {
            for j in 0..=N - i {
                let (u, v) = (i as f32 / N as f32, j as f32 / N as f32);
                let uv = mesh.uv_at(t, [u, v, 1.0 - u - v]).unwrap();
                counts[(map.nearest(uv)[0] as usize).min(regions - 1)] += 1;
                points += 1;
            }
        }
        for (k, c) in counts.iter().enumerate() {
            area[k] += f64::from(*a) * *c as f64 / points as f64;
        }
    }
    let total: f64 = area.iter().sum();
    area.iter().map(|a| a / total).collect()
}

#[test]
fn creature_mane_roots_follow_the_region_map() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/creature_mane.toml");
    let scene = SceneFile::load(&path).unwrap();
    let mesh = scene.mesh(&path).unwrap();
    let hair = &scene.hair;
    let map = hair.roots.textures.region.as_ref().unwrap();
    let image = map.image.as_deref().unwrap();
    let regions = hair.growth.regions.len() + 1;
    let expected = region_area_shares(&mesh, image, regions);
    let roots = sample_roots(&mesh, &hair.roots, &hair.growth).unwrap();
    let n = roots.len() as f64;
    let resolved = hair.growth.resolved_regions();
    for k in 0..regions {
        let mine: Vec<_> = roots.iter().filter(|r| r.region as usize == k).collect();
        let share = mine.len() as f64 / n;
        let mean_length = mine.iter().map(|r| f64::from(r.length)).sum::<f64>() / mine.len() as f64;
        println!(
            "region {k}: {} of {} roots = {:.4}, the map's area share {:.4}; mean length {:.3} \
             (region length {:.3})",
            mine.len(),
            roots.len(),
            share,
            expected[k],
            mean_length,
            resolved[k].length
        );
        // Binomial standard deviation, 4 sigma, plus the density map's skew (none here).
        let sigma = (expected[k] * (1.0 - expected[k]) / n).sqrt();
        assert!(
            (share - expected[k]).abs() <= 4.0 * sigma + 0.005,
            "region {k}: {share} against {}",
            expected[k]
        );
        assert!(mine.iter().all(|r| r.width == resolved[k].width));
    }
    // The mane is long and wavy, the fur short and straight.
    assert!(resolved[1].length > 2.0 * resolved[0].length);
    assert!(matches!(resolved[1].hair_type, HairType::Wavy { .. }));
    assert_eq!(resolved[0].hair_type, HairType::Straight);
    // Every root's region is the texel under its UV.
    for r in roots.iter().take(500) {
        let (u, v) = (r.bary.x, r.bary.y);
        let uv: Vec2 = mesh
            .uv_at(r.triangle as usize, [u, v, 1.0 - u - v])
            .unwrap();
        assert_eq!(r.region, u32::from(image.nearest(uv)[0]));
    }
}

/// Each strand's tip-to-root distance over its length, per region (1 for straight hair).
fn chord_ratios(
    vertices: &[glam::Vec4],
    roots: &[pelage_strands::StrandRoot],
    per_strand: usize,
) -> Vec<f32> {
    let mut sums = [(0.0f32, 0usize); 3];
    for (root, strand) in roots.iter().zip(vertices.chunks(per_strand)) {
        let chord = (strand[per_strand - 1] - strand[0]).truncate().length() / root.length;
        let slot = &mut sums[root.region as usize];
        *slot = (slot.0 + chord, slot.1 + 1);
    }
    sums.iter().map(|(sum, n)| sum / *n as f32).collect()
}

/// Simulated fur grown with regions starts in each region's shape: with no force, its
/// strands' mean chord over length per region is the growth pass's (wavy and curly
/// strands are shorter from tip to root than they are long; straight ones are not).
#[test]
fn simulated_strands_rest_in_their_regions_shapes() {
    let gpu = gpu();
    let mesh = Mesh::creature();
    let buffers = MeshBuffers::upload(&gpu, &mesh).unwrap();
    let mut params = three_regions(600);
    params.growth.gravity = Vec3::ZERO;
    params.growth.direction_jitter = 0.0;
    params.wind = pelage_scene::WindParams::calm();
    let per_strand = params.growth.segments as usize + 1;
    let mut grown = GrowStrands::new(&gpu, &mesh, &buffers, &params).unwrap();
    let grown_ratios = chord_ratios(
        &grow_on_gpu(&gpu, &mut grown, 0.0),
        grown.roots(),
        per_strand,
    );
    let still = pelage_scene::DynamicsParams {
        gravity: Vec3::ZERO,
        ..Default::default()
    };
    let mut sim =
        pelage_strands::SimulateStrands::grown(&gpu, &mesh, &buffers, &params, &still).unwrap();
    let rest = grow_on_gpu(&gpu, &mut sim, 0.0);
    let sim_ratios = chord_ratios(&rest, sim.roots(), per_strand);
    println!("chord / length per region: grown {grown_ratios:?}, simulated {sim_ratios:?}");
    assert!(grown_ratios[0] > 0.999, "{grown_ratios:?}");
    assert!(
        grown_ratios[1] < 0.98 && grown_ratios[2] < 0.9,
        "{grown_ratios:?}"
    );
    for (g, s) in grown_ratios.iter().zip(&sim_ratios) {
        assert!(
            (g - s).abs() < 1e-3,
            "grown {grown_ratios:?}, simulated {sim_ratios:?}"
        );
    }
}
