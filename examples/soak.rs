//! Soak: thousands of frames of the animated default scene, watching memory.
//!
//! ```text
//! cargo run --release --example soak -- [--frames N] [--size WxH] [--strands N] [--out DIR]
//! ```
//!
//! Renders `N` frames (10 000 by default) of the built-in creature in gusting wind,
//! with voxel shadows, one after the other on one renderer. Every 250 frames it records
//! the process's resident memory (on lavapipe the "GPU" memory is host memory, so this
//! covers both) and the frame time. At the end it renders the last frame again on a
//! fresh renderer that never drew the frames before it, and checks the two images are
//! identical. Writes `DIR/soak.csv` (default `out/soak`) and prints a summary; exits
//! with an error if any frame failed, memory grew, or the images differ.

use std::path::PathBuf;
use std::time::Instant;

use pelage::{Renderer, Scene, gpu::Gpu};
use pelage_lab::Table;

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

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let mut frames = 10_000u32;
    let (mut width, mut height) = (160u32, 120u32);
    let mut out = PathBuf::from("out/soak");
    let mut strands = None;
    let mut args = std::env::args().skip(1);
    while let Some(flag) = args.next() {
        let value = args.next().ok_or(format!("{flag} needs a value"))?;
        match flag.as_str() {
            "--frames" => frames = value.parse()?,
            "--out" => out = PathBuf::from(value),
            "--strands" => strands = Some(value.parse::<u32>()?),
            "--size" => {
                let (w, h) = value.split_once('x').ok_or("--size takes WxH")?;
                (width, height) = (w.parse()?, h.parse()?);
            }
            other => {
                return Err(format!(
                    "unknown argument {other} (--frames, --size, --strands, --out)"
                )
                .into());
            }
        }
    }
    if frames == 0 {
        return Err("--frames must be at least 1".into());
    }
    let gpu = Gpu::headless()?;
    let mut scene = Scene::default();
    if let Some(n) = strands {
        scene.hair.roots.count = n;
    }
    let fps = 24.0;
    let mut renderer = Renderer::new(&gpu, &scene, width, height)?;
    let mut table = Table::new(&["frame", "t_s", "resident_mb", "frame_ms", "gpu_ms"]);
    let started = Instant::now();
    let mut samples = Vec::new();
    let mut last_image = None;
    for f in 0..frames {
        let t = f as f32 / fps;
        let frame_started = Instant::now();
        renderer.render(&gpu, t, &scene.camera)?;
        let stats = renderer.finish(&gpu)?;
        let frame_ms = frame_started.elapsed().as_secs_f64() * 1e3;
        if f % 250 == 0 || f + 1 == frames {
            let resident = resident_bytes() as f64 / 1e6;
            samples.push((f, resident));
            table.push(vec![
                f.to_string(),
                format!("{t:.3}"),
                format!("{resident:.1}"),
                format!("{frame_ms:.2}"),
                format!("{:.2}", stats.gpu_ms()),
            ])?;
            println!("frame {f:>6}: {resident:8.1} MB resident, {frame_ms:7.2} ms");
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

    // Memory is flat if the last sample is within 5% (or 5 MB) of the one after warm-up.
    let warm = samples.get(1).or(samples.first()).map_or(0.0, |s| s.1);
    let last = samples.last().map_or(0.0, |s| s.1);
    let growth = last - warm;
    let flat = growth <= (0.05 * warm).max(5.0);
    println!(
        "{frames} frames of {width}x{height} in {elapsed:.0} s ({:.1} ms/frame), no error",
        elapsed * 1e3 / f64::from(frames)
    );
    println!(
        "resident memory: {warm:.1} MB after warm-up, {last:.1} MB at the end ({growth:+.1} MB): {}",
        if flat { "flat" } else { "GROWING" }
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
    if !flat || !identical {
        return Err("soak failed".into());
    }
    Ok(())
}
