//! Root placement: N strands spread over the mesh by area, deterministic from a seed.
//!
//! Strand `i` draws its random numbers from `pcg_hash(i ^ pcg_hash(seed))` alone,
//! so it keeps its root, length and jitter when the strand count changes.

use crate::StrandRoot;
use glam::{Vec2, Vec3};
use pelage_scene::{GrowthParams, Mesh, RootParams};

/// PCG hash (Jarzynski and Olano 2020), the same as `pcg_hash` in `wgsl/shared/noise.wgsl`.
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// A float in [0, 1) from the top 24 bits of a hash, the same as `hash_to_unit` in WGSL.
pub fn hash_to_unit(h: u32) -> f32 {
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// A strand's brightness factor `1 + jitter·(2u − 1)`, `u` being the `draw`-th hash draw
/// after its `seed` ([`StrandRoot::seed`]): what its colour is the base colour times.
/// [`sample_roots`] takes it from draw 8, a groom ([`GroomStrands`](crate::GroomStrands))
/// from draw 2; recolouring strands with it reproduces their colours exactly.
pub fn strand_brightness(seed: u32, draw: u32, jitter: f32) -> f32 {
    let mut h = seed;
    for _ in 0..draw {
        h = pcg_hash(h);
    }
    1.0 + jitter * (2.0 * hash_to_unit(h) - 1.0)
}

/// The hash draw [`sample_roots`] takes a grown strand's brightness from.
pub(crate) const GROWN_BRIGHTNESS_DRAW: u32 = 8;

/// Barycentrics of the four points a triangle's density texture is averaged over: its
/// centroid and the midpoints from the centroid to each corner (exact for a map linear
/// over the triangle).
const DENSITY_SAMPLES: [[f32; 3]; 4] = [
    [1.0 / 3.0; 3],
    [2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0],
    [1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0],
    [1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0],
];

/// The region of a root at barycentrics `bary` of triangle `tri`: the per-vertex map's
/// value at the nearest corner, or the region texture's texel there (nearest), or 0.
pub fn root_region(mesh: &Mesh, roots: &RootParams, tri: usize, bary: [f32; 3]) -> u32 {
    if let Some(map) = &roots.region {
        let corner = (0..3)
            .max_by(|&a, &b| bary[a].total_cmp(&bary[b]))
            .unwrap_or(0);
        let idx = mesh.indices.get(tri * 3 + corner).copied().unwrap_or(0) as usize;
        return map.get(idx).copied().unwrap_or(0);
    }
    match (roots.textures.region.as_ref(), mesh.uv_at(tri, bary)) {
        (Some(map), Some(uv)) => map
            .image
            .as_deref()
            .map_or(0, |image| u32::from(image.nearest(uv)[0])),
        _ => 0,
    }
}

/// The colour texture's linear RGB at a root (what its colour is multiplied by), or 1
/// without a colour texture.
pub fn root_tint(mesh: &Mesh, roots: &RootParams, tri: usize, bary: [f32; 3]) -> Vec3 {
    let image = roots
        .textures
        .color
        .as_ref()
        .and_then(|m| m.image.as_deref());
    match (image, mesh.uv_at(tri, bary)) {
        (Some(image), Some(uv)) => image.color(uv),
        _ => Vec3::ONE,
    }
}

/// A scalar texture's value (red / 255, bilinear) at a root, or 1 without the texture.
fn texture_scalar(
    mesh: &Mesh,
    map: Option<&pelage_scene::TextureMap>,
    tri: usize,
    bary: [f32; 3],
) -> f32 {
    match (map.and_then(|m| m.image.as_deref()), mesh.uv_at(tri, bary)) {
        (Some(image), Some(uv)) => image.scalar(uv),
        _ => 1.0,
    }
}

/// Places `roots.count` strands over `mesh`, each triangle getting a share proportional
/// to its area (times its corners' mean density and its density texture's mean, if
/// given). Zero-area triangles get no strands. Each root takes its region from the
/// region map ([`root_region`]) and grows with that region's length, jitters, width and
/// colour (times the colour texture, [`root_tint`]); the length maps scale its length.
pub fn sample_roots(
    mesh: &Mesh,
    roots: &RootParams,
    growth: &GrowthParams,
) -> crate::Result<Vec<StrandRoot>> {
    let report = mesh.validate()?;
    roots.validate(mesh.positions.len())?;
    growth.validate()?;
    roots.validate_maps(growth.regions.len() + 1, Some(mesh))?;
    roots.validate_lengths(growth)?;
    let regions = growth.resolved_regions();

    let areas = mesh.triangle_areas();
    let mut degenerate = vec![false; areas.len()];
    for &t in &report.degenerate_triangles {
        if let Some(d) = degenerate.get_mut(t as usize) {
            *d = true;
        }
    }
    let corner_mean = |map: &Option<Vec<f32>>, tri: usize, bary: [f32; 3]| -> f32 {
        let Some(map) = map else { return 1.0 };
        (0..3)
            .map(|k| {
                let idx = mesh.indices.get(tri * 3 + k).copied().unwrap_or(0) as usize;
                map.get(idx).copied().unwrap_or(0.0) * bary[k]
            })
            .sum()
    };

    // Cumulative weights in f64 so a million small triangles still sum exactly enough.
    let mut cdf = Vec::with_capacity(areas.len());
    let mut total = 0.0f64;
    for (t, &area) in areas.iter().enumerate() {
        let w = if degenerate[t] {
            0.0
        } else {
            let texture = roots.textures.density.as_ref().map_or(1.0, |_| {
                DENSITY_SAMPLES
                    .iter()
                    .map(|&b| texture_scalar(mesh, roots.textures.density.as_ref(), t, b))
                    .sum::<f32>()
                    / DENSITY_SAMPLES.len() as f32
            });
            f64::from(area)
                * f64::from(corner_mean(&roots.density, t, [1.0 / 3.0; 3]))
                * f64::from(texture)
        };
        total += w.max(0.0);
        cdf.push(total);
    }
    if total <= 0.0 || !total.is_finite() {
        // Name the maps that weighted the area: they are what the user wrote.
        let mut maps = Vec::new();
        if roots.density.is_some() {
            maps.push("the per-vertex map roots.density".to_string());
        }
        if let Some(map) = &roots.textures.density {
            maps.push(format!(
                "the texture map roots.textures.density = {} (read at the triangles' UVs)",
                map.path.display()
            ));
        }
        let weighted = if maps.is_empty() || total.is_nan() || total > 0.0 {
            String::new()
        } else {
            format!(
                ", weighted by {}, which is 0 on every triangle",
                maps.join(" and ")
            )
        };
        return Err(crate::StrandsError::NoSurface(format!(
            "total weighted area is {total} over {} triangles ({} degenerate){weighted}",
            areas.len(),
            report.degenerate_triangles.len()
        )));
    }

    let seed_hash = pcg_hash(roots.seed);
    let out = (0..roots.count)
        .map(|i| {
            let h0 = pcg_hash(i ^ seed_hash);
            let mut h = h0;
            let mut next = || {
                h = pcg_hash(h);
                hash_to_unit(h)
            };
            let target = f64::from(next()) * total;
            // First triangle whose cumulative weight exceeds the target (never a zero-weight one).
            let tri = cdf.partition_point(|&c| c <= target).min(cdf.len() - 1);
            let su = next().sqrt();
            let bu = 1.0 - su;
            let bv = next() * su;
            let bw = (1.0 - bu - bv).max(0.0);
            let bary = [bu, bv, bw];
            let region = root_region(mesh, roots, tri, bary);
            let g = regions.get(region as usize).unwrap_or(growth);
            let length_scale = corner_mean(&roots.length_scale, tri, bary)
                * texture_scalar(mesh, roots.textures.length_scale.as_ref(), tri, bary);
            let length = g.length * (1.0 + g.length_jitter * (2.0 * next() - 1.0)) * length_scale;
            let phase = next();
            let tilt = g.direction_jitter * next();
            let azimuth = std::f32::consts::TAU * next();
            let brightness = 1.0 + g.color_jitter * (2.0 * next() - 1.0);
            StrandRoot {
                triangle: tri as u32,
                seed: h0,
                bary: Vec2::new(bu, bv),
                // A zero length-map value makes a zero-length strand, which is legal and invisible.
                length: length.max(0.0),
                width: g.width,
                phase,
                tilt,
                azimuth,
                color: g.color * root_tint(mesh, roots, tri, bary) * brightness,
                region,
            }
        })
        .collect();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn per_vertex_regions_take_the_nearest_corner() {
        let mesh = Mesh::plane(1.0, 1.0, 1, 1).unwrap();
        let roots = RootParams {
            count: 2000,
            region: Some(vec![1, 0, 0, 0]),
            ..Default::default()
        };
        let growth = GrowthParams {
            regions: vec![pelage_scene::RegionParams {
                width: Some(0.01),
                ..Default::default()
            }],
            ..Default::default()
        };
        let sampled = sample_roots(&mesh, &roots, &growth).unwrap();
        for r in &sampled {
            let bary = [r.bary.x, r.bary.y, 1.0 - r.bary.x - r.bary.y];
            let nearest = (0..3).max_by(|&a, &b| bary[a].total_cmp(&bary[b])).unwrap();
            let vertex = mesh.indices[r.triangle as usize * 3 + nearest];
            assert_eq!(r.region, u32::from(vertex == 0));
            assert_eq!(r.width, if r.region == 1 { 0.01 } else { growth.width });
        }
        // Only the roots nearest vertex 0 are in region 1: some, not all.
        let ones = sampled.iter().filter(|r| r.region == 1).count();
        assert!(ones > 0 && ones < sampled.len(), "{ones}");
    }

    #[test]
    fn brightness_reproduces_sampled_colours_exactly() {
        let mesh = Mesh::icosphere(1.0, 2).unwrap();
        let growth = GrowthParams::default();
        let roots = sample_roots(
            &mesh,
            &RootParams {
                count: 500,
                ..Default::default()
            },
            &growth,
        )
        .unwrap();
        for r in &roots {
            let b = strand_brightness(r.seed, GROWN_BRIGHTNESS_DRAW, growth.color_jitter);
            assert_eq!(r.color, growth.color * b);
        }
    }

    #[test]
    fn strand_keeps_its_root_when_count_changes() {
        let mesh = Mesh::icosphere(1.0, 2).unwrap();
        let growth = GrowthParams::default();
        let few = sample_roots(
            &mesh,
            &RootParams {
                count: 100,
                ..Default::default()
            },
            &growth,
        )
        .unwrap();
        let many = sample_roots(
            &mesh,
            &RootParams {
                count: 1000,
                ..Default::default()
            },
            &growth,
        )
        .unwrap();
        assert_eq!(few[..], many[..100]);
    }

    #[test]
    fn roots_follow_area() {
        // Two triangles, the second four times the area of the first.
        let mesh = Mesh {
            positions: vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::Z,
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(4.0, 0.0, 0.0),
                Vec3::new(2.0, 0.0, 2.0),
            ],
            normals: vec![Vec3::Y; 6],
            indices: vec![0, 2, 1, 3, 5, 4],
            uvs: Vec::new(),
        };
        let roots = sample_roots(
            &mesh,
            &RootParams {
                count: 20_000,
                ..Default::default()
            },
            &GrowthParams::default(),
        )
        .unwrap();
        let on_second = roots.iter().filter(|r| r.triangle == 1).count() as f32 / 20_000.0;
        assert!((on_second - 0.8).abs() < 0.02, "{on_second}");
        assert!(
            roots
                .iter()
                .all(|r| r.bary.x >= 0.0 && r.bary.y >= 0.0 && r.bary.x + r.bary.y <= 1.0 + 1e-6)
        );
    }

    #[test]
    fn density_and_length_maps_steer_roots() {
        let mesh = Mesh {
            positions: vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::Z,
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(3.0, 0.0, 0.0),
                Vec3::new(2.0, 0.0, 1.0),
            ],
            normals: vec![Vec3::Y; 6],
            indices: vec![0, 2, 1, 3, 5, 4],
            uvs: Vec::new(),
        };
        let params = RootParams {
            count: 1000,
            density: Some(vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0]),
            length_scale: Some(vec![1.0, 1.0, 1.0, 2.0, 2.0, 2.0]),
            ..Default::default()
        };
        let growth = GrowthParams {
            length_jitter: 0.0,
            ..Default::default()
        };
        let roots = sample_roots(&mesh, &params, &growth).unwrap();
        assert!(roots.iter().all(|r| r.triangle == 1));
        assert!(
            roots
                .iter()
                .all(|r| (r.length - 2.0 * growth.length).abs() < 1e-5)
        );
    }

    #[test]
    fn zero_density_everywhere_is_an_error() {
        let mesh = Mesh::icosphere(1.0, 0).unwrap();
        let roots = RootParams {
            density: Some(vec![0.0; mesh.positions.len()]),
            ..Default::default()
        };
        let result = sample_roots(&mesh, &roots, &GrowthParams::default());
        assert!(
            matches!(&result, Err(crate::StrandsError::Param(e)) if e.name == "roots.density"),
            "{result:?}"
        );
    }
}
