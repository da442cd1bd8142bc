//! The performance report: GPU time per stage, bandwidth against a plain copy kernel,
//! scaling with strand count, memory, and the cost of shadows and transparency over
//! the bare lit strand pass.
//!
//! ```text
//! pelage bench [--quick] [--out DIR]
//! pelage bench --gpu [--quick] [--allow-cpu] [--out DIR]
//! ```
//!
//! `--gpu` runs the real-GPU bench instead (`gpu_bench.rs`, docs/src/gpu_bench.md).
//!
//! Writes `DIR/bench.csv` (default `out/bench`), `DIR/scaling.png|svg` (stage time
//! against strand count, log-log) and prints the tables. `--quick` uses small scenes
//! and few frames (CI).
//!
//! How it measures (lavapipe misplaces compute-pass timestamps once a render pass has
//! run on a device, so the two kinds never share one):
//! - compute stages (strand expansion, grid fit, splat, scan) and the copy kernel run
//!   on a device that never draws: timestamp queries, median of the frames after
//!   three of warm-up. Bytes are the buffers each stage reads and writes; the ratio
//!   is the stage's bytes per second over the copy kernel's, same device, same run;
//! - raster stages (the lit strand pass, each transparency method's passes) are timed
//!   with timestamps on a device of their own, same frames;
//! - whole stages that mix both (each shadow method, whole frames) use the wall clock
//!   of the stage submitted alone and waited for (`Renderer::stage_wall_times`).

use std::time::Instant;

use pelage::gpu::{Gpu, GpuTimer, ShaderSources, compute_pipeline, dispatch_size, wgpu};
use pelage::scene::{
    ChiangParams, DirectionalLight, DynamicsParams, MultipleScattering, ShadingModel, ShadowParams,
    SkinBend, Transparency, VoxelParams, WindParams,
};
use pelage::scene::{GuideParams, Resampled};
use pelage::shadow::{ShadowMethod, VoxelShadow};
use pelage::strands::{
    BodySdf, GroomStrands, GrowStrands, GuideMemory, GuideStrands, MeshBuffers, MeshSkin,
    SDF_LABEL, SDF_SKIN_LABEL, SIMULATE_LABEL, SKIN_LABEL, SdfSkin, SimulateStrands, StrandStage,
    body_triangles,
};
use pelage::{Renderer, scene::Scene};
use pelage_lab::{ScatterChart, ScatterPoint, Table};

use crate::lab::LabOpts;
use crate::progress;

/// The benchmark's kernels (`wgsl/bench/*.wgsl`).
static SHADERS: ShaderSources =
    pelage::gpu::wgsl_sources!("bench/copy.wgsl", "bench/strand_writes.wgsl",);

type Error = Box<dyn std::error::Error>;

/// The options of `pelage bench`.
#[derive(Clone, Debug, clap::Args)]
pub struct BenchOpts {
    /// `--quick` and `--out`, as the labs take them.
    #[command(flatten)]
    pub lab: LabOpts,
    /// The real-GPU bench: GPU time per stage of whole frames at 1920x1080, every
    /// transparency method and shadow, the anchors; writes gpu_bench.csv and gpu_bench.md.
    #[arg(long)]
    pub gpu: bool,
    /// With --gpu: run on a CPU adapter (lavapipe) too (a smoke run; not GPU figures).
    #[arg(long, requires = "gpu")]
    pub allow_cpu: bool,
}

/// Runs `pelage bench` as `opts` asks: the lavapipe report ([`run`]) or, with `--gpu`,
/// the real-GPU bench.
pub fn run_command(opts: &BenchOpts) -> Result<(), Error> {
    if opts.gpu {
        crate::gpu_bench::run(&opts.lab, opts.allow_cpu)
    } else {
        run(&opts.lab)
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// The copy kernel (`wgsl/bench/copy.wgsl`) over two buffers of `bytes`.
struct Copy {
    pipeline: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    groups: (u32, u32),
    bytes: u64,
}

impl Copy {
    fn new(gpu: &Gpu, bytes: u64) -> Result<Self, Error> {
        let usage = wgpu::BufferUsages::STORAGE;
        let source = pelage::gpu::zeroed_storage(gpu, "bench copy source", bytes, usage)?;
        let target = pelage::gpu::zeroed_storage(gpu, "bench copy target", bytes, usage)?;
        let module = SHADERS.library().module(gpu, "bench/copy.wgsl")?;
        let (pipeline, group) = gpu.scoped(|device| {
            let pipeline = compute_pipeline(device, "bench copy", &module, "main");
            let group = pelage::gpu::bind_buffers(
                device,
                "bench copy",
                &pipeline.get_bind_group_layout(0),
                &[&source, &target],
            );
            (pipeline, group)
        })?;
        Ok(Self {
            pipeline,
            group,
            groups: dispatch_size(gpu.limits(), bytes / 16, 64),
            bytes,
        })
    }

    fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("copy"),
            timestamp_writes: timer.and_then(|t| t.compute_pass("copy")),
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.group, &[]);
        pass.dispatch_workgroups(self.groups.0, self.groups.1, 1);
    }
}

/// Strand-major writes with no arithmetic (`wgsl/bench/strand_writes.wgsl`): what the
/// expansion's memory layout alone costs.
struct StrandWrites {
    pipeline: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    groups: (u32, u32),
}

impl StrandWrites {
    fn new(
        gpu: &Gpu,
        vertices: &wgpu::Buffer,
        strands: u32,
        per_strand: u32,
    ) -> Result<Self, Error> {
        let uniform = pelage::gpu::UniformBuffer::new(
            gpu,
            "bench per strand",
            &glam::UVec4::new(per_strand, 0, 0, 0),
        )?;
        let module = SHADERS.library().module(gpu, "bench/strand_writes.wgsl")?;
        let (pipeline, group) = gpu.scoped(|device| {
            let pipeline = compute_pipeline(device, "bench strand writes", &module, "main");
            let group = pelage::gpu::bind_buffers(
                device,
                "bench strand writes",
                &pipeline.get_bind_group_layout(0),
                &[&uniform.buffer, vertices],
            );
            (pipeline, group)
        })?;
        Ok(Self {
            pipeline,
            group,
            groups: dispatch_size(gpu.limits(), u64::from(strands), 64),
        })
    }

    fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("strand writes"),
            timestamp_writes: timer.and_then(|t| t.compute_pass("strand writes")),
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.group, &[]);
        pass.dispatch_workgroups(self.groups.0, self.groups.1, 1);
    }
}

/// The strands `grow` grows at t = 0, read back as a groom of the same strands and segments.
fn grown_groom(gpu: &Gpu, grow: &mut GrowStrands) -> Result<Resampled, Error> {
    let frame = grow.prepare(&gpu.queue, 0.0)?;
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    grow.encode(&mut encoder, &frame, None)?;
    gpu.submit_and_wait([encoder.finish()])?;
    let bytes = pelage::gpu::read_buffer(gpu, &grow.buffers().vertices)?;
    let points = bytes
        .chunks_exact(16)
        .map(|v| {
            let f = |i: usize| f32::from_le_bytes([v[i], v[i + 1], v[i + 2], v[i + 3]]);
            glam::Vec3::new(f(0), f(4), f(8))
        })
        .collect();
    let strands = grow.buffers().strand_count;
    Ok(Resampled {
        points,
        widths: None,
        segments: grow.buffers().segments,
        strands,
        skipped: 0,
        source_strands: (0..strands).collect(),
        colors: None,
    })
}

/// Every `every`-th strand of `groom` (at least one): guides to interpolate from.
fn subsampled(groom: &Resampled, every: u32) -> Resampled {
    let per_strand = groom.segments as usize + 1;
    let kept: Vec<usize> = (0..groom.strands as usize)
        .step_by(every.max(1) as usize)
        .collect();
    Resampled {
        points: kept
            .iter()
            .flat_map(|&i| {
                groom.points[i * per_strand..(i + 1) * per_strand]
                    .iter()
                    .copied()
            })
            .collect(),
        widths: None,
        segments: groom.segments,
        strands: kept.len() as u32,
        skipped: 0,
        source_strands: kept.iter().map(|&i| i as u32).collect(),
        colors: groom
            .colors
            .as_ref()
            .map(|c| kept.iter().filter_map(|&i| c.get(i).copied()).collect()),
    }
}

/// Grown strands taken as guides: one guide per this many render strands.
const STRANDS_PER_GUIDE: u32 = 50;

/// Frames (after 3 of warm-up) the interpolation pass is timed against the growth pass,
/// in both modes: a few milliseconds each.
const GUIDE_FRAMES: usize = 20;

/// The default creature with `strands` strands of `segments` segments, in the default wind.
fn scene(strands: u32, segments: u32) -> Scene {
    let mut scene = Scene::default();
    scene.hair.roots.count = strands;
    scene.hair.growth.segments = segments;
    scene.hair.wind = WindParams::default();
    scene
}

/// Median GPU milliseconds per timer label over `frames` frames after 3 of warm-up.
fn time_frames(
    gpu: &Gpu,
    frames: usize,
    encode: impl FnMut(&mut wgpu::CommandEncoder, Option<&mut GpuTimer>, usize) -> Result<(), Error>,
) -> Result<Vec<(String, f64)>, Error> {
    let samples = frame_samples(gpu, frames, encode)?;
    Ok(samples.into_iter().map(|(l, v)| (l, median(v))).collect())
}

