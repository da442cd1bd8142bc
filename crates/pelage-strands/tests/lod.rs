//! Stage 1's level of detail on a real adapter: the simplified strands against the CPU
//! mirror, the widths against seed 002's scale, and segment reduction's error against
//! its bound.

use glam::Vec3;
use pelage_gpu::read_buffer;
use pelage_reference::strands::{Level, drawn_width, grow_strands};
use pelage_scene::{Camera, HairParams, HairType, Mesh, Transition};
use pelage_strands::{GrowStrands, LodLevel, MeshBuffers, StrandLayout, StrandRoot, StrandStage};

mod common;
use common::{gpu, grow_on_gpu, mirror_roots};

fn hair(count: u32, hair_type: HairType) -> HairParams {
    let mut p = HairParams::default();
    p.roots.count = count;
    p.growth.segments = 12;
    p.growth.length = 0.4;
    p.growth.hair_type = hair_type;
    p.lod.enabled = true;
    p
}

#[test]
fn simplified_strands_match_the_cpu_mirror_and_seed_002_widths() {
    let gpu = gpu();
    let mesh = Mesh::creature();
    let buffers = MeshBuffers::upload(&gpu, &mesh).unwrap();
    let params = hair(3000, HairType::Straight);
    let mut strands = GrowStrands::new(&gpu, &mesh, &buffers, &params).unwrap();
    let roots = mirror_roots(strands.roots());
    for (lambda, segments) in [(1.0, 12), (0.6, 6), (0.25, 4), (0.1, 3), (0.93, 12)] {
        let zone = Transition::new(lambda, params.lod.transition);
        let level = LodLevel {
            pixels: 0.0,
            extent_pixels: 0.0,
            zone,
            strands: zone.drawn(params.roots.count),
            segments,
            segment_error_pixels: 0.0,
        };
        strands.set_lod(level).unwrap();
        let gpu_vertices = grow_on_gpu(&gpu, &mut strands, 0.7);
        let mirror_level = Level {
            strands: level.strands,
            segments,
        };
        let cpu = grow_strands(&mesh, &roots, &params, 0.7, mirror_level);
        let layout = strands.frame().unwrap().layout;
        assert_eq!(
            layout,
            StrandLayout {
                strands: level.strands,
                segments
            }
        );
        assert_eq!(cpu.len() as u64, layout.vertices());
        let worst = cpu
            .iter()
            .zip(&gpu_vertices)
            .map(|(c, g)| (*c - *g).abs().max_element())
            .fold(0.0f32, f32::max);
        assert!(
            worst < 1e-5,
            "lambda {lambda}: GPU and mirror differ by {worst}"
        );

        // Widths: seed 002's s(x) times the rest width, for every grown strand.
        let bytes = read_buffer(&gpu, &strands.buffers().roots).unwrap();
        let drawn: Vec<StrandRoot> = encase::StorageBuffer::new(&bytes[..])
            .create()
            .expect("roots decode");
        let mut area = 0.0f64;
        for (i, (root, gpu_root)) in roots.iter().zip(drawn).enumerate() {
            if i as u32 >= level.strands {
                break;
            }
            let want = drawn_width(root, i as u32, params.roots.count, &zone);
            assert!(
                (gpu_root.width - want).abs() <= 1e-6 * want.max(1.0),
                "strand {i}"
            );
            area += f64::from(gpu_root.width * root.length);
        }
        // Area preservation: the grown strands cover what all strands cover at rest.
        let rest: f64 = strands
            .roots()
            .iter()
            .map(|r| f64::from(r.width * r.length))
            .sum();
        let ratio = area / rest;
        println!(
            "lambda {lambda}: {} of {} strands, {segments} segments, covered area x {ratio:.4}",
            level.strands, params.roots.count
        );
        assert!(
            (ratio - 1.0).abs() < 0.06,
            "lambda {lambda}: area x {ratio}"
        );
    }
}

/// Largest distance of the points `fine` from the polyline through `coarse`.
fn polyline_distance(fine: &[Vec3], coarse: &[Vec3]) -> f32 {
    fine.iter()
        .map(|p| {
            coarse
                .windows(2)
                .map(|s| {
                    let d = s[1] - s[0];
                    let t = ((*p - s[0]).dot(d) / d.length_squared().max(1e-20)).clamp(0.0, 1.0);
                    (s[0] + d * t - *p).length()
                })
                .fold(f32::MAX, f32::min)
        })
        .fold(0.0, f32::max)
}

