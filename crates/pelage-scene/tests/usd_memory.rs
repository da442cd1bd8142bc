//! Peak heap of reading a 100 MB USD groom (feature `usd`; `#[ignore]`d: it writes
//! and reads 100 MB). Run it, with its report, by
//!
//! ```sh
//! cargo test -p pelage-scene --features usd --test usd_memory -- --ignored --nocapture
//! ```
//!
//! The heap is counted by a global allocator that forwards to the system's and keeps
//! the live and the peak bytes.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicU64, Ordering};

use glam::Vec3;
use pelage_scene::Groom;
use pelage_scene::usd_file;

/// The system allocator, counting the bytes live and their peak.
struct Counting;

static LIVE_BYTES: AtomicU64 = AtomicU64::new(0);
static PEAK_BYTES: AtomicU64 = AtomicU64::new(0);

fn grew(bytes: u64) {
    let live = LIVE_BYTES.fetch_add(bytes, Ordering::Relaxed) + bytes;
    PEAK_BYTES.fetch_max(live, Ordering::Relaxed);
}

// SAFETY: every call is forwarded unchanged to `System`; the counters are only updated.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract for `alloc` is passed on unchanged.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size() as u64);
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as for `alloc`.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grew(layout.size() as u64);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from this allocator with `layout` (the caller's contract).
        unsafe { System.dealloc(ptr, layout) };
        LIVE_BYTES.fetch_sub(layout.size() as u64, Ordering::Relaxed);
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: the caller's contract for `realloc` is passed on unchanged.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            LIVE_BYTES.fetch_sub(layout.size() as u64, Ordering::Relaxed);
            grew(new_size as u64);
        }
        p
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// A groom of `strands` wavy strands of 32 points with widths, in awkward decimals so
/// that the text is as long as a real export's.
fn groom(strands: usize) -> Groom {
    let strands: Vec<Vec<Vec3>> = (0..strands)
        .map(|s| {
            let root = Vec3::new(s as f32 * 0.001_37, (s % 97) as f32 * 0.013_1, 0.1);
            (0..32)
                .map(|k| {
                    root + Vec3::new(
                        0.003_1 * (k as f32).sin(),
                        -0.031_7 * k as f32,
                        0.000_9 * k as f32,
                    )
                })
                .collect()
        })
        .collect();
    Groom::from_strands(&strands).unwrap()
}

/// Peak heap above what was live before, while `f` runs.
fn peak_during<T>(f: impl FnOnce() -> T) -> (T, u64) {
    let before = LIVE_BYTES.load(Ordering::Relaxed);
    PEAK_BYTES.store(before, Ordering::Relaxed);
    let out = f();
    (out, PEAK_BYTES.load(Ordering::Relaxed) - before)
}

#[test]
#[ignore = "writes and reads a 100 MB file; run with --ignored --nocapture"]
fn a_100_mb_usd_file_is_read_within_twice_its_size() {
    let dir = std::env::temp_dir().join(format!("pelage-usd-memory-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // Size the groom from a small sample's bytes per strand to about 100 MB of text.
    let sample = usd_file::to_usda(&groom(1000)).unwrap().len() as f64 / 1000.0;
    let strands = (101e6 / sample) as usize;
    let written = groom(strands);
    let mut sizes = Vec::new();
    for ext in ["usda", "usdc"] {
        let path = dir.join(format!("groom.{ext}"));
        usd_file::write_path(&written, &path).unwrap();
        let size = std::fs::metadata(&path).unwrap().len();
        let (read, peak) = peak_during(|| Groom::load(&path).unwrap());
        assert_eq!(read.point_count(), written.point_count());
        drop(read);
        let ratio = peak as f64 / size as f64;
        println!(
            "{ext}: {strands} strands, {} points, file {:.1} MB, peak heap while reading {:.1} MB = {ratio:.2}x the file",
            written.point_count(),
            size as f64 / 1e6,
            peak as f64 / 1e6
        );
        sizes.push((ext, size, ratio));
        std::fs::remove_file(&path).unwrap();
    }
    std::fs::remove_dir_all(&dir).unwrap();
    let (_, size, ratio) = sizes[0];
    assert!(size > 90_000_000, "the text file is {size} bytes");
    assert!(
        ratio <= 2.0,
        "reading the 100 MB .usda held {ratio:.2}x its size"
    );
}
