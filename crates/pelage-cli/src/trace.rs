//! `pelage trace`: the path tracer's image of a scene file, the ground truth `pelage
//! render` is compared with (`pelage compare`).
//!
//! The scene is loaded as `render` loads it ([`SceneOpts::scene`]), its strands grown on
//! the GPU for `--time` and read back ([`TracedScene::from_renderer`]), then path traced
//! on the CPU with the scene's camera, lights and mesh: `shade.background` is what camera
//! rays that miss see and `shade.ambient / π` the sky that lights, as the renderer means
//! them.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::DVec3;
use pelage::Renderer;
use pelage::gpu::Gpu;
use pelage::scene::{ShadowParams, Transparency};

use crate::output::{save_png, write_atomically};
use pelage_reference::path_tracer::{
    MAX_BOUNCES_LIMIT, MAX_IMAGE_SIDE, MAX_SPP, PathTracedImage, PathTracerSettings,
};

use crate::error::CliError;
use crate::path_trace::{TraceError, TracedScene};
use crate::progress;
use crate::scene_opts::SceneOpts;

/// clap's parser of a samples-per-pixel count: 1..=[`MAX_SPP`]. Parsed as an `i64` first,
/// so a negative count is reported against the range too.
pub fn spp_parser() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..=i64::from(MAX_SPP))
}

/// clap's parser of a bounce count: 1..=[`MAX_BOUNCES_LIMIT`] (negative ones as above).
fn bounces_parser() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..=i64::from(MAX_BOUNCES_LIMIT))
}

/// Options of `pelage trace`.
#[derive(Clone, Debug, clap::Args)]
pub struct TraceOpts {
    /// The scene and its overrides, as `pelage render` takes them.
    #[command(flatten)]
    pub scene: SceneOpts,
    /// Samples (paths) per pixel, in 1..=65536. The noise falls as 1/sqrt(N).
    #[arg(long, value_name = "N", default_value_t = 64, value_parser = spp_parser(),
        allow_hyphen_values = true)]
    pub spp: u32,
    /// Most scattering events per path, in 1..=1024; 1 is direct light only (lights and
    /// sky seen after one scattering).
    #[arg(long, value_name = "N", default_value_t = 16, value_parser = bounces_parser(),
        allow_hyphen_values = true)]
    pub bounces: u32,
    /// Seed of the random numbers: a seed gives the same image on any number of threads.
    #[arg(
        long,
        value_name = "N",
        default_value_t = 0,
        allow_hyphen_values = true
    )]
    pub seed: u64,
    /// Time in seconds at which the wind is evaluated (as `pelage render --time`).
    #[arg(
        long,
        value_name = "T",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub time: f32,
    /// The image to write: FILE.png (8-bit sRGB) or FILE.hdr (Radiance RGBE, linear). The
    /// hair mask goes beside it as FILE.mask.png. Folders are created if missing.
    #[arg(short, long, value_name = "FILE", default_value = "out/trace.png")]
    pub out: PathBuf,
}

/// The image formats `pelage trace` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    /// 8-bit sRGB PNG.
    Png,
    /// Radiance RGBE, linear.
    Hdr,
}

/// The format `-o` asks for by its extension.
fn format_of(path: &Path) -> Result<Format, CliError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("png") => Ok(Format::Png),
        Some("hdr") => Ok(Format::Hdr),
        _ => Err(CliError::Usage(format!(
            "-o {}: the image must be a .png (8-bit sRGB) or a .hdr (Radiance, linear)",
            path.display()
        ))),
    }
}

/// Where the hair mask of `out` goes: `out` with the extension `.mask.png`.
pub fn mask_path(out: &Path) -> PathBuf {
    out.with_extension("mask.png")
}

/// Refuses the scene options the path tracer has no use for (naming them and why).
fn refuse_renderer_options(opts: &SceneOpts) -> Result<(), CliError> {
    let given: Vec<&str> = [
        opts.shadow.as_ref().map(|_| "--shadow"),
        opts.shadow_res.map(|_| "--shadow-res"),
        opts.oit.as_ref().map(|_| "--oit"),
        opts.dual_scattering.map(|_| "--dual-scattering"),
        opts.multiple_scattering.map(|_| "--multiple-scattering"),
        opts.lod.then_some("--lod"),
    ]
    .into_iter()
    .flatten()
    .collect();
    if given.is_empty() {
        return Ok(());
    }
    Err(CliError::Usage(format!(
        "{}: the path tracer does not use this: it traces every strand at full detail as an \
         opaque cylinder, with exact shadows and every bounce of light between fibres; leave \
         it out",
        given.join(", ")
    )))
}

/// An error of the path tracing itself (not of the user's input).
fn failed(e: impl std::error::Error + 'static) -> CliError {
    CliError::Lab(Box::new(e))
}

impl From<TraceError> for CliError {
    fn from(e: TraceError) -> Self {
        match e {
            TraceError::Render(e) => CliError::Render(e),
            TraceError::Gpu(e) => e.into(),
            e => failed(e),
        }
    }
}

