//! The scattering lab: pelage's Chiang fibres, single, dual and volume scattering, against an
//! independent path tracer (`pelage_reference::path_tracer`: the real strand cylinders,
//! Chiang's near-field BSDF at the true fibre offset, every bounce up to 16, the mesh as a
//! diffuse occluder) on the same strands, camera, lights (a key light, the sun over the
//! camera's shoulder, and a back light from above and behind the hair) and sky.
//!
//! ```text
//! pelage lab scattering [--quick] [--out DIR] [--spp N]
//! ```
//!
//! Black, brown, blond and red hair × fur on the creature, long hair from a groom file
//! (`scenes/long_hair.hair`) and a dense curly groom grown on a head, 256x256 (`--quick`:
//! 64x64, fur and the curly groom, brown and blond, 16 spp). The reference is the mean of
//! two path-traced images with different seeds (16 bounces); their own difference (FLIP of
//! one seed against the other) is the noise floor each row reports. pelage renders the
//! same scene with the k-buffer (k = 8) and the voxel shadow, once per row of [`METHODS`]
//! (the Chiang model with multiple scattering none, dual and volume).
//!
//! **Where the light comes from**: more path-traced images of seed 1 cap the bounces at 1,
//! 2, 4 and 8, and one at 64 shows how much 16 truncates (the same paths stopped earlier or
//! later, so the differences are not swamped by noise). Their hair luminance against seed
//! 1's at 16 bounces splits it by bounce order (1, 2, 3-4, 5-8, 9-16, 17-64): the
//! `path_tracer_le_K` rows, and per method the columns `lum_vs_le_K` (the method's hair
//! luminance over that of orders 1..K) and a printed line saying which orders it carries.
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
use pelage::gpu::read_buffer;
use pelage::scene::{
    AdsmParams, Camera, ChiangParams, DeepOpacityParams, DirectionalLight, HairType, Light, Mesh,
    MultipleScattering, ShadingModel, ShadowMapParams, ShadowParams, Transparency, VoxelParams,
    WindParams, chiang_color_scale, sigma_a_from_melanin,
};
use pelage::{Renderer, Scene};
use pelage_lab::{ScatterChart, ScatterPoint, Table, contact_sheet};
use pelage_reference::flip::{DEFAULT_PIXELS_PER_DEGREE, LinearImage, flip};
use pelage_reference::path_tracer::{PathTracedImage, PathTracerSettings};
use pelage_reference::transmittance::SegmentBvh;

use super::LabOpts;
use crate::path_trace::{TracedScene, hair_luminance, heat, masked_mean};
use crate::progress;

/// Sky radiance of the lab's scenes (pelage's `ambient` is π times it, see `hair_ambient`).
const SKY: f32 = 0.06;

/// Switches that take one source of light out of both renderers, to measure its share of
/// a method's error apart (`--black-mesh`, `--no-sky`).
#[derive(Clone, Copy, Debug, Default)]
pub struct Variant {
    /// The mesh black (`shade.mesh_color` 0: nothing bounces off the skin).
    pub black_mesh: bool,
    /// No sky: `ambient`, the background and the path tracer's sky 0.
    pub no_sky: bool,
    /// No back light: the key light and the sky only.
    pub no_back_light: bool,
}

impl Variant {
    /// The sky radiance of the lab's scenes under this variant.
    fn sky(self) -> f32 {
        if self.no_sky { 0.0 } else { SKY }
    }
}

/// Irradiance of the back light (the key light's is 2.5).
const BACK_LIGHT: f32 = 1.5;

/// The hair colours: name, eumelanin, pheomelanin (pbrt's coefficients).
const HAIR: [(&str, f32, f32); 4] = [
    ("black", 8.0, 0.0),
    ("brown", 1.3, 0.0),
    ("blond", 0.3, 0.0),
    ("red", 0.3, 1.2),
];

