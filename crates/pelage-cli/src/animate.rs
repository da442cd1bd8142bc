//! `pelage animate`: a PNG sequence of a scene in wind and an animated GIF preview.

use std::io::Write;
use std::ops::Range;
use std::path::PathBuf;
use std::time::Instant;

use pelage::Renderer;
use pelage::gpu::Gpu;

use crate::output::{AtomicFile, OutputError, save_png};

use crate::error::CliError;
use crate::progress;
use crate::report::{DroppedWork, median_per_pass, notice_gl_compile, print_pass_times};
use crate::scene_opts::SceneOpts;

/// The most frames one animation may have (`--frames`): 11.6 hours at 24 frames a
/// second. Memory does not grow with it (the GIF is encoded frame by frame).
pub const MAX_FRAMES: u32 = 1_000_000;

/// The GPU times of at most this many frames (the first ones rendered) enter the
/// printed medians, so their memory does not grow with the frame count.
pub const MAX_TIMED_FRAMES: usize = 1000;

/// Options of `pelage animate`.
#[derive(Clone, Debug, clap::Args)]
pub struct AnimateOpts {
    /// The scene and its overrides.
    #[command(flatten)]
    pub scene: SceneOpts,
    /// Number of frames of the animation, 1 to 1000000.
    #[arg(long, value_name = "N", default_value_t = 48,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_FRAMES)))]
    pub frames: u32,
    /// Frames per second of the animation: frame i shows the wind at i / FPS seconds,
    /// and the GIF plays at this rate.
    #[arg(long, value_name = "N", default_value_t = 24,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_FRAMES)))]
    pub fps: u32,
    /// Render only frames A to B-1 of the animation (half-open, 0 <= A < B <= N). They
    /// keep their index in the file names (frame_0040.png, ...) and are identical to
    /// the same frames of the full run; the GIF holds only them. A scene with
    /// `[dynamics]` is still simulated from frame 0 (frames before A are simulated,
    /// not drawn). Default: all frames.
    #[arg(long, value_name = "A..B", allow_hyphen_values = true)]
    pub range: Option<FrameRange>,
    /// Output folder for frame_0000.png, frame_0001.png, ... and wind.gif; created if
    /// missing. A run that fails removes the frames it wrote and writes no GIF.
    #[arg(long, value_name = "DIR", default_value = "out/wind")]
    pub out: PathBuf,
}

/// Frames `A..B` on the command line (half-open), each a frame index from 0 to
/// [`MAX_FRAMES`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange(pub u32, pub u32);

impl std::str::FromStr for FrameRange {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let (a, b) = text
            .split_once("..")
            .ok_or_else(|| format!("expected A..B, e.g. 40..80, not `{text}`"))?;
        let parse = |s: &str| match s.trim().parse::<u32>() {
            Ok(n) if n <= MAX_FRAMES => Ok(n),
            _ => Err(format!(
                "`{s}` in `{text}` is not a frame index (a whole number from 0 to {MAX_FRAMES})"
            )),
        };
        let (a, b) = (parse(a)?, parse(b)?);
        if a >= b {
            return Err(format!(
                "`{text}` is empty or reversed (A..B renders A to B-1, so A < B)"
            ));
        }
        Ok(Self(a, b))
    }
}

impl std::fmt::Display for FrameRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}..{}", self.0, self.1)
    }
}

/// The file name of frame `f`.
pub fn frame_name(f: u32) -> String {
    format!("frame_{f:04}.png")
}

/// Which frames to render and when each is: planned up front in constant memory.
#[derive(Clone, Debug, PartialEq)]
pub struct FramePlan {
    /// Frames of the whole animation.
    pub total: u32,
    /// Frames per second.
    pub fps: u32,
    /// The frames to render (global indices).
    pub range: Range<u32>,
}

impl FramePlan {
    /// Plans `frames` frames at `fps`, restricted to `range` when given.
    /// The error names `--frames` or `--range`.
    pub fn new(frames: u32, fps: u32, range: Option<FrameRange>) -> Result<Self, String> {
        if frames == 0 || frames > MAX_FRAMES {
            return Err(format!(
                "--frames {frames}: must be between 1 and {MAX_FRAMES}"
            ));
        }
        if fps == 0 {
            return Err("--fps 0: must be at least 1".into());
        }
        let range = match range {
            None => 0..frames,
            Some(FrameRange(a, b)) => {
                if b > frames {
                    return Err(format!(
                        "--range {a}..{b}: beyond --frames {frames} (B is at most {frames})"
                    ));
                }
                a..b
            }
        };
        Ok(Self {
            total: frames,
            fps,
            range,
        })
    }

