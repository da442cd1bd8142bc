//! The level-of-detail lab: stochastic simplification and segment reduction at several
//! screen coverages, frame time against the full-detail frame, image error against the
//! full-detail image, and the auto quality mode's picks.
//!
//! ```text
//! pelage lab lod [--quick] [--out DIR]
//! ```
//!
//! For each coverage (the hair's bounding box covering 60% down to 2% of the screen;
//! the camera backs away along its view direction until it does) the built-in scene is
//! rendered at full detail and with several LOD settings (`B0` as a fraction of the
//! screen, `h`, segment reduction on or off). Each run: 2 frames of warm-up, then the
//! median over 9 frames (27 for the full-detail frame, every row's denominator) of the
//! wall clock of `Renderer::render` (submit and wait: on a software device this is the
//! GPU time, and it does not depend on lavapipe's compute timestamps, which are
//! misplaced after a render pass) and of the timestamp sum. The image is compared with the full-detail image by LDR-FLIP, over the whole
//! image and over the pixels the creature covers (either image differs from the
//! background there). "full detail, other seed" is the same fur grown from other random
//! roots: the error any change of strands makes, the floor for the LOD rows.
//!
//! Writes `DIR/lod.csv`, `DIR/lod.png|svg` (FLIP on the creature against the frame
//! time ratio), `DIR/lod_auto.csv` (the auto mode's picks: per coverage the cheapest
//! LOD setting whose mean FLIP over the image is within the budget, the shadow resolution and k-buffer depth derived
//! from the hair's size on screen and its measured depth complexity, and, when
//! `DIR/shadows.csv` and `DIR/oit.csv` from the other labs are there, the cheapest
//! shadow and transparency configurations within budget) and `DIR/lod_<coverage>.png`
//! (full detail beside the auto pick).

use std::time::Instant;

use glam::Vec3;
use pelage::gpu::Gpu;
use pelage::scene::{Camera, LodParams, ShadowParams, Transparency};
use pelage::strands::LodLevel;
use pelage::{Renderer, scene::Scene};
use pelage_lab::{ScatterChart, ScatterPoint, Table, contact_sheet};

use super::{LabOpts, background, flip_scores};
use crate::auto::{self, Budget, Candidate};
use crate::progress;

type LabResult<T> = Result<T, Box<dyn std::error::Error>>;

/// One LOD setting.
struct Config {
    name: String,
    lod: LodParams,
}

fn configs(screen_pixels: f32, quick: bool) -> Vec<Config> {
    let mut out = vec![
        Config {
            name: "full detail".into(),
            lod: LodParams::default(),
        },
        // The noise floor: the same fur from other random strands, at full detail.
        Config {
            name: "full detail, other seed".into(),
            lod: LodParams::default(),
        },
    ];
    let settings: &[(f32, f32, bool)] = if quick {
        &[(1.0, 0.5, true), (0.5, 0.3, true)]
    } else {
        &[
            (1.0, 0.5, true),
            (1.0, 0.5, false),
            (1.0, 0.3, true),
            (0.5, 0.5, true),
            (0.5, 0.3, true),
            (0.25, 0.5, true),
        ]
    };
    for &(b0, h, segments) in settings {
        out.push(Config {
            name: format!(
                "B0={b0} h={h}{}",
                if segments { "" } else { " strands only" }
            ),
            lod: LodParams {
                enabled: true,
                start_pixels: b0 * screen_pixels,
                half_at: h,
                segment_error_pixels: if segments {
                    LodParams::default().segment_error_pixels
                } else {
                    0.0
                },
                ..LodParams::default()
            },
        });
    }
    out
}

/// Screen pixels covered by the hair's box seen from `camera`.
fn coverage_pixels(scene: &Scene, camera: &Camera, width: u32, height: u32) -> f32 {
    let mut hair = scene.hair.clone();
    hair.lod = LodParams {
        enabled: true,
        start_pixels: f32::MAX,
        ..LodParams::default()
    };
    let level = LodLevel::for_view(
        &hair,
        pelage::strands::scene_reach(scene),
        &camera.matrices(width, height),
        width,
        height,
    );
    if level.pixels.is_finite() {
        level.pixels
    } else {
        (width * height) as f32
    }
}