/// A pelage variant: its name and how it sets up the scene's Chiang parameters.
type Method = (&'static str, fn(&mut ChiangParams));

/// The pelage variants measured against the path tracer: name, and how the variant sets
/// up the scene's Chiang parameters. A new multiple-scattering method adds a row.
const METHODS: [Method; 5] = [
    ("single", |p| {
        p.multiple_scattering = MultipleScattering::None
    }),
    ("dual", |p| p.multiple_scattering = MultipleScattering::Dual),
    // The volume method beside its defaults (16³ cells, 12 steps): a finer grid (with
    // the steps a beam needs to cross it), and more steps (light still in flight after
    // the last step is lost).
    ("volume_g32", |p| {
        p.multiple_scattering = MultipleScattering::Volume;
        p.volume_grid = 32;
        p.volume_iterations = 32;
    }),
    ("volume_s64", |p| {
        p.multiple_scattering = MultipleScattering::Volume;
        p.volume_iterations = 64;
    }),
    // The defaults last: the sheet shows its FLIP.
    ("volume", |p| {
        p.multiple_scattering = MultipleScattering::Volume
    }),
];

/// Bounce caps of the bounce-order split below the reference's 16 (one seed each).
const BOUNCE_CAPS: [u32; 4] = [1, 2, 4, 8];

/// The reference's bounces.
const REFERENCE_BOUNCES: u32 = 16;

/// The deep run: how much stopping at 16 bounces leaves out.
const DEEP_BOUNCES: u32 = 64;

/// The long groom file the lab reads (the repository's `scenes/long_hair.toml`).
const LONG_HAIR_SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/long_hair.toml");

/// The colour a fibre of absorption `sigma` appears as a volume (Chiang eq. 9 inverted).
fn apparent_color(sigma: Vec3, beta_n: f32) -> Vec3 {
    let s = chiang_color_scale(beta_n);
    Vec3::new(
        (-sigma.x.sqrt() * s).exp(),
        (-sigma.y.sqrt() * s).exp(),
        (-sigma.z.sqrt() * s).exp(),
    )
}

/// A lab scene: `groom` ("fur", "long_hair" or "curly") with hair of melanin `eu`, `pheo`,
/// shaded by `method` (see [`METHODS`]).
fn scene(
    groom: &str,
    eu: f32,
    pheo: f32,
    quick: bool,
    method: fn(&mut ChiangParams),
    variant: Variant,
) -> Result<Scene, Box<dyn std::error::Error>> {
    let mut params = ChiangParams::melanin(eu, pheo);
    method(&mut params);
    let sigma = sigma_a_from_melanin(eu, pheo);
    let mut scene = match groom {
        "long_hair" => {
            let path = std::path::Path::new(LONG_HAIR_SCENE);
            Scene::from_file(path).map_err(|e| format!("{}: {e}", path.display()))?
        }
        _ => Scene::default(),
    };
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
        "long_hair" => {
            // The groom file's strands, on its head, seen from the lab's camera.
            scene.camera = Camera {
                eye: Vec3::new(1.6, 0.2, 3.0),
                target: Vec3::new(0.0, -0.35, 0.0),
                ..Default::default()
            };
        }
        _ => {
            // A dense curly groom: tight helices packed on a head.
            scene.mesh = Mesh::icosphere(0.5, 3)?;
            scene.camera = Camera {
                eye: Vec3::new(1.5, 0.35, 1.9),
                target: Vec3::new(0.0, -0.1, 0.0),
                ..Default::default()
            };
            hair.roots.count = if quick { 2_500 } else { 8_000 };
            hair.growth.segments = 24;
            hair.growth.length = 0.35;
            hair.growth.force_weight = 0.05;
            hair.growth.direction_jitter = 0.3;
            hair.growth.hair_type = HairType::Curly {
                radius: 0.025,
                pitch: 0.06,
            };
        }
    }
    scene.shade.model = ShadingModel::Chiang(params);
    scene.shade.transparency = Transparency::KBuffer { k: 8 };
    scene.shade.background = Vec3::splat(variant.sky());
    scene.shade.ambient = variant.sky() * std::f32::consts::PI;
    if variant.black_mesh {
        scene.shade.mesh_color = Vec3::ZERO;
    }
    // The key light: the sun, from the upper left, behind the camera's shoulder. The
    // back light: from above and behind the hair, toward the camera (the light the
    // fibres carry forward, the TT lobe, rims the hair).
    let toward_camera = (scene.camera.eye - scene.camera.target).normalize_or_zero();
    scene.lights = vec![
        Light::Directional(DirectionalLight {
            direction: Vec3::new(-0.7, -0.6, -0.4).normalize(),
            color: Vec3::ONE,
            intensity: 2.5,
        }),
        Light::Directional(DirectionalLight {
            direction: (toward_camera + Vec3::new(0.3, -0.6, 0.0)).normalize(),
            color: Vec3::ONE,
            intensity: BACK_LIGHT,
        }),
    ];
    if variant.no_back_light {
        scene.lights.truncate(1);
    }
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

/// What [`path_trace`] returns: the two reference seeds (16 bounces), then one image per
/// entry of [`BOUNCE_CAPS`], then the deep run ([`DEEP_BOUNCES`]).
struct Traced {
    reference: [PathTracedImage; 2],
    capped: Vec<PathTracedImage>,
    deep: PathTracedImage,
}

/// Path-traces the strands `renderer` drew for `scene`: twice (seeds 1 and 2) with 16
/// bounces, once per bounce cap of [`BOUNCE_CAPS`] and once with [`DEEP_BOUNCES`] (seed 1). The sky that lights the hair and the background camera rays see are both the
/// variant's sky ([`SKY`], or 0 with `--no-sky`).
fn path_trace(
    scene: &Scene,
    renderer: &Renderer,
    gpu: &Gpu,
    size: u32,
    spp: u32,
    variant: Variant,
) -> Result<Traced, Box<dyn std::error::Error>> {
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
                background: DVec3::splat(f64::from(variant.sky())),
                sky: DVec3::splat(f64::from(variant.sky())),
                ..Default::default()
            },
        )
    };
    // The caps share seed 1 with the first reference image: a path capped at K bounces is
    // the same path stopped early, so the bands between caps are differences of correlated
    // estimates (far less noisy than images of independent seeds).
    let mut capped = Vec::new();
    for &cap in &BOUNCE_CAPS {
        capped.push(render(1, cap)?);
    }
    Ok(Traced {
        reference: [render(1, REFERENCE_BOUNCES)?, render(2, REFERENCE_BOUNCES)?],
        capped,
        deep: render(1, DEEP_BOUNCES)?,
    })
}

