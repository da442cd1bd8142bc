//! The scattering lab: pelage's Chiang fibres, single, dual and volume scattering, against an
//! independent path tracer (`pelage_reference::path_tracer`: the real strand cylinders,
//! Chiang's near-field BSDF at the true fibre offset, every bounce up to 16, the mesh as a
//! diffuse occluder) on the same strands, camera, lights (a key light, the sun over the
//! camera's shoulder, and a back light from above and behind the hair) and sky.
//!
//! ```text
//! pelage lab scattering [--quick] [--out DIR] [--spp N] [--groom NAMES] [--hair NAMES]
//! ```
//!
//! Black, brown, blond and red hair × fur on the creature, long hair from a groom file
//! (`scenes/long_hair.hair`) and a dense curly groom grown on a head, 256x256 (`--quick`:
//! 64x64, fur and the curly groom, brown and blond, 16 spp). The reference is the mean of
//! two path-traced images with different seeds (16 bounces); their own difference (FLIP of
//! one seed against the other) is the noise floor each row reports. pelage renders the
//! same scene with the k-buffer (k = 8) and the voxel shadow, once per row of [`METHODS`]
//! (the Chiang model with multiple scattering none, dual, volume and dual_volume).
//!
//! **Where the light comes from**: more path-traced images of seed 1 cap the bounces at 1,
//! 2, 4 and 8, and one at 64 shows how much 16 truncates (the same paths stopped earlier or
//! later, so the differences are not swamped by noise). Their hair luminance against seed
//! 1's at 16 bounces splits it by bounce order (1, 2, 3-4, 5-8, 9-16, 17-64): the
//! `path_tracer_le_K` rows, and per method the columns `lum_vs_le_K` (the method's hair
//! luminance over that of orders 1..K) and a printed line saying which orders it carries.
//!
//! **The light at the visible fibres**: camera rays followed to the first fibre they hit;
//! there the volume grid's light (its CPU mirror) against the path tracer's
//! ([`PathTracer::field_at`]), and the fibre's reading of each against the exact response
//! (`DIR/scattering_field.csv` and a printed line per scene).
//!
//! Writes `DIR/scattering.csv` (mean FLIP over the image and over the hair pixels, the
//! hair's luminance against the reference's, the shade stage's wall clock and the
//! reference's noise floor), `DIR/scattering.png|svg` (FLIP over the hair against time),
//! `DIR/scattering_sheet.png` (per scene: path tracer | single | dual | FLIP of dual) and
//! the path-traced images in `DIR/scattering/` (linear HDR and sRGB PNG) beside each
//! method's (sRGB PNG, `GROOM_HAIR_METHOD.png`) and the hair's share of each pixel
//! (`GROOM_HAIR_hair_mask.png`).

use std::time::Instant;

use glam::{DVec3, DVec4, Vec3, Vec4Swizzles};
use image::RgbaImage;
use pelage::gpu::Gpu;
use pelage::gpu::read_buffer;
use pelage::scene::{
    AdsmParams, Camera, ChiangParams, DeepOpacityParams, DirectionalLight, HairType, Light, Mesh,
    MultipleScattering, ShadingModel, ShadowMapParams, ShadowParams, Transparency, VoxelParams,
    WindParams, chiang_color_scale, sigma_a_from_melanin,
};
use pelage::{Renderer, scene::Scene};
use pelage_lab::{ScatterChart, ScatterPoint, Table, contact_sheet};
use pelage_reference::flip::{DEFAULT_PIXELS_PER_DEGREE, LinearImage, flip};
use pelage_reference::path_tracer::{
    FieldSample, PathTraceError, PathTracedImage, PathTracer, PathTracerSettings, Pcg32,
};
use pelage_reference::transmittance::SegmentBvh;
use pelage_reference::volume::{
    FibreResponse, VolumeGridCpu, VolumeInput, VolumeMesh, lattice_direction, volume_grid,
};
use rayon::prelude::*;

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
    /// No key light: the back light and the sky only.
    pub no_key_light: bool,
    /// The voxel shadow's lookup bias (`VoxelParams::bias_voxels`) in both the scenes
    /// and the fibre counts; `None`: the default.
    pub voxel_bias: Option<f32>,
}