/// The camera on the default camera's line of sight whose view of the hair's box covers
/// `fraction` of the screen (bisection on the distance).
fn camera_for(scene: &Scene, fraction: f32, width: u32, height: u32) -> Camera {
    let base = &scene.camera;
    let dir = (base.eye - base.target).normalize_or(Vec3::Z);
    let at = |d: f32| Camera {
        eye: base.target + dir * d,
        far: base.far.max(d * 4.0),
        ..base.clone()
    };
    let target = fraction * (width * height) as f32;
    let (mut near, mut far) = (0.5f32, 400.0f32);
    for _ in 0..60 {
        let mid = (near * far).sqrt();
        if coverage_pixels(scene, &at(mid), width, height) > target {
            near = mid;
        } else {
            far = mid;
        }
    }
    at(far)
}

struct Run {
    image: image::RgbaImage,
    wall_ms: f64,
    gpu_ms: f64,
    level: LodLevel,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

fn measure(
    gpu: &Gpu,
    scene: &Scene,
    camera: &Camera,
    size: (u32, u32),
    frames: usize,
) -> LabResult<Run> {
    let mut renderer = Renderer::new(gpu, scene, size.0, size.1)?;
    for _ in 0..2 {
        renderer.render(gpu, 0.5, camera)?;
    }
    let (mut wall, mut stamps) = (Vec::new(), Vec::new());
    for _ in 0..frames {
        let started = Instant::now();
        renderer.render(gpu, 0.5, camera)?;
        let stats = renderer.finish(gpu)?;
        wall.push(started.elapsed().as_secs_f64() * 1e3);
        stamps.push(stats.total_ms());
    }
    Ok(Run {
        image: renderer.image(gpu)?,
        wall_ms: median(wall),
        gpu_ms: median(stamps),
        level: *renderer.frame().strands().lod(),
    })
}

/// Mean hair fragments per covered pixel, counted by an A-buffer frame.
fn mean_fragments(gpu: &Gpu, scene: &Scene, camera: &Camera, size: (u32, u32)) -> LabResult<f64> {
    let mut s = scene.clone();
    s.shade.transparency = Transparency::ABuffer {
        nodes_per_pixel: 48.0,
        resolve_k: 16,
    };
    s.shade.sample_count = 1;
    let mut renderer = Renderer::new(gpu, &s, size.0, size.1)?;
    renderer.render(gpu, 0.5, camera)?;
    let stats = renderer.frame().hair_pass().stats(gpu)?;
    // The pool counts fragments, not pixels: spread them over the creature's pixels.
    let image = renderer.image(gpu)?;
    let bg = background(scene);
    let covered = image
        .pixels()
        .filter(|p| (0..3).any(|c| (i16::from(p.0[c]) - i16::from(bg[c])).abs() > 1))
        .count()
        .max(1);
    Ok(stats.stored as f64 / covered as f64)
}

/// A row of `lod_auto.csv` for `pick`.
fn pick_row(coverage: &str, what: &str, pick: &auto::Pick) -> Vec<String> {
    vec![
        coverage.to_string(),
        what.to_string(),
        pick.chosen.name.clone(),
        format!("{:.4}", pick.chosen.error),
        format!("{:.2}", pick.chosen.time_ms),
        pick.why.clone(),
    ]
}

/// The shadow resolution and transparency of `scene`, briefly.
fn describe(scene: &Scene) -> String {
    let shadow = match &scene.shadow {
        ShadowParams::None => "no shadow".to_string(),
        ShadowParams::Voxel(v) => format!("voxels {}^3", v.resolution[0]),
        ShadowParams::DeepOpacity(d) => format!("dom {}", d.map.size),
        ShadowParams::ShadowMap(m) => format!("map {}", m.map.size),
        ShadowParams::Adsm(a) => format!("adsm {}", a.map.size),
    };
    match scene.shade.transparency {
        Transparency::KBuffer { k } => format!("{shadow}, k={k}"),
        _ => shadow,
    }
}

/// Runs the lab.
pub fn run(opts: &LabOpts) -> LabResult<()> {
    pelage_lab::create_dir(&opts.out)?;
    let (size, frames, coverages, strands): ((u32, u32), usize, &[f32], u32) = if opts.quick {
        ((240, 180), 3, &[0.1], 6_000)
    } else {
        ((480, 360), 9, &[0.6, 0.3, 0.1, 0.05, 0.02], 20_000)
    };
    let mut scene = Scene::default();
    scene.hair.roots.count = strands;
    // Widened strands keep their covered area through coverage alpha, which the opaque
    // method ignores (it draws every ribbon at least min_pixels wide, fully covering):
    // the lab runs the k-buffer, the transparency method the OIT lab recommends.
    scene.shade.transparency = Transparency::k_buffer(8);
    let screen = (size.0 * size.1) as f32;
    let configs = configs(screen, opts.quick);
    let budget = Budget::default();
    let bg = background(&scene);
    let gpu = Gpu::headless()?;
    println!("lod lab on {}", gpu.describe());

    let mut table = Table::new(&[
        "coverage",
        "box_pixels",
        "config",
        "lambda",
        "strands",
        "segments",
        "wall_ms",
        "gpu_ms",
        "wall_ratio",
        "gpu_ratio",
        "mean_flip",
        "mean_flip_creature",
    ]);
    let mut auto_table = Table::new(&["coverage", "what", "pick", "error", "time_ms", "why"]);
    let mut points = Vec::new();
    let mut sheet = Vec::new();
    let bar = progress::bar((coverages.len() * configs.len()) as u64, "runs")?;
    for &coverage in coverages {
        let camera = camera_for(&scene, coverage, size.0, size.1);
        let pixels = coverage_pixels(&scene, &camera, size.0, size.1);
        let mut full: Option<Run> = None;
        let mut candidates = Vec::new();
        let mut images = Vec::new();
        for config in &configs {
            bar.set_message(format!("{:.0}% {}", coverage * 100.0, config.name));
            let mut s = scene.clone();
            s.hair.lod = config.lod.clone();
            if config.name.ends_with("other seed") {
                s.hair.roots.seed = s.hair.roots.seed.wrapping_add(1);
            }
            let mut adapted = String::new();
            if config.lod.enabled {
                // Sized to the picture: the shadow grid and maps to the hair's size on
                // screen, the k-buffer to the depth complexity this level draws.
                s = pelage::strands::sized_for_view(&s, &camera, size.0, size.1);
                let depth = mean_fragments(&gpu, &s, &camera, size)?;
                s.shade.transparency = s.shade.transparency.sized_for_depth(depth);
                adapted = format!(" ({})", describe(&s));
            }
            // The full-detail frame is every row's denominator: time it over more frames.
            let n = if full.is_none() { 3 * frames } else { frames };
            let run = measure(&gpu, &s, &camera, size, n)?;
            let reference = full.as_ref().unwrap_or(&run);
            let (flip_all, flip_creature) = flip_scores(&reference.image, &run.image, bg)?;
            let (wall_ratio, gpu_ratio) = (
                run.wall_ms / reference.wall_ms,
                run.gpu_ms / reference.gpu_ms,
            );
            table.push(vec![
                format!("{coverage}"),
                format!("{pixels:.0}"),
                format!("{}{adapted}", config.name),
                format!("{:.3}", run.level.zone.lambda),
                run.level.strands.to_string(),
                run.level.segments.to_string(),
                format!("{:.2}", run.wall_ms),
                format!("{:.2}", run.gpu_ms),
                format!("{wall_ratio:.3}"),
                format!("{gpu_ratio:.3}"),
                format!("{flip_all:.4}"),
                format!("{flip_creature:.4}"),
            ])?;
            bar.println(format!(
                "{:>5.1}% {:<44} lambda {:.3} {:>6} strands {:>2} segments  {:>8.2} ms ({wall_ratio:.2}x)  FLIP {flip_all:.4} / creature {flip_creature:.4}",
                coverage * 100.0,
                format!("{}{adapted}", config.name),
                run.level.zone.lambda,
                run.level.strands,
                run.level.segments,
                run.wall_ms
            ));
            if full.is_some() {
                points.push(ScatterPoint {
                    series: if config.name.ends_with("other seed") {
                        "floor: other random strands".into()
                    } else {
                        format!("{:.0}% of the screen", coverage * 100.0)
                    },
                    label: format!("{}{adapted}", config.name),
                    x: wall_ratio,
                    y: flip_creature,
                    size: None,
                });
            }
            if !config.name.ends_with("other seed") {
                candidates.push(Candidate {
                    name: format!("{}{adapted}", config.name),
                    error: flip_all,
                    time_ms: run.wall_ms,
                });
            }
            images.push((format!("{}{adapted}", config.name), run.image.clone()));
            if full.is_none() {
                full = Some(run);
            }
            bar.inc(1);
        }

        // The auto mode: the cheapest LOD setting within the budget ...
        let label = format!("{coverage}");
        if let Some(pick) = auto::cheapest(&candidates, budget.flip) {
            auto_table.push(pick_row(&label, "lod", &pick))?;
            if let Some((_, image)) = images.iter().find(|(n, _)| *n == pick.chosen.name) {
                sheet.push((
                    format!("{:.0}%: full detail", coverage * 100.0),
                    images[0].1.clone(),
                ));
                sheet.push((
                    format!("{:.0}%: auto ({})", coverage * 100.0, pick.chosen.name),
                    image.clone(),
                ));
            }
        }
        // ... the shadow resolution from the hair's size on screen ...
        let sized = pelage::strands::sized_for_view(&scene, &camera, size.0, size.1);
        let extent = LodLevel::for_view(
            &scene.hair,
            pelage::strands::scene_reach(&scene),
            &camera.matrices(size.0, size.1),
            size.0,
            size.1,
        )
        .extent_pixels;
        auto_table.push(vec![
            label.clone(),
            "shadow resolution".into(),
            describe(&sized),
            "-".into(),
            "-".into(),
            format!("hair box {extent:.0} px across on screen: a voxel per 4 px, a map texel per px (ShadowParams::sized_for)"),
        ])?;
        // ... and the k-buffer depth from the measured depth complexity.
        let mean = mean_fragments(&gpu, &scene, &camera, size)?;
        auto_table.push(vec![
            label.clone(),
            "oit k".into(),
            format!("{:?}", scene.shade.transparency.sized_for_depth(mean)),
            "-".into(),
            "-".into(),
            format!("{mean:.1} hair fragments per covered pixel at full detail, A-buffer count (Transparency::sized_for_depth)"),
        ])?;
    }
    bar.finish_and_clear();

    // From the other labs' measurements, when they are in DIR.
    let opacity = f64::from(scene.hair.growth.opacity);
    if let Ok(text) = std::fs::read_to_string(opts.out.join("shadows.csv")) {
        let rows = auto::shadow_candidates(&Table::from_csv(&text)?, "dense_fur")?;
        if let Some(pick) = auto::cheapest(&rows, budget.transmittance_rmse) {
            auto_table.push(pick_row("-", "shadow (dense fur, shadows.csv)", &pick))?;
        }
    } else {
        println!(
            "no {}: run `pelage lab shadows` for the shadow pick",
            opts.out.join("shadows.csv").display()
        );
    }
    if let Ok(text) = std::fs::read_to_string(opts.out.join("oit.csv")) {
        let (measured, rows) = auto::oit_candidates(&Table::from_csv(&text)?, "creature", opacity)?;
        if let Some(pick) = auto::cheapest(&rows, budget.flip) {
            let what = format!("transparency (creature, opacity {measured}, oit.csv)");
            auto_table.push(pick_row("-", &what, &pick))?;
        }
    } else {
        println!(
            "no {}: run `pelage lab oit` for the transparency pick",
            opts.out.join("oit.csv").display()
        );
    }

    table.write_csv(&opts.out.join("lod.csv"))?;
    auto_table.write_csv(&opts.out.join("lod_auto.csv"))?;
    println!("{}", table.to_text());
    println!(
        "auto mode (FLIP budget {}, transmittance RMSE budget {}):",
        budget.flip, budget.transmittance_rmse
    );
    println!("{}", auto_table.to_text());
    let chart = ScatterChart {
        title: "Level of detail: error against frame time (lavapipe)".into(),
        x_label: "frame time / full-detail frame time".into(),
        y_label: "mean FLIP on the creature vs full detail".into(),
        x_log: false,
        y_log: false,
        points,
        mark_pareto: false,
        size_label: None,
    };
    chart.write_svg(&opts.out.join("lod.svg"), 900, 600)?;
    chart.write_png(&opts.out.join("lod.png"), 900, 600)?;
    if !sheet.is_empty() {
        contact_sheet(&sheet, 2)?.save(opts.out.join("lod_auto.png"))?;
    }
    Ok(())
}
