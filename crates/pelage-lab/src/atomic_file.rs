//! Atomic file writes, shared by every program of pelage that writes a file (the
//! command line's images, GIFs, `.hair` and USD grooms, the labs' CSV and charts).
//! The library crates write no files: they hand out bytes (`HairFile::write`,
//! `usd_file::encode`), and the programs write them here.
//!
//! [`AtomicFile`] writes a regular file (or a path that does not exist yet) to
//! a short temporary name in the same folder, `.pelage-<pid>-<n>.tmp`, and
//! renames it over the target on [`AtomicFile::commit`]: readers see the old
//! content or the complete new content, never a partial file. Anything that
//! is not a regular file (`/dev/null`, `/dev/stdout`, a FIFO) is written
//! through instead, and symbolic links are followed, so the file they point
//! to is replaced and the link is kept.
//!
//! Temporaries that a killed process leaves behind are removed by a later
//! writer to the same folder ([`AtomicFile::create`] does it once per folder
//! and process): a name of the pattern above whose process is gone (on Linux,
//! no `/proc/<pid>`) and that has not been modified for a minute, or on other
//! systems for a day. On SIGINT or SIGTERM a program calls
//! [`remove_pending_temporaries`] from its signal handler.

use std::collections::HashSet;
use std::ffi::OsStr;
use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};
use std::time::{Duration, SystemTime};

/// Distinguishes temporary files of concurrent writes within one process.
static COUNTER: AtomicU64 = AtomicU64::new(0);

/// The temporaries of this process not yet renamed into place or removed.
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Folders already swept for stale temporaries by this process.
static SWEPT: Mutex<Option<HashSet<PathBuf>>> = Mutex::new(None);

/// Symbolic links followed before giving up (Linux's limit, `ELOOP`).
const MAX_LINKS: usize = 40;

/// Prefix of every temporary file name.
const TMP_PREFIX: &str = ".pelage-";
/// Suffix of every temporary file name.
const TMP_SUFFIX: &str = ".tmp";