/// Writes `image` to `path` as `format`, atomically.
fn write_image(image: &PathTracedImage, path: &Path, format: Format) -> Result<(), CliError> {
    match format {
        Format::Png => {
            let rgba = image::RgbaImage::from_raw(image.width, image.height, image.to_srgb8_rgba())
                .ok_or_else(|| CliError::Usage("the traced image has the wrong size".into()))?;
            save_png(&rgba, path)?;
        }
        Format::Hdr => {
            let rgb: Vec<image::Rgb<f32>> = image.pixels.iter().map(|p| image::Rgb(*p)).collect();
            write_atomically(path, |w| {
                image::codecs::hdr::HdrEncoder::new(w)
                    .encode(&rgb, image.width as usize, image.height as usize)
                    .map_err(|e| e.to_string())
            })?;
        }
    }
    Ok(())
}

/// The hair mask as an 8-bit grey PNG: the fraction of each pixel's samples whose first
/// hit is hair, 255 = all.
fn write_mask(image: &PathTracedImage, path: &Path) -> Result<(), CliError> {
    let bytes: Vec<u8> = image
        .hair_mask
        .iter()
        .map(|m| (m.clamp(0.0, 1.0) * 255.0).round() as u8)
        .collect();
    let grey = image::GrayImage::from_raw(image.width, image.height, bytes)
        .ok_or_else(|| CliError::Usage("the hair mask has the wrong size".into()))?;
    write_atomically(path, |w| {
        grey.write_with_encoder(image::codecs::png::PngEncoder::new(w))
            .map_err(|e| e.to_string())
    })?;
    Ok(())
}

/// Path-traces the scene (see the module docs), writes the image and its hair mask.
pub fn run(opts: &TraceOpts) -> Result<(), CliError> {
    let started = Instant::now();
    let format = format_of(&opts.out)?;
    refuse_renderer_options(&opts.scene)?;
    let size = opts.scene.size;
    if size.width > MAX_IMAGE_SIDE || size.height > MAX_IMAGE_SIDE {
        return Err(CliError::Usage(format!(
            "--size {size}: the path tracer takes each side in 1..={MAX_IMAGE_SIDE}"
        )));
    }
    if !opts.time.is_finite() {
        return Err(CliError::Usage(format!(
            "--time {}: must be a finite number of seconds",
            opts.time
        )));
    }
    let scene = opts.scene.scene()?;
    // Only the strands are needed from the GPU: no shadows, the cheapest compositing,
    // every strand at full detail.
    let mut grow = scene.clone();
    grow.shadow = ShadowParams::None;
    grow.shade.transparency = Transparency::Opaque;
    if grow.hair.lod.enabled {
        println!(
            "note: the scene's level of detail is off here: the path tracer traces every strand"
        );
        grow.hair.lod.enabled = false;
    }
    let gpu = Gpu::headless()?;
    println!("adapter: {}", gpu.describe());
    let mut renderer = Renderer::new(&gpu, &grow, size.width, size.height)?;
    renderer.render(&gpu, opts.time, &scene.camera)?;
    renderer.finish(&gpu)?;
    let traced = TracedScene::from_renderer(&scene, &renderer, &gpu)?;
    drop(renderer);
    for note in [&traced.model_note, &traced.mesh_note]
        .into_iter()
        .flatten()
    {
        println!("note: {note}");
    }
    let opacity = scene.hair.growth.opacity;
    if opacity < 1.0 {
        println!(
            "note: hair.growth.opacity = {opacity}: the path tracer's fibres are opaque \
             cylinders (only their own width lets light past)"
        );
    }
    let tracer = traced.tracer().map_err(failed)?;
    let settings = PathTracerSettings {
        spp: opts.spp,
        max_bounces: opts.bounces,
        seed: opts.seed,
        background: scene.shade.background.as_dvec3(),
        sky: DVec3::splat(f64::from(scene.shade.ambient) / std::f64::consts::PI),
        ..Default::default()
    };
    println!(
        "tracing {} strands ({} segments), {} triangles, {} lights: {size}, {} spp, up to {} \
         bounces, seed {}",
        traced.strands,
        traced.segments.len(),
        traced.mesh_triangles.len(),
        traced.lights.len(),
        opts.spp,
        opts.bounces,
        opts.seed
    );
    let bar = progress::bar(u64::from(size.height), "rows")?;
    let image = tracer
        .render_with_progress(&scene.camera, size.width, size.height, &settings, &|| {
            bar.inc(1)
        })
        .map_err(failed)?;
    bar.finish_and_clear();
    if let Some(i) = (image.pixels.iter()).position(|p| p.iter().any(|v| !v.is_finite())) {
        // The path tracer never returns one; refuse to write a wrong picture if it did.
        return Err(CliError::Lab(
            format!("pixel {i} of the traced image is not finite").into(),
        ));
    }
    write_image(&image, &opts.out, format)?;
    let mask = mask_path(&opts.out);
    write_mask(&image, &mask)?;
    let hair = image.hair_mask.iter().filter(|m| **m >= 0.5).count();
    println!(
        "wrote {} and its hair mask {} ({hair} hair pixels)",
        opts.out.display(),
        mask.display()
    );
    println!("wall time: {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_formats_by_extension() {
        assert_eq!(format_of(Path::new("a/b.png")).unwrap(), Format::Png);
        assert_eq!(format_of(Path::new("b.HDR")).unwrap(), Format::Hdr);
        for bad in ["b.jpg", "b", "b.png.txt"] {
            let e = format_of(Path::new(bad)).unwrap_err().to_string();
            assert!(e.contains("-o") && e.contains(bad), "{e}");
        }
        assert_eq!(
            mask_path(Path::new("out/t.hdr")),
            PathBuf::from("out/t.mask.png")
        );
    }
}
