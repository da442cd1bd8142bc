//! The strand path tracer: direct light against the analytic Chiang model, noise that falls as
//! 1/sqrt(spp), determinism, energy conservation in a white furnace, typed errors, and the
//! time of a mid-size render.

use std::f64::consts::PI;

use glam::{DVec3, DVec4, Vec3, Vec4};
use pelage_reference::chiang::ChiangFibre;
use pelage_reference::path_tracer::{
    HairScene, MAX_SPP, PathTraceError, PathTracedImage, PathTracer, PathTracerSettings, Pcg32,
};
use pelage_reference::transmittance::{Segment, segments_from_strands};
use pelage_scene::{Camera, DirectionalLight, Light, Mesh, PointLight};

/// Straight strands along x at the given (y, z), from x = -len/2 to len/2, in `n` segments.
fn straight_strands(centres: &[(f32, f32)], len: f32, n: usize, width: f32) -> Vec<Segment> {
    let mut verts = Vec::new();
    for &(y, z) in centres {
        for i in 0..=n {
            let w = i as f32 / n as f32;
            verts.push(Vec4::new(-0.5 * len + len * w, y, z, w));
        }
    }
    segments_from_strands(&verts, n + 1, &vec![width; centres.len()], 1.0, 1.0)
}

fn scene<'a>(segments: &'a [Segment], fibre: ChiangFibre, lights: &'a [Light]) -> HairScene<'a> {
    HairScene {
        segments,
        fibre,
        strand_sigma_a: None,
        mesh_positions: &[],
        mesh_triangles: &[],
        mesh_albedo: DVec3::splat(0.5),
        lights,
    }
}

fn directional(to_light: Vec3, intensity: f32) -> Light {
    Light::Directional(DirectionalLight {
        direction: -to_light,
        color: Vec3::ONE,
        intensity,
    })
}

fn front_camera(distance: f32, fov_deg: f32) -> Camera {
    Camera {
        eye: Vec3::new(0.0, 0.0, distance),
        target: Vec3::ZERO,
        fov_y: fov_deg.to_radians(),
        near: 0.05,
        far: 20.0,
    }
}

fn luminance(p: [f32; 3]) -> f64 {
    (f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2])) / 3.0
}

