//! Atomic file writes.

use std::fs::{self, File};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::LabError;

/// Distinguishes temporary files of concurrent writes within one process.
static COUNTER: AtomicU64 = AtomicU64::new(0);

/// Write `path` atomically: to a temporary name in the same folder, then
/// rename (creates parent folders).
///
/// Readers see either the old content or the complete new content, never a
/// partial file. On failure the temporary file is removed and an existing
/// file at `path` is left untouched.
pub fn write_file_atomically(path: &Path, bytes: &[u8]) -> Result<(), LabError> {
    let name = path
        .file_name()
        .ok_or_else(|| LabError::Invalid(format!("{} does not name a file", path.display())))?;
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(dir) = parent {
        fs::create_dir_all(dir).map_err(|source| LabError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
    }
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(
        ".{}.{}.tmp",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let tmp: PathBuf = match parent {
        Some(dir) => dir.join(&tmp_name),
        None => PathBuf::from(&tmp_name),
    };
    let result = write_and_sync(&tmp, bytes).and_then(|()| {
        fs::rename(&tmp, path).map_err(|source| LabError::Io {
            path: path.to_path_buf(),
            source,
        })
    });
    if result.is_err() {
        // Best effort: the original error is the one worth reporting.
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Create `tmp`, write `bytes` and flush them to disk.
fn write_and_sync(tmp: &Path, bytes: &[u8]) -> Result<(), LabError> {
    let io = |source| LabError::Io {
        path: tmp.to_path_buf(),
        source,
    };
    let mut file = File::create(tmp).map_err(io)?;
    file.write_all(bytes).map_err(io)?;
    file.sync_all().map_err(io)?;
    Ok(())
}