#[test]
fn segment_reduction_stays_within_its_pixel_bound() {
    let gpu = gpu();
    let mesh = Mesh::creature();
    let buffers = MeshBuffers::upload(&gpu, &mesh).unwrap();
    let camera = Camera::default();
    let (width, height) = (320, 240);
    for hair_type in [
        HairType::Straight,
        HairType::Wavy {
            amplitude: 0.02,
            frequency: 4.0,
        },
        HairType::Curly {
            radius: 0.015,
            pitch: 0.05,
        },
    ] {
        let mut params = hair(400, hair_type);
        params.lod.start_pixels = 1.0; // never drop strands: this test is about segments
        let mut strands = GrowStrands::new(&gpu, &mesh, &buffers, &params).unwrap();
        let full = grow_on_gpu(&gpu, &mut strands, 0.3);
        for distance in [1.0f32, 3.0, 8.0, 20.0] {
            let eye = camera.target + (camera.eye - camera.target).normalize() * distance * 3.6;
            let view = Camera { eye, ..camera };
            let (lo, hi) = mesh.bounds();
            let reach = Vec3::splat(params.growth.length * 1.3);
            let matrices = view.matrices(width, height);
            let level =
                LodLevel::for_view(&params, (lo - reach, hi + reach), &matrices, width, height);
            strands.set_lod(level).unwrap();
            let reduced = grow_on_gpu(&gpu, &mut strands, 0.3);
            // Pixels per world unit at the nearest point of the hair, as the bound uses.
            let focal = height as f32 / (2.0 * (view.fov_y * 0.5).tan());
            let nearest = (eye - camera.target).length() - (hi - lo).length() * 0.5 - reach.x;
            let per_unit = focal / nearest.max(view.near);
            let (fs, rs) = (
                params.growth.segments as usize + 1,
                level.segments as usize + 1,
            );
            let mut worst = 0.0f32;
            for s in 0..params.roots.count as usize {
                let fine: Vec<Vec3> = full[s * fs..(s + 1) * fs]
                    .iter()
                    .map(|v| v.truncate())
                    .collect();
                let coarse: Vec<Vec3> = reduced[s * rs..(s + 1) * rs]
                    .iter()
                    .map(|v| v.truncate())
                    .collect();
                worst = worst.max(polyline_distance(&fine, &coarse));
            }
            let worst_px = worst * per_unit;
            println!(
                "{hair_type:?} at {distance}x: {} of 12 segments, predicted {:.3} px, measured {worst_px:.3} px",
                level.segments, level.segment_error_pixels
            );
            assert!(
                worst_px <= params.lod.segment_error_pixels + 1e-3,
                "{hair_type:?} at {distance}x: {worst_px} px off with {} segments",
                level.segments
            );
        }
        // Far away, straight hair loses segments.
        if hair_type == HairType::Straight {
            assert!(strands.lod().segments < params.growth.segments);
        }
    }
}

#[test]
fn a_level_the_groom_cannot_grow_is_refused() {
    let gpu = gpu();
    let mesh = Mesh::creature();
    let buffers = MeshBuffers::upload(&gpu, &mesh).unwrap();
    let params = hair(100, HairType::Straight);
    let mut strands = GrowStrands::new(&gpu, &mesh, &buffers, &params).unwrap();
    let mut level = LodLevel::full(&params);
    level.segments = 5; // does not divide 12
    let err = strands.set_lod(level).unwrap_err().to_string();
    assert!(err.contains("lod.segments"), "{err}");
    level.segments = 12;
    level.strands = 101;
    let err = strands.set_lod(level).unwrap_err().to_string();
    assert!(err.contains("lod.strands"), "{err}");
    level.strands = 0;
    assert!(strands.set_lod(level).is_err());
}

/// The level of detail comes from the view and projection alone: the same camera's
/// matrices in either handedness and either depth direction (finite or infinite, as
/// Bevy projects) choose the same strands and segments, from the same screen size.
#[test]
fn the_level_is_the_same_in_every_handedness_and_depth_direction() {
    use glam::camera::{lh, rh};
    use pelage_scene::CameraMatrices;
    let (width, height) = (320, 240);
    let aspect = width as f32 / height as f32;
    let mut params = hair(400, HairType::Straight);
    params.lod.start_pixels = 1.0e9; // drop strands at every distance
    let (lo, hi) = Mesh::creature().bounds();
    let reach = Vec3::splat(params.growth.length * 1.3);
    let bounds = (lo - reach, hi + reach);
    for distance in [4.0f32, 8.0, 16.0] {
        let camera = Camera::default();
        let eye = camera.target + (camera.eye - camera.target).normalize() * distance;
        let camera = Camera { eye, ..camera };
        let (fov, near, far) = (camera.fov_y, camera.near, camera.far);
        let views = [
            camera.matrices(width, height),
            camera.matrices_reverse_z(width, height),
            CameraMatrices {
                view: camera.view(),
                projection: rh::proj::directx::perspective_infinite_reverse(fov, aspect, near),
            },
            CameraMatrices {
                view: lh::view::look_at_mat4(eye, camera.target, glam::Vec3::Y),
                projection: lh::proj::directx::perspective(fov, aspect, near, far),
            },
        ];
        let levels: Vec<LodLevel> = views
            .iter()
            .map(|m| LodLevel::for_view(&params, bounds, m, width, height))
            .collect();
        let first = levels[0];
        assert!(
            first.strands < params.roots.count && first.pixels.is_finite(),
            "at {distance}: {first:?}"
        );
        for (i, level) in levels.iter().enumerate() {
            assert_eq!(
                (level.strands, level.segments),
                (first.strands, first.segments),
                "view {i} at {distance}"
            );
            let off = (level.pixels - first.pixels).abs() / first.pixels;
            assert!(off < 1e-4, "view {i} at {distance}: {level:?} vs {first:?}");
        }
    }
}