#[test]
fn direct_light_matches_the_analytic_model() {
    // One wide strand (radius 0.15, along x) seen close up at 48 x 32 pixels, two
    // directional lights (one in front, one behind it for TT), 1 bounce, black background.
    // Reference per pixel: a 16 x 16 midpoint grid of exact rays through the pixel against the
    // infinite cylinder, each eval_projected(wo, wi, h) · E summed over the lights with the h
    // of that ray from the hit normal (h = sin(φ_o - φ_n)). With one bounce and no occlusion
    // the only noise is the position in the pixel, so each fully covered pixel must match
    // within 4 standard errors (σ of the sub-grid / sqrt(spp)) plus 0.2%. Pixels at the
    // silhouette (some |h| > 0.95) use an 8 x 1024 grid: grazing R/TRT is a bright band a few
    // hundredths of a pixel wide there.
    let radius = 0.15f64;
    let segments = straight_strands(&[(0.0, 0.0)], 20.0, 4, 2.0 * radius as f32);
    let fibre = ChiangFibre {
        sigma_a: DVec3::new(0.3, 0.6, 1.2),
        beta_m: 0.3,
        beta_n: 0.3,
        alpha: 2f64.to_radians(),
        eta: 1.55,
    };
    let key = Vec3::new(0.3, 0.6, 0.7).normalize();
    let back = Vec3::new(-0.2, 0.15, -1.0).normalize();
    let lights = [directional(key, 2.0), directional(back, 1.5)];
    let tracer = PathTracer::new(&scene(&segments, fibre, &lights)).unwrap();
    let camera = front_camera(1.5, 30.0);
    let (w, h) = (48u32, 32u32);
    let spp = 256;
    let settings = PathTracerSettings {
        spp,
        max_bounces: 1,
        seed: 3,
        ..Default::default()
    };
    let img = tracer.render(&camera, w, h, &settings).unwrap();

    let inv = camera
        .view_projection(w as f32 / h as f32)
        .as_dmat4()
        .inverse();
    let prepared = fibre.prepare();
    let radiance = |px: f64, py: f64| -> Option<(DVec3, f64)> {
        let nx = 2.0 * px / f64::from(w) - 1.0;
        let ny = 1.0 - 2.0 * py / f64::from(h);
        let a = inv * DVec4::new(nx, ny, 0.0, 1.0);
        let b = inv * DVec4::new(nx, ny, 1.0, 1.0);
        let (a, b) = (a.truncate() / a.w, b.truncate() / b.w);
        let d = (b - a).normalize();
        // y² + z² = r² from a along d.
        let (qa, qb, qc) = (
            d.y * d.y + d.z * d.z,
            a.y * d.y + a.z * d.z,
            a.y * a.y + a.z * a.z - radius * radius,
        );
        let disc = qb * qb - qa * qc;
        if disc <= 0.0 {
            return None;
        }
        let t = (-qb - disc.sqrt()) / qa;
        let p = a + t * d;
        let n = DVec3::new(0.0, p.y, p.z) / radius;
        let wo = -d;
        let hh = (wo.z.atan2(wo.y) - n.z.atan2(n.y)).sin();
        let mut l = DVec3::ZERO;
        for (to, e) in [(key, 2.0), (back, 1.5)] {
            l += prepared.eval_projected(wo, to.as_dvec3(), hh) * e;
        }
        Some((l, hh))
    };
    // Pixel means and variances of the analytic radiance over a kx x ky midpoint grid;
    // `None` when some grid ray misses the strand.
    let grid = |x: u32, y: u32, kx: usize, ky: usize| -> Option<(f64, f64, f64)> {
        let mut vals = Vec::with_capacity(kx * ky);
        let mut max_h = 0.0f64;
        for j in 0..ky {
            for i in 0..kx {
                let px = f64::from(x) + (i as f64 + 0.5) / kx as f64;
                let py = f64::from(y) + (j as f64 + 0.5) / ky as f64;
                let (l, hh) = radiance(px, py)?;
                max_h = max_h.max(hh.abs());
                vals.push((l.x + l.y + l.z) / 3.0);
            }
        }
        let n = vals.len() as f64;
        let mean = vals.iter().sum::<f64>() / n;
        let var = vals.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
        Some((mean, var, max_h))
    };
    let (mut checked, mut edges, mut sum_pt, mut sum_ref, mut worst_z) = (0, 0, 0.0, 0.0, 0.0f64);
    for y in 0..h {
        for x in 0..w {
            let idx = (y * w + x) as usize;
            let pt = luminance(img.pixels[idx]);
            let Some((mut mean, mut var, max_h)) = grid(x, y, 16, 16) else {
                // The strand covers rows 10..22 (radius 0.15 at 40 pixels per unit): rows
                // well away from it see nothing.
                if !(6..=25).contains(&y) {
                    assert_eq!(img.pixels[idx], [0.0; 3], "pixel {x},{y} should be empty");
                    assert_eq!(img.hair_mask[idx], 0.0);
                }
                continue;
            };
            if max_h > 0.95 {
                // Near the silhouette (|h| -> 1) grazing R and TRT are very bright in a band
                // a few hundredths of a pixel wide: resolve it with 1024 rows in the pixel.
                let Some((m, v, _)) = grid(x, y, 8, 1024) else {
                    continue;
                };
                (mean, var) = (m, v);
                edges += 1;
            }
            let se = (var / f64::from(spp)).sqrt();
            let z = (pt - mean).abs() / (se + 1e-12);
            worst_z = worst_z.max(z.min(1e9));
            assert!(
                (pt - mean).abs() <= 4.0 * se + 2e-3 * mean,
                "pixel {x},{y}: path traced {pt} vs analytic {mean} (se {se})"
            );
            assert_eq!(img.hair_mask[idx], 1.0);
            checked += 1;
            sum_pt += pt;
            sum_ref += mean;
        }
    }
    let rel = (sum_pt - sum_ref).abs() / sum_ref;
    println!(
        "direct light: {checked} covered pixels ({edges} at the silhouette), mean radiance {:.5} (path traced) vs {:.5} (analytic), relative {rel:.2e}, worst |z| {worst_z:.2}",
        sum_pt / f64::from(checked),
        sum_ref / f64::from(checked)
    );
    assert!(checked > 400, "{checked}");
    assert!(rel < 2e-3, "{rel}");
}

#[test]
fn rows_run_top_down_and_columns_left_to_right() {
    // A strand above the centre (y = +0.3) lands in the top rows; a vertical one right of the
    // centre in the right columns.
    let mut verts = Vec::new();
    for i in 0..=4 {
        let w = i as f32 / 4.0;
        verts.push(Vec4::new(-5.0 + 10.0 * w, 0.3, 0.0, w));
    }
    for i in 0..=4 {
        let w = i as f32 / 4.0;
        verts.push(Vec4::new(0.4, -5.0 + 10.0 * w, 0.0, w));
    }
    let segments = segments_from_strands(&verts, 5, &[0.05, 0.05], 1.0, 1.0);
    let tracer = PathTracer::new(&scene(&segments, ChiangFibre::default(), &[])).unwrap();
    let img = tracer
        .render(
            &front_camera(2.0, 60.0),
            64,
            64,
            &PathTracerSettings {
                spp: 4,
                ..Default::default()
            },
        )
        .unwrap();
    let row_mask = |y: usize| (0..64).map(|x| img.hair_mask[y * 64 + x]).sum::<f32>();
    let col_mask = |x: usize| (0..64).map(|y| img.hair_mask[y * 64 + x]).sum::<f32>();
    let top: f32 = (0..32).map(row_mask).sum();
    let bottom: f32 = (32..64).map(row_mask).sum();
    let left: f32 = (0..32).map(col_mask).sum();
    let right: f32 = (32..64).map(col_mask).sum();
    // The horizontal strand is all in the top half; the vertical one all in the right half.
    assert!(top > 2.0 * bottom, "top {top} bottom {bottom}");
    assert!(right > 2.0 * left, "left {left} right {right}");
}

/// 7 x 7 parallel strands along x in the plane y-z, `gap` radii apart, radius 0.02.
fn bundle(gap: f32) -> Vec<Segment> {
    let r = 0.02f32;
    let mut centres = Vec::new();
    for i in 0..7 {
        for j in 0..7 {
            let y = (i as f32 - 3.0) * gap * r + if j % 2 == 1 { 0.5 * gap * r } else { 0.0 };
            let z = (j as f32 - 3.0) * gap * r * 0.866;
            centres.push((y, z));
        }
    }
    straight_strands(&centres, 3.0, 12, 2.0 * r)
}

