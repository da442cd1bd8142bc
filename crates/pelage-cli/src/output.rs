//! Every file the command line writes, without leaving half-written files: through
//! [`pelage_lab::atomic_file::AtomicFile`] (the one atomic writer of pelage: a short
//! temporary in the same folder renamed over the target, symbolic links followed,
//! devices such as `/dev/null` written through). Image outputs take their format from
//! the file name's extension.

use std::path::{Path, PathBuf};

pub use pelage_lab::atomic_file::{AtomicFile, WriteError, remove_pending_temporaries};

use crate::error::CliError;

/// Writing a file failed.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The file system refused.
    #[error("cannot write {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// Opening, writing or renaming the file failed (the message says which).
    #[error(transparent)]
    Write(#[from] WriteError),
    /// Encoding an image failed, or writing its bytes did.
    #[error("cannot write {}: {message}", path.display())]
    Encode {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

/// Writes `path` by letting `write` fill a temporary file beside it, then renaming it
/// into place, so an interrupted run never leaves a half-written file. Creates parent
/// folders, follows symbolic links and writes through anything that is not a regular
/// file (`/dev/null`); see [`AtomicFile`].
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut AtomicFile) -> Result<(), String>,
) -> Result<(), OutputError> {
    let mut file = AtomicFile::create(path)?;
    if let Err(message) = write(&mut file) {
        // A write error the encoder met (a full disk) is clearer than its own wording.
        return Err(match file.commit() {
            Err(e) => e.into(),
            Ok(()) => OutputError::Encode {
                path: path.to_path_buf(),
                message,
            },
        });
    }
    Ok(file.commit()?)
}

/// Saves an RGBA image as PNG, atomically.
pub fn save_png(image: &image::RgbaImage, path: &Path) -> Result<(), OutputError> {
    write_atomically(path, |w| {
        image
            .write_with_encoder(image::codecs::png::PngEncoder::new(w))
            .map_err(|e| e.to_string())
    })
}

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
            Self::Png => save_png(image, path),
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
