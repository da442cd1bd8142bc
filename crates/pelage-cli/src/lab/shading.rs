//! The shading lab: every hair shading model side by side on long hair, and the cost of
//! each per shaded fragment.
//!
//! ```text
//! pelage lab shading [--quick] [--out DIR]
//! ```
//!
//! Writes `DIR/shading_sheet.png` (default `out/lab`): Kajiya-Kay (plain and with
//! Scheuermann's shifted highlights), Marschner analytic for three hair colours (their
//! absorption from `sigma_a_from_color`), Marschner from its lookup tables, and Sadeghi;
//! and `DIR/shading.csv` with each model's stage 3 time (wall clock of the mesh and
//! hair passes submitted alone, median of the frames, 1 sample per pixel), the number
//! of hair fragments shaded (counted by an A-buffer over the same frame) and the
//! nanoseconds per fragment, also as the extra over plain Kajiya-Kay (what the model
//! itself costs). `--quick` renders smaller images, fewer frames.

use std::time::Instant;

use glam::Vec3;
use pelage::gpu::Gpu;
use pelage::scene::{
    Camera, KajiyaKayParams, Light, MarschnerParams, Mesh, SadeghiParams, ShadingModel,
    Transparency, WindParams, sigma_a_from_color,
};
use pelage::{Renderer, scene::Scene};
use pelage_lab::{Table, contact_sheet};

use super::LabOpts;
use crate::progress;

/// Long hair on a head, lit by a key light and a back light.
fn scene(color: Vec3, strands: u32) -> Result<Scene, Box<dyn std::error::Error>> {
    let mut scene = Scene {
        mesh: Mesh::icosphere(0.5, 3)?,
        camera: Camera {
            eye: Vec3::new(1.5, 0.35, 1.9),
            target: Vec3::new(0.0, -0.1, 0.0),
            ..Default::default()
        },
        ..Scene::default()
    };
    let hair = &mut scene.hair;
    hair.roots.count = strands;
    hair.growth.segments = 16;
    hair.growth.length = 0.9;
    hair.growth.force_weight = 0.12;
    hair.growth.direction_jitter = 0.15;
    hair.growth.color = color;
    hair.wind = WindParams::calm();
    // Seed 003 Fig. 31: a key light and a warm back light, each with its own voxel shadow.
    scene.lights = Light::key_and_back(&scene.camera);
    Ok(scene)
}

fn models() -> Vec<(&'static str, Vec3, ShadingModel)> {
    let blonde = Vec3::new(0.75, 0.55, 0.32);
    let brown = Vec3::new(0.32, 0.17, 0.08);
    let black = Vec3::new(0.05, 0.04, 0.035);
    let marschner = |color: Vec3, lut: bool| ShadingModel::Marschner {
        params: MarschnerParams {
            sigma_a: sigma_a_from_color(color),
            ..Default::default()
        },
        lut,
    };
    vec![
        (
            "kajiya-kay",
            brown,
            ShadingModel::KajiyaKay(KajiyaKayParams::default()),
        ),
        (
            "kajiya-kay shifted",
            brown,
            ShadingModel::KajiyaKay(KajiyaKayParams {
                shift_primary: -0.1,
                shift_secondary: 0.1,
                secondary_specular: 0.3,
                ..Default::default()
            }),
        ),
        ("marschner blonde", blonde, marschner(blonde, false)),
        ("marschner brown", brown, marschner(brown, false)),
        ("marschner black", black, marschner(black, false)),
        ("marschner brown lut", brown, marschner(brown, true)),
        (
            "sadeghi brown",
            brown,
            ShadingModel::Sadeghi(SadeghiParams::default()),
        ),
    ]
}

fn median(mut v: Vec<f64>) -> f64 {
    // One value per model today; kept general.
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// Runs the shading lab: writes `shading.csv` and `shading_sheet.png` under `opts.out`.
pub fn run(opts: &LabOpts) -> Result<(), Box<dyn std::error::Error>> {
    let started = Instant::now();
    let (size, strands, frames) = if opts.quick {
        (160, 1500, 2)
    } else {
        (320, 6000, 10)
    };
    let gpu = Gpu::headless()?;
    println!("adapter: {}", gpu.describe());

    // Fragments shaded per frame at 1 sample per pixel: an A-buffer over the same view counts them.
    let mut counting = scene(Vec3::splat(0.3), strands)?;
    counting.shade.transparency = Transparency::ABuffer {
        nodes_per_pixel: 64.0,
        resolve_k: 8,
    };
    let mut counter = Renderer::new(&gpu, &counting, size, size)?;
    counter.render(&gpu, 0.0, &counting.camera)?;
    let fragments = counter.frame().hair_pass().stats(&gpu)?.stored.max(1);
    println!("{fragments} hair fragments per frame at {size}x{size}");
    let models = models();
    let bar = progress::bar(models.len() as u64, "models")?;

    let mut table = Table::new(&[
        "model",
        "shade_wall_ms",
        "fragments",
        "ns_per_fragment",
        "extra_ns_over_kajiya_kay",
        "lut_mb",
    ]);
    let mut cells = Vec::new();
    let mut base_ns = None;
    for (name, color, model) in models {
        bar.set_message(name);
        // Timing: one sample per pixel, so every covered pixel shades once per strand.
        let mut timed = scene(color, strands)?;
        timed.shade.model = model.clone();
        timed.shade.sample_count = 1;
        let gpu = Gpu::headless()?;
        let mut renderer = Renderer::new(&gpu, &timed, size, size)?;
        renderer.render(&gpu, 0.0, &timed.camera)?; // warm-up: lavapipe compiles on first use
        // Wall clock of stage 3 submitted alone and waited for (lavapipe misplaces
        // timestamps of the compute stages into the first render pass after them).
        let stages = renderer.stage_wall_times(&gpu, 0.0, &timed.camera, frames)?;
        let times: Vec<f64> = stages
            .iter()
            .filter(|(stage, _)| stage == "shade")
            .map(|(_, ms)| *ms)
            .collect();
        let ms = median(times);
        let ns = ms * 1e6 / fragments as f64;
        let base = *base_ns.get_or_insert(ns);
        let lut_mb = pelage::shade::HairModel::new(&gpu, &model)?.memory_bytes() as f64 / 1e6;
        table.push(vec![
            name.into(),
            format!("{ms:.3}"),
            fragments.to_string(),
            format!("{ns:.1}"),
            format!("{:.1}", ns - base),
            format!("{lut_mb:.2}"),
        ])?;
        bar.println(format!(
            "{name:<22} stage 3 {ms:8.2} ms  {ns:7.1} ns per fragment"
        ));

        // The sheet: 4x MSAA, the default look.
        let mut pretty = timed.clone();
        pretty.shade.sample_count = 4;
        let mut renderer = Renderer::new(&gpu, &pretty, size, size)?;
        renderer.render(&gpu, 0.0, &pretty.camera)?;
        cells.push((name.to_string(), renderer.image(&gpu)?));
        bar.inc(1);
    }
    bar.finish_and_clear();
    let sheet = contact_sheet(&cells, 4)?;
    crate::output::save_png(&sheet, &opts.out.join("shading_sheet.png"))?;
    table.write_csv(&opts.out.join("shading.csv"))?;
    println!("{}", table.to_text());
    println!(
        "wrote {}/shading.csv and shading_sheet.png in {:.0} s",
        opts.out.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
