//! The error type of this crate.

use std::path::PathBuf;

/// Everything that can go wrong while writing lab output.
#[derive(Debug, thiserror::Error)]
pub enum LabError {
    /// Reading or writing a file (or creating its folder) failed.
    #[error("cannot read or write {}: {source}", path.display())]
    Io {
        /// The file or folder involved.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// Creating an output folder failed.
    #[error("cannot create the folder {}: {source}", path.display())]
    CreateDir {
        /// The folder.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// Drawing or encoding an image, or writing it, failed.
    #[error("cannot write the image {}: {message}", path.display())]
    Encode {
        /// The file that was being written.
        path: PathBuf,
        /// What the encoder reported.
        message: String,
    },
    /// The input was not acceptable (the message says what was wrong).
    #[error("invalid input: {0}")]
    Invalid(String),
}
