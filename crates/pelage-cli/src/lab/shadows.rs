//! The shadow lab: every shadow method, at several resolutions and PCF kernels, on
//! three grooms, timed on the GPU and measured against transmittance ray-traced
//! through the real strands.
//!
//! ```text
//! pelage lab shadows [--quick] [--out DIR]
//! ```
//!
//! Writes `DIR/shadows.csv` (default `out/lab`; GPU time from timestamp queries, median
//! of repeated frames, with the wall clock of each frame beside it), a chart per groom
//! (`shadows_<groom>.png` and `.svg`: error against time, the Pareto front marked,
//! marker area = memory) and prints a table and the best method for each time budget.
//! `--quick` runs small grooms and a few configurations (for CI).

use std::time::Instant;

use glam::Vec4;
use pelage::gpu::{Gpu, GpuTimer, read_buffer, wgpu, zeroed_storage};
use pelage::scene::{
    AdsmParams, DeepOpacityParams, DirectionalLight, HairParams, HairType, LayerSpacing, MapParams,
    Mesh, OpacityFormat, ShadowMapParams, ShadowParams, Splat, VoxelParams, WindParams,
};
use pelage::shadow::{ShadowMethod, TransmittanceProbe};
use pelage::strands::{GrowStrands, MeshBuffers, StrandStage};
use pelage_lab::{ScatterChart, ScatterPoint, Table, pareto_front};
use pelage_reference::transmittance::{
    SegmentBvh, rmse_p95, segments_from_strands, transmittance_at_vertices,
};

use super::LabOpts;
use crate::progress;

/// One groom of the lab.
struct Groom {
    name: &'static str,
    mesh: Mesh,
    hair: HairParams,
}

fn grooms(quick: bool) -> Result<Vec<Groom>, Box<dyn std::error::Error>> {
    let scale = |full: u32, small: u32| if quick { small } else { full };
    let mut fur = HairParams::default();
    fur.roots.count = scale(20_000, 3_000);
    let mut long = HairParams::default();
    long.roots.count = scale(6_000, 1_500);
    long.growth.segments = 16;
    long.growth.length = 0.9;
    long.growth.force_weight = 0.12;
    long.growth.direction_jitter = 0.15;
    let mut curly = long.clone();
    curly.growth.segments = 24;
    curly.growth.length = 0.7;
    curly.growth.hair_type = HairType::Curly {
        radius: 0.03,
        pitch: 0.08,
    };
    let head = Mesh::icosphere(0.5, 3)?;
    let mut out = vec![
        Groom {
            name: "dense_fur",
            mesh: Mesh::creature(),
            hair: fur,
        },
        Groom {
            name: "long_hair",
            mesh: head.clone(),
            hair: long,
        },
        Groom {
            name: "curly_hair",
            mesh: head,
            hair: curly,
        },
    ];
    for g in &mut out {
        g.hair.wind = WindParams::calm();
    }
    Ok(out)
}

fn map(size: u32, pcf_radius: u32) -> MapParams {
    MapParams {
        size,
        pcf_radius,
        mesh_map_size: 0,
    }
}

/// Every configuration the lab sweeps: (method, resolution, PCF radius if it has one, parameters).
fn configurations(quick: bool) -> Vec<(&'static str, String, Option<u32>, ShadowParams)> {
    let mut out = Vec::new();
    let voxel_sizes: &[u32] = if quick {
        &[32, 64]
    } else {
        &[32, 64, 128, 192]
    };
    for &n in voxel_sizes {
        let p = VoxelParams {
            resolution: [n; 3],
            mesh_map_size: 0,
            ..VoxelParams::default()
        };
        out.push(("voxel", format!("{n}^3"), None, ShadowParams::Voxel(p)));
    }
    let p = VoxelParams {
        resolution: [64; 3],
        splat: Splat::Nearest,
        mesh_map_size: 0,
        ..VoxelParams::default()
    };
    out.push(("voxel nearest", "64^3".into(), None, ShadowParams::Voxel(p)));
    let dom_sizes: &[u32] = if quick { &[256] } else { &[256, 512, 1024] };
    for &n in dom_sizes {
        let p = DeepOpacityParams {
            map: map(n, 0),
            ..DeepOpacityParams::default()
        };
        out.push((
            "dom 3 layers",
            format!("{n}^2"),
            None,
            ShadowParams::DeepOpacity(p),
        ));
    }
    if !quick {
        let p = DeepOpacityParams {
            map: map(512, 0),
            layers: 6,
            spacing: LayerSpacing::Linear { depth: 0.04 },
            ..DeepOpacityParams::default()
        };
        out.push((
            "dom 6 linear",
            "512^2".into(),
            None,
            ShadowParams::DeepOpacity(p),
        ));
        let p = DeepOpacityParams {
            map: map(512, 0),
            format: OpacityFormat::Unorm8,
            ..DeepOpacityParams::default()
        };
        out.push((
            "dom unorm8",
            "512^2".into(),
            None,
            ShadowParams::DeepOpacity(p),
        ));
    }
    let map_sizes: &[u32] = if quick { &[512] } else { &[512, 1024, 2048] };
    let radii: &[u32] = if quick { &[0, 2] } else { &[0, 1, 2] };
    for &n in map_sizes {
        for &r in radii {
            let p = ShadowMapParams {
                map: map(n, r),
                ..ShadowMapParams::default()
            };
            out.push((
                "shadow map",
                format!("{n}^2"),
                Some(r),
                ShadowParams::ShadowMap(p),
            ));
        }
        let p = AdsmParams {
            map: map(n, 1),
            ..AdsmParams::default()
        };
        out.push(("adsm", format!("{n}^2"), Some(1), ShadowParams::Adsm(p)));
    }
    out
}

