//! The scattering lab: pelage's Chiang fibres, single and dual scattering, against an
//! independent path tracer (`pelage_reference::path_tracer`: the real strand cylinders,
//! Chiang's near-field BSDF at the true fibre offset, every bounce up to 16, the mesh as a
//! diffuse occluder) on the same strands, camera, sun and sky.
//!
//! ```text
//! pelage lab scattering [--quick] [--out DIR] [--spp N]
//! ```
//!
//! Black, brown and blond hair (eumelanin 8, 1.3, 0.3) × fur on the creature and long hair
//! on a head, 256x256 (`--quick`: 64x64, one groom, two colours, 16 spp). The reference is
//! the mean of two path-traced images with different seeds (a third, with one bounce, is
//! the single-scattering reference); their own difference (FLIP of
//! one seed against the other) is the noise floor each row reports. pelage renders the
//! same scene with the k-buffer (k = 8) and the voxel shadow, the Chiang model with dual
//! scattering off and on.
//!
//! Writes `DIR/scattering.csv` (mean FLIP over the image and over the hair pixels, the
//! hair's luminance against the reference's, the shade stage's wall clock and the
//! reference's noise floor), `DIR/scattering.png|svg` (FLIP over the hair against time),
//! `DIR/scattering_sheet.png` (per scene: path tracer | single | dual | FLIP of dual) and
//! the path-traced images in `DIR/scattering/` (linear HDR and sRGB PNG).

use std::time::Instant;

use glam::{DVec3, Vec3};
use image::RgbaImage;
use pelage::gpu::Gpu;
use pelage::scene::{
    Camera, ChiangParams, DirectionalLight, Light, Mesh, ShadingModel, Transparency, WindParams,
    chiang_color_scale, sigma_a_from_melanin,
};
use pelage::{Renderer, Scene};
use pelage_lab::{ScatterChart, ScatterPoint, Table, contact_sheet};
use pelage_reference::flip::{DEFAULT_PIXELS_PER_DEGREE, LinearImage, flip};
use pelage_reference::path_tracer::{PathTracedImage, PathTracerSettings};

use super::LabOpts;
use crate::path_trace::{TracedScene, hair_luminance, heat, masked_mean};
use crate::progress;

/// Sky radiance of the lab's scenes (pelage's `ambient` is π times it, see `hair_ambient`).
const SKY: f32 = 0.06;

/// The hair colours: name, eumelanin, pheomelanin.
const HAIR: [(&str, f32, f32); 3] = [
    ("black", 8.0, 0.0),
    ("brown", 1.3, 0.0),
    ("blond", 0.3, 0.0),
];

/// The colour a fibre of absorption `sigma` appears as a volume (Chiang eq. 9 inverted).
fn apparent_color(sigma: Vec3, beta_n: f32) -> Vec3 {
    let s = chiang_color_scale(beta_n);
    Vec3::new(
        (-sigma.x.sqrt() * s).exp(),
        (-sigma.y.sqrt() * s).exp(),
        (-sigma.z.sqrt() * s).exp(),
    )
}

/// A lab scene: `groom` ("fur" or "long_hair") with hair of melanin `eu`, `pheo`.
fn scene(
    groom: &str,
    eu: f32,
    pheo: f32,
    quick: bool,
    dual: bool,
) -> Result<Scene, Box<dyn std::error::Error>> {
    let mut scene = Scene::default();
    let params = ChiangParams {
        dual_scattering: dual,
        ..ChiangParams::melanin(eu, pheo)
    };
    let sigma = sigma_a_from_melanin(eu, pheo);
    let hair = &mut scene.hair;
    hair.wind = WindParams::calm();
    hair.growth.color = apparent_color(sigma, params.beta_n);
    hair.growth.color_jitter = 0.0;
    // Fibres are opaque cylinders (the path tracer's): the ribbons' coverage alone makes
    // sub-pixel strands see-through, and the shadows count every fibre as opaque.
    hair.growth.opacity = 1.0;
    match groom {
        "fur" => {
            hair.roots.count = if quick { 3_000 } else { 12_000 };
        }
        _ => {
            scene.mesh = Mesh::icosphere(0.5, 3)?;
            scene.camera = Camera {
                eye: Vec3::new(1.5, 0.35, 1.9),
                target: Vec3::new(0.0, -0.1, 0.0),
                ..Default::default()
            };
            hair.roots.count = if quick { 1_500 } else { 5_000 };
            hair.growth.segments = 16;
            hair.growth.length = 0.9;
            hair.growth.force_weight = 0.12;
            hair.growth.direction_jitter = 0.15;
        }
    }
    scene.shade.model = ShadingModel::Chiang(params);
    scene.shade.transparency = Transparency::KBuffer { k: 8 };
    scene.shade.background = Vec3::splat(SKY);
    scene.shade.ambient = SKY * std::f32::consts::PI;
    // The sun, from the upper left, behind the camera's shoulder.
    scene.lights = vec![Light::Directional(DirectionalLight {
        direction: Vec3::new(-0.7, -0.6, -0.4).normalize(),
        color: Vec3::ONE,
        intensity: 2.5,
    })];
    Ok(scene)
}

