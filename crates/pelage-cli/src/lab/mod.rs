//! `pelage lab`: the experiments that chart every method's speed against its accuracy.
//!
//! One module per lab, each with `pub fn run(&LabOpts)`. A new lab is a module here,
//! a variant of [`Lab`] and its arm in [`Lab::run`].

use std::path::PathBuf;

use pelage::scene::Scene;
use pelage_reference::flip::{DEFAULT_PIXELS_PER_DEGREE, LinearImage, flip};
use pelage_reference::oit::linear_to_srgb8;

pub mod dynamics;
pub mod lod;
pub mod oit;
pub mod scattering;
pub mod shading;
pub mod shadows;

/// The options every lab (and `pelage bench`) takes.
#[derive(Clone, Debug, clap::Args)]
pub struct LabOpts {
    /// Small scenes and few configurations: a smoke run of every method in about a
    /// minute (what CI runs).
    #[arg(long)]
    pub quick: bool,
    /// Output folder for the CSV tables, charts and images; created if missing.
    #[arg(long, value_name = "DIR", default_value = "out/lab")]
    pub out: PathBuf,
}

/// The labs.
#[derive(Clone, Debug, clap::Subcommand)]
pub enum Lab {
    /// Every shadow method, resolution and PCF kernel against ray-traced transmittance.
    #[command(
        long_about = "Every shadow method (voxel, deep opacity maps, shadow map + PCF, ADSM) at \
                      several resolutions and PCF kernels, on three grooms (dense fur, long hair, \
                      curly hair). Times each run's shadow stage with timestamp queries (median of \
                      20 frames after 3 of warm-up, a fresh device per run), measures its memory, \
                      and compares its transmittance at every strand vertex with transmittance \
                      ray-traced through the real strands (RMSE, 95th percentile).\n\n\
                      Writes DIR/shadows.csv and DIR/shadows_<groom>.png|svg (error against GPU \
                      time, Pareto front marked), prints the table and the best method for each \
                      time budget. About 3 minutes on 2 CPU cores with lavapipe; --quick: under 1."
    )]
    Shadows(LabOpts),
    /// Every transparency method against the exact sorted composite.
    #[command(
        long_about = "Every order-independent transparency method and parameter (opaque, WBOIT, \
                      k-buffer, A-buffer, DBK, random subsets) on three scenes at hair opacities \
                      0.3 and 0.8, 320x240. Each image is compared with the exact composite (every \
                      fragment captured, sorted and blended on the CPU) by LDR-FLIP and linear \
                      RMSE; flicker is measured while the camera turns.\n\n\
                      Writes DIR/oit.csv, DIR/oit_<scene>_<opacity>.png|svg (mean FLIP against GPU \
                      time), DIR/oit_memory.csv (every method at 656x861 and 1920x1080) and the \
                      creature's images DIR/oit_<method>.png. About 3 minutes on 2 CPU cores; \
                      --quick: one small scene, a few configurations."
    )]
    Oit(LabOpts),
    /// The shading models side by side and their cost per shaded fragment.
    #[command(
        long_about = "Kajiya-Kay (plain and with shifted highlights), Marschner (analytic, for \
                      blonde, brown and black hair, and from its lookup tables) and Sadeghi on \
                      long hair under a key and a back light.\n\n\
                      Writes DIR/shading_sheet.png (a contact sheet of the models) and \
                      DIR/shading.csv (stage 3 wall clock, hair fragments shaded, nanoseconds per \
                      fragment and the extra over Kajiya-Kay). About 30 s on 2 CPU cores; --quick: \
                      smaller images, fewer frames."
    )]
    Shading(LabOpts),
    /// Level of detail at shrinking screen coverage, and the auto quality mode's picks.
    #[command(
        long_about = "Stochastic simplification (seed 002: lambda from the hair's screen \
                      coverage, B0 and h, widened strands, a transition zone) and segment \
                      reduction on the built-in creature, with its bounding box covering 60% down \
                      to 2% of a 480x360 screen. Every LOD setting's frame time (wall clock of \
                      submit and wait, median of 7 frames) is set against the full-detail frame, \
                      its image against the full-detail image (mean FLIP over the image and over \
                      the creature).\n\n\
                      Writes DIR/lod.csv, DIR/lod.png|svg, DIR/lod_auto.csv (the auto mode: per \
                      coverage the cheapest LOD setting within a FLIP budget of 0.05, the shadow \
                      resolution and k-buffer depth derived from the hair's size on screen and its \
                      depth complexity, and the cheapest shadow and transparency methods within \
                      budget from DIR/shadows.csv and DIR/oit.csv when the other labs wrote them) \
                      and DIR/lod_auto.png. About 4 minutes on 2 CPU cores; --quick: 10% only."
    )]
    Lod(LabOpts),
    /// Chiang fibres, single and dual scattering, against a path tracer.
    #[command(
        long_about = "Black, brown, blond and red hair as fur on the creature, long hair \
                      from a groom file (scenes/long_hair.hair) and a dense curly groom on a head, \
                      256x256, lit by a sun and a sky: pelage's Chiang model with dual scattering \
                      off and on (k-buffer k = 8, voxel shadows) against an independent path \
                      tracer of the same strands (real cylinders, Chiang's BSDF at the true fibre \
                      offset, 16 bounces, the mesh a diffuse occluder), the mean of two seeds; \
                      their difference is the reference's noise floor. The path tracer is also \
                      run capped at 1, 2, 4, 8 and 64 bounces: the table splits the hair's light \
                      by bounce order and says which orders each method carries.\n\n\
                      Writes DIR/scattering.csv (mean FLIP over the image and over the hair, the \
                      hair's luminance against the reference's and against orders 1..K, the shade \
                      stage's wall clock, the noise floor), DIR/scattering_field.csv (the volume \
                      grid's light at the visible fibres and the fibres' reading of it against the \
                      path tracer's), DIR/scattering_fibre_counts.csv, DIR/scattering.png|svg (FLIP \
                      against time), DIR/scattering_sheet.png (path tracer | single | dual | FLIP) and the \
                      path-traced images (HDR and PNG) in DIR/scattering/. Most of an hour on 2 \
                      CPU cores at 64 spp; --quick: 64x64, fur and the curly groom, brown and \
                      blond, 16 spp (under 2 minutes)."
    )]
    Scattering(ScatteringOpts),
    /// Simulated hair against the stateless wind while the head turns and nods, and
    /// simulated fur on a running, skinned creature.
    #[command(
        long_about = "Long hair grown on a head that turns and nods (scenes/head_turn.toml's \
                      motion, wind and dynamics), rendered twice from the same roots: stateless \
                      (GrowStrands: each frame grown for its time alone, so the hair turns \
                      rigidly with the head) and simulated (SimulateStrands: the hair lags, \
                      swings and settles). Every frame (30 per second for 4 s) compares the two \
                      images by LDR-FLIP (over the image and over the head and hair), with the \
                      same stateless hair from other random roots as the floor (what any change \
                      of strands shows), the strands' tips (distance between a strand's two \
                      tips as a fraction of its length) and how kinked each is (its largest turn \
                      between segments); each variant's frame wall clock and, at the end, its \
                      strand stage alone. --scene FILE compares a scene file's [dynamics] with \
                      its stateless wind instead (a groom has no floor of other roots). Without \
                      --scene a second row does the same for fur: scenes/creature_skinned.toml's \
                      creature (20 000 strands; its body bent and twisted by a two-joint rig, \
                      skinned on the GPU) with a [dynamics] table whose shape stiffnesses hold the groom.\n\n\
                      Writes DIR/dynamics.csv (a row per frame and scenario), \
                      DIR/dynamics_summary.csv (a column per scenario), DIR/dynamics_sheet.png \
                      and DIR/dynamics_sheet_fur.png (stateless over simulated at six times). \
                      A few minutes in a release build on 2 CPU cores; --quick: 1 s of frames, \
                      smaller."
    )]
    Dynamics(DynamicsOpts),
}

