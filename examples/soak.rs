//! Soak: thousands of frames of the animated default scene, watching memory.
//!
//! ```text
//! cargo run --release --example soak -- [--frames N] [--every N] [--size WxH] [--strands N] [--out DIR]
//! WGPU_BACKEND=gl cargo run --release --example soak -- ...     # the same on OpenGL
//! ```
//!
//! Renders `N` frames (10 000 by default) of the built-in creature in gusting wind,
//! with voxel shadows, one after the other on one renderer, as `pelage animate` does.
//! Every `--every` frames (250) it records four measures of memory:
//!
//! - the process's resident memory (on a software adapter "GPU" memory is host memory,
//!   so this covers everything);
//! - the C heap in use (glibc's `mallinfo2`: every `malloc`, the driver's included);
//! - the Rust heap in use, counted by this program's global allocator: pelage's own
//!   allocations and wgpu's, which are all Rust (the driver allocates through `malloc`,
//!   never through Rust's allocator);
//! - the buffers and bind groups pelage created since the first frame
//!   ([`pelage::gpu::Created`]).
//!
//! At the end it renders the last frame again on a fresh renderer that never drew the
//! frames before it, and checks the two images are identical. Writes `DIR/soak.csv`
//! (default `out/soak`) and prints a summary. Exits with an error if a frame failed,
//! the Rust heap grew (more than 1 MB after warm-up), pelage created a buffer or bind
//! group after the first frame, or the images differ. Growth outside the Rust heap is
//! reported, split between the driver's `malloc` and memory mapped outside it, but
//! is not pelage's to fix and does not fail the run.

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use pelage::gpu::Created;
use pelage::{Renderer, gpu::Gpu, scene::Scene};
use pelage_lab::Table;

/// The system allocator, counting the bytes live and the calls made.
struct Counting;

static LIVE_BYTES: AtomicU64 = AtomicU64::new(0);
static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);

// SAFETY: every call is forwarded unchanged to `System`; the counters are only updated.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract for `alloc` is passed on unchanged.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            LIVE_BYTES.fetch_add(layout.size() as u64, Ordering::Relaxed);
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as for `alloc`.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            LIVE_BYTES.fetch_add(layout.size() as u64, Ordering::Relaxed);
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
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
            LIVE_BYTES.fetch_add(new_size as u64, Ordering::Relaxed);
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        p
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Resident set size of this process in bytes, from /proc (0 where there is none).
fn resident_bytes() -> u64 {
    std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| {
            s.split_whitespace()
                .nth(1)
                .and_then(|p| p.parse::<u64>().ok())
        })
        .map_or(0, |pages| pages * 4096)
}

/// Bytes in use on the C heap (glibc: `mallinfo2`, small chunks plus mmapped ones);
/// `None` elsewhere.
fn c_heap_bytes() -> Option<u64> {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: mallinfo2 takes no arguments and only reads the allocator's state.
        let info = unsafe { libc::mallinfo2() };
        Some((info.uordblks + info.hblkhd) as u64)
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    None
}

/// One sample of memory.
#[derive(Clone, Copy)]
struct Sample {
    frame: u32,
    resident_mb: f64,
    c_heap_mb: Option<f64>,
    rust_mb: f64,
    created: Created,
}