/// pelage's image of `scene` and the median wall clock of its shade stage (ms).
fn render_pelage(
    scene: &Scene,
    size: u32,
    frames: usize,
) -> Result<(RgbaImage, f64, Renderer, Gpu), Box<dyn std::error::Error>> {
    let gpu = Gpu::headless()?;
    let mut renderer = Renderer::new(&gpu, scene, size, size)?;
    renderer.render(&gpu, 0.0, &scene.camera)?;
    let image = renderer.image(&gpu)?;
    let stages = renderer.stage_wall_times(&gpu, 0.0, &scene.camera, frames)?;
    let mut times: Vec<f64> = stages
        .iter()
        .filter(|(stage, _)| stage == "shade")
        .map(|(_, ms)| *ms)
        .collect();
    times.sort_by(f64::total_cmp);
    let ms = times.get(times.len() / 2).copied().unwrap_or(f64::NAN);
    Ok((image, ms, renderer, gpu))
}

/// Path-traces the strands `renderer` drew for `scene`: twice (seeds 1 and 2) with every
/// bounce, and once (seed 3) with one bounce only, the single-scattering reference. The
/// sky that lights the hair and the background camera rays see are both [`SKY`].
fn path_trace(
    scene: &Scene,
    renderer: &Renderer,
    gpu: &Gpu,
    size: u32,
    spp: u32,
) -> Result<[PathTracedImage; 3], Box<dyn std::error::Error>> {
    if !matches!(scene.shade.model, ShadingModel::Chiang(_)) {
        return Err("the scattering lab's scenes use the Chiang model".into());
    }
    let tracer = TracedScene::from_renderer(scene, renderer, gpu)?.tracer()?;
    let render = |seed, max_bounces| {
        tracer.render(
            &scene.camera,
            size,
            size,
            &PathTracerSettings {
                spp,
                seed,
                max_bounces,
                background: DVec3::splat(f64::from(SKY)),
                sky: DVec3::splat(f64::from(SKY)),
                ..Default::default()
            },
        )
    };
    Ok([render(1, 16)?, render(2, 16)?, render(3, 1)?])
}

fn srgb_image(image: &PathTracedImage) -> Result<RgbaImage, Box<dyn std::error::Error>> {
    RgbaImage::from_raw(image.width, image.height, image.to_srgb8_rgba())
        .ok_or_else(|| "path-traced image has the wrong size".into())
}