/// The strands of `groom` grown at t = 0 on `gpu`.
fn grow(
    gpu: &Gpu,
    groom: &Groom,
) -> Result<(GrowStrands, MeshBuffers), Box<dyn std::error::Error>> {
    let mesh_buffers = MeshBuffers::upload(gpu, &groom.mesh)?;
    let mut strands = GrowStrands::new(gpu, &groom.mesh, &mesh_buffers, &groom.hair)?;
    let frame = strands.prepare(&gpu.queue, 0.0)?;
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    strands.encode(&mut encoder, &frame, None)?;
    gpu.submit_and_wait([encoder.finish()])?;
    Ok((strands, mesh_buffers))
}

/// Median of a list of times.
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

struct Run {
    timestamp_ms: f64,
    wall_ms: f64,
    memory_mb: f64,
    rmse: f32,
    p95: f32,
}

/// Times `method` (median over `frames` after warm-up) and measures it against `truth`.
fn measure(
    gpu: &Gpu,
    method: &dyn ShadowMethod,
    strands: &GrowStrands,
    light: &DirectionalLight,
    truth: &[f32],
    frames: usize,
) -> Result<Run, Box<dyn std::error::Error>> {
    let strand_frame = strands.frame().ok_or("the strands were never grown")?;
    method.prepare(&gpu.queue, &strand_frame, light)?;
    let mut timer = GpuTimer::new(gpu, 8)?;
    let mut stamps = Vec::new();
    let mut walls = Vec::new();
    for frame in 0..frames + 3 {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        method.encode(&mut encoder, &strand_frame, timer.as_mut())?;
        if let Some(t) = &timer {
            t.resolve(&mut encoder);
        }
        let command = encoder.finish();
        let started = Instant::now();
        gpu.submit_and_wait([command])?;
        let wall = started.elapsed().as_secs_f64() * 1e3;
        let report = match &mut timer {
            Some(t) => Some(t.read(gpu)?),
            None => None,
        };
        if frame >= 3 {
            walls.push(wall);
            if let Some(r) = report {
                stamps.push(r.total_ms());
            }
        }
    }
    let buffers = strands.buffers();
    let out = zeroed_storage(
        gpu,
        "lab transmittance",
        buffers.vertices.size() / 4,
        wgpu::BufferUsages::STORAGE,
    )?;
    let probe = TransmittanceProbe::new(gpu, &method.binding())?;
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    probe.encode(gpu, &mut encoder, &buffers.vertices, &out)?;
    gpu.submit_and_wait([encoder.finish()])?;
    let t: Vec<f32> = bytemuck::cast_slice(&read_buffer(gpu, &out)?).to_vec();
    let (rmse, p95) = rmse_p95(&t, truth).ok_or("transmittance and reference differ in length")?;
    Ok(Run {
        timestamp_ms: if stamps.is_empty() {
            f64::NAN
        } else {
            median(stamps)
        },
        wall_ms: median(walls),
        memory_mb: method.memory_bytes() as f64 / 1e6,
        rmse,
        p95,
    })
}