fn bundle_scene_render(spp: u32, seed: u64) -> PathTracedImage {
    let segments = bundle(3.0);
    let fibre = ChiangFibre {
        sigma_a: DVec3::new(0.1, 0.2, 0.4),
        ..ChiangFibre::default()
    };
    let lights = [
        directional(Vec3::new(0.2, 0.8, 0.5), 2.0),
        Light::Point(PointLight {
            position: Vec3::new(-0.5, -0.4, -1.0),
            color: Vec3::new(1.0, 0.8, 0.6),
            intensity: 3.0,
        }),
    ];
    let tracer = PathTracer::new(&scene(&segments, fibre, &lights)).unwrap();
    tracer
        .render(
            &front_camera(1.2, 25.0),
            32,
            32,
            &PathTracerSettings {
                spp,
                max_bounces: 8,
                seed,
                background: DVec3::splat(0.1),
                sky: DVec3::splat(0.1),
                ..Default::default()
            },
        )
        .unwrap()
}

fn rmse(a: &PathTracedImage, b: &PathTracedImage) -> f64 {
    let s: f64 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| {
            (0..3)
                .map(|c| (f64::from(p[c]) - f64::from(q[c])).powi(2))
                .sum::<f64>()
        })
        .sum();
    (s / (3 * a.pixels.len()) as f64).sqrt()
}

#[test]
fn error_halves_for_four_times_the_samples() {
    // RMSE against a 1024-spp render (another seed) at 16 and 64 spp: Monte Carlo error falls
    // as 1/sqrt(spp), so the ratio is 0.5 (0.51 with the reference's own noise).
    let reference = bundle_scene_render(1024, 100);
    let e16 = rmse(&bundle_scene_render(16, 1), &reference);
    let e64 = rmse(&bundle_scene_render(64, 2), &reference);
    let ratio = e64 / e16;
    println!("RMSE 16 spp {e16:.5}, 64 spp {e64:.5}, ratio {ratio:.3}");
    assert!((0.4..=0.62).contains(&ratio), "{ratio}");
    // The image is not black: the bundle is lit and scatters.
    let lit = reference
        .pixels
        .iter()
        .filter(|p| luminance(**p) > 0.15)
        .count();
    assert!(lit > 50, "{lit}");
}

#[test]
fn same_seed_same_image_on_any_thread_count() {
    let a = bundle_scene_render(8, 5);
    let b = bundle_scene_render(8, 5);
    assert_eq!(a, b);
    let single = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| bundle_scene_render(8, 5));
    assert_eq!(a, single);
    let c = bundle_scene_render(8, 6);
    assert_ne!(a.pixels, c.pixels);
}