impl Variant {
    /// The sky radiance of the lab's scenes under this variant.
    fn sky(self) -> f32 {
        if self.no_sky { 0.0 } else { SKY }
    }
}

/// Irradiance of the back light (the key light's is 2.5).
const BACK_LIGHT: f32 = 1.5;

/// The grooms of the full lab, in its order (`--quick` runs fur and curly).
pub const GROOMS: [&str; 3] = ["fur", "long_hair", "curly"];

/// The names of the hair colours (`--hair`), in [`HAIR`]'s order.
pub const HAIR_NAMES: [&str; 4] = [HAIR[0].0, HAIR[1].0, HAIR[2].0, HAIR[3].0];

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
const METHODS: [Method; 6] = [
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
    // Dual scattering for the lights, the grid for the sky and the body's bounce.
    ("dual_volume", |p| {
        p.multiple_scattering = MultipleScattering::DualVolume
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
    if let (Some(bias), ShadowParams::Voxel(v)) = (variant.voxel_bias, &mut scene.shadow) {
        v.bias_voxels = bias;
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
    if variant.no_key_light {
        // Off rather than removed: a frame needs a light (the sky alone, with
        // --no-back-light too, keeps one of no intensity).
        if let Some(Light::Directional(key)) = scene.lights.first_mut() {
            key.intensity = 0.0;
        }
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

/// Path-traces `scene` (the strands its renderer drew, in `tracer`): twice (seeds 1 and 2)
/// with 16 bounces, once per bounce cap of [`BOUNCE_CAPS`] and once with
/// [`DEEP_BOUNCES`] (seed 1). The sky that lights the hair and the background camera rays
/// see are both the variant's sky ([`SKY`], or 0 with `--no-sky`).
fn path_trace(
    scene: &Scene,
    tracer: &PathTracer,
    size: u32,
    spp: u32,
    variant: Variant,
) -> Result<Traced, Box<dyn std::error::Error>> {
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

/// The shadow methods whose fibre counts [`fibre_counts`] measures, at their defaults (the
/// voxel shadow's lookup bias `variant`'s when it sets one).
fn shadow_methods(variant: Variant) -> [(&'static str, ShadowParams); 4] {
    let voxel = VoxelParams::default();
    [
        (
            "voxel",
            ShadowParams::Voxel(VoxelParams {
                bias_voxels: variant.voxel_bias.unwrap_or(voxel.bias_voxels),
                ..voxel
            }),
        ),
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

/// The traced body's triangles by their corners (those whose indices are in range).
fn triangles_of(traced: &TracedScene) -> Vec<[Vec3; 3]> {
    traced
        .mesh_triangles
        .iter()
        .filter_map(|t| {
            let p = |k: u32| traced.mesh_positions.get(k as usize).copied();
            Some([p(t[0])?, p(t[1])?, p(t[2])?])
        })
        .collect()
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
/// own strand excluded), and the light that reaches the vertices: the method's mean
/// `exp(-τ)` against the share of those rays no fibre crosses. `variant`'s voxel bias
/// applies (its lighting does not: the key light alone counts). Adds one row per method to
/// `table` and returns the printed lines.
fn fibre_counts(
    groom: &str,
    quick: bool,
    size: u32,
    variant: Variant,
    table: &mut Table,
) -> Result<String, Box<dyn std::error::Error>> {
    let mut text = String::new();
    let mut truth: Option<Vec<(usize, f64)>> = None;
    for (method, shadow) in shadow_methods(variant) {
        let mut s = scene(groom, 1.3, 0.0, quick, METHODS[0].1, Variant::default())?;
        s.shadow = shadow;
        let gpu = Gpu::headless()?;
        let mut renderer = Renderer::new(&gpu, &s, size, size)?;
        renderer.render(&gpu, 0.0, &s.camera)?;
        let vertices = renderer
            .frame()
            .strands()
            .buffers()
            .full_layout()
            .vertices() as usize;
        let visibility = renderer
            .frame()
            .visibility()
            .ok_or("the lab's scene has no shadows")?
            .read(&gpu, 1, vertices)?
            .into_iter()
            .next()
            .ok_or("the lab's scene has no light")?;
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
            let triangles = triangles_of(&traced);
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
        // What the shading sees of it: the light reaching the vertices, the method's mean
        // exp(-tau) against the share of shadow rays no fibre crosses (opaque fibres: a ray
        // with a crossing is dark). The crossings are over-dispersed (strands lie in
        // clumps and sheets), so a tau short of the mean count can still light right.
        let lit = taus.iter().map(|t| (-t).exp()).sum::<f64>() / n;
        let open = counts.iter().filter(|&&c| c == 0.0).count() as f64 / n;
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
            format!("{open:.4}"),
            format!("{lit:.4}"),
        ])?;
        // Where every ray crosses a fibre there is no ratio to print.
        let lit_ratio = if open > 0.0 {
            format!("x{:.2}", lit / open)
        } else {
            "no ray open".to_string()
        };
        text.push_str(&format!(
            "{groom:<9} {method:<12} fibres crossed {mean_count:.2}, tau {mean_tau:.2} \
             (x{:.2}), spread of tau - fibres {spread:.2}, correlation {correlation:.2}, best \
             scale {scale:.2}; lit: open rays {open:.3}, exp(-tau) {lit:.3} ({lit_ratio})\n",
            mean_tau / mean_count.max(1e-12),
        ));
    }
    Ok(text)
}

/// Which of the lab's rows to run: the grooms and hair colours named (empty: the lab's
/// own, all four colours and three grooms, or `--quick`'s fur and curly, brown and blond).
#[derive(Clone, Debug, Default)]
pub struct Rows {
    /// Names from [`GROOMS`].
    pub grooms: Vec<String>,
    /// Names from [`HAIR_NAMES`].
    pub hair: Vec<String>,
}

/// Runs the lab (see the module docs); `spp` overrides the path tracer's samples per pixel,
/// `size` the images' side; `variant` takes the skin's bounce, the sky or a light out of
/// both renderers; `rows` picks the grooms and colours (the lab's own when empty).
pub fn run(
    opts: &LabOpts,
    spp: Option<u32>,
    size: Option<u32>,
    variant: Variant,
    rows: &Rows,
) -> Result<(), Box<dyn std::error::Error>> {
    if variant.no_key_light && variant.no_back_light && variant.no_sky {
        return Err(
            "--no-key-light with --no-back-light and --no-sky leaves the scenes \
                    unlit: keep at least one of the key light, the back light or the sky"
                .into(),
        );
    }
    let started = Instant::now();
    let quick = opts.quick;
    let size = size.unwrap_or(if quick { 64 } else { 256 });
    let spp = spp.unwrap_or(if quick { 16 } else { 64 });
    let frames = if quick { 2 } else { 5 };
    let grooms: Vec<&str> = if !rows.grooms.is_empty() {
        GROOMS
            .into_iter()
            .filter(|g| rows.grooms.iter().any(|r| r == g))
            .collect()
    } else if quick {
        vec![GROOMS[0], GROOMS[2]]
    } else {
        GROOMS.to_vec()
    };
    let hair: Vec<(&str, f32, f32)> = if !rows.hair.is_empty() {
        HAIR.into_iter()
            .filter(|h| rows.hair.iter().any(|r| r == h.0))
            .collect()
    } else if quick {
        HAIR[1..3].to_vec()
    } else {
        HAIR.to_vec()
    };
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
        "open_rays",
        "mean_exp_neg_tau",
    ]);
    let mut counts_text = String::new();
    for &groom in &grooms {
        counts_text.push_str(&fibre_counts(groom, quick, size, variant, &mut counts)?);
    }
    counts.write_csv(&opts.out.join("scattering_fibre_counts.csv"))?;
    println!("fibre counts (dual scattering's n) against the path tracer's shadow rays:");
    print!("{counts_text}");
    let mut fields = Table::new(&FieldStats::COLUMNS);
    let mut field_text = String::new();
    let bar = progress::bar((grooms.len() * hair.len()) as u64, "scenes")?;
    for &groom in &grooms {
        for &(name, eu, pheo) in &hair {
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
            let strands = TracedScene::from_renderer(&first_scene, &renderer, &gpu)?;
            let tracer = strands.tracer()?;
            let t = path_trace(&first_scene, &tracer, size, spp, variant)?;
            let reference_s = traced.elapsed().as_secs_f64() / (3 + BOUNCE_CAPS.len()) as f64;
            let [a, b] = &t.reference;
            let stem = format!("{groom}_{name}");
            let mut written: Vec<(&PathTracedImage, String)> =
                vec![(a, "seed1".into()), (b, "seed2".into())];
            for (img, cap) in t.capped.iter().zip(BOUNCE_CAPS) {
                written.push((img, format!("le_{cap}_bounces")));
            }
            written.push((&t.deep, format!("le_{DEEP_BOUNCES}_bounces")));
            let dir = opts.out.join("scattering");
            for (img, what) in &written {
                img.write_hdr(&dir.join(format!("{stem}_{what}.hdr")))?;
                img.write_png(&dir.join(format!("{stem}_{what}.png")))?;
            }
            for (method, image, _) in &rendered {
                crate::output::save_png(image, &dir.join(format!("{stem}_{method}.png")))?;
            }
            let mask: Vec<f32> = a
                .hair_mask
                .iter()
                .zip(&b.hair_mask)
                .map(|(x, y)| 0.5 * (x + y))
                .collect();
            // The hair's share of each pixel, as the path tracer saw it (the mask the
            // hair's figures average over).
            let mask_image = RgbaImage::from_fn(size, size, |x, y| {
                let v = mask[(y * size + x) as usize].clamp(0.0, 1.0);
                let g = (v * 255.0).round() as u8;
                image::Rgba([g, g, g, 255])
            });
            crate::output::save_png(&mask_image, &dir.join(format!("{stem}_hair_mask.png")))?;
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
            // The volume method's grid at the visible fibres against the path tracer's light
            // there (the default volume row's parameters).
            let (_, volume_method) = METHODS[METHODS.len() - 1];
            let volume_scene = scene(groom, eu, pheo, quick, volume_method, variant)?;
            let field = field_at_fibres(&volume_scene, &strands, &tracer, quick, variant)?;
            fields.push(field.row(groom, name))?;
            field_text.push_str(&format!("{groom:<9} {name:<6} {}\n", field.line()));
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
    fields.write_csv(&opts.out.join("scattering_field.csv"))?;
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
        "the volume grid's light at the visible fibres against the path tracer's (luminance \
         sums over the fibres; the response is the radiance the fibre sends to the camera):"
    );
    print!("{field_text}");
    println!(
        "wrote {}/scattering.csv, scattering_field.csv, scattering.png|svg, scattering_sheet.png in {:.0} s",
        opts.out.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Pixels per side of the grid of camera rays [`field_at_fibres`] follows to the fibres
/// (quick, full).
const FIELD_PIXELS: (u32, u32) = (32, 48);

/// Directions of the path tracer's light at each fibre (quick, full).
const FIELD_DIRECTIONS: (u32, u32) = (512, 1024);

/// The volume method's grid against the path tracer's light at the fibres the camera
/// sees: where its error comes from, the grid's light or the fibre's reading of it.
#[derive(Clone, Copy, Debug, Default)]
struct FieldStats {
    /// Fibres measured (camera rays whose first hit is hair).
    fibres: usize,
    /// Σ fluence of the grid over Σ the path tracer's (luminance).
    fluence_ratio: f64,
    /// Σ |Φ| over Σ φ (green), the path tracer's and the grid's: how directional the light is.
    flux_share_reference: f64,
    flux_share_grid: f64,
    /// The cosine between the two flux vectors (luminance), weighted by the path tracer's
    /// flux.
    flux_cosine: f64,
    /// Σ luminance of the exact response (orders >= 2 of the lights and all of the sky's
    /// at those fibres), per fibre.
    response: f64,
    /// The shading's reading applied to the path tracer's light, over the exact response.
    reading_ratio: f64,
    /// The shading's reading of the grid (what pelage draws), over the exact response.
    grid_ratio: f64,
    /// The difference between two independent halves of the path tracer's directions, of
    /// `fluence_ratio`, `reading_ratio` and `grid_ratio`: the reference's noise.
    noise: [f64; 3],
    /// The sky's unscattered light at the fibres, as the share of the sky each sees: the
    /// path traced strands' and body's (rays from the fibre's axis in [`SKY_RAYS`]
    /// directions that nothing stops) and the grid's (its sky fluence over the whole
    /// sky's). NaN without a sky (an empty cell in the CSV).
    sky_seen_reference: f64,
    sky_seen_grid: f64,
    /// Over the same rays that the body does not stop, the hair alone: the other fibres a
    /// traced ray crosses and the grid's optical depth along it from the fibre (its
    /// `depth`, marched cell by cell: what the grid's Poisson model expects to cross),
    /// means over the rays; and the share of those rays no fibre stops, traced, against
    /// the mean of `exp(-τ)` along them. NaN without a sky (an empty cell in the CSV).
    sky_rays: SkyRays,
}

/// [`FieldStats::sky_rays`].
#[derive(Clone, Copy, Debug)]
struct SkyRays {
    crossings: f64,
    grid_depth: f64,
    open_traced: f64,
    open_grid: f64,
}

/// None measured (no sky): NaN.
impl Default for SkyRays {
    fn default() -> Self {
        Self {
            crossings: f64::NAN,
            grid_depth: f64::NAN,
            open_traced: f64::NAN,
            open_grid: f64::NAN,
        }
    }
}

/// Directions of the rays [`FieldStats::sky_seen_reference`] follows from each fibre.
const SKY_RAYS: usize = 256;

impl FieldStats {
    const COLUMNS: [&'static str; 19] = [
        "groom",
        "hair",
        "fibres",
        "fluence_grid_over_reference",
        "flux_share_reference",
        "flux_share_grid",
        "flux_cosine",
        "response_reference",
        "reading_of_reference_over_reference",
        "reading_of_grid_over_reference",
        "noise_fluence",
        "noise_reading",
        "noise_grid",
        "sky_seen_reference",
        "sky_seen_grid",
        "sky_rays_crossings",
        "sky_rays_grid_depth",
        "sky_rays_open_traced",
        "sky_rays_open_grid",
    ];

    fn row(&self, groom: &str, hair: &str) -> Vec<String> {
        // The sky's figures: empty without a sky (as the CSV's other figures that do not
        // apply).
        let sky = |v: f64| {
            if v.is_nan() {
                String::new()
            } else {
                format!("{v:.3}")
            }
        };
        vec![
            groom.into(),
            hair.into(),
            self.fibres.to_string(),
            format!("{:.3}", self.fluence_ratio),
            format!("{:.3}", self.flux_share_reference),
            format!("{:.3}", self.flux_share_grid),
            format!("{:.3}", self.flux_cosine),
            format!("{:.5}", self.response),
            format!("{:.3}", self.reading_ratio),
            format!("{:.3}", self.grid_ratio),
            format!("{:.3}", self.noise[0]),
            format!("{:.3}", self.noise[1]),
            format!("{:.3}", self.noise[2]),
            sky(self.sky_seen_reference),
            sky(self.sky_seen_grid),
            sky(self.sky_rays.crossings),
            sky(self.sky_rays.grid_depth),
            sky(self.sky_rays.open_traced),
            sky(self.sky_rays.open_grid),
        ]
    }

    fn line(&self) -> String {
        // Without a sky (`--no-sky`) there is nothing to measure the sky figures on.
        let sky = if self.sky_seen_reference.is_nan() {
            "no sky, so no sky seen nor sky rays".to_string()
        } else {
            format!(
                "sky seen {:.3} (path traced), {:.3} (grid); sky rays the body does not \
                 stop: fibres crossed {:.2}, the grid's depth {:.2} (x{:.2}), open {:.3} \
                 (traced), {:.3} (exp(-depth))",
                self.sky_seen_reference,
                self.sky_seen_grid,
                self.sky_rays.crossings,
                self.sky_rays.grid_depth,
                self.sky_rays.grid_depth / self.sky_rays.crossings,
                self.sky_rays.open_traced,
                self.sky_rays.open_grid
            )
        };
        format!(
            "{} fibres: fluence x{:.2} (±{:.2}); |flux| / fluence {:.2} (path tracer {:.2}), \
             cos {:.2}; response x{:.2} (±{:.2}) read from the path tracer's light, x{:.2} \
             (±{:.2}) from the grid's; {sky}",
            self.fibres,
            self.fluence_ratio,
            self.noise[0],
            self.flux_share_grid,
            self.flux_share_reference,
            self.flux_cosine,
            self.reading_ratio,
            self.noise[1],
            self.grid_ratio,
            self.noise[2],
        )
    }
}

/// Follows a grid of camera rays of `scene` (shaded by the volume method) to the fibres
/// they hit first, and there compares the light of the volume grid (its CPU mirror,
/// `pelage_reference::volume`, on the strands and posed mesh the renderer drew) with the
/// path tracer's ([`PathTracer::field_at`]: the light that scattered at least once or comes
/// from the sky, as the grid holds it), and the fibre's response to each as the shading
/// reads it (`FibreResponse`) with the exact response.
fn field_at_fibres(
    scene: &Scene,
    strands: &TracedScene,
    tracer: &PathTracer,
    quick: bool,
    variant: Variant,
) -> Result<FieldStats, Box<dyn std::error::Error>> {
    let ShadingModel::Chiang(params) = &scene.shade.model else {
        return Err("the scattering lab's scenes use the Chiang model".into());
    };
    let grid = volume_grid(&VolumeInput {
        vertices: &strands.vertices,
        segments: strands.segments_per_strand,
        widths: &strands.widths,
        colors: &strands.colors,
        tip_width: strands.tip_width,
        lights: &scene.lights,
        ambient: scene.shade.ambient,
        params,
        mesh: (!strands.mesh_triangles.is_empty()).then(|| VolumeMesh {
            positions: &strands.mesh_positions,
            normals: &strands.mesh_normals,
            indices: bytemuck::cast_slice(&strands.mesh_triangles),
            color: scene.shade.mesh_color,
        }),
    });
    // Every strand has the lab's one colour: one response.
    let reading = FibreResponse::new(&strands.fibre);
    let (k, directions) = if quick {
        (FIELD_PIXELS.0, FIELD_DIRECTIONS.0)
    } else {
        (FIELD_PIXELS.1, FIELD_DIRECTIONS.1)
    };
    let settings = PathTracerSettings {
        // The fibre is the path's first vertex.
        max_bounces: REFERENCE_BOUNCES - 1,
        sky: DVec3::splat(f64::from(variant.sky())),
        ..Default::default()
    };
    let inv = scene.camera.view_projection(1.0).as_dmat4().inverse();
    // Two independent estimates per fibre (seeds 3 and 4, half the directions each): their
    // difference is the reference's own noise.
    let samples: Vec<Option<[FieldSample; 2]>> = (0..k * k)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % k, i / k);
            let nx = 2.0 * (f64::from(x) + 0.5) / f64::from(k) - 1.0;
            let ny = 1.0 - 2.0 * (f64::from(y) + 0.5) / f64::from(k);
            let near = inv * DVec4::new(nx, ny, 0.0, 1.0);
            let far = inv * DVec4::new(nx, ny, 1.0, 1.0);
            let near = near.truncate() / near.w;
            let d = (far.truncate() / far.w - near).normalize_or_zero();
            let mut a = Pcg32::new(3, u64::from(i));
            let mut b = Pcg32::new(4, u64::from(i));
            let half = (directions / 2).max(1);
            Ok(
                match (
                    tracer.field_at(near, d, half, &settings, &mut a)?,
                    tracer.field_at(near, d, half, &settings, &mut b)?,
                ) {
                    (Some(a), Some(b)) => Some([a, b]),
                    _ => None,
                },
            )
        })
        .collect::<Result<_, PathTraceError>>()?;
    let samples: Vec<[FieldSample; 2]> = samples.into_iter().flatten().collect();
    let mean = |[a, b]: &[FieldSample; 2]| FieldSample {
        fluence: 0.5 * (a.fluence + b.fluence),
        flux: [0, 1, 2].map(|c| 0.5 * (a.flux[c] + b.flux[c])),
        response: 0.5 * (a.response + b.response),
        ..*a
    };
    let both: Vec<FieldSample> = samples.iter().map(mean).collect();
    let first: Vec<FieldSample> = samples.iter().map(|s| s[0]).collect();
    let second: Vec<FieldSample> = samples.iter().map(|s| s[1]).collect();
    let mut stats = field_stats(&both, &grid, &reading);
    let (a, b) = (
        field_stats(&first, &grid, &reading),
        field_stats(&second, &grid, &reading),
    );
    stats.noise = [
        (a.fluence_ratio - b.fluence_ratio).abs(),
        (a.reading_ratio - b.reading_ratio).abs(),
        (a.grid_ratio - b.grid_ratio).abs(),
    ];
    (
        stats.sky_seen_reference,
        stats.sky_seen_grid,
        stats.sky_rays,
    ) = if variant.no_sky {
        (f64::NAN, f64::NAN, SkyRays::default())
    } else {
        sky_seen(&both, strands, &grid, f64::from(scene.shade.ambient))
    };
    Ok(stats)
}

/// The mean share of the sky the fibres at `samples` see unscattered: through the traced
/// strands and body (rays from each fibre's axis, which its own cylinder does not stop,
/// in [`SKY_RAYS`] directions of a Fibonacci lattice turned per fibre) and as `grid`
/// holds it (its sky fluence there over the unoccluded sky's, `4 ambient`); and, over
/// the rays the body does not stop, the fibres they cross against the grid's depth along
/// them ([`FieldStats::sky_rays`]).
fn sky_seen(
    samples: &[FieldSample],
    strands: &TracedScene,
    grid: &VolumeGridCpu,
    ambient: f64,
) -> (f64, f64, SkyRays) {
    let bvh = SegmentBvh::build(strands.segments.clone());
    let triangles = triangles_of(strands);
    // Per fibre: the share open, the grid's share; over the rays the body does not stop,
    // their count, crossings, depths, rays open and exp(-depth).
    let seen: Vec<(f64, f64, [f64; 5])> = samples
        .par_iter()
        .enumerate()
        .map(|(i, s)| {
            let turn = std::f64::consts::TAU * (i as f64 * 0.618_033_988_749_894_9).fract();
            let (mut open, mut hair) = (0usize, [0.0; 5]);
            for k in 0..SKY_RAYS {
                let d = lattice_direction(k, SKY_RAYS, turn);
                let body = triangles
                    .iter()
                    .any(|t| ray_hits_triangle(s.point.as_vec3(), d.as_vec3(), t));
                open += usize::from(!body && !bvh.occluded(s.point, d, f64::INFINITY, None));
                if !body {
                    let crossed = bvh.crossings(s.point.as_vec3(), d.as_vec3(), f32::INFINITY);
                    let depth = grid.optical_depth_toward(s.point, d);
                    hair[0] += 1.0;
                    hair[1] += f64::from(crossed);
                    hair[2] += depth;
                    hair[3] += f64::from(u8::from(crossed == 0));
                    hair[4] += (-depth).exp();
                }
            }
            (
                open as f64 / SKY_RAYS as f64,
                grid.sample_sky(s.point).x / (4.0 * ambient),
                hair,
            )
        })
        .collect();
    let n = seen.len().max(1) as f64;
    let hair = seen.iter().fold([0.0; 5], |mut sum, s| {
        sum.iter_mut().zip(s.2).for_each(|(a, b)| *a += b);
        sum
    });
    let rays = hair[0].max(1.0);
    (
        seen.iter().map(|s| s.0).sum::<f64>() / n,
        seen.iter().map(|s| s.1).sum::<f64>() / n,
        SkyRays {
            crossings: hair[1] / rays,
            grid_depth: hair[2] / rays,
            open_traced: hair[3] / rays,
            open_grid: hair[4] / rays,
        },
    )
}

/// [`FieldStats`] of the path tracer's `samples` against `grid` read by `reading`.
fn field_stats(
    samples: &[FieldSample],
    grid: &VolumeGridCpu,
    reading: &FibreResponse,
) -> FieldStats {
    let lum = |c: DVec3| c.dot(DVec3::new(0.2126, 0.7152, 0.0722));
    let luma_flux = |f: [DVec3; 3]| 0.2126 * f[0] + 0.7152 * f[1] + 0.0722 * f[2];
    let mut stats = FieldStats::default();
    let (mut phi_ref, mut phi_grid) = (0.0, 0.0);
    let (mut flux_ref, mut flux_grid, mut green_ref, mut green_grid) = (0.0, 0.0, 0.0, 0.0);
    let (mut cos_sum, mut cos_weight) = (0.0, 0.0);
    let (mut exact, mut of_reference, mut of_grid) = (0.0, 0.0, 0.0);
    for sample in samples {
        stats.fibres += 1;
        let cell = grid.sample(sample.point);
        let reference = [0, 1, 2].map(|c| {
            let f = sample.flux[c];
            DVec4::new(sample.fluence[c], f.x, f.y, f.z)
        });
        phi_ref += lum(sample.fluence);
        phi_grid += lum(DVec3::new(cell[0].x, cell[1].x, cell[2].x));
        green_ref += sample.fluence.y;
        green_grid += cell[1].x;
        flux_ref += sample.flux[1].length();
        flux_grid += cell[1].yzw().length();
        let a = luma_flux(sample.flux);
        let b = luma_flux([cell[0].yzw(), cell[1].yzw(), cell[2].yzw()]);
        if a.length() > 0.0 && b.length() > 0.0 {
            cos_sum += a.normalize().dot(b.normalize()) * a.length();
            cos_weight += a.length();
        }
        exact += lum(sample.response);
        of_reference += lum(reading.radiance(sample.tangent, sample.view, &reference));
        of_grid += lum(reading.radiance(sample.tangent, sample.view, &cell));
    }
    let ratio = |a: f64, b: f64| if b > 0.0 { a / b } else { f64::NAN };
    stats.fluence_ratio = ratio(phi_grid, phi_ref);
    stats.flux_share_reference = ratio(flux_ref, green_ref);
    stats.flux_share_grid = ratio(flux_grid, green_grid);
    stats.flux_cosine = ratio(cos_sum, cos_weight);
    stats.response = ratio(exact, stats.fibres as f64);
    stats.reading_ratio = ratio(of_reference, exact);
    stats.grid_ratio = ratio(of_grid, exact);
    stats
}
