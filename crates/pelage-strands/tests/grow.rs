//! Stage 1 on a real adapter (lavapipe in CI), against the CPU mirror in pelage-reference.

use glam::{Vec3, Vec4};
use pelage_gpu::Gpu;
use pelage_reference::strands::{Level, eval_surface, grow_strands};
use pelage_scene::{
    HairParams, HairType, MAX_FORCE, Mesh, RootParams, SurfaceInterpolation, WindParams,
};
use pelage_strands::{GrowStrands, MeshBuffers, StrandStage};

mod common;
use common::{gpu, grow_on_gpu, mirror_roots, read_vertices};

fn scene_size(mesh: &Mesh) -> f32 {
    let (lo, hi) = mesh.bounds();
    (hi - lo).length()
}

fn params(count: u32, hair_type: HairType, surface: SurfaceInterpolation) -> HairParams {
    let mut p = HairParams::default();
    p.roots.count = count;
    p.growth.hair_type = hair_type;
    p.growth.surface = surface;
    p.growth.segments = 12;
    p.growth.length = 0.4;
    p
}

#[test]
fn gpu_matches_cpu_mirror_for_every_hair_type_and_time() {
    let gpu = gpu();
    let mesh = Mesh::creature();
    let buffers = MeshBuffers::upload(&gpu, &mesh).unwrap();
    let tolerance = 1e-5 * scene_size(&mesh);
    let types = [
        HairType::Straight,
        HairType::Wavy {
            amplitude: 0.02,
            frequency: 6.0,
        },
        HairType::Curly {
            radius: 0.015,
            pitch: 0.05,
        },
    ];
    for hair_type in types {
        for surface in [SurfaceInterpolation::Flat, SurfaceInterpolation::PnTriangle] {
            let p = params(300, hair_type, surface);
            let mut strands = GrowStrands::new(&gpu, &mesh, &buffers, &p).unwrap();
            let roots = mirror_roots(strands.roots());
            for t in [0.0, 0.37, 5.0, 1234.5] {
                let gpu_vertices = grow_on_gpu(&gpu, &mut strands, t);
                let cpu_vertices = grow_strands(&mesh, &roots, &p, t, Level::full(&p));
                assert_eq!(gpu_vertices.len(), cpu_vertices.len());
                let worst = gpu_vertices
                    .iter()
                    .zip(&cpu_vertices)
                    .map(|(g, c)| (g.truncate() - c.truncate()).abs().max_element())
                    .fold(0.0f32, f32::max);
                println!("{hair_type:?} {surface:?} t={t}: max |GPU - CPU| = {worst:.2e}");
                assert!(
                    worst <= tolerance,
                    "{hair_type:?} {surface:?} t={t}: GPU and CPU differ by {worst} (tolerance {tolerance})"
                );
                // The strand parameter channel is exact.
                assert!(
                    gpu_vertices
                        .iter()
                        .zip(&cpu_vertices)
                        .all(|(g, c)| g.w == c.w)
                );
            }
        }
    }
}

/// Mean distance of the strand roots from the unit sphere, for roots on an icosphere of subdivision 1.
fn mean_radial_error(gpu: &Gpu, surface: SurfaceInterpolation) -> f32 {
    let mesh = Mesh::icosphere(1.0, 1).unwrap();
    let buffers = MeshBuffers::upload(gpu, &mesh).unwrap();
    let mut p = params(4000, HairType::Straight, surface);
    p.wind = WindParams::calm();
    let mut strands = GrowStrands::new(gpu, &mesh, &buffers, &p).unwrap();
    let vertices = grow_on_gpu(gpu, &mut strands, 0.0);
    let per_strand = (p.growth.segments + 1) as usize;
    let errors: Vec<f32> = vertices
        .chunks(per_strand)
        .map(|s| (s[0].truncate().length() - 1.0).abs())
        .collect();
    errors.iter().sum::<f32>() / errors.len() as f32
}

#[test]
fn pn_triangles_put_roots_closer_to_the_true_sphere() {
    let gpu = gpu();
    let flat = mean_radial_error(&gpu, SurfaceInterpolation::Flat);
    let pn = mean_radial_error(&gpu, SurfaceInterpolation::PnTriangle);
    println!(
        "mean radial error on an icosphere of subdivision 1: flat {flat:.2e}, PN {pn:.2e}, ratio {:.1}",
        flat / pn
    );
    assert!(flat > 5.0 * pn, "PN {pn} is not 5x closer than flat {flat}");
}

