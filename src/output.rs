//! Writing outputs without leaving half-written files, with
//! [`pelage_scene::atomic_file::AtomicFile`] (the one atomic writer of pelage): a short
//! temporary in the same folder renamed over the target, symbolic links
//! followed, devices such as `/dev/null` written through.

use std::path::{Path, PathBuf};

pub use pelage_scene::atomic_file::{AtomicFile, remove_pending_temporaries};

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
    Write(#[from] pelage_scene::atomic_file::WriteError),
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

/// Saves an RGBA image as PNG, atomically (feature `png`).
#[cfg(feature = "png")]
pub fn save_png(image: &image::RgbaImage, path: &Path) -> Result<(), OutputError> {
    write_atomically(path, |w| {
        image
            .write_with_encoder(image::codecs::png::PngEncoder::new(w))
            .map_err(|e| e.to_string())
    })
}
