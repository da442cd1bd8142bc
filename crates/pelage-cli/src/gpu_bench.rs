//! The real-GPU bench (`pelage bench --gpu`): absolute GPU time per stage of whole
//! frames at 1920x1080, for the configurations a reader compares with published
//! figures. Made to run on a machine with a Vulkan GPU and nothing else (see
//! `scripts/gpu-bench` and docs/src/gpu_bench.md).
//!
//! ```text
//! pelage bench --gpu [--quick] [--allow-cpu] [--out DIR]
//! ```
//!
//! For 10 000, 50 000 and 200 000 strands of 16 segments, as grown fur and as a groom
//! (the same strands grown once and read back, bent by the wind every frame), it renders
//! every transparency method with the default voxel shadows, and the opaque method with
//! deep opacity maps and with a shadow map; then the two anchors (Frostbite: 10 000
//! strands of 24 points at 1600x900; vkhr: 136 000 strands at 1920x1080) with the same
//! configurations. Each configuration is a renderer of its own, timed with timestamp
//! queries over `FRAMES` frames after `WARM_UP` (median per pass label), plus the wall
//! clock of a frame submitted and waited for.
//!
//! Writes `DIR/gpu_bench.csv` (one row per configuration and pass) and
//! `DIR/gpu_bench.md` (one row per configuration: strands, shadow and shade stages,
//! the GPU total and the wall clock). Refuses a CPU adapter (lavapipe, llvmpipe,
//! SwiftShader) unless `--allow-cpu`: its figures are not a GPU's. Stops starting new
//! configurations once [`BUDGET_S`] seconds have passed and lists the ones left out.
//!
//! On lavapipe, compute-pass timestamps recorded after a render pass are misplaced (see
//! `bench.rs`): the per-stage figures of `--allow-cpu` runs are for the smoke test, not
//! for reading.

use std::fmt::Write as _;
use std::time::Instant;

use pelage::gpu::{Gpu, wgpu};
use pelage::scene::{DeepOpacityParams, ShadowMapParams, ShadowParams, Transparency, VoxelParams};
use pelage::scene::{Named, Resampled, WindParams};
use pelage::strands::{GrowStrands, MeshBuffers, StrandStage};
use pelage::{Renderer, scene::Scene};
use pelage_lab::Table;

type Error = Box<dyn std::error::Error>;

/// Seconds after which no new configuration starts (the whole run must end within 8
/// minutes; the slowest configuration on a real GPU takes a few seconds).
pub const BUDGET_S: f64 = 420.0;

/// What one configuration draws.
#[derive(Clone, Debug)]
struct Case {
    /// The case's name in the tables: `grid`, `frostbite anchor` or `vkhr anchor`.
    case: &'static str,
    /// `grown` (fur grown from the creature every frame) or `groom` (the same strands
    /// read back once and bent by the wind every frame).
    source: &'static str,
    strands: u32,
    segments: u32,
    width: u32,
    height: u32,
    transparency: Transparency,
    shadow: ShadowParams,
}

impl Case {
    fn shadow_name(&self) -> &'static str {
        self.shadow.method_name()
    }

    fn describe(&self) -> String {
        format!(
            "{} {} {} strands x {} segments {}x{} {} + {}",
            self.case,
            self.source,
            self.strands,
            self.segments,
            self.width,
            self.height,
            self.transparency.name(),
            self.shadow_name()
        )
    }
}

/// The configurations of one (strands, segments, size): every transparency method with
/// voxel shadows, then opaque with deep opacity maps and with a shadow map.
fn configurations() -> Vec<(Transparency, ShadowParams)> {
    let mut out: Vec<(Transparency, ShadowParams)> = Transparency::defaults()
        .into_iter()
        .map(|t| (t, ShadowParams::Voxel(VoxelParams::default())))
        .collect();
    out.push((
        Transparency::Opaque,
        ShadowParams::DeepOpacity(DeepOpacityParams::default()),
    ));
    out.push((
        Transparency::Opaque,
        ShadowParams::ShadowMap(ShadowMapParams::default()),
    ));
    out
}

/// Every case of the run, in the order they run (the grid's smallest size, the anchors,
/// the larger sizes). `--quick`: tiny sizes; every configuration once on grown fur, one on
/// the groom and on each anchor.
fn cases(quick: bool) -> Vec<Case> {
    let configs = configurations();
    let (sizes, segments, full): (&[u32], u32, (u32, u32)) = if quick {
        (&[1_000], 16, (192, 108))
    } else {
        (&[10_000, 50_000, 200_000], 16, (1920, 1080))
    };
    let mut out = Vec::new();
    let mut push = |case, source, strands, segments, (width, height): (u32, u32), all: bool| {
        let take = if all { configs.len() } else { 1 };
        for (transparency, shadow) in configs.iter().take(take) {
            out.push(Case {
                case,
                source,
                strands,
                segments,
                width,
                height,
                transparency: transparency.clone(),
                shadow: shadow.clone(),
            });
        }
    };
    // Frostbite: 10 000 strands of 24 points on a PS4 at 900p in 4.5 ms; vkhr: 136 000
    // strands in 7 ms (segments not given: 16, as the grid). Quick: a hundredth of the
    // strands, a tenth of the size. They run after the smallest grid size, so a run
    // that reaches the time budget leaves out the largest grid sizes first.
    let (frostbite, vkhr, scale) = if quick {
        (100, 1_360, 10)
    } else {
        (10_000, 136_000, 1)
    };
    for (i, &strands) in sizes.iter().enumerate() {
        push("grid", "grown", strands, segments, full, true);
        push("grid", "groom", strands, segments, full, !quick);
        if i == 0 {
            push(
                "frostbite anchor",
                "grown",
                frostbite,
                23,
                (1600 / scale, 900 / scale),
                !quick,
            );
            push(
                "vkhr anchor",
                "grown",
                vkhr,
                16,
                (1920 / scale, 1080 / scale),
                !quick,
            );
        }
    }
    out
}

