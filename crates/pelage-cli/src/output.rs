//! Image outputs: the format follows the file name's extension.

use std::path::Path;

use pelage::{OutputError, write_atomically};

use crate::error::CliError;

/// The image formats an output path may name, by extension (any case).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// `.png`, or no extension at all (`/dev/null`, `/dev/stdout`): lossless RGBA.
    Png,
    /// `.jpg` or `.jpeg`: baseline JPEG at [`JPEG_QUALITY`], without alpha (every
    /// pixel pelage draws is opaque).
    Jpeg,
}

/// The quality JPEG outputs are encoded at (1 to 100).
pub const JPEG_QUALITY: u8 = 92;

/// The extensions an image output may have, for error messages.
pub const IMAGE_EXTENSIONS: &str = ".png, .jpg, .jpeg (or none, for PNG)";

impl ImageFormat {
    /// The format `path`'s extension names; another extension is a usage error naming
    /// `option`, the path and the supported extensions. Checked before any work, so a
    /// typo costs nothing.
    pub fn for_path(path: &Path, option: &str) -> Result<Self, CliError> {
        let Some(extension) = path.extension() else {
            return Ok(Self::Png);
        };
        match extension.to_string_lossy().to_ascii_lowercase().as_str() {
            "png" => Ok(Self::Png),
            "jpg" | "jpeg" => Ok(Self::Jpeg),
            other => Err(CliError::Usage(format!(
                "{option} {}: cannot write a `.{other}` image; the format follows the \
                 extension: {IMAGE_EXTENSIONS}",
                path.display()
            ))),
        }
    }

    /// Writes `image` to `path` in this format, atomically (a temporary renamed into
    /// place; devices written through).
    pub fn save(self, image: &image::RgbaImage, path: &Path) -> Result<(), OutputError> {
        match self {
            Self::Png => pelage::save_png(image, path),
            Self::Jpeg => {
                let rgb = image::DynamicImage::ImageRgba8(image.clone()).into_rgb8();
                write_atomically(path, |w| {
                    rgb.write_with_encoder(image::codecs::jpeg::JpegEncoder::new_with_quality(
                        w,
                        JPEG_QUALITY,
                    ))
                    .map_err(|e| e.to_string())
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_extension_picks_the_format() {
        for (path, format) in [
            ("a.png", ImageFormat::Png),
            ("a.PNG", ImageFormat::Png),
            ("/dev/null", ImageFormat::Png),
            ("out/frame", ImageFormat::Png),
            ("a.jpg", ImageFormat::Jpeg),
            ("a.JPEG", ImageFormat::Jpeg),
        ] {
            assert_eq!(
                ImageFormat::for_path(Path::new(path), "-o").unwrap(),
                format,
                "{path}"
            );
        }
        for path in ["a.gif", "a.exr", "a.png.txt", "a."] {
            let e = ImageFormat::for_path(Path::new(path), "-o")
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with("-o ") && e.contains(path) && e.contains(IMAGE_EXTENSIONS),
                "{path}: {e}"
            );
        }
    }
}
