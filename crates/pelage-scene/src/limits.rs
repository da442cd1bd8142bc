//! The most bytes each kind of input file may have: reading stops there, so a
//! path to `/dev/zero` or a runaway file fails with an error naming the file and
//! the limit instead of filling memory.

use std::io::{self, Read};
use std::path::Path;

/// Scene files (TOML): 16 MiB.
pub const MAX_SCENE_FILE_BYTES: u64 = 16 << 20;
/// OBJ meshes: 2 GiB.
pub const MAX_OBJ_FILE_BYTES: u64 = 2 << 30;
/// Groom files (`.hair`, `.tfx`, USD): 2 GiB.
///
/// The cap on a file's size `B` is a cap on the memory reading it takes (the peak heap
/// of `Groom::load`, measured by a counting allocator in `tests/usd_memory.rs`):
/// - `.hair` and `.tfx`: at most `8 × B` (the bytes, the parsed arrays, the groom);
/// - USD text (`.usda`, a `.usdz`'s text layer): at most
///   `(USD_MEMORY_FACTOR + 16) × B + USD_MEMORY_ALLOWANCE` = `32 × B + 64 MiB`: a text
///   whose estimated openusd memory exceeds `16 × B + 64 MiB` is refused before it is
///   parsed (`usd_file::USD_MEMORY_FACTOR`), and pelage's own copies take at most
///   `16 × B` more;
/// - USD binary crates (`.usdc`) are not bounded by a factor: openusd builds every prim
///   path as a string, so a deep hierarchy of long names costs more than its bytes
///   (the depth is capped at `usd_file::MAX_USD_NESTING`).
pub const MAX_GROOM_FILE_BYTES: u64 = 2 << 30;

/// The largest coordinate, length or width a scene may hold, in scene units. The
/// shaders square distances in 32-bit floats, which overflow past about 1.8e19, so a
/// groom with `width = 1e38` drew nothing and a mesh with 1e38 coordinates drew black;
/// 1e9 keeps every square (1e18) and sum of squares finite with room to spare.
pub const MAX_EXTENT: f32 = 1e9;

/// `limit` in words: "16 MiB", "2 GiB".
fn size_words(limit: u64) -> String {
    if limit >= 1 << 30 && limit.is_multiple_of(1 << 30) {
        format!("{} GiB", limit >> 30)
    } else if limit >= 1 << 20 && limit.is_multiple_of(1 << 20) {
        format!("{} MiB", limit >> 20)
    } else {
        format!("{limit} bytes")
    }
}

/// What a path that is not a regular file is, in words ("a FIFO (named pipe)", ...);
/// `None` for a regular file (or a link to one).
fn special_kind(metadata: &std::fs::Metadata) -> Option<&'static str> {
    let kind = metadata.file_type();
    if kind.is_file() {
        return None;
    }
    if kind.is_dir() {
        return Some("a directory");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return Some("a FIFO (named pipe)");
        }
        if kind.is_socket() {
            return Some("a socket");
        }
        if kind.is_char_device() {
            return Some("a character device");
        }
        if kind.is_block_device() {
            return Some("a block device");
        }
    }
    Some("not a regular file")
}

/// Opens `path` for reading after checking, before the open, that it is a regular file
/// (or a link to one): opening a FIFO blocks until a writer comes, and a device or a
/// socket is a stream without an end. Anything else is an error of kind `InvalidInput`
/// that says what the path is. Every reader of the crate opens its input here.
pub(crate) fn open_regular(path: &Path) -> io::Result<std::fs::File> {
    let metadata = std::fs::metadata(path)?;
    if let Some(kind) = special_kind(&metadata) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("it is {kind}, not a regular file; pelage reads input from regular files only"),
        ));
    }
    std::fs::File::open(path)
}

/// Reads all of `path`, at most `limit` bytes; more is an error (of kind
/// `InvalidData`) that says the limit for `kind` ("scene files", ...). A path that is
/// not a regular file is refused before it is opened ([`open_regular`]). The
/// callers' errors name the path.
pub(crate) fn read_capped(path: &Path, limit: u64, kind: &str) -> io::Result<Vec<u8>> {
    let file = open_regular(path)?;
    let expected = file.metadata().map(|m| m.len()).unwrap_or(0);
    let mut bytes = Vec::with_capacity(expected.min(limit) as usize + 1);
    file.take(limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(limit, kind));
    }
    Ok(bytes)
}

/// The error for a file larger than `limit`, the limit for `kind`.
pub(crate) fn too_large(limit: u64, kind: &str) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidData,
        format!(
            "larger than {}, the limit for {kind} (is it a device or a stream?)",
            size_words(limit)
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_stop_at_the_limit() {
        let path = std::env::temp_dir().join(format!("pelage-limits-big-{}", std::process::id()));
        std::fs::write(&path, [7u8; 1001]).unwrap();
        let e = read_capped(&path, 1000, "test files").unwrap_err();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(e.kind(), io::ErrorKind::InvalidData);
        assert!(
            e.to_string()
                .contains("larger than 1000 bytes, the limit for test files")
        );
        assert_eq!(size_words(MAX_SCENE_FILE_BYTES), "16 MiB");
        assert_eq!(size_words(MAX_OBJ_FILE_BYTES), "2 GiB");
    }

    #[cfg(unix)]
    #[test]
    fn devices_and_directories_are_refused_before_opening() {
        for (path, kind) in [
            ("/dev/zero", "a character device"),
            ("/dev/null", "a character device"),
            ("/", "a directory"),
        ] {
            let e = read_capped(Path::new(path), 1000, "test files").unwrap_err();
            assert_eq!(e.kind(), io::ErrorKind::InvalidInput, "{path}");
            assert!(e.to_string().contains(kind), "{path}: {e}");
        }
    }

    #[test]
    fn a_file_at_the_limit_is_read() {
        let path = std::env::temp_dir().join(format!("pelage-limits-{}", std::process::id()));
        std::fs::write(&path, [7u8; 100]).unwrap();
        assert_eq!(read_capped(&path, 100, "x").unwrap().len(), 100);
        assert!(read_capped(&path, 99, "x").is_err());
        std::fs::remove_file(&path).unwrap();
    }
}