impl Sample {
    fn now(frame: u32, first: &Created) -> Sample {
        Sample {
            frame,
            resident_mb: resident_bytes() as f64 / 1e6,
            c_heap_mb: c_heap_bytes().map(|b| b as f64 / 1e6),
            rust_mb: LIVE_BYTES.load(Ordering::Relaxed) as f64 / 1e6,
            created: Created::now().since(first),
        }
    }
}

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let mut frames = 10_000u32;
    let mut every = 250u32;
    let (mut width, mut height) = (160u32, 120u32);
    let mut out = PathBuf::from("out/soak");
    let mut strands = None;
    let mut args = std::env::args().skip(1);
    while let Some(flag) = args.next() {
        let value = args.next().ok_or(format!("{flag} needs a value"))?;
        match flag.as_str() {
            "--frames" => frames = value.parse()?,
            "--every" => every = value.parse()?,
            "--out" => out = PathBuf::from(value),
            "--strands" => strands = Some(value.parse::<u32>()?),
            "--size" => {
                let (w, h) = value.split_once('x').ok_or("--size takes WxH")?;
                (width, height) = (w.parse()?, h.parse()?);
            }
            other => {
                return Err(format!(
                    "unknown argument {other} (--frames, --every, --size, --strands, --out)"
                )
                .into());
            }
        }
    }
    if frames < 2 || every == 0 {
        return Err("--frames must be at least 2 and --every at least 1".into());
    }
    let gpu = Gpu::headless()?;
    println!("adapter: {}", gpu.describe());
    let mut scene = Scene::default();
    if let Some(n) = strands {
        scene.hair.roots.count = n;
    }
    let fps = 24.0;
    let mut renderer = Renderer::new(&gpu, &scene, width, height)?;
    let mut table = Table::new(&[
        "frame",
        "t_s",
        "resident_mb",
        "c_heap_mb",
        "rust_heap_mb",
        "rust_allocations_per_frame",
        "buffers_created",
        "bind_groups_created",
        "frame_ms",
        "gpu_ms",
    ]);
    let started = Instant::now();
    let mut samples: Vec<Sample> = Vec::new();
    let mut last_image = None;
    let mut first = Created::now();
    let mut allocations_then = ALLOCATIONS.load(Ordering::Relaxed);
    for f in 0..frames {
        let t = f as f32 / fps;
        let frame_started = Instant::now();
        renderer.render(&gpu, t, &scene.camera)?;
        let stats = renderer.finish(&gpu)?;
        let frame_ms = frame_started.elapsed().as_secs_f64() * 1e3;
        if f == 0 {
            // What the first frame creates (its pools, the timer's readback) is set-up.
            first = Created::now();
        }
        if f % every == 0 || f + 1 == frames {
            let sample = Sample::now(f, &first);
            let allocations = ALLOCATIONS.load(Ordering::Relaxed);
            let since = samples.last().map_or(1, |s| f - s.frame).max(1);
            let per_frame = (allocations - allocations_then) as f64 / f64::from(since);
            allocations_then = allocations;
            table.push(vec![
                f.to_string(),
                format!("{t:.3}"),
                format!("{:.2}", sample.resident_mb),
                sample.c_heap_mb.map_or("n/a".into(), |m| format!("{m:.2}")),
                format!("{:.3}", sample.rust_mb),
                format!("{per_frame:.0}"),
                sample.created.buffers.to_string(),
                sample.created.bind_groups.to_string(),
                format!("{frame_ms:.2}"),
                format!("{:.2}", stats.total_ms()),
            ])?;
            println!(
                "frame {f:>6}: resident {:8.1} MB, C heap {:>8} MB, Rust heap {:7.3} MB, \
                 {per_frame:5.0} Rust allocations a frame, {frame_ms:7.2} ms",
                sample.resident_mb,
                sample.c_heap_mb.map_or("n/a".into(), |m| format!("{m:.1}")),
                sample.rust_mb
            );
            samples.push(sample);
        }
        if f + 1 == frames {
            last_image = Some(renderer.image(&gpu)?);
        }
    }
    let elapsed = started.elapsed().as_secs_f64();
    table.write_csv(&out.join("soak.csv"))?;

    // Frame N on its own: a fresh renderer that drew nothing before it.
    let t_last = (frames - 1) as f32 / fps;
    let mut fresh = Renderer::new(&gpu, &scene, width, height)?;
    fresh.render(&gpu, t_last, &scene.camera)?;
    let alone = fresh.image(&gpu)?;
    let soaked = last_image.ok_or("no frame rendered")?;
    let identical = alone.as_raw() == soaked.as_raw();

    // Warm-up: the second sample (the first is frame 0, before pools settle).
    let warm = *samples.get(1).or(samples.first()).ok_or("no sample")?;
    let last = *samples.last().ok_or("no sample")?;
    let span = f64::from((last.frame - warm.frame).max(1));
    let per_frame_kb = |a: f64, b: f64| (b - a) * 1e3 / span;
    let rust_growth = last.rust_mb - warm.rust_mb;
    let ours_flat = rust_growth <= 1.0 && last.created == Created::default();
    println!(
        "{frames} frames of {width}x{height} in {elapsed:.0} s ({:.1} ms/frame), no error",
        elapsed * 1e3 / f64::from(frames)
    );
    println!(
        "from frame {} to {}, per frame: resident {:+.1} kB",
        warm.frame,
        last.frame,
        per_frame_kb(warm.resident_mb, last.resident_mb)
    );
    if let (Some(c0), Some(c1)) = (warm.c_heap_mb, last.c_heap_mb) {
        println!(
            "  the driver's malloc (C heap less the Rust heap): {:+.1} kB; memory mapped \
             outside malloc (resident less the C heap): {:+.1} kB",
            per_frame_kb(c0 - warm.rust_mb, c1 - last.rust_mb),
            per_frame_kb(warm.resident_mb - c0, last.resident_mb - c1)
        );
    }
    println!(
        "  pelage and wgpu (the Rust heap): {:+.3} kB ({:.3} MB at frame {}, {:.3} MB at \
         frame {}); buffers and bind groups created after the first frame: {} and {}: {}",
        per_frame_kb(warm.rust_mb, last.rust_mb),
        warm.rust_mb,
        warm.frame,
        last.rust_mb,
        last.frame,
        last.created.buffers,
        last.created.bind_groups,
        if ours_flat { "flat" } else { "GROWING" }
    );
    println!(
        "frame {} rendered after {} others and on its own: {}",
        frames - 1,
        frames - 1,
        if identical {
            "bit-identical"
        } else {
            "DIFFERENT"
        }
    );
    println!("wrote {}", out.join("soak.csv").display());
    if !ours_flat || !identical {
        return Err("soak failed".into());
    }
    Ok(())
}