/// The options of `pelage lab dynamics`.
#[derive(Clone, Debug, clap::Args)]
pub struct DynamicsOpts {
    /// What every lab takes.
    #[command(flatten)]
    pub lab: LabOpts,
    /// A scene file with a `[dynamics]` table (e.g. scenes/head_turn.toml) instead of the
    /// built-in head; compared with the same scene without it.
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
}

/// The options of `pelage lab scattering`.
#[derive(Clone, Debug, clap::Args)]
pub struct ScatteringOpts {
    /// What every lab takes.
    #[command(flatten)]
    pub lab: LabOpts,
    /// Samples per pixel of each of the path tracer's two renders, in 1..=65536 (default
    /// 64; 16 with --quick). Each row's noise floor says whether it was enough.
    #[arg(
        long,
        value_name = "N",
        value_parser = crate::trace::spp_parser(),
        allow_hyphen_values = true
    )]
    pub spp: Option<u32>,
    /// Measure a cause apart: the mesh black in both renderers (no bounce off the skin;
    /// the body still occludes).
    #[arg(long)]
    pub black_mesh: bool,
    /// Measure a cause apart: no sky in both renderers (pelage's `ambient` and background
    /// 0, the path tracer's sky and background 0).
    #[arg(long)]
    pub no_sky: bool,
    /// The key light and the sky only, as the lab was before the back light (the tables
    /// of issue 36's causes were measured so).
    #[arg(long)]
    pub no_back_light: bool,
    /// Measure a cause apart: the back light and the sky only (the key light off in both
    /// renderers). With --no-back-light and --no-sky too it is an error (nothing lit).
    #[arg(long)]
    pub no_key_light: bool,
    /// The voxel shadow's lookup bias in voxels toward the light (`[shadow] bias_voxels`),
    /// in 0..=8, for the lab's scenes and its fibre counts (default: the scene's, 1.5).
    /// The shadow lab measures the shadows against ray tracing; this shows what the bias
    /// does to the shaded hair against the path tracer.
    #[arg(long, value_name = "VOXELS", value_parser = voxel_bias, allow_hyphen_values = true)]
    pub voxel_bias: Option<f32>,
    /// Side of the square images in pixels, in 16..=1024 (default 256; 64 with --quick).
    /// Strands are a fraction of a pixel wide at 64: the silhouettes' coverage then weighs
    /// in the luminance (see docs/src/path-tracer.md).
    #[arg(
        long,
        value_name = "N",
        value_parser = clap::value_parser!(u32).range(16..=1024),
        allow_hyphen_values = true
    )]
    pub size: Option<u32>,
    /// Only these grooms (comma-separated or repeated; default: the lab's own).
    #[arg(
        long = "groom",
        value_name = "NAME",
        value_delimiter = ',',
        value_parser = clap::builder::PossibleValuesParser::new(scattering::GROOMS)
    )]
    pub grooms: Vec<String>,
    /// Only these hair colours (comma-separated or repeated; default: the lab's own).
    #[arg(
        long,
        value_name = "NAME",
        value_delimiter = ',',
        value_parser = clap::builder::PossibleValuesParser::new(scattering::HAIR_NAMES)
    )]
    pub hair: Vec<String>,
}