/// GPU milliseconds per timer label, one per frame, over `frames` frames after 3 of
/// warm-up (what [`time_frames`] takes the median of).
fn frame_samples(
    gpu: &Gpu,
    frames: usize,
    mut encode: impl FnMut(&mut wgpu::CommandEncoder, Option<&mut GpuTimer>, usize) -> Result<(), Error>,
) -> Result<Vec<(String, Vec<f64>)>, Error> {
    let mut timer = GpuTimer::new(gpu, 64)?.ok_or("this adapter has no timestamp queries")?;
    let mut samples: Vec<(String, Vec<f64>)> = Vec::new();
    for frame in 0..frames + 3 {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encode(&mut encoder, Some(&mut timer), frame)?;
        timer.resolve(&mut encoder);
        gpu.submit_and_wait([encoder.finish()])?;
        let report = timer.read(gpu)?;
        if frame < 3 {
            continue;
        }
        for (label, ms) in report.by_label() {
            match samples.iter_mut().find(|(l, _)| *l == label) {
                Some((_, v)) => v.push(ms),
                None => samples.push((label, vec![ms])),
            }
        }
    }
    Ok(samples)
}

fn get(times: &[(String, f64)], label: &str) -> f64 {
    times
        .iter()
        .find(|(l, _)| l == label)
        .map_or(f64::NAN, |(_, ms)| *ms)
}