/// Runs the shadow lab: writes `shadows.csv` and a chart per groom under `opts.out`.
pub fn run(opts: &LabOpts) -> Result<(), Box<dyn std::error::Error>> {
    let started = Instant::now();
    let light = DirectionalLight::default();
    let to_light = light.to_light()?;
    let frames = if opts.quick { 5 } else { 20 };
    let mut table = Table::new(&[
        "groom",
        "method",
        "resolution",
        "pcf",
        "gpu_ms",
        "wall_ms",
        "memory_mb",
        "rmse",
        "p95",
    ]);
    let configs = configurations(opts.quick);
    let grooms = grooms(opts.quick)?;
    let bar = progress::bar((grooms.len() * configs.len()) as u64, "runs")?;
    let mut budgets_text = String::new();
    for groom in grooms {
        // Ground truth once per groom.
        let gpu = Gpu::headless()?;
        let (strands, _) = grow(&gpu, &groom)?;
        let buffers = strands.buffers();
        let vertices: Vec<Vec4> =
            bytemuck::cast_slice::<u8, [f32; 4]>(&read_buffer(&gpu, &buffers.vertices)?)
                .iter()
                .map(|v| Vec4::from_array(*v))
                .collect();
        let widths: Vec<f32> = strands.roots().iter().map(|r| r.width).collect();
        let per = (buffers.segments + 1) as usize;
        let g = &groom.hair.growth;
        let bvh = SegmentBvh::build(segments_from_strands(
            &vertices,
            per,
            &widths,
            g.tip_width,
            g.opacity,
        ));
        let reference_started = Instant::now();
        let truth = transmittance_at_vertices(&bvh, &vertices, per, to_light, 0.01, 16);
        bar.println(format!(
            "{}: {} strands, {} vertices; reference ray-traced in {:.1} s",
            groom.name,
            buffers.strand_count,
            vertices.len(),
            reference_started.elapsed().as_secs_f64()
        ));

        let mut points = Vec::new();
        for (method, resolution, pcf, params) in &configs {
            bar.set_message(format!("{} {method} {resolution}", groom.name));
            // A fresh device per run: lavapipe misplaces compute timestamps once a
            // render pass has run on a device, and the map methods are render passes.
            let gpu = Gpu::headless()?;
            let (strands, mesh_buffers) = grow(&gpu, &groom)?;
            let built = pelage::shadow::build(&gpu, params, strands.buffers(), &mesh_buffers)?
                .ok_or("a configuration without a method")?;
            let run = measure(&gpu, built.as_ref(), &strands, &light, &truth, frames)?;
            let time = if run.timestamp_ms.is_finite() {
                run.timestamp_ms
            } else {
                run.wall_ms
            };
            table.push(vec![
                groom.name.to_string(),
                method.to_string(),
                resolution.clone(),
                pcf.map_or("-".to_string(), |r| format!("{}x{}", 2 * r + 1, 2 * r + 1)),
                format!("{:.3}", run.timestamp_ms),
                format!("{:.3}", run.wall_ms),
                format!("{:.2}", run.memory_mb),
                format!("{:.4}", run.rmse),
                format!("{:.4}", run.p95),
            ])?;
            let label = match pcf {
                Some(r) => format!("{resolution} pcf{}", 2 * r + 1),
                None => resolution.clone(),
            };
            points.push(ScatterPoint {
                series: method.to_string(),
                label,
                x: time,
                y: f64::from(run.rmse),
                size: Some(run.memory_mb),
            });
            bar.inc(1);
        }

        // The best configuration for each time budget: the Pareto front, read left to right.
        let xy: Vec<(f64, f64)> = points.iter().map(|p| (p.x, p.y)).collect();
        budgets_text.push_str(&format!(
            "{}: best RMSE within a time budget (Pareto front)\n",
            groom.name
        ));
        for i in pareto_front(&xy) {
            let p = &points[i];
            budgets_text.push_str(&format!(
                "  <= {:8.2} ms: {} {} (RMSE {:.3})\n",
                p.x, p.series, p.label, p.y
            ));
        }
        let chart = ScatterChart {
            title: format!(
                "Shadow methods on {}: error against GPU time (lavapipe)",
                groom.name.replace('_', " ")
            ),
            x_label: "shadow stage GPU time, ms (log)".into(),
            y_label: "transmittance RMSE vs ray tracing".into(),
            x_log: true,
            y_log: false,
            points,
            mark_pareto: true,
            size_label: Some("memory, MB".into()),
        };
        chart.write_svg(
            &opts.out.join(format!("shadows_{}.svg", groom.name)),
            900,
            600,
        )?;
        chart.write_png(
            &opts.out.join(format!("shadows_{}.png", groom.name)),
            900,
            600,
        )?;
    }
    bar.finish_and_clear();
    table.write_csv(&opts.out.join("shadows.csv"))?;
    println!("{}", table.to_text());
    print!("{budgets_text}");
    println!(
        "wrote {}/shadows.csv and shadows_<groom>.png|svg in {:.0} s",
        opts.out.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
