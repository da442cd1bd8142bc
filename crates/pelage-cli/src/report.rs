//! Printing GPU times, the work a frame dropped, and notices.

use pelage::Renderer;
use pelage::gpu::{Gpu, wgpu};
use pelage::scene::Transparency;
use pelage::shade::OitStats;

/// Prints `title` and one line per pass (label, milliseconds) and their total; says so
/// when there are none (the adapter has no timestamp queries).
pub fn print_pass_times(passes: &[(String, f64)], title: &str) {
    if passes.is_empty() {
        println!("GPU time per pass: n/a (the adapter has no timestamp queries)");
        return;
    }
    println!("{title}");
    for (label, ms) in passes {
        println!("  {label:<28} {ms:9.3} ms");
    }
    let total: f64 = passes.iter().map(|(_, ms)| ms).sum();
    println!("  {:<28} {total:9.3} ms", "frame");
}

/// The median of each pass over frames: `frames` holds each frame's (label, ms) list;
/// labels keep the order they first appeared in.
pub fn median_per_pass(frames: &[Vec<(String, f64)>]) -> Vec<(String, f64)> {
    let mut per_pass: Vec<(String, Vec<f64>)> = Vec::new();
    for passes in frames {
        for (label, ms) in passes {
            match per_pass.iter_mut().find(|(l, _)| l == label) {
                Some((_, v)) => v.push(*ms),
                None => per_pass.push((label.clone(), vec![*ms])),
            }
        }
    }
    per_pass
        .into_iter()
        .map(|(label, mut v)| {
            v.sort_by(f64::total_cmp);
            let median = v.get(v.len() / 2).copied().unwrap_or(f64::NAN);
            (label, median)
        })
        .collect()
}

/// Work a run's frames dropped because a pool of stage 3 was full (the strand
/// rasterizer's segment references, the A-buffer's and DBK's list nodes): counted frame
/// by frame from `HairPass::stats` (through `Renderer::frame`), reported once at the end
/// of the run
/// with the scene key to raise ([`DroppedWork::report`]).
#[derive(Clone, Debug, Default)]
pub struct DroppedWork {
    /// The counters after the last frame checked (they count since the method was built).
    last: OitStats,
    /// Frames checked.
    frames: u64,
    /// Frames that dropped work.
    dropped_frames: u64,
    /// The first frame that dropped work (the caller's frame number).
    first: Option<u32>,
    /// What was dropped, in all.
    dropped: u64,
    /// The most one frame (or slice) needed.
    peak: u64,
    /// The pool's size before the first frame (the strand rasterizer's grows after a
    /// frame that overflowed it).
    capacity: u64,
}

impl DroppedWork {
    /// Starts counting: reads the counters of `renderer` before its first frame.
    pub fn start(renderer: &Renderer, gpu: &Gpu) -> pelage::Result<Self> {
        let last = renderer.frame().hair_pass().stats(gpu)?;
        Ok(Self {
            last,
            capacity: last.capacity,
            ..Self::default()
        })
    }

    /// Reads the counters after `frame` (waits for the GPU) and counts what it dropped.
    pub fn after_frame(
        &mut self,
        renderer: &Renderer,
        gpu: &Gpu,
        frame: u32,
    ) -> pelage::Result<()> {
        let stats = renderer.frame().hair_pass().stats(gpu)?;
        self.frames += 1;
        let dropped = stats.dropped.saturating_sub(self.last.dropped);
        if dropped > 0 {
            self.dropped_frames += 1;
            self.first.get_or_insert(frame);
            self.dropped += dropped;
            self.peak = self.peak.max(stats.peak_nodes);
        }
        self.last = stats;
        Ok(())
    }

    /// What was dropped and the scene key to raise, or `None` when nothing was.
    /// `transparency` is the method the frames were drawn with.
    pub fn report(&self, transparency: &Transparency) -> Option<String> {
        let first = self.first?;
        let frames = if self.frames == 1 {
            "the frame".to_string()
        } else {
            format!(
                "{} of {} frames (the first: frame {first})",
                self.dropped_frames, self.frames
            )
        };
        // The factor the pool is short by, from the largest request seen.
        let factor = self.peak as f64 / self.capacity.max(1) as f64;
        let (what, key, now) = match *transparency {
            Transparency::StrandRaster { pool, .. } => (
                "segment references found the strand rasterizer's pool full",
                "pool",
                pool,
            ),
            Transparency::ABuffer {
                nodes_per_pixel, ..
            }
            | Transparency::Dbk {
                nodes_per_pixel, ..
            } => (
                "fragments found the linked-list node pool full",
                "nodes_per_pixel",
                nodes_per_pixel,
            ),
            _ => ("fragments found a pool full", "its pool size", f32::NAN),
        };
        let advice = if factor > 1.0 && now.is_finite() {
            format!(
                "raise [shade.transparency] {key} from {now} to about {:.3} (a frame \
                 needed {} where {} fit)",
                f64::from(now) * factor * 1.05,
                self.peak,
                self.capacity
            )
        } else {
            format!("raise [shade.transparency] {key} (now {now})")
        };
        Some(format!(
            "warning: {} {what} in {frames}: that hair is missing from the picture; {advice}",
            self.dropped
        ))
    }

    /// Prints [`DroppedWork::report`] to stderr, if anything was dropped.
    pub fn print(&self, transparency: &Transparency) {
        if let Some(line) = self.report(transparency) {
            eprintln!("{line}");
        }
    }
}

/// The line printed before building the pipelines on the GL backend (a cold Mesa
/// shader cache takes about a minute and half a gigabyte on llvmpipe for the strand
/// rasterizer, with nothing else to say why).
pub const GL_COMPILE_NOTICE: &str =
    "compiling shaders for the GL backend; the first run can take a minute";

/// Prints [`GL_COMPILE_NOTICE`] to stderr when `gpu` runs on GL.
pub fn notice_gl_compile(gpu: &Gpu) {
    if gpu
        .adapter_info
        .as_ref()
        .is_some_and(|info| info.backend == wgpu::Backend::Gl)
    {
        eprintln!("{GL_COMPILE_NOTICE}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dropped_work_names_the_key_to_raise() {
        let mut work = DroppedWork::default();
        assert!(work.report(&Transparency::Opaque).is_none());
        work.frames = 3;
        work.dropped_frames = 1;
        work.first = Some(7);
        work.dropped = 1234;
        work.peak = 4000;
        work.capacity = 1000;
        let raster = Transparency::by_name("strand_raster").unwrap();
        let line = work.report(&raster).unwrap();
        for word in [
            "1234",
            "1 of 3 frames",
            "frame 7",
            "[shade.transparency] pool",
            "4000",
        ] {
            assert!(line.contains(word), "{word}: {line}");
        }
        let a_buffer = Transparency::by_name("a_buffer").unwrap();
        let line = work.report(&a_buffer).unwrap();
        assert!(
            line.contains("[shade.transparency] nodes_per_pixel"),
            "{line}"
        );
    }
}