    /// Seconds of the whole animation.
    pub fn duration(&self) -> f32 {
        self.total as f32 / self.fps as f32
    }

    /// The time of frame `f`, in seconds.
    pub fn time(&self, f: u32) -> f32 {
        f as f32 / self.fps as f32
    }

    /// Number of frames rendered.
    pub fn len(&self) -> u32 {
        self.range.end - self.range.start
    }

    /// The frames to render with their times, lazily.
    pub fn frames(&self) -> impl Iterator<Item = (u32, f32)> + '_ {
        self.range.clone().map(|f| (f, self.time(f)))
    }
}

/// Renders the animation, writes the frames and the GIF, prints the GPU time per pass
/// (median over the frames) and the wall clock of each stage submitted alone. Errors
/// about a value an option gave name the option.
pub fn run(opts: &AnimateOpts) -> Result<(), CliError> {
    animate(opts).map_err(|e| opts.scene.blame(e))
}

/// Refuses a frame name taken by a folder (or anything else that is not a file and
/// would make the frame fail), before any frame is drawn.
fn check_frame_names(out: &std::path::Path, plan: &FramePlan) -> Result<(), CliError> {
    for (f, _) in plan.frames() {
        let path = out.join(frame_name(f));
        if std::fs::metadata(&path).is_ok_and(|m| m.is_dir()) {
            return Err(CliError::Usage(format!(
                "--out {}: the name of frame {f}, {}, is taken by a folder; remove it or \
                 choose another --out",
                out.display(),
                path.display()
            )));
        }
    }
    Ok(())
}

/// The frames a run wrote (`range.start..next`), removed unless the run finishes:
/// a failed run leaves no partial sequence beside its missing GIF.
struct WrittenFrames<'a> {
    out: &'a std::path::Path,
    first: u32,
    next: u32,
    finished: bool,
}

impl Drop for WrittenFrames<'_> {
    fn drop(&mut self) {
        if !self.finished {
            for f in self.first..self.next {
                let _ = std::fs::remove_file(self.out.join(frame_name(f)));
            }
        }
    }
}