#[test]
fn white_furnace_conserves_energy_over_many_bounces() {
    // σ_a = 0 fibres (a bundle of 49 strands 2.2 radii apart) over a white Lambertian quad
    // (albedo 1), no lights, background radiance 1: every pixel sees radiance 1, however many
    // times its paths scatter. Without Russian roulette every sample is exactly 1 (the sample
    // weights are 1) provided it escapes within 1024 bounces; with it (from vertex 4) the
    // mean over the hair pixels is 1 within 4 standard errors.
    let segments = bundle(2.2);
    let quad = [
        Vec3::new(-2.0, -0.3, -2.0),
        Vec3::new(2.0, -0.3, -2.0),
        Vec3::new(2.0, -0.3, 2.0),
        Vec3::new(-2.0, -0.3, 2.0),
    ];
    let tris = [[0u32, 1, 2], [0, 2, 3]];
    let fibre = ChiangFibre {
        sigma_a: DVec3::ZERO,
        ..ChiangFibre::default()
    };
    let tracer = PathTracer::new(&HairScene {
        segments: &segments,
        fibre,
        strand_sigma_a: None,
        mesh_positions: &quad,
        mesh_triangles: &tris,
        mesh_albedo: DVec3::ONE,
        lights: &[],
    })
    .unwrap();
    let camera = Camera {
        eye: Vec3::new(0.0, 0.35, 1.0),
        target: Vec3::ZERO,
        fov_y: 25f32.to_radians(),
        near: 0.05,
        far: 20.0,
    };
    let base = PathTracerSettings {
        spp: 64,
        max_bounces: 1024,
        seed: 9,
        background: DVec3::ONE,
        sky: DVec3::ONE,
        roulette_start: 2000,
    };
    let exact = tracer.render(&camera, 32, 32, &base).unwrap();
    let hair_pixels: Vec<usize> = (0..exact.pixels.len())
        .filter(|&i| exact.hair_mask[i] == 1.0)
        .collect();
    assert!(hair_pixels.len() > 100, "{}", hair_pixels.len());
    let worst = exact
        .pixels
        .iter()
        .flat_map(|p| p.iter())
        .map(|v| (f64::from(*v) - 1.0).abs())
        .fold(0.0f64, f64::max);
    println!(
        "furnace without roulette: {} hair pixels, worst |L - 1| over all pixels {worst:.2e}",
        hair_pixels.len()
    );
    assert!(worst < 1e-5, "{worst}");

    let rr = tracer
        .render(
            &camera,
            32,
            32,
            &PathTracerSettings {
                roulette_start: 4,
                ..base
            },
        )
        .unwrap();
    let vals: Vec<f64> = hair_pixels
        .iter()
        .map(|&i| luminance(rr.pixels[i]))
        .collect();
    let n = vals.len() as f64;
    let mean = vals.iter().sum::<f64>() / n;
    let sd = (vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let se = sd / n.sqrt();
    println!("furnace with roulette: mean over hair pixels {mean:.5} (standard error {se:.5})");
    assert!((mean - 1.0).abs() < 4.0 * se + 1e-3, "{mean} ± {se}");
    // The roulette does add noise: it is on.
    assert!(sd > 1e-3, "{sd}");
}

#[test]
fn absorbing_fibres_in_the_furnace_are_darker_and_more_bounces_add_light() {
    // σ_a > 0: less than 1; more bounces never remove light (each adds a non-negative term).
    let segments = bundle(2.2);
    let lights: [Light; 0] = [];
    let fibre = ChiangFibre {
        sigma_a: DVec3::splat(0.3),
        ..ChiangFibre::default()
    };
    let tracer = PathTracer::new(&scene(&segments, fibre, &lights)).unwrap();
    let camera = front_camera(1.0, 25.0);
    let render = |bounces| {
        tracer
            .render(
                &camera,
                16,
                16,
                &PathTracerSettings {
                    spp: 64,
                    max_bounces: bounces,
                    seed: 1,
                    background: DVec3::ONE,
                    sky: DVec3::ONE,
                    roulette_start: 2000,
                },
            )
            .unwrap()
    };
    let one = render(1);
    let many = render(64);
    let centre = (8 * 16 + 8) as usize;
    let (a, b) = (
        luminance(one.pixels[centre]),
        luminance(many.pixels[centre]),
    );
    println!("absorbing bundle centre pixel: 1 bounce {a:.4}, 64 bounces {b:.4}");
    assert!(a < b && b < 0.95 && a > 0.02, "{a} {b}");
}

#[test]
fn per_strand_sigma_a_colours_each_strand() {
    // Two strands side by side, one white-ish and one dark: per-strand σ_a changes them.
    let segments = straight_strands(&[(-0.1, 0.0), (0.1, 0.0)], 4.0, 4, 0.08);
    let sig = [DVec3::splat(0.01), DVec3::splat(5.0)];
    let lights = [directional(Vec3::new(0.0, 0.3, -1.0).normalize(), 2.0)];
    let tracer = PathTracer::new(&HairScene {
        strand_sigma_a: Some(&sig),
        ..scene(&segments, ChiangFibre::default(), &lights)
    })
    .unwrap();
    let img = tracer
        .render(
            &front_camera(1.0, 30.0),
            32,
            32,
            &PathTracerSettings {
                spp: 16,
                max_bounces: 4,
                ..Default::default()
            },
        )
        .unwrap();
    // Back light: TT dominates; the clear strand (y = -0.1, lower rows) outshines the dark one.
    let row = |y: usize| {
        (0..32)
            .map(|x| luminance(img.pixels[y * 32 + x]))
            .sum::<f64>()
    };
    let upper: f64 = (0..16).map(row).sum();
    let lower: f64 = (16..32).map(row).sum();
    assert!(lower > 3.0 * upper, "lower {lower} upper {upper}");
}

#[test]
fn mesh_direct_light_is_lambert() {
    // A quad facing the camera, albedo ρ, one directional light at 60° from its normal:
    // radiance ρ/π · E cos 60°, exactly (no noise with one bounce and no hair).
    let quad = [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    let tris = [[0u32, 1, 2], [0, 2, 3]];
    let to_light = Vec3::new(0.0, 60f32.to_radians().sin(), 60f32.to_radians().cos());
    let lights = [directional(to_light, 3.0)];
    let albedo = DVec3::new(0.8, 0.5, 0.2);
    let tracer = PathTracer::new(&HairScene {
        segments: &[],
        fibre: ChiangFibre::default(),
        strand_sigma_a: None,
        mesh_positions: &quad,
        mesh_triangles: &tris,
        mesh_albedo: albedo,
        lights: &lights,
    })
    .unwrap();
    let img = tracer
        .render(
            &front_camera(1.0, 40.0),
            8,
            8,
            &PathTracerSettings {
                spp: 4,
                max_bounces: 1,
                ..Default::default()
            },
        )
        .unwrap();
    let expect = albedo / PI * 3.0 * 0.5;
    for p in &img.pixels {
        for c in 0..3 {
            assert!(
                (f64::from(p[c]) - expect[c]).abs() < 1e-5 * expect[c].max(1.0),
                "{p:?} vs {expect}"
            );
        }
    }
}

#[test]
fn camera_misses_see_the_background_and_scattered_rays_the_sky() {
    // pelage's semantics: `background` is what camera rays that miss see (it lights
    // nothing), `sky` lights what they hit. A red background, a blue sky, no lights: a
    // white quad over the left half of the view behind a strand. Pixels missing everything
    // are exactly the background; the quad and the strand are lit blue only, never red.
    let segments = straight_strands(&[(0.0, 0.0)], 4.0, 4, 0.08);
    let quad = [
        Vec3::new(-3.0, -3.0, -0.5),
        Vec3::new(0.0, -3.0, -0.5),
        Vec3::new(0.0, 3.0, -0.5),
        Vec3::new(-3.0, 3.0, -0.5),
    ];
    let tris = [[0u32, 1, 2], [0, 2, 3]];
    let tracer = PathTracer::new(&HairScene {
        segments: &segments,
        fibre: ChiangFibre::default(),
        strand_sigma_a: None,
        mesh_positions: &quad,
        mesh_triangles: &tris,
        mesh_albedo: DVec3::splat(0.5),
        lights: &[],
    })
    .unwrap();
    let background = DVec3::new(1.0, 0.0, 0.0);
    let (w, h) = (16usize, 16usize);
    let img = tracer
        .render(
            &front_camera(1.0, 40.0),
            w as u32,
            h as u32,
            &PathTracerSettings {
                spp: 16,
                max_bounces: 8,
                seed: 3,
                background,
                sky: DVec3::new(0.0, 0.0, 1.0),
                ..Default::default()
            },
        )
        .unwrap();
    let (mut misses, mut mesh, mut hair) = (0, Vec::new(), Vec::new());
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let p = img.pixels[i];
            if img.hair_mask[i] == 1.0 {
                assert_eq!(
                    p[0], 0.0,
                    "hair pixel ({x}, {y}) {p:?} has background in it"
                );
                hair.push(f64::from(p[2]));
            } else if img.hair_mask[i] > 0.0 {
                continue; // the strand's edge: hair and background or quad
            } else if x >= w / 2 {
                assert_eq!(p, [1.0, 0.0, 0.0], "miss pixel ({x}, {y})");
                misses += 1;
            } else {
                assert_eq!((p[0], p[1]), (0.0, 0.0), "quad pixel ({x}, {y}) {p:?}");
                mesh.push(f64::from(p[2]));
            }
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    println!(
        "{misses} misses, {} quad pixels (mean blue {:.3}), {} hair pixels (mean blue {:.3})",
        mesh.len(),
        mean(&mesh),
        hair.len(),
        mean(&hair)
    );
    assert!(misses > 40 && mesh.len() > 40 && hair.len() >= 4);
    // The quad sees the sky over (most of) its hemisphere: radiance albedo · sky = 0.5.
    assert!((0.4..=0.55).contains(&mean(&mesh)), "{}", mean(&mesh));
    assert!(hair.iter().all(|b| *b > 0.0), "{hair:?}");
}

#[test]
fn bad_settings_and_inputs_are_typed_errors() {
    let segments = straight_strands(&[(0.0, 0.0)], 2.0, 2, 0.05);
    let lights = [directional(Vec3::Y, 1.0)];
    let tracer = PathTracer::new(&scene(&segments, ChiangFibre::default(), &lights)).unwrap();
    let cam = front_camera(2.0, 30.0);
    let s = PathTracerSettings::default();
    let r = |set: PathTracerSettings, w, h| tracer.render(&cam, w, h, &set).unwrap_err();
    assert_eq!(
        r(
            PathTracerSettings {
                spp: 0,
                ..s.clone()
            },
            4,
            4
        ),
        PathTraceError::Spp(0)
    );
    assert_eq!(
        r(
            PathTracerSettings {
                spp: MAX_SPP + 1,
                ..s.clone()
            },
            4,
            4
        ),
        PathTraceError::Spp(MAX_SPP + 1)
    );
    assert!(
        PathTraceError::Spp(0)
            .to_string()
            .contains(&format!("1..={MAX_SPP}"))
    );
    assert_eq!(
        r(
            PathTracerSettings {
                max_bounces: 0,
                ..s.clone()
            },
            4,
            4
        ),
        PathTraceError::Bounces(0)
    );
    assert_eq!(
        r(
            PathTracerSettings {
                max_bounces: 1025,
                ..s.clone()
            },
            4,
            4
        ),
        PathTraceError::Bounces(1025)
    );
    assert_eq!(
        r(s.clone(), 0, 4),
        PathTraceError::Size {
            width: 0,
            height: 4
        }
    );
    assert!(matches!(
        r(
            PathTracerSettings {
                background: DVec3::new(f64::NAN, 0.0, 0.0),
                ..s.clone()
            },
            4,
            4
        ),
        PathTraceError::NonFinite { .. }
    ));
    assert_eq!(
        r(
            PathTracerSettings {
                sky: DVec3::new(0.0, f64::INFINITY, 0.0),
                ..s.clone()
            },
            4,
            4
        ),
        PathTraceError::NonFinite { what: "sky".into() }
    );
    assert!(matches!(
        r(
            PathTracerSettings {
                sky: DVec3::new(0.0, -0.1, 0.0),
                ..s.clone()
            },
            4,
            4
        ),
        PathTraceError::Invalid { what, .. } if what == "sky"
    ));
    let bad_cam = Camera {
        fov_y: f32::NAN,
        ..cam.clone()
    };
    assert!(matches!(
        tracer.render(&bad_cam, 4, 4, &s),
        Err(PathTraceError::Param(_))
    ));

    let mut nan_seg = segments.clone();
    nan_seg[1].a.y = f32::NAN;
    assert_eq!(
        PathTracer::new(&scene(&nan_seg, ChiangFibre::default(), &lights)).unwrap_err(),
        PathTraceError::NonFinite {
            what: "segments[1]".into()
        }
    );
    let bad_fibre = ChiangFibre {
        beta_n: f64::NAN,
        ..ChiangFibre::default()
    };
    assert!(matches!(
        PathTracer::new(&scene(&segments, bad_fibre, &lights)),
        Err(PathTraceError::Fibre(_))
    ));
    let bad_light = [directional(Vec3::ZERO, 1.0)];
    assert!(matches!(
        PathTracer::new(&scene(&segments, ChiangFibre::default(), &bad_light)),
        Err(PathTraceError::Param(_))
    ));
    let short = [DVec3::ZERO; 0];
    assert!(matches!(
        PathTracer::new(&HairScene {
            strand_sigma_a: Some(&short),
            ..scene(&segments, ChiangFibre::default(), &lights)
        }),
        Err(PathTraceError::Invalid { .. })
    ));
    let pos = [Vec3::ZERO, Vec3::X, Vec3::Y];
    assert!(matches!(
        PathTracer::new(&HairScene {
            mesh_positions: &pos,
            mesh_triangles: &[[0, 1, 3]],
            ..scene(&segments, ChiangFibre::default(), &lights)
        }),
        Err(PathTraceError::Invalid { .. })
    ));
    // A skin brighter than a Lambertian can be (`scenes/long_hair.toml`'s old skin, π ·
    // mesh_color = 1.73, 1.26, 1.04) is refused: it made light at every bounce.
    let bright = PathTracer::new(&HairScene {
        mesh_albedo: DVec3::new(1.73, 1.26, 1.04),
        ..scene(&segments, ChiangFibre::default(), &lights)
    })
    .unwrap_err();
    assert!(
        matches!(&bright, PathTraceError::Invalid { what, reason }
            if what == "mesh_albedo" && reason.contains("[0, 1]")),
        "{bright}"
    );
    let nan_pos = [Vec3::ZERO, Vec3::X, Vec3::new(0.0, f32::INFINITY, 0.0)];
    assert!(matches!(
        PathTracer::new(&HairScene {
            mesh_positions: &nan_pos,
            mesh_triangles: &[[0, 1, 2]],
            ..scene(&segments, ChiangFibre::default(), &lights)
        }),
        Err(PathTraceError::NonFinite { .. })
    ));
}

#[test]
fn images_convert_and_write() {
    let img = bundle_scene_render(2, 1);
    let lin = img.to_linear_image().unwrap();
    assert_eq!((lin.width, lin.height), (32, 32));
    let bytes = img.to_srgb8_rgba();
    assert_eq!(bytes.len(), 32 * 32 * 4);
    let dir = std::env::temp_dir().join(format!("pelage-pt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    img.write_hdr(&dir.join("a.hdr")).unwrap();
    img.write_png(&dir.join("a.png")).unwrap();
    let back = image::open(dir.join("a.hdr")).unwrap().into_rgb32f();
    assert_eq!(back.dimensions(), (32, 32));
    let p = back.get_pixel(16, 16).0;
    let q = img.pixels[16 * 32 + 16];
    let largest = q[0].max(q[1]).max(q[2]);
    for c in 0..3 {
        // Radiance HDR keeps an 8-bit mantissa per channel with a shared exponent: steps of
        // up to 2^-7 of the largest channel.
        assert!(
            (p[c] - q[c]).abs() <= largest / 128.0 + 1e-6,
            "{p:?} vs {q:?}"
        );
    }
    assert!(image::open(dir.join("a.png")).is_ok());
    std::fs::remove_dir_all(&dir).ok();
    assert!(matches!(
        img.write_png(&dir.join("missing").join("x.png")),
        Err(PathTraceError::Image(_))
    ));
}

/// About 3000 strands of 16 segments on a sphere of radius 0.5 (a head-sized ball of fur),
/// drooping under gravity.
fn furry_ball() -> (Vec<Segment>, Mesh) {
    let mesh = Mesh::icosphere(0.5, 3).unwrap();
    let strands = 3000;
    let vps = 17;
    let mut verts = Vec::with_capacity(strands * vps);
    let mut rng = pelage_reference::path_tracer::Pcg32::new(42, 0);
    for _ in 0..strands {
        let z = 2.0 * rng.next_f64() - 1.0;
        let phi = 2.0 * PI * rng.next_f64();
        let r = (1.0 - z * z).sqrt();
        let n = Vec3::new((r * phi.cos()) as f32, z as f32, (r * phi.sin()) as f32);
        let len = 0.35 + 0.1 * rng.next_f64() as f32;
        let mut p = n * 0.5;
        let mut dir = n;
        for i in 0..vps {
            let w = i as f32 / (vps - 1) as f32;
            verts.push(p.extend(w));
            dir = (dir + Vec3::new(0.0, -0.12, 0.0)).normalize();
            p += dir * (len / (vps - 1) as f32);
        }
    }
    let segs = segments_from_strands(&verts, vps, &vec![0.006; strands], 0.3, 1.0);
    (segs, mesh)
}

#[test]
#[ignore = "timing: about 30 s on two cores; run with --ignored --nocapture"]
fn timing_256x256_64spp_3000_strands() {
    let (segments, mesh) = furry_ball();
    let tris: Vec<[u32; 3]> = mesh
        .indices
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let camera = Camera::default();
    let lights = Light::key_and_back(&camera);
    let tracer = PathTracer::new(&HairScene {
        segments: &segments,
        fibre: ChiangFibre::default(),
        strand_sigma_a: None,
        mesh_positions: &mesh.positions,
        mesh_triangles: &tris,
        mesh_albedo: DVec3::new(0.5, 0.4, 0.35),
        lights: &lights,
    })
    .unwrap();
    let settings = PathTracerSettings {
        spp: 64,
        background: DVec3::splat(0.05),
        sky: DVec3::splat(0.05),
        ..Default::default()
    };
    let start = std::time::Instant::now();
    let img = tracer.render(&camera, 256, 256, &settings).unwrap();
    let secs = start.elapsed().as_secs_f64();
    let hair = img.hair_mask.iter().filter(|m| **m > 0.0).count();
    println!(
        "path tracer: 256x256, 64 spp, {} segments ({} strands), {} triangles, {} threads: {secs:.1} s ({hair} pixels touch hair)",
        segments.len(),
        segments.len() / 16,
        tris.len(),
        rayon::current_num_threads()
    );
    if let Ok(dir) = std::env::var("PELAGE_PT_OUT") {
        let dir = std::path::Path::new(&dir);
        img.write_png(&dir.join("furry_ball.png")).unwrap();
        img.write_hdr(&dir.join("furry_ball.hdr")).unwrap();
    }
    assert!(
        img.pixels
            .iter()
            .all(|p| p.iter().all(|v| v.is_finite() && *v >= 0.0))
    );
    assert!(hair > 5000, "{hair}");
    assert!(secs < 120.0, "{secs} s");
}

#[test]
fn closest_hit_is_the_nearest_entry_of_any_cylinder() {
    // SegmentBvh::closest_hit against a brute force over every segment: the entry distance of
    // a segment is the smallest max_t for which the exact any-hit test ray_hits_segment is
    // true (found by bisection), for rays from outside every cylinder. 2000 rays into the
    // furry ball's 48 000 segments.
    use pelage_reference::path_tracer::Pcg32;
    use pelage_reference::transmittance::{SegmentBvh, ray_hits_segment};
    let (segments, _) = furry_ball();
    let bvh = SegmentBvh::build(segments.clone());
    let mut rng = Pcg32::new(8, 8);
    let (mut hits, mut misses) = (0, 0);
    for _ in 0..2000 {
        let target = DVec3::new(
            rng.next_f64() - 0.5,
            rng.next_f64() - 0.5,
            rng.next_f64() - 0.5,
        ) * 1.6;
        let o = DVec3::new(3.0 * (rng.next_f64() - 0.5), 2.0, 3.0);
        let d = (target - o).normalize();
        let (of, df) = (o.as_vec3(), d.as_vec3());
        // f32 rays for the any-hit test: use exactly the rounded ray in f64 too.
        let (o, d) = (of.as_dvec3(), df.as_dvec3().normalize());
        let df = d.as_vec3();
        let mut best = (f64::INFINITY, usize::MAX);
        for (i, s) in segments.iter().enumerate() {
            if !ray_hits_segment(s, of, df, f32::INFINITY) {
                continue;
            }
            let (mut lo, mut hi) = (0.0f32, 20.0f32);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if ray_hits_segment(s, of, df, mid) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            if f64::from(hi) < best.0 {
                best = (f64::from(hi), i);
            }
        }
        let hit = bvh.closest_hit(o, d, f64::INFINITY, None);
        assert_eq!(bvh.occluded(o, d, f64::INFINITY, None), hit.is_some());
        match hit {
            None => {
                assert!(best.0.is_infinite(), "missed a hit at {}", best.0);
                misses += 1;
            }
            Some(h) => {
                // f32 bisection of the brute force: agree to its resolution.
                assert!(
                    (h.t - best.0).abs() < 1e-5 * (1.0 + best.0),
                    "t {} vs {}",
                    h.t,
                    best.0
                );
                assert!((-1.0..=1.0).contains(&h.h));
                // The hit point lies on the cylinder's surface.
                let s = h.segment;
                let (a, b) = (s.a.as_dvec3(), s.b.as_dvec3());
                let p = o + h.t * d;
                let axis = a + (b - a) * h.s;
                let dist = (p - axis).length();
                let r = f64::from(s.radius);
                assert!(dist <= r * (1.0 + 1e-6), "{dist} vs {r}");
                // And nothing is hit before it.
                assert!(bvh.closest_hit(o, d, h.t * (1.0 - 1e-9), None).is_none());
                hits += 1;
            }
        }
    }
    println!("closest hit: {hits} hits, {misses} misses, all equal to the brute force");
    assert!(hits > 500 && misses > 100, "{hits} {misses}");
}

#[test]
fn closest_hit_skips_the_inside_and_the_own_strand_close_by() {
    use pelage_reference::transmittance::SegmentBvh;
    let segments = straight_strands(&[(0.0, 0.0), (0.0, 1.0)], 2.0, 2, 0.2);
    let bvh = SegmentBvh::build(segments);
    // From inside strand 0 toward strand 1: strand 0 is not hit (the ray starts inside it).
    let hit = bvh
        .closest_hit(DVec3::new(0.2, 0.0, 0.0), DVec3::Z, f64::INFINITY, None)
        .unwrap();
    assert_eq!(hit.segment.strand, 1);
    assert!((hit.t - (1.0 - f64::from(0.1f32))).abs() < 1e-12);
    // A ray through the axis has h = 0; one offset by half the radius toward +y, travelling
    // +z along a fibre along +x, has h = x · (d × q)/r = x · (z × y)/2 = -1/2.
    assert!(hit.h.abs() < 1e-12);
    let off = bvh
        .closest_hit(DVec3::new(0.2, 0.05, -1.0), DVec3::Z, f64::INFINITY, None)
        .unwrap();
    assert_eq!(off.segment.strand, 0);
    assert!((off.h + 0.5).abs() < 1e-6, "{}", off.h);
    // Skipping strand 0 closer than 2 units finds strand 1 instead.
    let skipped = bvh
        .closest_hit(
            DVec3::new(0.2, 0.05, -1.0),
            DVec3::Z,
            f64::INFINITY,
            Some((0, 2.0)),
        )
        .unwrap();
    assert_eq!(skipped.segment.strand, 1);
    // max_t limits the search.
    assert!(
        bvh.closest_hit(DVec3::new(0.2, 0.05, -1.0), DVec3::Z, 0.5, None)
            .is_none()
    );
    assert!(!bvh.occluded(DVec3::new(0.2, 0.05, -1.0), DVec3::ZERO, 5.0, None));
}

#[test]
fn the_light_at_a_fibre_is_the_sky_and_a_lit_plane() {
    // One straight fibre along x seen from +z.
    let segments = straight_strands(&[(0.0, 0.0)], 2.0, 4, 0.01);
    let camera_ray = (DVec3::new(0.0, 0.0, 2.0), DVec3::new(0.0, 0.0, -1.0));
    // Alone under a sky of radiance S: every direction sees the sky, φ = 4π S exactly,
    // and the stratified directions leave almost no flux.
    let sky = DVec3::new(0.2, 0.3, 0.4);
    let tracer = PathTracer::new(&scene(&segments, ChiangFibre::default(), &[])).unwrap();
    let settings = PathTracerSettings {
        sky,
        ..Default::default()
    };
    let mut rng = Pcg32::new(1, 0);
    let s = tracer
        .field_at(camera_ray.0, camera_ray.1, 256, &settings, &mut rng)
        .unwrap()
        .expect("the camera ray hits the fibre");
    assert!((s.tangent.x.abs() - 1.0).abs() < 1e-9, "{:?}", s.tangent);
    assert!((s.view - DVec3::Z).length() < 1e-9, "{:?}", s.view);
    for c in 0..3 {
        let want = 4.0 * PI * sky[c];
        assert!(
            (s.fluence[c] - want).abs() < 1e-9 * want,
            "{} vs {want}",
            s.fluence[c]
        );
        assert!(s.flux[c].length() < 0.05 * want, "{:?}", s.flux[c]);
        assert!(
            s.response[c] > 0.0 && s.response[c] < want,
            "{:?}",
            s.response
        );
    }
    // Half a unit above a wide Lambertian plane (albedo ρ) lit head-on (irradiance E), no
    // sky: the plane's radiance ρE/π fills the lower hemisphere, so φ = 2ρE and Φ = ρE
    // upward, less the plane's edge (0.5 % of the hemisphere's φ beyond 89.4°) and the
    // fibre's shadow on it (a strip 0.02 rad across: 0.6 %). The fibre's own direct
    // light is not in the field.
    let plane = [
        Vec3::new(-50.0, -50.0, -0.5),
        Vec3::new(50.0, -50.0, -0.5),
        Vec3::new(50.0, 50.0, -0.5),
        Vec3::new(-50.0, 50.0, -0.5),
    ];
    let lights = [directional(Vec3::Z, 3.0)];
    let albedo = DVec3::new(0.8, 0.5, 0.2);
    let tracer = PathTracer::new(&HairScene {
        mesh_positions: &plane,
        mesh_triangles: &[[0, 1, 2], [0, 2, 3]],
        mesh_albedo: albedo,
        ..scene(&segments, ChiangFibre::default(), &lights)
    })
    .unwrap();
    let s = tracer
        .field_at(
            camera_ray.0,
            camera_ray.1,
            1024,
            &PathTracerSettings::default(),
            &mut rng,
        )
        .unwrap()
        .expect("the camera ray hits the fibre");
    for c in 0..3 {
        let e = albedo[c] * 3.0;
        let phi = s.fluence[c] / (2.0 * e);
        assert!((phi - 0.985).abs() < 0.02, "channel {c}: φ / 2ρE = {phi}");
        let up = s.flux[c].z / e;
        assert!((up - 1.0).abs() < 0.03, "channel {c}: Φ_z / ρE = {up}");
        let aside = s.flux[c].truncate().length() / e;
        assert!(aside < 0.03, "channel {c}: |Φ_xy| / ρE = {aside}");
    }
    // A ray that misses has no fibre; no directions is an error.
    let miss = tracer
        .field_at(DVec3::new(0.0, 5.0, 2.0), DVec3::Z, 16, &settings, &mut rng)
        .unwrap();
    assert!(miss.is_none());
    assert!(matches!(
        tracer.field_at(camera_ray.0, camera_ray.1, 0, &settings, &mut rng),
        Err(PathTraceError::Invalid { .. })
    ));
}
