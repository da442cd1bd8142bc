//! `pelage render`: one frame of a scene to a PNG or JPEG.

use std::path::PathBuf;
use std::time::Instant;

use pelage::Renderer;
use pelage::gpu::Gpu;

use crate::animate::MAX_FRAMES;
use crate::error::CliError;
use crate::output::ImageFormat;
use crate::progress;
use crate::report::{DroppedWork, notice_gl_compile};
use crate::scene_opts::SceneOpts;

/// The frame rate a simulated scene is stepped at up to `--time` when `--fps` is not
/// given: `animate`'s default, so that `render --time T` draws what `animate` draws at T.
pub const DEFAULT_FPS: u32 = 24;

/// Options of `pelage render`.
#[derive(Clone, Debug, clap::Args)]
pub struct RenderOpts {
    /// The scene and its overrides.
    #[command(flatten)]
    pub scene: SceneOpts,
    /// Time in seconds, any finite number (negative too). The stateless wind is
    /// evaluated at T on its own. A scene with [dynamics] is simulated from 0 s up to T
    /// (T >= 0) in frames of 1/FPS s, as `animate` does, only the last one drawn.
    #[arg(
        long,
        value_name = "T",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub time: f32,
    /// Frames per second a scene with [dynamics] is simulated at up to --time (default
    /// 24, animate's); refused for a scene without dynamics, which has no frames.
    #[arg(long, value_name = "N",
          value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_FRAMES)))]
    pub fps: Option<u32>,
    /// The image to write, PNG or JPEG by its extension (.png, .jpg, .jpeg; none: PNG);
    /// its folder is created if missing.
    #[arg(short, long, value_name = "FILE.png", default_value = "out/render.png")]
    pub out: PathBuf,
}

/// The frames a simulated scene is stepped through before the drawn one at `time`.
#[derive(Clone, Debug, PartialEq)]
pub struct SimulatedTime {
    /// Frames per second.
    pub fps: u32,
    /// The frames stepped through without drawing: frame i at i / fps seconds.
    pub before: u32,
    /// The time drawn: `time`, or animate's time of the frame it is (within a
    /// millionth of a frame), so that both draw the same state.
    pub time: f32,
}

impl SimulatedTime {
    /// Plans the simulation up to `time` at `fps`; the errors name `--time`.
    pub fn new(time: f32, fps: u32) -> Result<Self, String> {
        if time < 0.0 {
            return Err(format!(
                "--time {time}: a scene with [dynamics] is simulated from 0 s, so the time \
                 must be at least 0"
            ));
        }
        let frames = f64::from(time) * f64::from(fps);
        if frames > f64::from(MAX_FRAMES) {
            return Err(format!(
                "--time {time}: at {fps} frames a second that is {frames:.0} frames to \
                 simulate; at most {MAX_FRAMES} (time x fps)"
            ));
        }
        let nearest = frames.round();
        let (before, time) = if (frames - nearest).abs() < 1e-6 {
            // Exactly frame n of an animation: its time as animate computes it.
            let n = nearest as u32;
            (n, n as f32 / fps as f32)
        } else {
            (frames.ceil() as u32, time)
        };
        Ok(Self { fps, before, time })
    }

    /// The time of frame `f` stepped through.
    pub fn frame_time(&self, f: u32) -> f32 {
        f as f32 / self.fps as f32
    }
}

/// Renders one frame, writes it and prints the GPU time of each pass. Errors about a
/// value an option gave name the option.
pub fn run(opts: &RenderOpts) -> Result<(), CliError> {
    render(opts).map_err(|e| opts.scene.blame(e))
}

fn render(opts: &RenderOpts) -> Result<(), CliError> {
    let started = Instant::now();
    let format = ImageFormat::for_path(&opts.out, "-o")?;
    let scene = opts.scene.scene()?;
    if !opts.time.is_finite() {
        return Err(CliError::Usage(format!(
            "--time {}: must be a finite number of seconds",
            opts.time
        )));
    }
    let simulated = match (&scene.dynamics, opts.fps) {
        (Some(_), fps) => Some(
            SimulatedTime::new(opts.time, fps.unwrap_or(DEFAULT_FPS)).map_err(CliError::Usage)?,
        ),
        (None, Some(fps)) => {
            return Err(CliError::Usage(format!(
                "--fps {fps}: the scene has no [dynamics]: its wind is stateless and the \
                 frame at --time is drawn on its own, so there are no frames; leave --fps out"
            )));
        }
        (None, None) => None,
    };
    let gpu = Gpu::headless()?;
    println!("adapter: {}", gpu.describe());
    notice_gl_compile(&gpu);
    let size = opts.scene.size;
    let mut renderer = Renderer::new(&gpu, &scene, size.width, size.height)?;
    let mut time = opts.time;
    if let Some(sim) = &simulated {
        // Step the simulation through every frame before `time`, drawing none.
        let bar = progress::bar(u64::from(sim.before), "frames simulated")?;
        for f in 0..sim.before {
            renderer.advance(&gpu, sim.frame_time(f), &scene.camera)?;
            bar.inc(1);
        }
        bar.finish_and_clear();
        time = sim.time;
        println!(
            "simulated {} frames at {} fps from 0 s up to t = {time} s",
            sim.before, sim.fps
        );
    }
    let mut dropped = DroppedWork::start(&renderer, &gpu)?;
    renderer.render(&gpu, time, &scene.camera)?;
    let stats = renderer.finish(&gpu)?;
    dropped.after_frame(&renderer, &gpu, 0)?;
    format.save(&renderer.image(&gpu)?, &opts.out)?;
    println!(
        "wrote {} ({size}, {} strands x {} segments, t = {} s)",
        opts.out.display(),
        renderer.frame().strands().params().roots.count,
        renderer.frame().strands().params().growth.segments,
        time
    );
    if scene.hair.lod.enabled {
        let lod = renderer.frame().strands().lod();
        println!(
            "level of detail: hair box {:.0} px on screen, lambda {:.3}: {} strands x {} segments drawn",
            lod.pixels, lod.zone.lambda, lod.strands, lod.segments
        );
    }
    crate::report::print_pass_times(&stats.by_label(), "GPU time per pass (one frame):");
    dropped.print(&scene.shade.transparency);
    println!("wall time: {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_simulated_time_steps_through_the_frames_before_it() {
        let at = SimulatedTime::new(0.5, 24).unwrap();
        assert_eq!((at.before, at.time), (12, 12.0 / 24.0));
        // Between frames: the frames before it, then the time itself.
        let at = SimulatedTime::new(0.51, 24).unwrap();
        assert_eq!((at.before, at.time), (13, 0.51));
        // Animate's time of frame 7 at 30 fps.
        let seven = 7.0f32 / 30.0;
        let at = SimulatedTime::new(seven, 30).unwrap();
        assert_eq!((at.before, at.time), (7, seven));
        assert_eq!(SimulatedTime::new(0.0, 24).unwrap().before, 0);
        for bad in [-0.5, 1e9] {
            let e = SimulatedTime::new(bad, 24).unwrap_err();
            assert!(e.starts_with("--time"), "{e}");
        }
    }
}