fn animate(opts: &AnimateOpts) -> Result<(), CliError> {
    let started = Instant::now();
    let plan = FramePlan::new(opts.frames, opts.fps, opts.range).map_err(CliError::Usage)?;
    let scene = opts.scene.scene()?;
    check_frame_names(&opts.out, &plan)?;
    let gpu = Gpu::headless()?;
    println!("adapter: {}", gpu.describe());
    notice_gl_compile(&gpu);
    let size = opts.scene.size;
    let mut renderer = Renderer::new(&gpu, &scene, size.width, size.height)?;

    // Animated preview, encoded frame by frame as they are rendered (a long
    // animation need not fit in memory), renamed into place at the end.
    let gif_path = opts.out.join("wind.gif");
    let mut gif = AtomicFile::create(&gif_path).map_err(OutputError::from)?;
    let encode_error = |e: image::ImageError| OutputError::Encode {
        path: gif_path.clone(),
        message: e.to_string(),
    };
    let delay = image::Delay::from_numer_denom_ms(1000, opts.fps);
    let bar = progress::bar(u64::from(plan.len()), "frames")?;
    let mut passes = Vec::new();
    let mut written = WrittenFrames {
        out: &opts.out,
        first: plan.range.start,
        next: plan.range.start,
        finished: false,
    };
    let mut dropped = DroppedWork::start(&renderer, &gpu)?;
    let encoded = (|| {
        let mut encoder = image::codecs::gif::GifEncoder::new_with_speed(&mut gif, 20);
        encoder
            .set_repeat(image::codecs::gif::Repeat::Infinite)
            .map_err(encode_error)?;
        // A simulation's frame depends on every frame before it: simulate from frame 0,
        // drawing nothing before the range.
        if scene.dynamics.is_some() {
            for f in 0..plan.range.start {
                let t = plan.time(f);
                renderer.advance(&gpu, t, &scene.camera.orbited(-0.5 * t / plan.duration()))?;
            }
        }
        for (f, t) in plan.frames() {
            // A slow orbit over the animation (a quarter of a radian in all), so the wind
            // is seen from several sides.
            let camera = scene.camera.orbited(-0.5 * t / plan.duration());
            renderer.render(&gpu, t, &camera)?;
            let stats = renderer.finish(&gpu)?;
            dropped.after_frame(&renderer, &gpu, f)?;
            if passes.len() < MAX_TIMED_FRAMES {
                passes.push(stats.by_label());
            }
            let image = renderer.image(&gpu)?;
            save_png(&image, &opts.out.join(frame_name(f)))?;
            written.next = f + 1;
            encoder
                .encode_frame(image::Frame::from_parts(image, 0, 0, delay))
                .map_err(encode_error)?;
            bar.inc(1);
        }
        Ok::<(), CliError>(())
    })();
    bar.finish_and_clear();
    if let Err(e) = encoded {
        // A write error (a full disk) says more than the encoder's wording of it. The
        // GIF is not committed: dropped, its temporary goes, and so do the frames.
        return Err(match gif.flush() {
            Err(write) => OutputError::Io {
                path: gif_path.clone(),
                source: write,
            }
            .into(),
            Ok(()) => e,
        });
    }
    gif.commit().map_err(OutputError::from)?;
    written.finished = true;

    println!(
        "wrote {} frames of {size} ({} strands x {} segments) to {}/frame_*.png and {}",
        plan.len(),
        renderer.frame().strands().params().roots.count,
        renderer.frame().strands().params().growth.segments,
        opts.out.display(),
        gif_path.display()
    );
    print_pass_times(
        &median_per_pass(&passes),
        &format!("GPU time per pass (median over {} frames):", passes.len()),
    );
    dropped.print(&scene.shade.transparency);
    // Cross-check that does not rely on the driver's timestamps: each stage alone, wall clock.
    let last = plan.time(plan.range.end - 1);
    println!("wall clock per stage, submitted alone (median of 5):");
    for (stage, ms) in renderer.stage_wall_times(&gpu, last, &scene.camera, 5)? {
        println!("  {stage:<28} {ms:9.3} ms");
    }
    println!("wall time: {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_plan_is_constant_memory_and_lazy() {
        // The largest animation plans in a few bytes, whatever its length: nothing is
        // reserved per frame.
        let plan = FramePlan::new(MAX_FRAMES, 24, None).unwrap();
        assert!(std::mem::size_of::<FramePlan>() <= 16);
        assert_eq!(plan.len(), MAX_FRAMES);
        let mut frames = plan.frames();
        assert_eq!(
            frames.size_hint(),
            (MAX_FRAMES as usize, Some(MAX_FRAMES as usize))
        );
        assert_eq!(frames.next(), Some((0, 0.0)));
        assert_eq!(frames.nth(47), Some((48, 2.0)));
    }

    #[test]
    fn frames_beyond_the_maximum_are_refused() {
        for frames in [0, MAX_FRAMES + 1, u32::MAX] {
            let e = FramePlan::new(frames, 24, None).unwrap_err();
            assert!(e.contains("--frames"), "{e}");
        }
    }

    #[test]
    fn a_range_keeps_global_times() {
        let full = FramePlan::new(120, 24, None).unwrap();
        let part = FramePlan::new(120, 24, Some(FrameRange(40, 80))).unwrap();
        assert_eq!(part.range, 40..80);
        assert_eq!(part.len(), 40);
        assert_eq!(part.duration(), full.duration());
        let full: Vec<_> = full.frames().skip(40).take(40).collect();
        assert_eq!(part.frames().collect::<Vec<_>>(), full);
    }

    #[test]
    fn bad_ranges_name_the_option() {
        for bad in [
            "5..5",
            "4..2",
            "x..3",
            "3",
            "1..2..3",
            "-1..2",
            "",
            "0..1000001",
        ] {
            let e = bad.parse::<FrameRange>().unwrap_err();
            assert!(e.contains(&format!("`{bad}`")), "{bad}: {e}");
        }
        let e = FramePlan::new(120, 24, Some(FrameRange(0, 121))).unwrap_err();
        assert!(e.starts_with("--range 0..121"), "{e}");
        assert_eq!("2..4".parse(), Ok(FrameRange(2, 4)));
    }
}