/// Least-squares slope of log(y) against log(x).
fn exponent(points: &[(f64, f64)]) -> f64 {
    let logs: Vec<(f64, f64)> = points.iter().map(|(x, y)| (x.ln(), y.ln())).collect();
    let n = logs.len() as f64;
    let (mx, my) = (
        logs.iter().map(|p| p.0).sum::<f64>() / n,
        logs.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxy: f64 = logs.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = logs.iter().map(|(x, _)| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

struct Row {
    section: &'static str,
    stage: String,
    strands: u32,
    pixels: u64,
    gpu_ms: f64,
    bytes: u64,
    copy_ratio: f64,
    note: String,
}

/// Runs the benchmark: writes `bench.csv` and `scaling.png|svg` under `opts.out` and
/// prints the tables.
pub fn run(opts: &LabOpts) -> Result<(), Error> {
    let started = Instant::now();
    pelage_lab::create_dir(&opts.out)?;
    let counts: &[u32] = if opts.quick {
        &[2_000, 8_000]
    } else {
        &[10_000, 50_000, 200_000]
    };
    let frames = if opts.quick { 3 } else { 20 };
    let (width, height) = if opts.quick { (160, 120) } else { (480, 360) };
    let mut rows: Vec<Row> = Vec::new();
    let light = DirectionalLight::default();
    // Every hardware-rasterized method (the strand rasterizer has its own section).
    let methods: Vec<Transparency> = Transparency::defaults()
        .into_iter()
        .filter(|t| !matches!(t, Transparency::StrandRaster { .. }))
        .collect();
    // Steps: each strand count's compute stages and each of its transparency methods,
    // then the bare lit pass and the three combinations of section 4.
    let bar = progress::bar((counts.len() * (1 + methods.len()) + 9) as u64, "steps")?;

    // 1. Compute stages and the copy kernel, on a device that never draws.
    bar.println(format!(
        "compute stages (timestamps, median of {frames} frames):"
    ));
    let mut scan_ms = Vec::new();
    let mut grow_points = Vec::new();
    let mut guide_ratios = Vec::new();
    for &strands in counts {
        let gpu = Gpu::headless()?;
        let s = scene(strands, 8);
        let mesh = MeshBuffers::upload(&gpu, &s.mesh)?;
        let mut grow = GrowStrands::new(&gpu, &s.mesh, &mesh, &s.hair)?;
        let b = grow.buffers();
        let voxel = VoxelShadow::new(
            &gpu,
            &VoxelParams::default(),
            b,
            &mesh,
            pelage::strands::scene_reach(&s),
        )?;
        let copy = Copy::new(&gpu, b.vertices.size().max(16 << 20))?;
        let scratch = pelage::gpu::zeroed_storage(
            &gpu,
            "bench strand writes",
            b.vertices.size(),
            wgpu::BufferUsages::STORAGE,
        )?;
        let writes = StrandWrites::new(&gpu, &scratch, b.strand_count, b.segments + 1)?;
        let (vertices, roots, volume) = (b.vertices.size(), b.roots.size(), voxel.volume().size());
        let times = time_frames(&gpu, frames, |encoder, mut timer, frame| {
            let frame = grow.prepare(&gpu.queue, frame as f32 / 24.0)?;
            voxel.prepare(&gpu.queue, &frame, &light)?;
            grow.encode(encoder, &frame, timer.as_deref_mut())?;
            voxel.encode_density(encoder, timer.as_deref_mut());
            voxel.encode_scan(encoder, timer.as_deref_mut());
            writes.encode(encoder, timer.as_deref_mut());
            copy.encode(encoder, timer);
            Ok(())
        })?;
        let copy_ms = get(&times, "copy");
        let copy_rate = 2.0 * copy.bytes as f64 / copy_ms;
        let mesh_bytes = mesh.positions.size() + mesh.normals.size() + mesh.indices.size();
        let stages = [
            (
                "strands: grow",
                roots + mesh_bytes + vertices,
                "reads roots and mesh, writes vertices",
            ),
            ("shadow: fit", vertices, "reads vertices"),
            (
                "shadow: splat",
                vertices + roots + volume,
                "reads vertices and roots, adds into the grid",
            ),
            ("shadow: scan", 2 * volume, "reads and writes the grid"),
            (
                "strand writes",
                vertices,
                "grow's writes without its arithmetic: the layout's limit",
            ),
            ("copy", 2 * copy.bytes, "the yardstick"),
        ];
        let compute_row = |stage: &str, ms: f64, bytes: u64, note: &str| {
            let ratio = (bytes as f64 / ms) / copy_rate;
            bar.println(format!(
                "  {strands:>7} strands  {stage:<15} {ms:9.3} ms  {:8.2} MB  {:6.2} GB/s  {:5.0}% of copy",
                bytes as f64 / 1e6,
                bytes as f64 / ms / 1e6,
                100.0 * ratio
            ));
            Row {
                section: "compute",
                stage: stage.into(),
                strands,
                pixels: 0,
                gpu_ms: ms,
                bytes,
                copy_ratio: ratio,
                note: note.into(),
            }
        };
        for (label, bytes, note) in stages {
            rows.push(compute_row(label, get(&times, label), bytes, note));
        }
        // The same expansion without wind forces (no noise to evaluate): how much of the
        // stage is arithmetic rather than memory traffic.
        let mut calm = s.hair.clone();
        calm.wind = WindParams::calm();
        let mut still = GrowStrands::new(&gpu, &s.mesh, &mesh, &calm)?;
        let still_frame = still.prepare(&gpu.queue, 0.0)?;
        let still_times = time_frames(&gpu, frames, |encoder, timer, _| {
            still.encode(encoder, &still_frame, timer)?;
            Ok(())
        })?;
        rows.push(compute_row(
            "strands: grow, no wind",
            get(&still_times, "strands: grow"),
            roots + mesh_bytes + vertices,
            "gravity and wind off: the surface evaluation and growth alone",
        ));
        // The same strands as a groom file would bring them (grown once, read back),
        // bent by the same wind every frame: the other stage 1 method.
        let groom = grown_groom(&gpu, &mut grow)?;
        let mut bent = GroomStrands::new(&gpu, &groom, &s.hair)?;
        let groom_times = time_frames(&gpu, frames, |encoder, timer, frame| {
            let frame = bent.prepare(&gpu.queue, frame as f32 / 24.0)?;
            bent.encode(encoder, &frame, timer)?;
            Ok(())
        })?;
        rows.push(compute_row(
            "strands: groom",
            get(&groom_times, "strands: groom"),
            2 * vertices + roots,
            "the grown strands as a groom: reads rest points and roots, writes vertices",
        ));
        // The grown strands simulated (the default dynamics, frames of 1/60 s): bytes are
        // what each substep moves per vertex (rest, position and previous position read,
        // position and previous written: 5 vec4) plus, once a frame, the mesh, roots and
        // vertices; the row's time is per frame.
        let mut sim =
            SimulateStrands::grown(&gpu, &s.mesh, &mesh, &s.hair, &DynamicsParams::default())?;
        let rest_frame = sim.prepare(&gpu.queue, 0.0)?;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        sim.encode(&mut encoder, &rest_frame, None)?;
        gpu.submit_and_wait([encoder.finish()])?;
        let sim_times = time_frames(&gpu, frames, |encoder, timer, frame| {
            let frame = sim.prepare(&gpu.queue, (frame + 1) as f32 / 60.0)?;
            sim.encode(encoder, &frame, timer)?;
            Ok(())
        })?;
        // The substeps of a frame of 1/60 s, as the dynamics cut it (every frame here).
        let substeps = u64::from(sim.dynamics().substeps(1.0 / 60.0).0.max(1));
        let vertex_count =
            u64::from(sim.buffers().strand_count) * u64::from(sim.buffers().vertices_per_strand());
        let sim_ms = get(&sim_times, "strands: simulate");
        let sim_note = format!(
            "{substeps} substeps a frame; {:.2} ns per vertex per substep; {:.2}x the groom pass's time",
            sim_ms * 1e6 / (substeps * vertex_count) as f64,
            sim_ms / get(&groom_times, "strands: groom")
        );
        rows.push(compute_row(
            "strands: simulate",
            sim_ms,
            substeps * vertex_count * 5 * 16 + roots + mesh_bytes + vertices,
            &sim_note,
        ));
        bar.println(format!("           simulate: {sim_note}"));
        // One grown strand in 50 as guides, interpolated into as many strands as grown:
        // the interpolation pass against the growth pass for the same strand count.
        let guide_groom = subsampled(&groom, STRANDS_PER_GUIDE);
        let guide_params = GuideParams {
            strands,
            ..GuideParams::default()
        };
        let mut guided =
            GuideStrands::new(&gpu, &s.mesh, &mesh, &guide_groom, &s.hair, &guide_params)?;
        // The growth pass and both guide passes in one command buffer per frame, so that
        // the ratio is taken frame by frame, both passes under the same load (on a
        // shared machine the load changes between frame loops).
        let guided_samples = frame_samples(&gpu, GUIDE_FRAMES, |encoder, mut timer, frame| {
            let time = frame as f32 / 24.0;
            let grown = grow.prepare(&gpu.queue, time)?;
            grow.encode(encoder, &grown, timer.as_deref_mut())?;
            let frame = guided.prepare(&gpu.queue, time)?;
            guided.encode(encoder, &frame, timer)?;
            Ok(())
        })?;
        let samples_of = |label: &str| {
            (guided_samples.iter())
                .find(|(l, _)| l == label)
                .map_or(&[][..], |(_, v)| &v[..])
        };
        let guided_times: Vec<(String, f64)> = (guided_samples.iter())
            .map(|(l, v)| (l.clone(), median(v.clone())))
            .collect();
        let guide_ratio = median(
            (samples_of("strands: guides").iter())
                .zip(samples_of("strands: grow"))
                .map(|(guides, grow)| guides / grow)
                .collect(),
        );
        // The fastest frame of each pass: other work on the machine only adds time, so
        // the fastest is the pass's own cost.
        let fastest = |label: &str| samples_of(label).iter().copied().fold(f64::NAN, f64::min);
        let fastest_ratio = fastest("strands: guides") / fastest("strands: grow");
        let memory = guided.memory();
        let bent_bytes = memory.guide_vertices;
        let interpolate_ms = get(&guided_times, "strands: guides");
        rows.push(compute_row(
            "strands: guides",
            interpolate_ms,
            roots + memory.records + mesh.positions.size() + mesh.indices.size() + bent_bytes
                + vertices,
            "interpolation from 1 guide per 50 strands: reads roots, records, mesh and bent guides, writes vertices",
        ));
        rows.push(compute_row(
            "strands: guides bend",
            get(&guided_times, "strands: guides bend"),
            memory.guide_rest + memory.guide_roots / 2 + bent_bytes,
            "the guides bent by the wind (groom.wgsl): the first of the two passes",
        ));
        bar.println(format!(
            "  {strands:>7} strands  interpolation from {} guides: {fastest_ratio:.2}x the growth pass \
             (fastest of {GUIDE_FRAMES} frames, both in one command buffer: {:.3} ms against {:.3} ms; \
             median of the per-frame ratios {guide_ratio:.2}x)",
            guide_groom.strands,
            fastest("strands: guides"),
            fastest("strands: grow"),
        ));
        guide_ratios.push(fastest_ratio);
        bar.inc(1);
        scan_ms.push(get(&times, "shadow: scan"));
        grow_points.push((f64::from(strands), get(&times, "strands: grow")));
    }

    // 1b. GPU skinning, stage 1's input, against the growth pass it feeds.
    let SkinningSection {
        rows: skin_rows,
        skin_ratio,
        sdf_times,
        skinned_steps,
    } = skinning_section(frames, &bar)?;
    rows.extend(skin_rows);
    bar.inc(1);

    // 2. Raster stages and whole frames, per strand count, on devices of their own.
    bar.println("raster stages (timestamps) and whole stages (wall clock, submitted alone):");
    let mut frame_points = Vec::new();
    let mut raster_points = Vec::new();
    for &strands in counts {
        for method in &methods {
            let gpu = Gpu::headless()?;
            let mut s = scene(strands, 8);
            s.shadow = ShadowParams::None;
            s.shade.transparency = method.clone();
            s.shade.sample_count = 1;
            let mut renderer = Renderer::new(&gpu, &s, width, height)?;
            let mut per_label: Vec<(String, Vec<f64>)> = Vec::new();
            for frame in 0..frames + 3 {
                renderer.render(&gpu, frame as f32 / 24.0, &s.camera)?;
                let stats = renderer.finish(&gpu)?;
                if frame < 3 {
                    continue;
                }
                for (label, ms) in stats.by_label() {
                    if !label.starts_with("shade: ") || label == "shade: mesh" {
                        continue;
                    }
                    match per_label.iter_mut().find(|(l, _)| *l == label) {
                        Some((_, v)) => v.push(ms),
                        None => per_label.push((label, vec![ms])),
                    }
                }
            }
            let pixels = u64::from(width) * u64::from(height);
            let memory = renderer.frame().hair_pass().memory_bytes();
            for (label, v) in per_label {
                let ms = median(v);
                bar.println(format!("  {strands:>7} strands  {label:<26} {ms:9.3} ms"));
                if *method == Transparency::Opaque {
                    raster_points.push((f64::from(strands), ms));
                }
                rows.push(Row {
                    section: "raster",
                    stage: label,
                    strands,
                    pixels,
                    gpu_ms: ms,
                    bytes: memory,
                    copy_ratio: f64::NAN,
                    note: format!("{} (bytes: the method's per-pixel memory)", method.label()),
                });
            }
            if *method == Transparency::Opaque {
                // The whole frame with the default voxel shadows, wall clock.
                let mut full = scene(strands, 8);
                full.shade.sample_count = 1;
                let gpu = Gpu::headless()?;
                let mut renderer = Renderer::new(&gpu, &full, width, height)?;
                renderer.render(&gpu, 0.0, &full.camera)?;
                let stages = renderer.stage_wall_times(&gpu, 0.0, &full.camera, frames.min(7))?;
                let total: f64 = stages.iter().map(|(_, ms)| ms).sum();
                for (stage, ms) in &stages {
                    rows.push(Row {
                        section: "wall",
                        stage: format!("{stage} (wall)"),
                        strands,
                        pixels,
                        gpu_ms: *ms,
                        bytes: 0,
                        copy_ratio: f64::NAN,
                        note: "submitted alone, median".into(),
                    });
                }
                bar.println(format!(
                    "  {strands:>7} strands  frame (wall, voxel shadows, opaque) {total:9.3} ms"
                ));
                frame_points.push((f64::from(strands), total));
            }
            bar.inc(1);
        }
    }

    // 2b. The strand rasterizer against the raster pipeline: the hair passes alone, wall
    //     clock (compute timestamps are wrong on lavapipe), on the default scene: the
    //     opaque method at 4x MSAA, the k-buffer of 8, the strand rasterizer; then the
    //     strand rasterizer's time against strands and against pixels.
    let raster = strand_raster_section(opts, frames, &bar)?;
    rows.extend(raster.rows);

    // 2c. The frame's target bridge: each transparency method on an engine's 4x MSAA,
    //     reverse-Z targets (Bevy's), its bridge passes against its own hair passes.
    let bridge = bridge_section(opts, frames, &bar)?;
    rows.extend(bridge.rows);

    // 3. Scaling.
    let frame_exponent = exponent(&frame_points);
    let raster_exponent = exponent(&raster_points);
    let grow_exponent = exponent(&grow_points);
    let scan_spread = scan_ms.iter().cloned().fold(f64::MIN, f64::max)
        / scan_ms.iter().cloned().fold(f64::MAX, f64::min);

    // 4. Shadows and transparency over the bare lit strand pass, at seed 000's sizes:
    //    10 000 hairs of 16 vertices, 800x800 (quick: 2 000 at 200x200).
    let (seed_strands, seed_size) = if opts.quick {
        (2_000, 200)
    } else {
        (10_000, 800)
    };
    let overhead =
        |shadow: ShadowParams, transparency: Transparency| -> Result<(f64, f64), Error> {
            let gpu = Gpu::headless()?;
            let mut s = scene(seed_strands, 15);
            s.shadow = shadow;
            s.shade.transparency = transparency;
            s.shade.sample_count = 1;
            let mut renderer = Renderer::new(&gpu, &s, seed_size, seed_size)?;
            renderer.render(&gpu, 0.0, &s.camera)?;
            let stages = renderer.stage_wall_times(&gpu, 0.0, &s.camera, frames.min(5))?;
            let of = |name: &str| {
                stages
                    .iter()
                    .find(|(n, _)| n == name)
                    .map_or(0.0, |(_, ms)| *ms)
            };
            Ok((of("shadow"), of("shade")))
        };
    let (_, bare) = overhead(ShadowParams::None, Transparency::Opaque)?;
    bar.inc(1);
    let combos = [
        (
            "voxel 128^3 + k-buffer k=8",
            ShadowParams::Voxel(VoxelParams::default()),
            Transparency::k_buffer(8),
        ),
        (
            "voxel 128^3 + WBOIT",
            ShadowParams::Voxel(VoxelParams::default()),
            Transparency::wboit(),
        ),
        (
            "deep opacity maps + WBOIT (seed 000's pair)",
            ShadowParams::DeepOpacity(Default::default()),
            Transparency::wboit(),
        ),
    ];
    let mut overheads = Vec::new();
    for (name, shadow, transparency) in combos {
        let (shadow_ms, shade_ms) = overhead(shadow, transparency)?;
        let ratio = (shadow_ms + shade_ms) / bare;
        bar.println(format!(
            "  {seed_strands} hairs x 16 vertices at {seed_size}x{seed_size}: {name}: shadow {shadow_ms:.1} ms + shade {shade_ms:.1} ms = {ratio:.2}x the bare lit pass ({bare:.1} ms)"
        ));
        bar.inc(1);
        overheads.push((name, ratio));
        rows.push(Row {
            section: "overhead",
            stage: name.into(),
            strands: seed_strands,
            pixels: u64::from(seed_size) * u64::from(seed_size),
            gpu_ms: shadow_ms + shade_ms,
            bytes: 0,
            copy_ratio: ratio,
            note: format!(
                "wall clock; copy_ratio column = ratio to the bare lit pass ({bare:.3} ms)"
            ),
        });
    }

    // 4b. The cost of the physically based fibre and of dual scattering in the shade
    //     stage: Chiang single and dual scattering (and Kajiya-Kay, the default) with voxel
    //     shadows, opaque, at seed 000's sizes. Wall clock of the shade stage submitted
    //     alone, median of the frames.
    let models = [
        (
            "kajiya-kay",
            ShadingModel::KajiyaKay(pelage::scene::KajiyaKayParams::default()),
        ),
        (
            "chiang single scattering",
            ShadingModel::Chiang(ChiangParams {
                multiple_scattering: MultipleScattering::None,
                ..ChiangParams::default()
            }),
        ),
        (
            "chiang dual scattering",
            ShadingModel::Chiang(ChiangParams {
                multiple_scattering: MultipleScattering::Dual,
                ..ChiangParams::default()
            }),
        ),
        (
            "chiang volume scattering 32³",
            ShadingModel::Chiang(ChiangParams {
                multiple_scattering: MultipleScattering::Volume,
                volume_grid: 32,
                ..ChiangParams::default()
            }),
        ),
        (
            "chiang dual scattering + volume",
            ShadingModel::Chiang(ChiangParams {
                multiple_scattering: MultipleScattering::DualVolume,
                ..ChiangParams::default()
            }),
        ),
        (
            "chiang volume scattering",
            ShadingModel::Chiang(ChiangParams {
                multiple_scattering: MultipleScattering::Volume,
                ..ChiangParams::default()
            }),
        ),
    ];
    let mut model_ms = Vec::new();
    for (name, model) in models {
        let gpu = Gpu::headless()?;
        let mut s = scene(seed_strands, 15);
        let grid_bytes = match &model {
            ShadingModel::Chiang(p) if p.multiple_scattering.uses_grid() => {
                pelage::shade::VolumeGrid::bytes_for(p.volume_grid)
            }
            _ => 0,
        };
        s.shade.model = model;
        s.shade.sample_count = 1;
        let mut renderer = Renderer::new(&gpu, &s, seed_size, seed_size)?;
        renderer.render(&gpu, 0.0, &s.camera)?;
        let stages = renderer.stage_wall_times(&gpu, 0.0, &s.camera, frames.min(7))?;
        let shade: Vec<f64> = stages
            .iter()
            .filter(|(n, _)| n == "shade")
            .map(|(_, ms)| *ms)
            .collect();
        model_ms.push((name, median(shade), grid_bytes));
        bar.inc(1);
    }
    let single_ms = model_ms[1].1;
    for &(name, ms, grid_bytes) in &model_ms {
        let ratio = ms / single_ms;
        let memory = if grid_bytes > 0 {
            format!(" (grid {:.2} MB)", grid_bytes as f64 / 1e6)
        } else {
            String::new()
        };
        bar.println(format!(
            "  {seed_strands} hairs at {seed_size}x{seed_size}, voxel shadows: shade stage with {name}: {ms:.1} ms = {ratio:.2}x chiang single scattering{memory}"
        ));
        rows.push(Row {
            section: "scattering",
            stage: name.into(),
            strands: seed_strands,
            pixels: u64::from(seed_size) * u64::from(seed_size),
            gpu_ms: ms,
            bytes: grid_bytes,
            copy_ratio: ratio,
            note:
                "wall clock of the shade stage; ratio column = ratio to chiang single scattering; \
                   bytes = the volume grid's GPU memory"
                    .into(),
        });
    }

    // 4c. The CPU cost of recording a frame: the default scene prepared and recorded
    //     (`Frame::prepare`, `Frame::record`: what an engine calls) into an encoder and
    //     finished, wall clock on the CPU, median of the frames after three of warm-up;
    //     submitted and waited for outside the timing. GPU objects created while
    //     recording are counted.
    {
        let gpu = Gpu::headless()?;
        let s = Scene::default();
        let format = pelage::shade::TargetFormat::for_params(&s.shade);
        let mut frame_stages =
            pelage::Frame::new(&gpu, &s, &pelage::FrameTarget::new(format, width, height))?;
        let targets = pelage::shade::Targets::with_format(&gpu, width, height, &format)?;
        let view_set = targets.view_set();
        let views = view_set.views();
        let record_frames = if opts.quick { 20 } else { 200 };
        let mut cpu = Vec::new();
        let mut created = pelage::gpu::Created::default();
        for frame in 0..record_frames + 3 {
            let t = frame as f32 / 24.0;
            let before = pelage::gpu::Created::now();
            let started = Instant::now();
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            frame_stages.prepare(&gpu.queue, t, &s.camera.matrices(width, height))?;
            frame_stages.record(&mut encoder, &views, None)?;
            let commands = encoder.finish();
            let ms = started.elapsed().as_secs_f64() * 1e3;
            if frame >= 3 {
                cpu.push(ms);
                let c = pelage::gpu::Created::now().since(&before);
                created.buffers += c.buffers;
                created.bind_groups += c.bind_groups;
            }
            gpu.submit_and_wait([commands])?;
            frame_stages.after_submit(&gpu)?;
        }
        let ms = median(cpu.clone());
        cpu.sort_by(f64::total_cmp);
        let p90 = cpu.get(cpu.len() * 9 / 10).copied().unwrap_or(f64::NAN);
        bar.println(format!(
            "  recording a default-scene frame ({width}x{height}): {ms:.3} ms CPU median, {p90:.3} ms p90, \
             over {record_frames} frames: {} buffers and {} bind groups created",
            created.buffers, created.bind_groups
        ));
        rows.push(Row {
            section: "record",
            stage: "record default frame (cpu)".into(),
            strands: s.hair.roots.count,
            pixels: u64::from(width) * u64::from(height),
            gpu_ms: ms,
            bytes: 0,
            copy_ratio: p90 / ms,
            note: format!(
                "CPU wall clock of Frame::prepare + Frame::record + finish, median; ratio column = p90/median; \
                 {} buffers and {} bind groups created over {record_frames} frames",
                created.buffers, created.bind_groups
            ),
        });
        // The same recording where the GPU's work does not run on the CPU: each frame's
        // uniform writes submitted without its passes (an empty command buffer), so the
        // caches hold what a program recording for a real GPU holds. After a lavapipe
        // frame the caches hold the frame's: the same recording made twice in a row took
        // 0.33 ms the first time and 0.11 the second (2026-12-05, lavapipe, 2 cores).
        let mut warm = Vec::new();
        for frame in 0..record_frames + 3 {
            let t = frame as f32 / 24.0;
            let started = Instant::now();
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            frame_stages.prepare(&gpu.queue, t, &s.camera.matrices(width, height))?;
            frame_stages.record(&mut encoder, &views, None)?;
            drop(encoder.finish());
            if frame >= 3 {
                warm.push(started.elapsed().as_secs_f64() * 1e3);
            }
            let pending = gpu.device.create_command_encoder(&Default::default());
            gpu.submit_and_wait([pending.finish()])?;
        }
        let warm_ms = median(warm);
        bar.println(format!(
            "  recording a default-scene frame, the GPU's work not on the CPU: {warm_ms:.3} ms CPU median \
             (target <= 0.2; after a lavapipe frame, above: {ms:.3} ms, the caches holding that frame's work)"
        ));
        rows.push(Row {
            section: "record",
            stage: "record default frame, no GPU work on the CPU (cpu)".into(),
            strands: s.hair.roots.count,
            pixels: u64::from(width) * u64::from(height),
            gpu_ms: warm_ms,
            bytes: 0,
            copy_ratio: warm_ms / ms,
            note: "CPU wall clock of Frame::prepare + Frame::record + finish, median, each frame's uniform \
                   writes submitted without its passes; ratio column = this / after a lavapipe frame"
                .into(),
        });
    }

    bar.finish_and_clear();

    // 5. Memory.
    let s = scene(10_000, 8);
    let gpu = Gpu::headless()?;
    let mesh = MeshBuffers::upload(&gpu, &s.mesh)?;
    let grow = GrowStrands::new(&gpu, &s.mesh, &mesh, &s.hair)?;
    let b = grow.buffers();
    let vertices = u64::from(b.strand_count) * u64::from(b.segments + 1);
    let per_vertex = b.vertices.size() as f64 / vertices as f64;
    let per_strand = (b.vertices.size() + b.roots.size()) as f64 / f64::from(b.strand_count);
    let guide_memory = guide_memory(&gpu, &s)?;
    let guide_simulation = guide_simulation(&gpu, &s, frames)?;

    let mut table = Table::new(&[
        "section", "stage", "strands", "pixels", "gpu_ms", "bytes", "ratio", "note",
    ]);
    for r in &rows {
        table.push(vec![
            r.section.into(),
            r.stage.clone(),
            r.strands.to_string(),
            r.pixels.to_string(),
            format!("{:.4}", r.gpu_ms),
            r.bytes.to_string(),
            format!("{:.3}", r.copy_ratio),
            r.note.clone(),
        ])?;
    }
    for (name, value, note) in [
        (
            "scaling: frame exponent",
            frame_exponent,
            "wall clock, voxel shadows, opaque",
        ),
        (
            "scaling: lit strand pass exponent",
            raster_exponent,
            "timestamps",
        ),
        (
            "scaling: strand expansion exponent",
            grow_exponent,
            "timestamps",
        ),
        (
            "scaling: scan max/min over strand counts",
            scan_spread,
            "1 = independent of strands",
        ),
        (
            "skinning: skin pass over growth pass",
            skin_ratio,
            "timestamps, the creature skinned by the [skin] rig, 20000 strands x 8 segments grown on it",
        ),
        (
            "memory: bytes per strand vertex",
            per_vertex,
            "StrandBuffers::vertices",
        ),
        (
            "memory: bytes per strand",
            per_strand,
            "vertices + StrandRoot, 8 segments",
        ),
        (
            "guides: interpolation over growth, same strands",
            guide_ratios.iter().copied().fold(f64::NAN, f64::max),
            "timestamps, the largest over the strand counts of the ratio of each pass's fastest of 20 frames (both passes in one command buffer), 1 guide per 50 strands",
        ),
        (
            "guides: memory over storing every strand",
            guide_memory,
            "1000 guides -> 50000 strands x 16 segments: guide rest + bent guides + guide roots + records, over GroomStrands' rest points",
        ),
        (
            "guides: simulated guides + interpolation over simulating every strand",
            guide_simulation,
            "timestamps, 1000 guides simulated and interpolated into 50000 strands x 8 segments, over 50000 strands simulated; default dynamics, frames of 1/60 s",
        ),
    ]
    .into_iter()
    .map(|(name, value, note)| (name.to_string(), value, note.to_string()))
    .chain(sdf_times.iter().map(|t| {
        let (case, target, what) = t.case();
        (
            format!(
                "sdf: body field {} ({case}) {} over growth pass",
                t.resolution,
                if t.case == SdfCase::ThroughSkin { "lattice pass" } else { "build" }
            ),
            t.ratio(),
            format!("timestamps, {what} (target: {target}), {SKIN_STRANDS} strands x 8 segments grown"),
        )
    }))
    .chain(skinned_steps.iter().map(|t| {
        (
            format!(
                "sdf: body field {} (skinned body), simulation through the skin over rebuilt",
                t.resolution
            ),
            t.ratio(),
            format!(
                "timestamps, the creature's {SKIN_STRANDS} strands x 8 segments simulated at the default dynamics, frames of 1/24 s: lattice pass + simulation over build + simulation (through {:.2} + {:.2} ms, rebuilt {:.2} + {:.2} ms)",
                t.through.0, t.through.1, t.rebuilt.0, t.rebuilt.1
            ),
        )
    })) {
        table.push(vec![
            "summary".into(),
            name,
            String::new(),
            String::new(),
            String::new(),
            String::new(),
            format!("{value:.3}"),
            note,
        ])?;
    }
    pelage_lab::create_dir(&opts.out)?;
    table.write_csv(&opts.out.join("bench.csv"))?;

    let mut points = Vec::new();
    for r in rows.iter().filter(|r| r.section != "overhead") {
        if r.gpu_ms.is_finite() && r.gpu_ms > 0.0 {
            points.push(ScatterPoint {
                series: r.stage.clone(),
                label: String::new(),
                x: f64::from(r.strands),
                y: r.gpu_ms,
                size: None,
            });
        }
    }
    let chart = ScatterChart {
        title: "pelage stages against strand count (lavapipe, 2 cores)".into(),
        x_label: "strands (log)".into(),
        y_label: "ms (log)".into(),
        x_log: true,
        y_log: true,
        points,
        mark_pareto: false,
        size_label: None,
    };
    chart.write_svg(&opts.out.join("scaling.svg"), 1000, 650)?;
    chart.write_png(&opts.out.join("scaling.png"), 1000, 650)?;

    println!();
    println!("summary:");
    println!(
        "  frame time grows as strands^{frame_exponent:.2} (target <= 1.1); lit strand pass ^{raster_exponent:.2}; expansion ^{grow_exponent:.2}"
    );
    println!(
        "  scan: slowest / fastest over {} strand counts = {scan_spread:.2} (independent of strands = 1)",
        counts.len()
    );
    let largest = counts.last().copied().unwrap_or(0);
    for stage in [
        "strands: grow",
        "shadow: scan",
        "shadow: splat",
        "shadow: fit",
    ] {
        if let Some(r) = rows
            .iter()
            .find(|r| r.stage == stage && r.strands == largest)
        {
            println!(
                "  {stage} at {largest} strands: {:.0}% of copy bandwidth (target >= 50% for grow and scan)",
                100.0 * r.copy_ratio
            );
        }
    }
    println!(
        "  skinning: the skin pass takes {skin_ratio:.3}x the growth pass of a {SKIN_STRANDS}-strand creature (target <= 0.1)"
    );
    for t in &sdf_times {
        let (case, target, _) = t.case();
        let pass = if t.case == SdfCase::ThroughSkin {
            "its lattice pass"
        } else {
            "its build"
        };
        println!(
            "  body sdf {}, {case}: {pass} takes {:.3}x the growth pass of a {SKIN_STRANDS}-strand creature (target: {target})",
            t.resolution,
            t.ratio()
        );
    }
    for t in &skinned_steps {
        println!(
            "  body sdf {}, skinned body: a simulation's field pass and simulation through the skin take {:.3}x those of the field rebuilt every frame ({SKIN_STRANDS} strands)",
            t.resolution,
            t.ratio()
        );
    }
    for line in raster.summary.iter().chain(&bridge.summary) {
        println!("  {line}");
    }
    for (name, ratio) in &overheads {
        println!(
            "  {name}: {ratio:.2}x the bare lit strand pass (target <= 3; seed 000: 8.4x to 12.6x)"
        );
    }
    println!(
        "  memory: {per_vertex:.1} bytes per strand vertex (target <= 16), {per_strand:.1} per strand of 8 segments"
    );
    println!(
        "wrote {}/bench.csv and scaling.png|svg in {:.0} s",
        opts.out.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// The strand count of the skinning section: issue 37's creature.
const SKIN_STRANDS: u32 = 20_000;

/// Section 1b of the benchmark: the creature skinned by the default [`SkinBend`] rig
/// ([`MeshSkin`], a compute pass over its vertices) then [`SKIN_STRANDS`] strands of 8
/// segments grown on it, both timed with timestamps in the same frames; then the body's
/// distance field at [`SDF_RESOLUTIONS`] (rebuilt on the skinned body, built on the still
/// one, its skin's lattice pass) and a simulation of the fur on the skinned body with the
/// field read through the skin and rebuilt every frame.
fn skinning_section(frames: usize, bar: &progress::Progress) -> Result<SkinningSection, Error> {
    let gpu = Gpu::headless()?;
    let s = scene(SKIN_STRANDS, 8);
    let mut mesh = MeshBuffers::upload(&gpu, &s.mesh)?;
    let rig = SkinBend::default();
    mesh.bounds = rig.reach(mesh.bounds);
    let skin = MeshSkin::new(&gpu, &s.mesh, &rig.skin(&s.mesh), &mesh)?;
    let mut grow = GrowStrands::new(&gpu, &s.mesh, &mesh, &s.hair)?;
    // The body's distance field of the skinned creature, rebuilt every frame (what a
    // simulation on a skinned body does; a rigid body builds the same pass once).
    let sdfs = SDF_RESOLUTIONS
        .iter()
        .map(|&r| BodySdf::of_body(&gpu, &mesh, &s.mesh, mesh.bounds, r))
        .collect::<Result<Vec<_>, _>>()?;
    let sdf_label = |r: u32| format!("{SDF_LABEL} {r}");
    let mut sdf_times = Vec::new();
    for (sdf, &r) in sdfs.iter().zip(&SDF_RESOLUTIONS) {
        let times = time_frames(&gpu, frames, |encoder, mut timer, frame| {
            let t = frame as f32 / 24.0;
            skin.set_joint_matrices(&gpu.queue, &rig.joint_matrices(t))?;
            let frame = grow.prepare(&gpu.queue, t)?;
            skin.encode(encoder, timer.as_deref_mut());
            sdf.encode(encoder, timer.as_deref_mut());
            grow.encode(encoder, &frame, timer)?;
            Ok(())
        })?;
        sdf_times.push(SdfTiming::measured(
            SdfCase::Rebuilt,
            (get(&times, SDF_LABEL), sdf.grid().nodes(), sdf.bytes()),
            r,
            &times,
            bar,
        ));
        // The same build, each stage in a pass of its own: where its time goes.
        let times = time_frames(&gpu, frames, |encoder, mut timer, frame| {
            let t = frame as f32 / 24.0;
            skin.set_joint_matrices(&gpu.queue, &rig.joint_matrices(t))?;
            let frame = grow.prepare(&gpu.queue, t)?;
            skin.encode(encoder, timer.as_deref_mut());
            sdf.encode_stages(encoder, timer.as_deref_mut());
            grow.encode(encoder, &frame, timer)?;
            Ok(())
        })?;
        let grow_ms = get(&times, "strands: grow");
        let stages: Vec<String> = BodySdf::STAGES
            .iter()
            .map(|stage| {
                let ms = get(&times, &format!("{SDF_LABEL} / {stage}"));
                format!("{stage} {ms:.3} ms ({:.3}x)", ms / grow_ms)
            })
            .collect();
        bar.println(format!(
            "  {SKIN_STRANDS:>7} strands  {} by stage, each in a pass of its own: {}; the growth pass {grow_ms:.3} ms",
            sdf_label(r),
            stages.join(", ")
        ));
    }
    // The same creature still (a rigid body's case, built once): the field over its own
    // box, built here every frame so that the timestamps catch it, against the growth
    // pass of the same frames.
    let still = MeshBuffers::upload(&gpu, &s.mesh)?;
    let mut still_grow = GrowStrands::new(&gpu, &s.mesh, &still, &s.hair)?;
    let skin_of_rig = rig.skin(&s.mesh);
    let body = body_triangles(&s.mesh);
    let mut skinned_steps = Vec::new();
    for &r in &SDF_RESOLUTIONS {
        let sdf = BodySdf::of_body(&gpu, &still, &s.mesh, still.bounds, r)?;
        let times = time_frames(&gpu, frames, |encoder, mut timer, frame| {
            let frame = still_grow.prepare(&gpu.queue, frame as f32 / 24.0)?;
            sdf.encode(encoder, timer.as_deref_mut());
            still_grow.encode(encoder, &frame, timer)?;
            Ok(())
        })?;
        sdf_times.push(SdfTiming::measured(
            SdfCase::Still,
            (get(&times, SDF_LABEL), sdf.grid().nodes(), sdf.bytes()),
            r,
            &times,
            bar,
        ));
        // The skinned creature's field as a simulation reads it: that bind-pose field,
        // built once, read through the skin, whose lattice pass runs every frame after
        // the skinning.
        let sdf_skin = SdfSkin::new(
            &gpu,
            &s.mesh,
            &skin_of_rig,
            &body,
            sdf.grid(),
            skin.joint_matrices(),
        )?;
        let times = time_frames(&gpu, frames, |encoder, mut timer, frame| {
            let t = frame as f32 / 24.0;
            skin.set_joint_matrices(&gpu.queue, &rig.joint_matrices(t))?;
            let frame = grow.prepare(&gpu.queue, t)?;
            skin.encode(encoder, timer.as_deref_mut());
            sdf_skin.encode(encoder, timer.as_deref_mut());
            grow.encode(encoder, &frame, timer)?;
            Ok(())
        })?;
        sdf_times.push(SdfTiming::measured(
            SdfCase::ThroughSkin,
            (
                get(&times, SDF_SKIN_LABEL),
                sdf_skin.lattice().nodes(),
                sdf.bytes() + sdf_skin.bytes(),
            ),
            r,
            &times,
            bar,
        ));
        // What each way costs a simulation in all: the creature's fur simulated at the
        // default dynamics on the skinned body, the field read through the skin (the
        // lattice's pass, then the simulation sampling through it) against the field
        // rebuilt every frame (the build, then the simulation sampling it directly).
        let dynamics = DynamicsParams {
            sdf_resolution: r,
            ..DynamicsParams::default()
        };
        let mut through = SimulateStrands::grown(&gpu, &s.mesh, &mesh, &s.hair, &dynamics)?;
        through.skin_body_sdf(&gpu, &mesh, &s.mesh, &skin_of_rig, skin.joint_matrices())?;
        let mut rebuilt = SimulateStrands::grown(&gpu, &s.mesh, &mesh, &s.hair, &dynamics)?;
        rebuilt.set_sdf_every_frame(true)?;
        let step = |sim: &mut SimulateStrands, field: &str| -> Result<(f64, f64), Error> {
            let times = time_frames(&gpu, frames, |encoder, mut timer, frame| {
                let t = frame as f32 / 24.0;
                skin.set_joint_matrices(&gpu.queue, &rig.joint_matrices(t))?;
                let prepared = sim.prepare(&gpu.queue, t)?;
                skin.encode(encoder, timer.as_deref_mut());
                sim.encode(encoder, &prepared, timer)?;
                Ok(())
            })?;
            Ok((get(&times, field), get(&times, SIMULATE_LABEL)))
        };
        let measured = SkinnedStep {
            resolution: r,
            through: step(&mut through, SDF_SKIN_LABEL)?,
            rebuilt: step(&mut rebuilt, SDF_LABEL)?,
        };
        bar.println(format!(
            "  {SKIN_STRANDS:>7} strands  simulated on the skinned creature, field {r}, frames of 1/24 s: through the skin {:.3} ms lattice + {:.3} ms simulation; rebuilt {:.3} ms build + {:.3} ms simulation: {:.3}x",
            measured.through.0,
            measured.through.1,
            measured.rebuilt.0,
            measured.rebuilt.1,
            measured.ratio()
        ));
        skinned_steps.push(measured);
    }
    let times = time_frames(&gpu, frames, |encoder, mut timer, frame| {
        let t = frame as f32 / 24.0;
        skin.set_joint_matrices(&gpu.queue, &rig.joint_matrices(t))?;
        let frame = grow.prepare(&gpu.queue, t)?;
        skin.encode(encoder, timer.as_deref_mut());
        grow.encode(encoder, &frame, timer)?;
        Ok(())
    })?;
    let (skin_ms, grow_ms) = (get(&times, SKIN_LABEL), get(&times, "strands: grow"));
    let vertices = u64::from(mesh.vertex_count);
    // Reads bind positions, normals (12 B each), joints and weights (16 B each); writes
    // positions and normals (12 B each).
    let skin_bytes = vertices * (12 + 12 + 16 + 16 + 12 + 12);
    bar.println(format!(
        "  {SKIN_STRANDS:>7} strands  {SKIN_LABEL} ({vertices} vertices) {skin_ms:9.3} ms, {:.3}x the growth pass ({grow_ms:.3} ms)",
        skin_ms / grow_ms
    ));
    let row = |stage: &str, ms: f64, bytes: u64, note: String| Row {
        section: "skinning",
        stage: stage.into(),
        strands: SKIN_STRANDS,
        pixels: 0,
        gpu_ms: ms,
        bytes,
        copy_ratio: skin_ms / grow_ms,
        note,
    };
    let mut rows = Vec::new();
    for t in &sdf_times {
        let (_, _, what) = t.case();
        rows.push(Row {
            stage: t.label(),
            copy_ratio: t.ratio(),
            ..row(
                SDF_LABEL,
                t.sdf_ms,
                t.bytes,
                format!(
                    "{what}, {} nodes; ratio: over the growth pass of the same frames",
                    t.nodes
                ),
            )
        });
    }
    rows.extend([
            row(
                SKIN_LABEL,
                skin_ms,
                skin_bytes,
                format!(
                    "linear blend skinning of the creature's {vertices} vertices (4 joints each); ratio: over the growth pass"
                ),
            ),
            row(
                "strands: grow (skinned)",
                grow_ms,
                0,
                "the growth pass on the skinned mesh, same frames; ratio: skin over grow".into(),
            ),
        ]);
    Ok(SkinningSection {
        rows,
        skin_ratio: skin_ms / grow_ms,
        sdf_times,
        skinned_steps,
    })
}

/// Label prefix of the frame's target bridge passes (`src/bridge.rs`).
const BRIDGE_PREFIX: &str = "bridge: ";

/// Section 2c of the benchmark: every transparency method the adapter runs, on an
/// engine's targets it cannot draw itself (4x MSAA, reverse-Z, drawn over: Bevy's), built
/// as an engine builds it ([`pelage::Frame`] recorded into the caller's views with
/// `load`), no shadow. Timestamps: the bridge's passes (render passes) and the rest of
/// stage 3 (the hair pass: the method's passes, the mesh, the volume grid), summed per
/// frame, medians. lavapipe misplaces compute timestamps after a
/// render pass, so the strand rasterizer's (compute) figure is marked as such.
fn bridge_section(
    opts: &LabOpts,
    frames: usize,
    bar: &progress::Progress,
) -> Result<RasterSection, Error> {
    let (strands, width, height) = if opts.quick {
        (2_000, 160, 120)
    } else {
        (20_000, 640, 480)
    };
    bar.println(format!(
        "target bridge (timestamps, median of {frames} frames): {strands} strands, {width}x{height}, 4x MSAA, reverse-Z, drawn over:"
    ));
    let mut rows = Vec::new();
    let mut summary = Vec::new();
    let probe = Gpu::headless()?;
    let supported = pelage::shade::supported_methods(&probe);
    for method in Transparency::defaults() {
        if method == Transparency::Opaque || !supported.contains(&method.name()) {
            continue;
        }
        let gpu = Gpu::headless()?;
        let mut s = scene(strands, 8);
        s.shadow = ShadowParams::None;
        s.shade.transparency = method.clone();
        let format = pelage::shade::TargetFormat {
            samples: 4,
            reverse_z: true,
            ..Default::default()
        };
        let target = pelage::FrameTarget::new(format, width, height);
        let mut frame = pelage::Frame::new(&gpu, &s, &target)?;
        let texture = |label: &str, format: wgpu::TextureFormat, samples: u32| {
            gpu.device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width,
                        height,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: samples,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                        | wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                })
                .create_view(&Default::default())
        };
        let color = texture("bench engine colour", format.color, 4);
        let resolve = texture("bench engine resolve", format.color, 1);
        let depth = texture("bench engine depth", format.depth, 4);
        let views = pelage::shade::TargetViews {
            color: &color,
            resolve: Some(&resolve),
            depth: &depth,
            depth_sampled: None,
            width,
            height,
            load: true,
        };
        let samples = frame_samples(&gpu, frames, |encoder, timer, i| {
            let camera = s.camera.matrices_reverse_z(width, height);
            frame.prepare(&gpu.queue, i as f32 / 24.0, &camera)?;
            frame.record(encoder, &views, timer)?;
            Ok(())
        })?;
        frame.after_submit(&gpu)?;
        // Per frame: the bridge's passes and the hair pass (every other pass but stage
        // 1's: the method's, the mesh, the volume grid).
        let frame_count = samples.first().map_or(0, |(_, v)| v.len());
        let sum = |bridge: bool| {
            median(
                (0..frame_count)
                    .map(|f| {
                        (samples.iter())
                            .filter(|(l, _)| !l.starts_with("strands: "))
                            .filter(|(l, _)| l.starts_with(BRIDGE_PREFIX) == bridge)
                            .map(|(_, v)| v.get(f).copied().unwrap_or(0.0))
                            .sum::<f64>()
                    })
                    .collect(),
            )
        };
        let (bridge_ms, hair_ms) = (sum(true), sum(false));
        let compute = matches!(method, Transparency::StrandRaster { .. });
        let caveat = if compute {
            " (compute passes: lavapipe's timestamps are not reliable here)"
        } else {
            ""
        };
        bar.println(format!(
            "  {:<15} bridge {bridge_ms:8.3} ms, the hair pass {hair_ms:8.3} ms: {:.2}x{caveat}",
            method.name(),
            bridge_ms / hair_ms
        ));
        summary.push(format!(
            "target bridge: {} on 4x MSAA, reverse-Z targets: bridge passes {:.2}x the hair pass{caveat}",
            method.name(),
            bridge_ms / hair_ms
        ));
        rows.push(Row {
            section: "target bridge",
            stage: format!("{BRIDGE_PREFIX}{}", method.name()),
            strands,
            pixels: u64::from(width) * u64::from(height),
            gpu_ms: bridge_ms,
            bytes: 0,
            copy_ratio: bridge_ms / hair_ms,
            note: format!(
                "resolve colour and depth, write back, 4x MSAA reverse-Z targets; ratio: over the hair pass ({hair_ms:.3} ms){caveat}"
            ),
        });
    }
    bar.inc(1);
    Ok(RasterSection { rows, summary })
}

/// What [`skinning_section`] measured: its CSV rows, the skin pass over the growth
/// pass, the body fields' passes and the simulations on the skinned body.
struct SkinningSection {
    rows: Vec<Row>,
    skin_ratio: f64,
    sdf_times: Vec<SdfTiming>,
    skinned_steps: Vec<SkinnedStep>,
}

/// A simulation on the skinned creature timed both ways: (the field's pass, the
/// simulation's pass) in milliseconds, through the skin and rebuilt every frame.
struct SkinnedStep {
    resolution: u32,
    through: (f64, f64),
    rebuilt: (f64, f64),
}

impl SkinnedStep {
    /// Through the skin over rebuilt, each the field's pass plus the simulation's.
    fn ratio(&self) -> f64 {
        (self.through.0 + self.through.1) / (self.rebuilt.0 + self.rebuilt.1)
    }
}

/// Which body's distance field a [`SdfTiming`] timed.
#[derive(Clone, Copy, PartialEq)]
enum SdfCase {
    /// The still creature's field over its own box (a rigid body's case: built once).
    Still,
    /// The skinned creature's field over the box of every pose, rebuilt every frame (a
    /// mesh its caller deforms without a pelage skin).
    Rebuilt,
    /// The skinned creature read through its skin: the lattice's pass every frame over
    /// the still field.
    ThroughSkin,
}

/// One body distance field's pass timed against the growth pass of the same frames.
struct SdfTiming {
    resolution: u32,
    case: SdfCase,
    sdf_ms: f64,
    grow_ms: f64,
    /// The field's nodes, or the lattice's points through the skin.
    nodes: usize,
    bytes: u64,
}

impl SdfTiming {
    /// The timing of the field at `resolution`, (its pass's time, its nodes, its bytes),
    /// with the growth pass's in `times`, printed as it is taken.
    fn measured(
        case: SdfCase,
        (sdf_ms, nodes, bytes): (f64, usize, u64),
        resolution: u32,
        times: &[(String, f64)],
        bar: &progress::Progress,
    ) -> Self {
        let timing = Self {
            resolution,
            case,
            sdf_ms,
            grow_ms: get(times, "strands: grow"),
            nodes,
            bytes,
        };
        let points = if case == SdfCase::ThroughSkin {
            "lattice points"
        } else {
            "nodes"
        };
        bar.println(format!(
            "  {SKIN_STRANDS:>7} strands  {} ({} {points}) {:9.3} ms, {:.3}x the growth pass ({:.3} ms)",
            timing.label(),
            timing.nodes,
            timing.sdf_ms,
            timing.ratio(),
            timing.grow_ms
        ));
        timing
    }

    /// The bench's label of the pass: the build's and its resolution ("still" for the
    /// still body), or the skin's lattice pass and the field's resolution.
    fn label(&self) -> String {
        match self.case {
            SdfCase::Still => format!("{SDF_LABEL} {} still", self.resolution),
            SdfCase::Rebuilt => format!("{SDF_LABEL} {}", self.resolution),
            SdfCase::ThroughSkin => format!("{SDF_SKIN_LABEL} {}", self.resolution),
        }
    }

    /// The build over the growth pass.
    fn ratio(&self) -> f64 {
        self.sdf_ms / self.grow_ms
    }

    /// The body as the summary names it, the issue's target for it, and what was timed.
    fn case(&self) -> (&'static str, &'static str, &'static str) {
        match self.case {
            SdfCase::Still => (
                "still body",
                "<= 1 built once for a rigid body",
                "the still creature's distance field over its own box",
            ),
            SdfCase::Rebuilt => (
                "deformed body, rebuilt",
                "none: for a mesh its caller deforms without a pelage skin",
                "the skinned creature's distance field over the box of every pose, rebuilt every frame",
            ),
            SdfCase::ThroughSkin => (
                "skinned body, through the skin",
                "<= 0.5 per frame for a skinned body",
                "the skinned creature read through its skin: the lattice's pass every frame over the still field",
            ),
        }
    }
}

/// The resolutions of the body's distance field the skinning section times: the lab's,
/// and 128 (its build about 8x as long, every stage's work growing with the nodes; read
/// through the skin, the same lattice pass and simulation at any resolution).
const SDF_RESOLUTIONS: [u32; 2] = [64, 128];

/// What [`strand_raster_section`] measured.
struct RasterSection {
    rows: Vec<Row>,
    summary: Vec<String>,
}

/// Section 2b of the benchmark (see [`run`]).
fn strand_raster_section(
    opts: &LabOpts,
    frames: usize,
    bar: &progress::Progress,
) -> Result<RasterSection, Error> {
    use crate::hair_timing::{HairCase, hair_wall_ms};
    let frames = frames.min(9);
    let mut rows = Vec::new();
    let mut summary = Vec::new();
    // `grid: false` takes the default model's volume grid out (single scattering): the
    // grid is built once per frame whatever the hair pass, so the hair passes are
    // compared without it as well as with it.
    let time_with =
        |grid: bool, strands: u32, transparency: Transparency, samples: u32, size: (u32, u32)| {
            let mut s = Scene::default();
            if !grid && let ShadingModel::Chiang(chiang) = &mut s.shade.model {
                chiang.multiple_scattering = MultipleScattering::None;
            }
            s.hair.roots.count = strands;
            s.shade.transparency = transparency;
            s.shade.sample_count = samples;
            let gpu = Gpu::headless()?;
            let case = HairCase {
                mesh: &s.mesh,
                hair: &s.hair,
                shade: &s.shade,
                camera: &s.camera,
            };
            hair_wall_ms(&gpu, &case, size.0, size.1, frames)
        };
    let time = |strands: u32, transparency: Transparency, samples: u32, size: (u32, u32)| {
        time_with(true, strands, transparency, samples, size)
    };
    let default_strands = if opts.quick {
        4_000
    } else {
        Scene::default().hair.roots.count
    };
    let size = if opts.quick { (160, 120) } else { (480, 360) };
    let pixels = u64::from(size.0) * u64::from(size.1);
    let raster = Transparency::strand_raster();
    let opaque = time(default_strands, Transparency::Opaque, 4, size)?;
    let k_buffer = time(default_strands, Transparency::k_buffer(8), 1, size).ok();
    let ours = time(default_strands, raster.clone(), 1, size)?;
    let mut push = |stage: String, strands: u32, pixels: u64, ms: f64, ratio: f64, note: &str| {
        bar.println(format!(
            "  {strands:>7} strands {pixels:>8} px  {stage:<34} {ms:9.3} ms"
        ));
        rows.push(Row {
            section: "strand_raster",
            stage,
            strands,
            pixels,
            gpu_ms: ms,
            bytes: 0,
            copy_ratio: ratio,
            note: note.into(),
        });
    };
    push(
        "hair: opaque 4x MSAA".into(),
        default_strands,
        pixels,
        opaque,
        1.0,
        "wall clock of the hair passes alone; ratio column = ratio to opaque 4x MSAA",
    );
    if let Some(k) = k_buffer {
        push(
            "hair: k-buffer k=8".into(),
            default_strands,
            pixels,
            k,
            k / opaque,
            "wall clock of the hair passes alone; ratio column = ratio to opaque 4x MSAA",
        );
    }
    push(
        format!("hair: {}", raster.label()),
        default_strands,
        pixels,
        ours,
        ours / opaque,
        "wall clock of the hair passes alone; ratio column = ratio to opaque 4x MSAA",
    );
    // The same three without the volume grid (built once per frame, whatever the pass).
    let opaque_single = time_with(false, default_strands, Transparency::Opaque, 4, size)?;
    let k_single = time_with(false, default_strands, Transparency::k_buffer(8), 1, size).ok();
    let ours_single = time_with(false, default_strands, raster.clone(), 1, size)?;
    let note = "wall clock of the hair passes alone, single scattering (no volume grid); \
                ratio column = ratio to opaque 4x MSAA";
    push(
        "hair, no grid: opaque 4x MSAA".into(),
        default_strands,
        pixels,
        opaque_single,
        1.0,
        note,
    );
    if let Some(k) = k_single {
        push(
            "hair, no grid: k-buffer k=8".into(),
            default_strands,
            pixels,
            k,
            k / opaque_single,
            note,
        );
    }
    push(
        format!("hair, no grid: {}", raster.label()),
        default_strands,
        pixels,
        ours_single,
        ours_single / opaque_single,
        note,
    );
    let against_k = |ours: f64, k: Option<f64>| {
        k.map_or(String::new(), |k| {
            format!(", {:.2}x the k-buffer k=8 ({k:.1} ms)", ours / k)
        })
    };
    summary.push(format!(
        "default scene ({default_strands} strands, {}x{}), hair passes alone: strand rasterizer {ours:.1} ms = {:.2}x opaque 4x MSAA ({opaque:.1} ms){}; \
         without the volume grid (built once a frame for any pass): {ours_single:.1} ms = {:.2}x ({opaque_single:.1} ms; target <= 0.15){}",
        size.0,
        size.1,
        ours / opaque,
        against_k(ours, k_buffer),
        ours_single / opaque_single,
        against_k(ours_single, k_single),
    ));
    // Against strands, at the default size.
    let counts: &[u32] = if opts.quick {
        &[2_000, 8_000]
    } else {
        &[10_000, 40_000, 160_000]
    };
    let mut by_strands = Vec::new();
    for &n in counts {
        let ms = time(n, raster.clone(), 1, size)?;
        push(
            "strand raster vs strands".into(),
            n,
            pixels,
            ms,
            f64::NAN,
            "wall clock of the hair passes alone",
        );
        by_strands.push((f64::from(n), ms));
    }
    // Against pixels, at the default strand count.
    let sizes: &[(u32, u32)] = if opts.quick {
        &[(80, 60), (160, 120), (320, 240)]
    } else {
        &[(240, 180), (480, 360), (960, 720)]
    };
    let mut by_pixels = Vec::new();
    for &(w, h) in sizes {
        let ms = time(default_strands, raster.clone(), 1, (w, h))?;
        let px = u64::from(w) * u64::from(h);
        push(
            "strand raster vs pixels".into(),
            default_strands,
            px,
            ms,
            f64::NAN,
            "wall clock of the hair passes alone",
        );
        by_pixels.push((px as f64, ms));
    }
    let (es, ep) = (exponent(&by_strands), exponent(&by_pixels));
    summary.push(format!(
        "strand rasterizer time grows as strands^{es:.2} and pixels^{ep:.2} (targets <= 1.0)"
    ));
    for (name, value) in [("strands", es), ("pixels", ep)] {
        rows.push(Row {
            section: "summary",
            stage: format!("scaling: strand raster exponent against {name}"),
            strands: 0,
            pixels: 0,
            gpu_ms: f64::NAN,
            bytes: 0,
            copy_ratio: value,
            note: "least squares of log time against log count".into(),
        });
    }
    Ok(RasterSection { rows, summary })
}

/// The memory of 1 000 guides interpolated into 50 000 strands of 16 segments on the
/// creature of `s` against storing every strand ([`GuideMemory`]): prints both sides
/// and returns their ratio. The guides are 1 000 strands grown on the creature.
fn guide_memory(gpu: &Gpu, s: &Scene) -> Result<f64, Error> {
    let mesh = MeshBuffers::upload(gpu, &s.mesh)?;
    let mut hair = s.hair.clone();
    hair.roots.count = 1_000;
    hair.growth.segments = 16;
    let mut grow = GrowStrands::new(gpu, &s.mesh, &mesh, &hair)?;
    let guides = grown_groom(gpu, &mut grow)?;
    let params = GuideParams {
        strands: 50_000,
        ..GuideParams::default()
    };
    let guided = GuideStrands::new(gpu, &s.mesh, &mesh, &guides, &hair, &params)?;
    let m = guided.memory();
    let groom = GuideMemory::groom_rest_bytes(50_000, 16);
    let ratio = m.total() as f64 / groom as f64;
    println!(
        "guides: 1000 guides -> 50000 strands x 16 segments: guide rest {} + bent guides {} + \
         guide roots {} + records {} = {} bytes against GroomStrands' rest points {} bytes: {ratio:.3}x \
         (not counted, in both: output vertices, the strands' rest and drawn roots)",
        m.guide_rest,
        m.guide_vertices,
        m.guide_roots,
        m.records,
        m.total(),
        groom
    );
    Ok(ratio)
}

/// The time of simulating 1 000 guides and interpolating 50 000 render strands from
/// them ([`GuideStrands::simulated`]) against simulating 50 000 strands
/// ([`SimulateStrands::grown`]) on the creature of `s`, 8 segments, the default
/// dynamics, frames of 1/60 s after a first frame at rest: prints both and returns
/// their ratio. The guides are 1 000 strands grown on the creature.
fn guide_simulation(gpu: &Gpu, s: &Scene, frames: usize) -> Result<f64, Error> {
    let mesh = MeshBuffers::upload(gpu, &s.mesh)?;
    let dynamics = DynamicsParams::default();
    let mut hair = s.hair.clone();
    hair.roots.count = 50_000;
    hair.growth.segments = 8;
    let mut every = SimulateStrands::grown(gpu, &s.mesh, &mesh, &hair, &dynamics)?;
    hair.roots.count = 1_000;
    let mut grow = GrowStrands::new(gpu, &s.mesh, &mesh, &hair)?;
    let guides = grown_groom(gpu, &mut grow)?;
    let params = GuideParams {
        strands: 50_000,
        ..GuideParams::default()
    };
    let mut guided =
        GuideStrands::simulated(gpu, &s.mesh, &mesh, &guides, &hair, &params, &dynamics)?;
    let time = |stage: &mut dyn StrandStage| -> Result<Vec<(String, f64)>, Error> {
        let rest = stage.prepare(&gpu.queue, 0.0)?;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        stage.encode(&mut encoder, &rest, None)?;
        gpu.submit_and_wait([encoder.finish()])?;
        time_frames(gpu, frames, |encoder, timer, frame| {
            let frame = stage.prepare(&gpu.queue, (frame + 1) as f32 / 60.0)?;
            stage.encode(encoder, &frame, timer)?;
            Ok(())
        })
    };
    let every_ms = get(&time(&mut every)?, "strands: simulate");
    let guided_times = time(&mut guided)?;
    let (simulate_ms, interpolate_ms) = (
        get(&guided_times, "strands: simulate"),
        get(&guided_times, "strands: guides"),
    );
    let ratio = (simulate_ms + interpolate_ms) / every_ms;
    println!(
        "guides: 1000 guides simulated {simulate_ms:.3} ms + interpolated into 50000 strands \
         {interpolate_ms:.3} ms against 50000 strands simulated {every_ms:.3} ms: {ratio:.3}x"
    );
    Ok(ratio)
}

#[cfg(test)]
mod tests {
    #[test]
    fn every_shader_is_listed_and_validates() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/wgsl");
        let count = super::SHADERS
            .check_against_dir(dir)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(count, 2);
    }
}