#[test]
fn same_scene_seed_and_time_give_bit_identical_buffers() {
    let gpu = gpu();
    let mesh = Mesh::creature();
    let buffers = MeshBuffers::upload(&gpu, &mesh).unwrap();
    let p = params(
        2000,
        HairType::Curly {
            radius: 0.01,
            pitch: 0.04,
        },
        SurfaceInterpolation::PnTriangle,
    );
    let mut a = GrowStrands::new(&gpu, &mesh, &buffers, &p).unwrap();
    let mut b = GrowStrands::new(&gpu, &mesh, &buffers, &p).unwrap();
    let va = grow_on_gpu(&gpu, &mut a, 2.5);
    // Render another time in between: frame t must not depend on what came before.
    grow_on_gpu(&gpu, &mut b, 7.0);
    let vb = grow_on_gpu(&gpu, &mut b, 2.5);
    let bits = |v: &[Vec4]| {
        v.iter()
            .flat_map(|x| x.to_array().map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&va), bits(&vb));
}

#[test]
fn strongest_wind_for_ten_thousand_frames_keeps_every_segment() {
    const FRAMES: u32 = 10_000;
    const BATCH: u32 = 250;
    let gpu = gpu();
    let mesh = Mesh::creature();
    let buffers = MeshBuffers::upload(&gpu, &mesh).unwrap();
    let mut p = params(64, HairType::Straight, SurfaceInterpolation::PnTriangle);
    p.roots = RootParams {
        count: 64,
        ..Default::default()
    };
    p.growth.segments = 16;
    p.growth.force_weight = 10.0;
    p.growth.gravity = Vec3::new(0.0, -1000.0, 0.0);
    p.wind = WindParams {
        strength: MAX_FORCE,
        gust_strength: 1.0,
        gust_frequency: 50.0,
        turbulence: MAX_FORCE,
        turbulence_scale: 40.0,
        turbulence_speed: 100.0,
        ..WindParams::default()
    };
    let mut strands = GrowStrands::new(&gpu, &mesh, &buffers, &p).unwrap();
    let vertices = strands.buffers().vertices.clone();
    let frame_bytes = vertices.size();
    let history = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("history"),
        size: frame_bytes * u64::from(BATCH),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let roots: Vec<Vec3> = strands
        .roots()
        .iter()
        .map(|r| eval_surface(&mesh, r.triangle, r.bary, true).position)
        .collect();
    let per_strand = (p.growth.segments + 1) as usize;

    let mut t = 0.0f32;
    let mut worst_stretch = 0.0f32;
    for batch in 0..FRAMES / BATCH {
        for k in 0..BATCH {
            // dt sweeps 1 ms .. 1 s geometrically, over and over.
            let frame = batch * BATCH + k;
            t += 1e-3 * 1000f32.powf((frame % 100) as f32 / 99.0);
            let frame = strands.prepare(&gpu.queue, t).unwrap();
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            strands.encode(&mut encoder, &frame, None).unwrap();
            encoder.copy_buffer_to_buffer(
                &vertices,
                0,
                &history,
                frame_bytes * u64::from(k),
                frame_bytes,
            );
            gpu.queue.submit([encoder.finish()]);
        }
        let vertices = read_vertices(&gpu, &history);
        for (s, strand) in vertices.chunks(per_strand).enumerate() {
            let root = &strands.roots()[s % roots.len()];
            let rest = root.length / p.growth.segments as f32;
            assert!(
                strand.iter().all(|v| v.is_finite()),
                "non-finite vertex in batch {batch}"
            );
            let on_surface = (strand[0].truncate() - roots[s % roots.len()]).length();
            assert!(on_surface <= 1e-5, "root left the surface by {on_surface}");
            for w in strand.windows(2) {
                let len = (w[1].truncate() - w[0].truncate()).length();
                let stretch = (len - rest).abs() / rest;
                worst_stretch = worst_stretch.max(stretch);
                assert!(
                    stretch <= 1e-4,
                    "segment of rest length {rest} has length {len}"
                );
            }
        }
    }
    println!(
        "{FRAMES} frames up to t = {t:.1} s: worst relative segment stretch {worst_stretch:.2e}"
    );
}