/// The bounce orders `method_luma` carries, given the cumulative luminances `cumulative`
/// (`(cap, luminance of orders 1..cap)`, increasing caps, the reference's among them):
/// a line naming the largest `K` whose orders 1..K it reaches and what it lacks of each
/// band above.
fn orders_line(method_luma: f64, cumulative: &[(u32, f64)], reference: f64) -> String {
    let mut line = String::new();
    let mut lo = 1;
    let mut previous = 0.0;
    let mut reached = 0;
    for &(cap, luma) in cumulative {
        if method_luma >= luma {
            reached = cap;
        }
        let band = if lo == cap {
            format!("{cap}")
        } else {
            format!("{lo}-{cap}")
        };
        line.push_str(&format!(" {band}: {:.3}", (luma - previous) / reference));
        previous = luma;
        lo = cap + 1;
    }
    let below = cumulative
        .iter()
        .find(|(_, l)| *l > method_luma)
        .map(|(cap, l)| {
            format!(
                "; short of orders 1..{cap} by {:.3}",
                (l - method_luma) / reference
            )
        })
        .unwrap_or_default();
    let carries = if reached == 0 {
        "less than order 1 alone".to_string()
    } else {
        format!("orders 1..{reached}")
    };
    format!(
        "luminance {:.3} of the reference: carries {carries}{below} (orders' shares:{line})",
        method_luma / reference
    )
}

fn srgb_image(image: &PathTracedImage) -> Result<RgbaImage, Box<dyn std::error::Error>> {
    RgbaImage::from_raw(image.width, image.height, image.to_srgb8_rgba())
        .ok_or_else(|| "path-traced image has the wrong size".into())
}