/// Runs the lab (see the module docs); `spp` overrides the path tracer's samples per pixel.
pub fn run(opts: &LabOpts, spp: Option<u32>) -> Result<(), Box<dyn std::error::Error>> {
    let started = Instant::now();
    let quick = opts.quick;
    let size = if quick { 64 } else { 256 };
    let spp = spp.unwrap_or(if quick { 16 } else { 64 });
    let frames = if quick { 2 } else { 5 };
    let grooms: &[&str] = if quick {
        &["fur"]
    } else {
        &["fur", "long_hair"]
    };
    let hair: &[(&str, f32, f32)] = if quick { &HAIR[1..] } else { &HAIR };
    pelage_lab::create_dir(&opts.out.join("scattering"))?;
    println!("adapter: {}", Gpu::headless()?.describe());
    let mut table = Table::new(&[
        "groom",
        "hair",
        "method",
        "mean_flip",
        "hair_flip",
        "hair_luminance_ratio",
        "shade_ms",
        "hair_flip_vs_1_bounce",
        "reference_spp",
        "noise_mean_flip",
        "noise_hair_flip",
        "reference_s",
    ]);
    let mut points = Vec::new();
    let mut cells = Vec::new();
    let bar = progress::bar((grooms.len() * hair.len()) as u64, "scenes")?;
    for &groom in grooms {
        for &(name, eu, pheo) in hair {
            bar.set_message(format!("{groom} {name}"));
            let single = scene(groom, eu, pheo, quick, false)?;
            let dual = scene(groom, eu, pheo, quick, true)?;
            let (single_image, single_ms, renderer, gpu) = render_pelage(&single, size, frames)?;
            let (dual_image, dual_ms, _, _) = render_pelage(&dual, size, frames)?;
            let traced = Instant::now();
            let [a, b, one] = path_trace(&single, &renderer, &gpu, size, spp)?;
            let reference_s = traced.elapsed().as_secs_f64() / 3.0;
            let stem = format!("{groom}_{name}");
            for (img, seed) in [(&a, "seed1"), (&b, "seed2"), (&one, "1_bounce")] {
                img.write_hdr(
                    &opts
                        .out
                        .join("scattering")
                        .join(format!("{stem}_{seed}.hdr")),
                )?;
                img.write_png(
                    &opts
                        .out
                        .join("scattering")
                        .join(format!("{stem}_{seed}.png")),
                )?;
            }
            let mask: Vec<f32> = a
                .hair_mask
                .iter()
                .zip(&b.hair_mask)
                .map(|(x, y)| 0.5 * (x + y))
                .collect();
            let la = a.to_linear_image()?;
            let lb = b.to_linear_image()?;
            let mean = PathTracedImage {
                pixels: a
                    .pixels
                    .iter()
                    .zip(&b.pixels)
                    .map(|(x, y)| {
                        [
                            0.5 * (x[0] + y[0]),
                            0.5 * (x[1] + y[1]),
                            0.5 * (x[2] + y[2]),
                        ]
                    })
                    .collect(),
                hair_mask: mask.clone(),
                spp: 2 * spp,
                ..a.clone()
            };
            let reference = mean.to_linear_image()?;
            let noise = flip(&la, &lb, DEFAULT_PIXELS_PER_DEGREE)?;
            let (noise_mean, noise_hair) = (noise.mean(), masked_mean(&noise, &mask));
            let ref_luma = hair_luminance(&reference, &mask);
            let single_reference = one.to_linear_image()?;
            {
                // How far single scattering itself is from the whole: the gap dual
                // scattering has to close.
                let map = flip(&reference, &single_reference, DEFAULT_PIXELS_PER_DEGREE)?;
                let ratio = hair_luminance(&single_reference, &mask) / ref_luma;
                table.push(vec![
                    groom.into(),
                    name.into(),
                    "path_tracer_1_bounce".into(),
                    format!("{:.4}", map.mean()),
                    format!("{:.4}", masked_mean(&map, &mask)),
                    format!("{ratio:.3}"),
                    String::new(),
                    "0".into(),
                    (2 * spp).to_string(),
                    format!("{noise_mean:.4}"),
                    format!("{noise_hair:.4}"),
                    format!("{reference_s:.1}"),
                ])?;
            }
            let mut dual_flip = None;
            for (method, image, ms) in [
                ("single", &single_image, single_ms),
                ("dual", &dual_image, dual_ms),
            ] {
                let test = LinearImage::from_srgb8_rgba(size, size, image.as_raw())?;
                let map = flip(&reference, &test, DEFAULT_PIXELS_PER_DEGREE)?;
                let hair_flip = masked_mean(&map, &mask);
                let ratio = hair_luminance(&test, &mask) / ref_luma;
                let vs_single = masked_mean(
                    &flip(&single_reference, &test, DEFAULT_PIXELS_PER_DEGREE)?,
                    &mask,
                );
                table.push(vec![
                    groom.into(),
                    name.into(),
                    method.into(),
                    format!("{:.4}", map.mean()),
                    format!("{hair_flip:.4}"),
                    format!("{ratio:.3}"),
                    format!("{ms:.2}"),
                    format!("{vs_single:.4}"),
                    (2 * spp).to_string(),
                    format!("{noise_mean:.4}"),
                    format!("{noise_hair:.4}"),
                    format!("{reference_s:.1}"),
                ])?;
                points.push(ScatterPoint {
                    series: format!("{method} scattering"),
                    label: format!("{groom} {name}"),
                    x: ms,
                    y: hair_flip,
                    size: None,
                });
                bar.println(format!(
                    "{groom:<9} {name:<6} {method:<6} FLIP {:.4} (hair {hair_flip:.4}, noise {noise_hair:.4}; against 1 bounce {vs_single:.4})  luminance x{ratio:.3}  shade {ms:.1} ms",
                    map.mean()
                ));
                if method == "dual" {
                    dual_flip = Some(map);
                }
            }
            let label = |what: &str| format!("{groom} {name}: {what}");
            cells.push((
                label(&format!("path tracer {} spp", 2 * spp)),
                srgb_image(&mean)?,
            ));
            cells.push((label("single"), single_image));
            cells.push((label("dual"), dual_image));
            if let Some(map) = dual_flip {
                cells.push((label("FLIP of dual"), heat(&map)?));
            }
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    table.write_csv(&opts.out.join("scattering.csv"))?;
    let chart = ScatterChart {
        title: "Chiang fibres against the path tracer".into(),
        x_label: "shade stage wall clock (ms)".into(),
        y_label: "mean FLIP over the hair".into(),
        x_log: false,
        y_log: false,
        points,
        mark_pareto: false,
        size_label: None,
    };
    chart.write_png(&opts.out.join("scattering.png"), 800, 500)?;
    chart.write_svg(&opts.out.join("scattering.svg"), 800, 500)?;
    let sheet = contact_sheet(&cells, 4)?;
    pelage::save_png(&sheet, &opts.out.join("scattering_sheet.png"))?;
    println!("{}", table.to_text());
    println!(
        "wrote {}/scattering.csv, scattering.png|svg, scattering_sheet.png in {:.0} s",
        opts.out.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