/// An atomic write failed.
#[derive(Debug, thiserror::Error)]
#[error("cannot {action} {}: {source}", path.display())]
pub struct WriteError {
    /// What was being done: "write", "create the folder of", ...
    pub action: &'static str,
    /// The path the caller asked to write (or the folder, for folder errors).
    pub path: PathBuf,
    /// Why.
    pub source: io::Error,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

/// A file being written: to a temporary beside the target that
/// [`commit`](Self::commit) renames into place, or, when the target is not a
/// regular file (a device, a FIFO), to the target itself. Dropped without a
/// commit, it removes its temporary and leaves the target untouched.
///
/// Write errors are kept: [`commit`](Self::commit) reports the first one even
/// when the writer that met it (an encoder's `Drop`) ignored it.
#[derive(Debug)]
pub struct AtomicFile {
    /// The path the caller asked to write (named in errors).
    path: PathBuf,
    /// The file symbolic links lead to.
    target: PathBuf,
    /// The temporary, or `None` when writing through to `target`.
    tmp: Option<PathBuf>,
    /// The open file.
    writer: BufWriter<File>,
    /// The first write error.
    failed: Option<io::ErrorKind>,
}

impl AtomicFile {
    /// Opens `path` for writing, creating its parent folders. Follows symbolic
    /// links; refuses a folder; writes through anything that is not a regular
    /// file; for a regular file or a new path, creates the temporary
    /// `.pelage-<pid>-<n>.tmp` in the target's folder (after removing stale
    /// temporaries there, see the module documentation).
    ///
    /// On the web (`wasm32-unknown-unknown`) there is no file system: every path is a
    /// [`WriteError`] of kind [`io::ErrorKind::Unsupported`] (instead of the panic
    /// the standard library's process id would raise there).
    pub fn create(path: &Path) -> Result<Self, WriteError> {
        let err = |action, source| WriteError {
            action,
            path: path.to_path_buf(),
            source,
        };
        if cfg!(all(target_arch = "wasm32", target_os = "unknown")) {
            return Err(err(
                "write",
                io::Error::new(
                    io::ErrorKind::Unsupported,
                    "this platform (the web) has no file system",
                ),
            ));
        }
        let target = resolve_links(path).map_err(|e| err("follow the links of", e))?;
        match fs::metadata(&target) {
            Ok(meta) if meta.is_dir() => {
                return Err(err(
                    "write",
                    io::Error::new(io::ErrorKind::IsADirectory, "it is a folder"),
                ));
            }
            Ok(meta) if !meta.is_file() => {
                let file = File::options()
                    .write(true)
                    .truncate(true)
                    .open(&target)
                    .map_err(|e| err("open", e))?;
                return Ok(Self {
                    path: path.to_path_buf(),
                    target,
                    tmp: None,
                    writer: BufWriter::new(file),
                    failed: None,
                });
            }
            _ => {}
        }
        if target.file_name().is_none() {
            return Err(err(
                "write",
                io::Error::new(io::ErrorKind::InvalidInput, "the path does not name a file"),
            ));
        }
        let dir = target
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .map(Path::to_path_buf);
        if let Some(dir) = &dir {
            fs::create_dir_all(dir).map_err(|source| WriteError {
                action: "create the folder",
                path: dir.clone(),
                source,
            })?;
        }
        let dir = dir.unwrap_or_else(|| PathBuf::from("."));
        sweep_once(&dir);
        let tmp = dir.join(format!(
            "{TMP_PREFIX}{}-{}{TMP_SUFFIX}",
            std::process::id(),
            COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        // Registered before it exists, so a signal between the two removes it too.
        lock(&PENDING).push(tmp.clone());
        let file = match File::options().write(true).create_new(true).open(&tmp) {
            Ok(file) => file,
            Err(e) => {
                unregister(&tmp);
                return Err(err("create a temporary file for", e));
            }
        };
        Ok(Self {
            path: path.to_path_buf(),
            target,
            tmp: Some(tmp),
            writer: BufWriter::new(file),
            failed: None,
        })
    }

    /// The path the caller asked to write.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flushes the data, syncs it to disk and renames the temporary over the
    /// target (for a write-through, only flushes). Reports the first write
    /// error, if any, naming the path.
    pub fn commit(mut self) -> Result<(), WriteError> {
        let err = |action, source| WriteError {
            action,
            path: self.path.clone(),
            source,
        };
        if let Some(kind) = self.failed {
            // Flushing again gives the full error where the buffer still holds the data.
            let e = self.writer.flush().err().unwrap_or_else(|| kind.into());
            return Err(err("write", e));
        }
        self.writer.flush().map_err(|e| err("write", e))?;
        let Some(tmp) = self.tmp.clone() else {
            return Ok(());
        };
        self.writer
            .get_ref()
            .sync_all()
            .map_err(|e| err("write", e))?;
        // Held across the rename, so a signal handler sweeping the pending
        // temporaries cannot remove this one half-way.
        let mut pending = lock(&PENDING);
        fs::rename(&tmp, &self.target).map_err(|e| err("write", e))?;
        pending.retain(|p| p != &tmp);
        self.tmp = None;
        Ok(())
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let r = self.writer.write(buf);
        if let Err(e) = &r {
            self.failed.get_or_insert(e.kind());
        }
        r
    }

    fn flush(&mut self) -> io::Result<()> {
        let r = self.writer.flush();
        if let Err(e) = &r {
            self.failed.get_or_insert(e.kind());
        }
        r
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if let Some(tmp) = self.tmp.take() {
            let mut pending = lock(&PENDING);
            // Best effort: the error that stopped the write is the one worth reporting.
            let _ = fs::remove_file(&tmp);
            pending.retain(|p| p != &tmp);
        }
    }
}

fn unregister(tmp: &Path) {
    lock(&PENDING).retain(|p| p != tmp);
}

/// Removes every temporary this process has open (for a SIGINT or SIGTERM
/// handler, just before the process exits). Leaves the registry locked, so a
/// write that is about to rename its temporary waits instead of racing.
pub fn remove_pending_temporaries() {
    let pending = lock(&PENDING);
    for tmp in pending.iter() {
        let _ = fs::remove_file(tmp);
    }
    // The process exits next; other threads must not rename or create now.
    std::mem::forget(pending);
}

/// Follows symbolic links from `path` to the file they lead to (which need
/// not exist yet). Relative link targets are taken from the link's folder.
fn resolve_links(path: &Path) -> io::Result<PathBuf> {
    let mut current = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        match fs::symlink_metadata(&current) {
            Ok(meta) if meta.file_type().is_symlink() => {
                let link = fs::read_link(&current)?;
                current = match current.parent() {
                    Some(dir) if link.is_relative() => dir.join(link),
                    _ => link,
                };
            }
            _ => return Ok(current),
        }
    }
    Err(io::Error::other(format!(
        "more than {MAX_LINKS} symbolic links in a row"
    )))
}

/// The process id in a temporary name of this module's pattern.
fn temporary_pid(name: &OsStr) -> Option<u32> {
    let name = name.to_str()?;
    let rest = name.strip_prefix(TMP_PREFIX)?.strip_suffix(TMP_SUFFIX)?;
    let (pid, n) = rest.split_once('-')?;
    n.parse::<u64>().ok()?;
    pid.parse().ok()
}

/// Whether a stale temporary of process `pid`, last modified at `modified`,
/// may be removed: not ours, its process gone and a minute quiet (Linux), or a
/// day old where processes cannot be checked.
fn is_stale(pid: u32, modified: SystemTime) -> bool {
    if pid == std::process::id() {
        return false;
    }
    let age = SystemTime::now()
        .duration_since(modified)
        .unwrap_or(Duration::ZERO);
    if Path::new("/proc/self").exists() {
        !Path::new(&format!("/proc/{pid}")).exists() && age >= Duration::from_secs(60)
    } else {
        age >= Duration::from_secs(24 * 3600)
    }
}

/// Removes the stale temporaries in `dir` the first time this process writes there.
fn sweep_once(dir: &Path) {
    let key = fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf());
    if !lock(&SWEPT).get_or_insert_with(HashSet::new).insert(key) {
        return;
    }
    remove_stale_temporaries(dir);
}

/// Removes the temporaries of this module's pattern in `dir` that processes
/// that are gone left behind (see the module documentation); returns how many.
/// Errors (an unreadable folder, a file removed meanwhile) are skipped.
pub fn remove_stale_temporaries(dir: &Path) -> usize {
    let Ok(entries) = fs::read_dir(dir) else {
        return 0;
    };
    let mut removed = 0;
    for entry in entries.flatten() {
        let Some(pid) = temporary_pid(&entry.file_name()) else {
            continue;
        };
        let Ok(meta) = entry.metadata() else {
            continue;
        };
        let Ok(modified) = meta.modified() else {
            continue;
        };
        if meta.is_file() && is_stale(pid, modified) && fs::remove_file(entry.path()).is_ok() {
            removed += 1;
        }
    }
    removed
}

/// Writes `bytes` to `path` through an [`AtomicFile`]: a short temporary file in the
/// same folder, then rename (creates parent folders, follows symbolic links, writes
/// through devices such as `/dev/null`). On failure the temporary is removed and an
/// existing file at `path` is left untouched.
pub fn write_bytes_atomically(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    let mut file = AtomicFile::create(path)?;
    file.write_all(bytes).map_err(|source| WriteError {
        action: "write",
        path: path.to_path_buf(),
        source,
    })?;
    file.commit()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temporary_names_parse() {
        assert_eq!(temporary_pid(OsStr::new(".pelage-123-4.tmp")), Some(123));
        assert_eq!(temporary_pid(OsStr::new(".pelage-123.tmp")), None);
        assert_eq!(temporary_pid(OsStr::new("frame.pelage-1-2.tmp")), None);
        assert_eq!(temporary_pid(OsStr::new(".pelage-x-2.tmp")), None);
    }

    #[test]
    fn own_temporaries_are_never_stale() {
        assert!(!is_stale(std::process::id(), SystemTime::UNIX_EPOCH));
    }
}