/// The shadow methods whose fibre counts [`fibre_counts`] measures, at their defaults.
fn shadow_methods() -> [(&'static str, ShadowParams); 4] {
    [
        ("voxel", ShadowParams::Voxel(VoxelParams::default())),
        (
            "deep_opacity",
            ShadowParams::DeepOpacity(DeepOpacityParams::default()),
        ),
        (
            "shadow_map",
            ShadowParams::ShadowMap(ShadowMapParams::default()),
        ),
        ("adsm", ShadowParams::Adsm(AdsmParams::default())),
    ]
}

/// Whether the ray from `origin` along `dir` (unit) hits triangle `t` beyond a small offset
/// (Möller-Trumbore).
fn ray_hits_triangle(origin: Vec3, dir: Vec3, t: &[Vec3; 3]) -> bool {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return false;
    }
    let inv = 1.0 / det;
    let s = origin - t[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    e2.dot(q) * inv > 1e-4
}

/// Deepest optical depth read from a visibility (V = 1e-6).
const MAX_TAU: f64 = 13.8;

/// Calibration of dual scattering's fibre count: at every strand vertex of `groom` (opaque
/// fibres, the lab's sun), the optical depth `τ = -ln V` each shadow method hands the
/// shading stage (an opaque fibre counts 1 in every method's convention, so `τ` is the
/// fibre count the model uses) against the number of fibres the path tracer's shadow ray
/// from that vertex toward the light crosses (ray against the real cylinders, the vertex's
/// own strand excluded). Adds one row per method to `table` and returns the printed lines.
fn fibre_counts(
    groom: &str,
    quick: bool,
    size: u32,
    table: &mut Table,
) -> Result<String, Box<dyn std::error::Error>> {
    let mut text = String::new();
    let mut truth: Option<Vec<(usize, f64)>> = None;
    for (method, shadow) in shadow_methods() {
        let mut s = scene(groom, 1.3, 0.0, quick, METHODS[0].1, Variant::default())?;
        s.shadow = shadow;
        let gpu = Gpu::headless()?;
        let mut renderer = Renderer::new(&gpu, &s, size, size)?;
        renderer.render(&gpu, 0.0, &s.camera)?;
        let visibility = renderer
            .light_visibility(&gpu)?
            .into_iter()
            .next()
            .ok_or("the lab's scene has no shadows")?;
        if truth.is_none() {
            let traced = TracedScene::from_renderer(&s, &renderer, &gpu)?;
            let to_light = match s.lights.first() {
                Some(Light::Directional(d)) => d.to_light()?,
                _ => return Err("the lab's key light is directional".into()),
            };
            let strands = renderer.frame().strands();
            let per = (strands.buffers().segments + 1) as usize;
            let bytes = read_buffer(&gpu, &strands.buffers().vertices)?;
            let floats: &[f32] =
                bytemuck::try_cast_slice(&bytes).map_err(|e| format!("strand vertices: {e:?}"))?;
            let bvh = SegmentBvh::build(traced.segments.clone());
            let triangles: Vec<[Vec3; 3]> = traced
                .mesh_triangles
                .iter()
                .filter_map(|t| {
                    let p = |k: u32| traced.mesh_positions.get(k as usize).copied();
                    Some([p(t[0])?, p(t[1])?, p(t[2])?])
                })
                .collect();
            // Every `step`-th vertex (at most ~8 000), those the mesh does not shadow: the
            // shadow methods' visibility includes the mesh, the crossings count fibres.
            let step = (visibility.len() / 8_000).max(1);
            truth = Some(
                floats
                    .chunks_exact(4)
                    .take(visibility.len())
                    .enumerate()
                    .step_by(step)
                    .filter_map(|(i, v)| {
                        let p = Vec3::new(v[0], v[1], v[2]);
                        if triangles.iter().any(|t| ray_hits_triangle(p, to_light, t)) {
                            return None;
                        }
                        let own = Some((i / per) as u32);
                        Some((i, f64::from(bvh.hit_count(p, to_light, f32::INFINITY, own))))
                    })
                    .collect(),
            );
        }
        let (counts, taus): (Vec<f64>, Vec<f64>) = truth
            .as_deref()
            .unwrap_or_default()
            .iter()
            .filter_map(|&(i, count)| {
                let v = f64::from(*visibility.get(i)?);
                Some((count, (-v.max((-MAX_TAU).exp()).ln()).min(MAX_TAU)))
            })
            .unzip();
        let counts = &counts[..];
        let n = taus.len().min(counts.len()).max(1) as f64;
        let mean_tau = taus.iter().sum::<f64>() / n;
        let mean_count = counts.iter().sum::<f64>() / n;
        let diffs: Vec<f64> = taus.iter().zip(counts).map(|(t, c)| t - c).collect();
        let mean_diff = diffs.iter().sum::<f64>() / n;
        let spread = (diffs.iter().map(|d| (d - mean_diff).powi(2)).sum::<f64>() / n).sqrt();
        let (st, sc) = (
            (taus.iter().map(|t| (t - mean_tau).powi(2)).sum::<f64>() / n).sqrt(),
            (counts.iter().map(|c| (c - mean_count).powi(2)).sum::<f64>() / n).sqrt(),
        );
        let correlation = taus
            .iter()
            .zip(counts)
            .map(|(t, c)| (t - mean_tau) * (c - mean_count))
            .sum::<f64>()
            / n
            / (st * sc).max(1e-12);
        // The least-squares scale that maps the method's tau to the crossings.
        let scale = taus.iter().zip(counts).map(|(t, c)| t * c).sum::<f64>()
            / taus.iter().map(|t| t * t).sum::<f64>().max(1e-12);
        table.push(vec![
            groom.into(),
            method.into(),
            format!("{n:.0}"),
            format!("{mean_count:.3}"),
            format!("{mean_tau:.3}"),
            format!("{:.3}", mean_tau / mean_count.max(1e-12)),
            format!("{spread:.3}"),
            format!("{correlation:.3}"),
            format!("{scale:.3}"),
        ])?;
        text.push_str(&format!(
            "{groom:<9} {method:<12} fibres crossed {mean_count:.2}, tau {mean_tau:.2} (x{:.2}), spread of tau - fibres {spread:.2}, correlation {correlation:.2}, best scale {scale:.2}\n",
            mean_tau / mean_count.max(1e-12)
        ));
    }
    Ok(text)
}

/// Runs the lab (see the module docs); `spp` overrides the path tracer's samples per pixel;
/// `variant` takes the skin's bounce or the sky out of both renderers.
pub fn run(
    opts: &LabOpts,
    spp: Option<u32>,
    variant: Variant,
) -> Result<(), Box<dyn std::error::Error>> {
    let started = Instant::now();
    let quick = opts.quick;
    let size = if quick { 64 } else { 256 };
    let spp = spp.unwrap_or(if quick { 16 } else { 64 });
    let frames = if quick { 2 } else { 5 };
    let grooms: &[&str] = if quick {
        &["fur", "curly"]
    } else {
        &["fur", "long_hair", "curly"]
    };
    let hair: &[(&str, f32, f32)] = if quick { &HAIR[1..3] } else { &HAIR };
    pelage_lab::create_dir(&opts.out.join("scattering"))?;
    println!("adapter: {}", Gpu::headless()?.describe());
    // Caps of the cumulative luminances: BOUNCE_CAPS, the reference's, the deep run's.
    let caps: Vec<u32> = BOUNCE_CAPS
        .iter()
        .copied()
        .chain([REFERENCE_BOUNCES, DEEP_BOUNCES])
        .collect();
    let mut header = vec![
        "groom",
        "hair",
        "method",
        "mean_flip",
        "hair_flip",
        "hair_luminance_ratio",
        "shade_ms",
        "reference_spp",
        "noise_mean_flip",
        "noise_hair_flip",
        "reference_s",
    ];
    let lum_columns: Vec<String> = caps.iter().map(|c| format!("lum_vs_le_{c}")).collect();
    header.extend(lum_columns.iter().map(String::as_str));
    let mut table = Table::new(&header);
    let mut points = Vec::new();
    let mut cells = Vec::new();
    let mut orders_text = String::new();
    // The fibre counts first: the shadow methods' optical depth against the crossings.
    let mut counts = Table::new(&[
        "groom",
        "shadow",
        "vertices",
        "mean_fibres_crossed",
        "mean_tau",
        "tau_over_fibres",
        "spread_tau_minus_fibres",
        "correlation",
        "best_scale",
    ]);
    let mut counts_text = String::new();
    for &groom in grooms {
        counts_text.push_str(&fibre_counts(groom, quick, size, &mut counts)?);
    }
    counts.write_csv(&opts.out.join("scattering_fibre_counts.csv"))?;
    println!("fibre counts (dual scattering's n) against the path tracer's shadow rays:");
    print!("{counts_text}");
    let bar = progress::bar((grooms.len() * hair.len()) as u64, "scenes")?;
    for &groom in grooms {
        for &(name, eu, pheo) in hair {
            bar.set_message(format!("{groom} {name}"));
            let mut rendered = Vec::new();
            let mut first = None;
            for (method, apply) in METHODS {
                let s = scene(groom, eu, pheo, quick, apply, variant)?;
                let (image, ms, renderer, gpu) = render_pelage(&s, size, frames)?;
                if first.is_none() {
                    first = Some((s, renderer, gpu));
                }
                rendered.push((method, image, ms));
            }
            let (first_scene, renderer, gpu) = first.ok_or("no methods")?;
            let traced = Instant::now();
            let t = path_trace(&first_scene, &renderer, &gpu, size, spp, variant)?;
            let reference_s = traced.elapsed().as_secs_f64() / (3 + BOUNCE_CAPS.len()) as f64;
            let [a, b] = &t.reference;
            let stem = format!("{groom}_{name}");
            let mut written: Vec<(&PathTracedImage, String)> =
                vec![(a, "seed1".into()), (b, "seed2".into())];
            for (img, cap) in t.capped.iter().zip(BOUNCE_CAPS) {
                written.push((img, format!("le_{cap}_bounces")));
            }
            written.push((&t.deep, format!("le_{DEEP_BOUNCES}_bounces")));
            for (img, what) in &written {
                let dir = opts.out.join("scattering");
                img.write_hdr(&dir.join(format!("{stem}_{what}.hdr")))?;
                img.write_png(&dir.join(format!("{stem}_{what}.png")))?;
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
            // Hair luminance of orders 1..cap for every cap, all of seed 1 (see path_trace).
            let mut cumulative = Vec::new();
            for (img, cap) in t.capped.iter().zip(BOUNCE_CAPS) {
                cumulative.push((cap, img.to_linear_image()?));
            }
            cumulative.push((REFERENCE_BOUNCES, la.clone()));
            cumulative.push((DEEP_BOUNCES, t.deep.to_linear_image()?));
            let seed1_luma = hair_luminance(&la, &mask);
            let common = |row: &mut Vec<String>| {
                row.extend([
                    (2 * spp).to_string(),
                    format!("{noise_mean:.4}"),
                    format!("{noise_hair:.4}"),
                    format!("{reference_s:.1}"),
                ]);
            };
            let mut lumas = Vec::new();
            for (cap, image) in &cumulative {
                let luma = hair_luminance(image, &mask);
                lumas.push((*cap, luma));
                if *cap == REFERENCE_BOUNCES {
                    continue;
                }
                // How far the orders 1..cap are from the whole: what a method that carries
                // only those orders misses.
                let map = flip(&reference, image, DEFAULT_PIXELS_PER_DEGREE)?;
                let mut row = vec![
                    groom.into(),
                    name.into(),
                    format!("path_tracer_le_{cap}"),
                    format!("{:.4}", map.mean()),
                    format!("{:.4}", masked_mean(&map, &mask)),
                    format!("{:.3}", luma / seed1_luma),
                    String::new(),
                ];
                common(&mut row);
                row.extend(caps.iter().map(|_| String::new()));
                table.push(row)?;
            }
            let mut flips = Vec::new();
            for (method, image, ms) in &rendered {
                let test = LinearImage::from_srgb8_rgba(size, size, image.as_raw())?;
                let map = flip(&reference, &test, DEFAULT_PIXELS_PER_DEGREE)?;
                let hair_flip = masked_mean(&map, &mask);
                let luma = hair_luminance(&test, &mask);
                let ratio = luma / ref_luma;
                let mut row = vec![
                    groom.into(),
                    name.into(),
                    (*method).into(),
                    format!("{:.4}", map.mean()),
                    format!("{hair_flip:.4}"),
                    format!("{ratio:.3}"),
                    format!("{ms:.2}"),
                ];
                common(&mut row);
                row.extend(lumas.iter().map(|(_, l)| format!("{:.3}", luma / l)));
                table.push(row)?;
                points.push(ScatterPoint {
                    series: format!("{method} scattering"),
                    label: format!("{groom} {name}"),
                    x: *ms,
                    y: hair_flip,
                    size: None,
                });
                bar.println(format!(
                    "{groom:<9} {name:<6} {method:<6} FLIP {:.4} (hair {hair_flip:.4}, noise {noise_hair:.4})  luminance x{ratio:.3}  shade {ms:.1} ms",
                    map.mean()
                ));
                orders_text.push_str(&format!(
                    "{groom:<9} {name:<6} {method:<6} {}\n",
                    orders_line(luma, &lumas, seed1_luma)
                ));
                flips.push((*method, map));
            }
            let label = |what: &str| format!("{groom} {name}: {what}");
            cells.push((
                label(&format!("path tracer {} spp", 2 * spp)),
                srgb_image(&mean)?,
            ));
            for (method, image, _) in rendered {
                cells.push((label(method), image));
            }
            if let Some((method, map)) = flips.last() {
                cells.push((label(&format!("FLIP of {method}")), heat(map)?));
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
    let sheet = contact_sheet(&cells, METHODS.len() as u32 + 2)?;
    crate::output::save_png(&sheet, &opts.out.join("scattering_sheet.png"))?;
    println!("{}", table.to_text());
    println!("where the light comes from (hair luminance over the reference's, by bounce order):");
    print!("{orders_text}");
    println!(
        "wrote {}/scattering.csv, scattering.png|svg, scattering_sheet.png in {:.0} s",
        opts.out.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