impl Lab {
    /// Runs the chosen lab.
    pub fn run(&self) -> Result<(), Box<dyn std::error::Error>> {
        // The output folder first, so an unwritable one stops the lab before its work,
        // naming the folder.
        let out = match self {
            Lab::Shadows(o) | Lab::Oit(o) | Lab::Shading(o) | Lab::Lod(o) => &o.out,
            Lab::Dynamics(o) => &o.lab.out,
            Lab::Scattering(o) => &o.lab.out,
        };
        pelage_lab::create_dir(out)?;
        match self {
            Lab::Shadows(opts) => shadows::run(opts),
            Lab::Oit(opts) => oit::run(opts),
            Lab::Shading(opts) => shading::run(opts),
            Lab::Lod(opts) => lod::run(opts),
            Lab::Scattering(opts) => scattering::run(
                &opts.lab,
                opts.spp,
                opts.size,
                scattering::Variant {
                    black_mesh: opts.black_mesh,
                    no_sky: opts.no_sky,
                    no_back_light: opts.no_back_light,
                    no_key_light: opts.no_key_light,
                    voxel_bias: opts.voxel_bias,
                },
                &scattering::Rows {
                    grooms: opts.grooms.clone(),
                    hair: opts.hair.clone(),
                },
            ),
            Lab::Dynamics(opts) => dynamics::run(&opts.lab, opts.scene.as_deref()),
        }
    }
}

/// Mean FLIP over the whole image and over the pixels where either image is not the
/// background.
pub(crate) fn flip_scores(
    reference: &image::RgbaImage,
    test: &image::RgbaImage,
    background: [u8; 3],
) -> Result<(f64, f64), Box<dyn std::error::Error>> {
    let (w, h) = reference.dimensions();
    let a = LinearImage::from_srgb8_rgba(w, h, reference.as_raw())?;
    let b = LinearImage::from_srgb8_rgba(w, h, test.as_raw())?;
    let map = flip(&a, &b, DEFAULT_PIXELS_PER_DEGREE)?;
    let (mut sum, mut n) = (0.0f64, 0usize);
    for ((p, q), v) in reference.pixels().zip(test.pixels()).zip(&map.values) {
        let off = |px: &image::Rgba<u8>| {
            (0..3).any(|c| (i16::from(px.0[c]) - i16::from(background[c])).abs() > 1)
        };
        if off(p) || off(q) {
            sum += f64::from(*v);
            n += 1;
        }
    }
    Ok((map.mean(), if n > 0 { sum / n as f64 } else { 0.0 }))
}

/// The scene's background as the sRGB bytes an image of it holds.
pub(crate) fn background(scene: &Scene) -> [u8; 3] {
    let b = scene.shade.background;
    [
        linear_to_srgb8(b.x),
        linear_to_srgb8(b.y),
        linear_to_srgb8(b.z),
    ]
}

/// `--voxel-bias`: a finite number of voxels in 0..=`VoxelParams::MAX_BIAS_VOXELS`.
fn voxel_bias(text: &str) -> Result<f32, String> {
    let max = pelage::scene::VoxelParams::MAX_BIAS_VOXELS;
    let bias: f32 = text
        .parse()
        .map_err(|_| format!("{text:?} is not a number (a bias in voxels, 0 to {max})"))?;
    if (0.0..=max).contains(&bias) {
        Ok(bias)
    } else {
        Err(format!("{text} voxels is outside 0..={max}"))
    }
}
