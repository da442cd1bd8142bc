//! `pelage compare REF TEST`: how far an image is from a reference, over the whole image
//! and over the hair.
//!
//! Both images are PNG (8-bit sRGB, decoded to linear) or Radiance HDR (linear). FLIP is
//! NVIDIA's LDR-FLIP (`pelage_reference::flip`, 67 pixels per degree), which clamps linear
//! values to [0, 1] first. The hair is the mask's pixels of at least half hair (a grey
//! PNG, as `pelage trace` writes beside its image).

use std::path::{Path, PathBuf};

use crate::output::save_png;
use pelage_reference::flip::{DEFAULT_PIXELS_PER_DEGREE, LinearImage, flip};

use crate::error::CliError;
use crate::path_trace::{hair_color, hair_luminance, heat, is_hair, masked_mean};
use crate::trace::mask_path;

/// Options of `pelage compare`.
#[derive(Clone, Debug, clap::Args)]
pub struct CompareOpts {
    /// The reference image (e.g. `pelage trace`'s), PNG (sRGB) or HDR (linear).
    #[arg(value_name = "REF")]
    pub reference: PathBuf,
    /// The image to measure (e.g. `pelage render`'s), the same size.
    #[arg(value_name = "TEST")]
    pub test: PathBuf,
    /// The hair mask, a grey PNG of REF's size (a pixel is hair at 128 and above).
    /// Default: REF's sibling REF.mask.png when it exists (`pelage trace` writes it);
    /// without a mask only the image-wide numbers are printed.
    #[arg(long, value_name = "MASK.png")]
    pub mask: Option<PathBuf>,
    /// Writes the FLIP heat map (black 0, red, yellow, white 1) to this PNG.
    #[arg(long, value_name = "OUT.png")]
    pub heat: Option<PathBuf>,
}

/// An image read for comparison, and what it was.
struct Loaded {
    image: LinearImage,
    kind: &'static str,
}

/// Reads `path` (named `what` in errors: REF, TEST) as linear RGB.
fn load(path: &Path, what: &str) -> Result<Loaded, CliError> {
    let bad = |why: String| CliError::Usage(format!("{what} {}: {why}", path.display()));
    let reader = image::ImageReader::open(path)
        .map_err(|e| bad(e.to_string()))?
        .with_guessed_format()
        .map_err(|e| bad(e.to_string()))?;
    let format = reader.format();
    let decoded = match format {
        Some(image::ImageFormat::Png | image::ImageFormat::Hdr) => {
            reader.decode().map_err(|e| bad(e.to_string()))?
        }
        _ => {
            return Err(bad(
                "not a PNG or a Radiance HDR image (the formats compare reads)".into(),
            ));
        }
    };
    let (width, height) = (decoded.width(), decoded.height());
    let (image, kind) = if format == Some(image::ImageFormat::Hdr) {
        let rgb = decoded.to_rgb32f();
        let pixels = rgb.pixels().map(|p| p.0).collect();
        (LinearImage::new(width, height, pixels), "HDR, linear")
    } else {
        let rgba = decoded.to_rgba8();
        (
            LinearImage::from_srgb8_rgba(width, height, rgba.as_raw()),
            "PNG, sRGB",
        )
    };
    Ok(Loaded {
        image: image.map_err(|e| bad(e.to_string()))?,
        kind,
    })
}

/// The hair mask for `opts` and where it came from, or `None` (with the reason printed).
fn mask(opts: &CompareOpts, width: u32, height: u32) -> Result<Option<Vec<f32>>, CliError> {
    let path = match &opts.mask {
        Some(path) => path.clone(),
        None => {
            let sibling = mask_path(&opts.reference);
            if !sibling.is_file() {
                println!(
                    "hair mask: none ({} does not exist and no --mask): image-wide numbers only",
                    sibling.display()
                );
                return Ok(None);
            }
            sibling
        }
    };
    let bad = |why: String| CliError::Usage(format!("--mask {}: {why}", path.display()));
    let grey = image::ImageReader::open(&path)
        .map_err(|e| bad(e.to_string()))?
        .with_guessed_format()
        .map_err(|e| bad(e.to_string()))?
        .decode()
        .map_err(|e| bad(e.to_string()))?
        .to_luma8();
    if grey.dimensions() != (width, height) {
        return Err(bad(format!(
            "the mask is {}x{}, the images {width}x{height}",
            grey.width(),
            grey.height()
        )));
    }
    let values: Vec<f32> = grey
        .as_raw()
        .iter()
        .map(|v| f32::from(*v) / 255.0)
        .collect();
    let hair = values.iter().filter(|m| is_hair(**m)).count();
    println!(
        "hair mask: {} ({hair} hair pixels, {:.1}% of the image)",
        path.display(),
        100.0 * hair as f64 / values.len().max(1) as f64
    );
    Ok(Some(values))
}

/// Compares, prints the numbers and writes the heat map.
pub fn run(opts: &CompareOpts) -> Result<(), CliError> {
    let reference = load(&opts.reference, "REF")?;
    let test = load(&opts.test, "TEST")?;
    let (a, b) = (&reference.image, &test.image);
    if (a.width, a.height) != (b.width, b.height) {
        return Err(CliError::Usage(format!(
            "REF {} is {}x{} but TEST {} is {}x{}: compare needs images of one size",
            opts.reference.display(),
            a.width,
            a.height,
            opts.test.display(),
            b.width,
            b.height
        )));
    }
    println!(
        "reference: {} ({}x{}, {})",
        opts.reference.display(),
        a.width,
        a.height,
        reference.kind
    );
    println!("test:      {} ({})", opts.test.display(), test.kind);
    let mask = mask(opts, a.width, a.height)?;
    let map = flip(a, b, DEFAULT_PIXELS_PER_DEGREE).map_err(|e| CliError::Lab(Box::new(e)))?;
    println!("mean FLIP, image: {:.4}", map.mean());
    if let Some(mask) = &mask {
        if !mask.iter().any(|m| is_hair(*m)) {
            println!("the mask marks no hair pixel: no numbers over the hair");
        } else {
            println!("mean FLIP, hair:  {:.4}", masked_mean(&map, mask));
            let (ref_luma, test_luma) = (hair_luminance(a, mask), hair_luminance(b, mask));
            if ref_luma > 0.0 {
                println!(
                    "hair luminance ratio (TEST/REF): {:.4} (REF {ref_luma:.5}, TEST {test_luma:.5})",
                    test_luma / ref_luma
                );
            } else {
                println!(
                    "hair luminance ratio (TEST/REF): n/a, the reference's hair is black \
                     (TEST {test_luma:.5})"
                );
            }
            let d = hair_color(b, mask) - hair_color(a, mask);
            println!(
                "hair colour difference (TEST - REF, linear): R {:+.5} G {:+.5} B {:+.5}",
                d.x, d.y, d.z
            );
        }
    }
    if let Some(path) = &opts.heat {
        save_png(&heat(&map)?, path)?;
        println!("wrote the FLIP heat map {}", path.display());
    }
    Ok(())
}
