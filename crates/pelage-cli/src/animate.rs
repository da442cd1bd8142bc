//! `pelage animate`: a PNG sequence of a scene in wind and an animated GIF preview.

use std::path::PathBuf;
use std::time::Instant;

use pelage::gpu::Gpu;
use pelage::{Renderer, save_png, write_atomically};

use crate::error::CliError;
use crate::progress;
use crate::report::{median_per_pass, print_pass_times};
use crate::scene_opts::SceneOpts;

/// Options of `pelage animate`.
#[derive(Clone, Debug, clap::Args)]
pub struct AnimateOpts {
    /// The scene and its overrides.
    #[command(flatten)]
    pub scene: SceneOpts,
    /// Number of frames to render.
    #[arg(long, value_name = "N", default_value_t = 48,
          value_parser = clap::value_parser!(u32).range(1..))]
    pub frames: u32,
    /// Frames per second of the animation: frame i shows the wind at i / FPS seconds,
    /// and the GIF plays at this rate.
    #[arg(long, value_name = "N", default_value_t = 24,
          value_parser = clap::value_parser!(u32).range(1..))]
    pub fps: u32,
    /// Output folder for frame_0000.png, frame_0001.png, ... and wind.gif; created if missing.
    #[arg(long, value_name = "DIR", default_value = "out/wind")]
    pub out: PathBuf,
}

/// Renders the animation, writes the frames and the GIF, prints the GPU time per pass
/// (median over the frames) and the wall clock of each stage submitted alone.
pub fn run(opts: &AnimateOpts) -> Result<(), CliError> {
    let started = Instant::now();
    let scene = opts.scene.scene()?;
    let gpu = Gpu::headless()?;
    println!("adapter: {}", gpu.describe());
    let size = opts.scene.size;
    let mut renderer = Renderer::new(&gpu, &scene, size.width, size.height)?;

    let bar = progress::bar(u64::from(opts.frames), "frames")?;
    let duration = opts.frames as f32 / opts.fps as f32;
    let mut passes = Vec::with_capacity(opts.frames as usize);
    let mut paths = Vec::with_capacity(opts.frames as usize);
    for f in 0..opts.frames {
        let t = f as f32 / opts.fps as f32;
        // A slow orbit over the animation (a quarter of a radian in all), so the wind is
        // seen from several sides.
        let camera = scene.camera.orbited(-0.5 * t / duration);
        passes.push(renderer.render(&gpu, t, &camera)?.passes);
        let path = opts.out.join(format!("frame_{f:04}.png"));
        save_png(&renderer.image(&gpu)?, &path)?;
        paths.push(path);
        bar.inc(1);
    }
    bar.finish_and_clear();

    // Animated preview: every frame, at the animation's frame rate, read back from the
    // PNGs one at a time (a long animation need not fit in memory).
    let gif_path = opts.out.join("wind.gif");
    let delay = image::Delay::from_numer_denom_ms(1000, opts.fps);
    write_atomically(&gif_path, |w| {
        let mut encoder = image::codecs::gif::GifEncoder::new_with_speed(w, 20);
        encoder
            .set_repeat(image::codecs::gif::Repeat::Infinite)
            .map_err(|e| e.to_string())?;
        for path in &paths {
            let frame = image::open(path)
                .map_err(|e| format!("{}: {e}", path.display()))?
                .into_rgba8();
            encoder
                .encode_frame(image::Frame::from_parts(frame, 0, 0, delay))
                .map_err(|e| e.to_string())?;
        }
        Ok(())
    })?;

    println!(
        "wrote {} frames of {size} ({} strands x {} segments) to {}/frame_*.png and {}",
        opts.frames,
        renderer.strands().params().roots.count,
        renderer.strands().params().growth.segments,
        opts.out.display(),
        gif_path.display()
    );
    print_pass_times(
        &median_per_pass(&passes),
        &format!("GPU time per pass (median over {} frames):", opts.frames),
    );
    // Cross-check that does not rely on the driver's timestamps: each stage alone, wall clock.
    let last = (opts.frames - 1) as f32 / opts.fps as f32;
    println!("wall clock per stage, submitted alone (median of 5):");
    for (stage, ms) in renderer.stage_wall_times(&gpu, last, &scene.camera, 5)? {
        println!("  {stage:<28} {ms:9.3} ms");
    }
    println!("wall time: {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}