/// The strands `scene` grows at t = 0, read back as a groom of the same strands.
fn grown_groom(gpu: &Gpu, scene: &Scene) -> Result<Resampled, Error> {
    let mesh = MeshBuffers::upload(gpu, &scene.mesh)?;
    let mut grow = GrowStrands::new(gpu, &scene.mesh, &mesh, &scene.hair)?;
    let frame = grow.prepare(&gpu.queue, 0.0)?;
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    grow.encode(&mut encoder, &frame, None)?;
    gpu.submit_and_wait([encoder.finish()])?;
    let bytes = pelage::gpu::read_buffer(gpu, &grow.buffers().vertices)?;
    let points = bytemuck::cast_slice::<u8, [f32; 4]>(&bytes)
        .iter()
        .map(|v| glam::Vec3::new(v[0], v[1], v[2]))
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

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// What one case measured: median milliseconds per pass label, and the wall clock of a
/// whole frame.
struct Measured {
    passes: Vec<(String, f64)>,
    wall_ms: f64,
}

fn measure(gpu: &Gpu, case: &Case, frames: usize, warm_up: usize) -> Result<Measured, Error> {
    let mut scene = Scene::default();
    scene.hair.roots.count = case.strands;
    scene.hair.growth.segments = case.segments;
    scene.hair.wind = WindParams::default();
    if case.source == "groom" {
        scene.groom = Some(grown_groom(gpu, &scene)?);
    }
    scene.shadow = case.shadow.clone();
    scene.shade.transparency = case.transparency.clone();
    let mut renderer = Renderer::new(gpu, &scene, case.width, case.height)?;
    let mut samples: Vec<(String, Vec<f64>)> = Vec::new();
    let mut walls = Vec::new();
    for frame in 0..frames + warm_up {
        let started = Instant::now();
        renderer.render(gpu, frame as f32 / 24.0, &scene.camera)?;
        let stats = renderer.finish(gpu)?;
        let wall = started.elapsed().as_secs_f64() * 1e3;
        if frame < warm_up {
            continue;
        }
        walls.push(wall);
        for (label, ms) in stats.by_label() {
            match samples.iter_mut().find(|(l, _)| *l == label) {
                Some((_, v)) => v.push(ms),
                None => samples.push((label, vec![ms])),
            }
        }
    }
    Ok(Measured {
        passes: samples.into_iter().map(|(l, v)| (l, median(v))).collect(),
        wall_ms: median(walls),
    })
}

/// The stage a pass label belongs to (`strands: grow` -> `strands`).
fn stage_of(label: &str) -> &str {
    label.split(':').next().unwrap_or(label).trim()
}

/// Runs the GPU bench: see the module's documentation.
pub fn run(opts: &crate::lab::LabOpts, allow_cpu: bool) -> Result<(), Error> {
    let started = Instant::now();
    pelage_lab::create_dir(&opts.out)?;
    let gpu = Gpu::headless()?;
    let adapter = gpu.describe();
    let driver = gpu.adapter_info.as_ref().map_or(String::new(), |i| {
        format!("{} {}", i.driver, i.driver_info).trim().to_string()
    });
    println!("adapter: {adapter}");
    println!("driver: {driver}");
    match std::env::var("VK_DRIVER_FILES") {
        Ok(files) => println!("VK_DRIVER_FILES: {files}"),
        Err(_) => println!("VK_DRIVER_FILES: (unset: the loader's default search)"),
    }
    let is_cpu = gpu
        .adapter_info
        .as_ref()
        .is_some_and(|i| i.device_type == wgpu::DeviceType::Cpu);
    if is_cpu && !allow_cpu {
        return Err(format!(
            "the adapter wgpu picked is a CPU adapter ({adapter}): its times are not a GPU's. \
             Point VK_DRIVER_FILES at the GPU driver's ICD file, or pass --allow-cpu to run anyway"
        )
        .into());
    }
    if !gpu.has_timestamps() {
        return Err(format!("the adapter ({adapter}) has no timestamp queries").into());
    }
    let (frames, warm_up) = if opts.quick { (2, 1) } else { (10, 3) };
    let cases = cases(opts.quick);
    let mut table = Table::new(&[
        "case",
        "source",
        "strands",
        "segments",
        "width",
        "height",
        "transparency",
        "shadow",
        "pass",
        "gpu_ms",
        "adapter",
    ]);
    let mut markdown = String::new();
    writeln!(
        markdown,
        "# pelage GPU bench\n\nAdapter: {adapter}  \nDriver: {driver}  \n\
         Median of {frames} frames after {warm_up} of warm-up; GPU milliseconds from timestamp \
         queries per stage; wall: a frame submitted and waited for.{}\n",
        if is_cpu {
            "  \n**CPU adapter (--allow-cpu): not GPU figures; compute timestamps after a \
             render pass are misplaced on lavapipe.**"
        } else {
            ""
        }
    )?;
    markdown.push_str(
        "| case | source | strands | segments | size | transparency | shadow | strands ms | shadow ms | shade ms | GPU total ms | wall ms |\n\
         |---|---|---:|---:|---|---|---|---:|---:|---:|---:|---:|\n",
    );
    let mut skipped = Vec::new();
    for (i, case) in cases.iter().enumerate() {
        if started.elapsed().as_secs_f64() > BUDGET_S {
            skipped.push(case.describe());
            continue;
        }
        let measured = measure(&gpu, case, frames, warm_up)
            .map_err(|e| format!("{}: {e}", case.describe()))?;
        let total: f64 = measured.passes.iter().map(|(_, ms)| ms).sum();
        let stage = |name: &str| -> f64 {
            measured
                .passes
                .iter()
                .filter(|(l, _)| stage_of(l) == name)
                .map(|(_, ms)| ms)
                .sum()
        };
        println!(
            "[{:>3}/{}] {}: GPU {total:.3} ms, wall {:.3} ms",
            i + 1,
            cases.len(),
            case.describe(),
            measured.wall_ms
        );
        let row = |pass: &str, ms: f64| {
            vec![
                case.case.to_string(),
                case.source.to_string(),
                case.strands.to_string(),
                case.segments.to_string(),
                case.width.to_string(),
                case.height.to_string(),
                case.transparency.name().to_string(),
                case.shadow_name().to_string(),
                pass.to_string(),
                format!("{ms:.4}"),
                adapter.clone(),
            ]
        };
        for (label, ms) in &measured.passes {
            table.push(row(label, *ms))?;
        }
        table.push(row("total (sum of passes)", total))?;
        table.push(row("frame (wall clock)", measured.wall_ms))?;
        writeln!(
            markdown,
            "| {} | {} | {} | {} | {}x{} | {} | {} | {:.3} | {:.3} | {:.3} | {total:.3} | {:.3} |",
            case.case,
            case.source,
            case.strands,
            case.segments,
            case.width,
            case.height,
            case.transparency.name(),
            case.shadow_name(),
            stage("strands"),
            stage("shadow"),
            stage("shade"),
            measured.wall_ms
        )?;
    }
    markdown.push_str(
        "\nAnchors: Frostbite, 10 000 strands of 24 points in 4.5 ms on a PS4 at 900p; \
         vkhr, 136 000 strands in 7 ms (its segment count is not given: 16 here).\n",
    );
    if !skipped.is_empty() {
        writeln!(
            markdown,
            "\nNot run (past the {BUDGET_S:.0} s budget): {}",
            skipped.join("; ")
        )?;
        println!(
            "{} configurations not run (past the {BUDGET_S:.0} s budget): {}",
            skipped.len(),
            skipped.join("; ")
        );
    }
    table.write_csv(&opts.out.join("gpu_bench.csv"))?;
    pelage_lab::write_file_atomically(&opts.out.join("gpu_bench.md"), markdown.as_bytes())?;
    println!(
        "wrote {0}/gpu_bench.csv and {0}/gpu_bench.md in {1:.0} s",
        opts.out.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_full_run_has_every_method_size_source_and_anchor() {
        let all = cases(false);
        // 3 sizes x 2 sources + 2 anchors, 9 configurations each.
        assert_eq!(all.len(), 8 * 9);
        for t in Transparency::defaults() {
            assert!(
                all.iter()
                    .any(|c| c.transparency == t && c.strands == 200_000)
            );
        }
        for shadow in ["voxel", "deep_opacity", "shadow_map"] {
            assert!(all.iter().any(|c| c.shadow_name() == shadow));
        }
        assert!(
            all.iter()
                .all(|c| c.case != "grid" || (c.width, c.height, c.segments) == (1920, 1080, 16))
        );
        assert!(
            all.iter()
                .any(|c| c.case == "frostbite anchor" && c.segments == 23 && c.height == 900)
        );
        assert!(
            all.iter()
                .any(|c| c.case == "vkhr anchor" && c.strands == 136_000)
        );
    }

    #[test]
    fn the_quick_run_takes_every_method_and_shadow_once() {
        let quick = cases(true);
        for t in Transparency::defaults() {
            assert!(quick.iter().any(|c| c.transparency == t));
        }
        assert!(quick.iter().any(|c| c.source == "groom"));
        assert!(quick.len() <= 12);
    }
}
