//! Atomic file writes for the lab: [`crate::atomic_file`] (the one atomic writer of
//! pelage) with the lab's error type.

use std::path::Path;

pub use crate::atomic_file::{
    AtomicFile, WriteError, remove_pending_temporaries, remove_stale_temporaries,
    write_bytes_atomically,
};

use crate::LabError;

impl From<WriteError> for LabError {
    fn from(e: WriteError) -> Self {
        LabError::Io {
            path: e.path,
            source: e.source,
        }
    }
}

/// Writes `bytes` to `path` atomically ([`write_bytes_atomically`]) with a [`LabError`].
pub fn write_file_atomically(path: &Path, bytes: &[u8]) -> Result<(), LabError> {
    write_bytes_atomically(path, bytes).map_err(LabError::from)
}

/// Creates the folder `path` and its parents (nothing to do when it exists); the error
/// names the folder (`cannot create the folder out/lod: Read-only file system`).
pub fn create_dir(path: &Path) -> Result<(), LabError> {
    std::fs::create_dir_all(path).map_err(|source| LabError::CreateDir {
        path: path.to_path_buf(),
        source,
    })
}
