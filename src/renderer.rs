//! The frame pipeline: strands, shadows, then shading into an offscreen image.

use pelage_gpu::{Gpu, GpuTimer, TimerReport, wgpu};
use pelage_scene::{Camera, CameraMatrices, Scene};
#[cfg(not(target_arch = "wasm32"))]
use pelage_shade::TargetViews;
use pelage_shade::{TargetFormat, TargetViewSet, Targets};
use pelage_strands::StrandFrame;

use crate::frame::{Frame, FrameTarget};

/// A [`Frame`] rendering into its own offscreen targets, with its timer, readback and
/// frames in flight.
#[derive(Debug)]
pub struct Renderer {
    /// The stages.
    frame: Frame,
    targets: Targets,
    timer: Option<GpuTimer>,
    /// The targets' views, made once (methods that sample the depth keep bind groups
    /// built for them).
    views: TargetViewSet,
    /// The timings of the newest frame read back.
    last_stats: TimerReport,
    /// Frames submitted by `render` the GPU may not have finished.
    in_flight: std::collections::VecDeque<wgpu::SubmissionIndex>,
}

/// Frames [`Renderer::render`] lets the GPU fall behind by before it waits.
pub(crate) const FRAMES_IN_FLIGHT: usize = 2;

impl Renderer {
    /// Uploads the mesh, samples the roots (or uploads the groom), builds every pipeline
    /// and a `width` x `height` target in the default formats
    /// ([`TargetFormat::for_params`]: sRGB colour, 32-bit depth, the shade sample count).
    pub fn new(gpu: &Gpu, scene: &Scene, width: u32, height: u32) -> crate::Result<Self> {
        Self::with_format(
            gpu,
            scene,
            width,
            height,
            &TargetFormat::for_params(&scene.shade),
        )
    }

    /// [`Renderer::new`] with targets of `format`: an HDR colour (`Rgba16Float`, linear
    /// light, for the caller's tone mapping), another depth format, reverse-Z (the
    /// renderer then projects with [`Camera::matrices_reverse_z`]).
    pub fn with_format(
        gpu: &Gpu,
        scene: &Scene,
        width: u32,
        height: u32,
        format: &TargetFormat,
    ) -> crate::Result<Self> {
        // The stages first: a scene they refuse allocates no target.
        let frame = Frame::new(gpu, scene, &FrameTarget::new(*format, width, height))?;
        let targets = Targets::with_format(gpu, width, height, format)?;
        let timer = GpuTimer::new(gpu, 64)?;
        let views = targets.view_set();
        Ok(Self {
            frame,
            targets,
            timer,
            views,
            in_flight: Default::default(),
            last_stats: TimerReport::default(),
        })
    }

    /// Advances stage 1 to time `t` without drawing: the mesh's motion, the colliders
    /// and the level of detail as [`Renderer::render`] sets them for `t` and `camera`,
    /// then only stage 1 recorded and submitted (no shadows, no shading, no timestamp
    /// queries, nothing read back). For a simulation (`Scene::dynamics`) this steps
    /// the hair to `t` as a rendered frame would, so that later frames are those of a
    /// renderer that drew this one, at a fraction of the cost; for the stateless
    /// methods it is wasted work. Like `render`, it returns without waiting for the GPU
    /// (at most two frames queued).
    pub fn advance(&mut self, gpu: &Gpu, t: f32, camera: &Camera) -> crate::Result<()> {
        let matrices = self.matrices(camera)?;
        self.frame.prepare_strands(&gpu.queue, t, Some(&matrices))?;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        self.frame.record_strands(&mut encoder, None)?;
        let index = gpu.submit([encoder.finish()])?;
        self.queue_frame(gpu, index)
    }

    /// `camera`'s view and projection for the renderer's targets (reverse-Z when their
    /// depth is).
    fn matrices(&self, camera: &Camera) -> crate::Result<CameraMatrices> {
        camera.validate()?;
        let (width, height) = (self.targets.width, self.targets.height);
        Ok(match self.targets.format.reverse_z {
            true => camera.matrices_reverse_z(width, height),
            false => camera.matrices(width, height),
        })
    }

    /// Remembers a submitted frame; beyond [`FRAMES_IN_FLIGHT`] waits for the oldest,
    /// as a swap chain would hold the CPU back.
    fn queue_frame(&mut self, gpu: &Gpu, index: wgpu::SubmissionIndex) -> crate::Result<()> {
        self.in_flight.push_back(index);
        while self.in_flight.len() > FRAMES_IN_FLIGHT {
            if let Some(oldest) = self.in_flight.pop_front() {
                pelage_gpu::wait(&gpu.device, Some(oldest))?;
            }
        }
        Ok(())
    }

    /// Prepares every stage for time `t` and `camera` ([`Frame::prepare`]) and records
    /// the frame into the renderer's targets, with the renderer's timestamp queries when
    /// `timed`.
    fn record_timed(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        t: f32,
        camera: &Camera,
        timed: bool,
    ) -> crate::Result<StrandFrame> {
        let matrices = self.matrices(camera)?;
        let frame = self.frame.prepare(&gpu.queue, t, &matrices)?;
        let timer = self.timer.as_mut().filter(|_| timed);
        self.frame.record(encoder, &self.views.views(), timer)?;
        Ok(frame)
    }

    /// Grows the strands for time `t`, shadows them and draws them from `camera`:
    /// records the frame ([`Frame::prepare`], [`Frame::record`]), submits it, takes the frame's
    /// after-submit step and returns without waiting for the GPU. The GPU times
    /// returned are those of the newest earlier frame the GPU has finished since the
    /// last call (read back a frame or more late; empty when none has finished yet, or
    /// without timestamp queries); [`Renderer::finish`] waits for this frame's.
    pub fn render(&mut self, gpu: &Gpu, t: f32, camera: &Camera) -> crate::Result<TimerReport> {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        self.record_timed(gpu, &mut encoder, t, camera, true)?;
        if let Some(timer) = &self.timer {
            timer.resolve(&mut encoder);
        }
        let index = gpu.submit([encoder.finish()])?;
        self.frame.after_submit(gpu)?;
        // At most FRAMES_IN_FLIGHT frames queued: beyond that the CPU waits for the
        // oldest, as a swap chain would hold it back.
        self.queue_frame(gpu, index)?;
        let Some(timer) = &mut self.timer else {
            return Ok(TimerReport::default());
        };
        timer.submitted(gpu)?;
        Ok(match timer.try_read(gpu)? {
            Some(report) => {
                self.last_stats = report;
                self.last_stats.clone()
            }
            None => TimerReport::default(),
        })
    }

    /// Waits for the GPU to finish every frame submitted so far and returns the GPU
    /// time of the last one per pass (empty without timestamp queries).
    pub fn finish(&mut self, gpu: &Gpu) -> crate::Result<TimerReport> {
        if let Some(report) = match &mut self.timer {
            Some(timer) => timer.wait(gpu)?,
            None => None,
        } {
            self.last_stats = report;
        }
        pelage_gpu::wait(&gpu.device, None)?;
        self.in_flight.clear();
        gpu.check()?;
        Ok(self.last_stats.clone())
    }

    /// Wall-clock time of each stage submitted on its own and waited for, median of
    /// `repeats` runs, in milliseconds: an upper bound on the stage's GPU time that does
    /// not rely on the driver's timestamps. (lavapipe in Mesa 22.3 reports about 0.05 ms
    /// for a compute pass once any render pass has run on the device, whatever the pass
    /// costs; this is the cross-check.) The stages are `strands`, `shadow` (each light's
    /// shadow and hand-over; left out without shadows) and `shade` (the volume grid, which
    /// a frame records with the shadows, and the hair pass). Not on the web (`wasm32`),
    /// where nothing may wait for the GPU and there is no clock to time it with.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn stage_wall_times(
        &mut self,
        gpu: &Gpu,
        t: f32,
        camera: &Camera,
        repeats: usize,
    ) -> crate::Result<Vec<(String, f64)>> {
        let matrices = self.matrices(camera)?;
        self.frame.prepare(&gpu.queue, t, &matrices)?;
        let (color, resolve) = self.targets.color_views();
        let depth = self.targets.depth_view();
        let frame = &self.frame;
        let mut stages = vec![(
            "strands".to_string(),
            time_alone(gpu, repeats, |e| frame.record_strands(e, None))?,
        )];
        if frame.shadowed_lights() > 0 {
            let ms = time_alone(gpu, repeats, |e| frame.record_stage2(e))?;
            stages.push(("shadow".to_string(), ms));
        }
        let depth_sampled = self.targets.depth_sampled_view();
        let views = TargetViews {
            depth_sampled: depth_sampled.as_ref(),
            ..self.targets.views(&color, resolve.as_ref(), &depth)
        };
        // The shade stage: the volume grid (recorded with the shadows in a frame) and the
        // hair pass.
        let shade = time_alone(gpu, repeats, |e| {
            frame.record_grid(e)?;
            frame.record_shade(e, &views, None)
        })?;
        stages.push(("shade".to_string(), shade));
        Ok(stages)
    }

    /// The last rendered image as an [`image::RgbaImage`]: [`Renderer::rgba8`]'s pixels
    /// (feature `png`).
    #[cfg(feature = "png")]
    pub fn image(&self, gpu: &Gpu) -> crate::Result<image::RgbaImage> {
        let (width, height, data) = self.rgba8(gpu)?;
        image::RgbaImage::from_raw(width, height, data).ok_or_else(|| {
            crate::Error::Gpu(pelage_gpu::GpuError::Map(
                "colour readback has the wrong size for its image".into(),
            ))
        })
    }

    /// The last rendered image as sRGB RGBA8, `(width, height, pixels)` with rows top to
    /// bottom and no padding: an `Rgba8UnormSrgb` target as it is, a `Bgra8UnormSrgb`
    /// one swizzled, an `Rgba16Float` one clamped to [0, 1] and sRGB-encoded (no tone
    /// mapping beyond the clamp); other formats are an error (bind
    /// [`Renderer::color_texture`] instead). A frame with any pixel that is not opaque
    /// was never drawn (every frame clears to an opaque background) and is
    /// [`Error::Undrawn`](crate::Error::Undrawn), never a blank image.
    pub fn rgba8(&self, gpu: &Gpu) -> crate::Result<(u32, u32, Vec<u8>)> {
        let mut data = self.targets.read_color(gpu)?;
        data.data = match self.targets.format.color {
            wgpu::TextureFormat::Rgba8UnormSrgb => data.data,
            wgpu::TextureFormat::Bgra8UnormSrgb => {
                for px in data.data.chunks_exact_mut(4) {
                    px.swap(0, 2);
                }
                data.data
            }
            wgpu::TextureFormat::Rgba16Float => data
                .data
                .chunks_exact(2)
                .enumerate()
                .map(|(i, h)| {
                    let v =
                        pelage_gpu::f16_to_f32(u16::from_le_bytes([h[0], h[1]])).clamp(0.0, 1.0);
                    if i % 4 == 3 {
                        (v * 255.0).round() as u8
                    } else {
                        linear_to_srgb8(v)
                    }
                })
                .collect(),
            other => {
                return Err(crate::Error::Gpu(pelage_gpu::GpuError::Map(format!(
                    "no conversion to RGBA8 for a {other:?} target; read Renderer::color_texture yourself"
                ))));
            }
        };
        // Every frame clears to an opaque background and every method blends over it
        // keeping alpha 1: a pixel that is not opaque was never drawn.
        let transparent = data.data.chunks_exact(4).filter(|p| p[3] != 255).count();
        if transparent > 0 {
            return Err(crate::Error::Undrawn {
                transparent,
                pixels: data.data.len() / 4,
                adapter: gpu.describe(),
            });
        }
        Ok((data.width, data.height, data.data))
    }

    /// The stages, for an engine that records them itself into its own targets (see
    /// [`Frame`]).
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// The stages, to change in place ([`Frame::update`], [`Frame::set_lights`]).
    pub fn frame_mut(&mut self) -> &mut Frame {
        &mut self.frame
    }

    /// The final single-sample colour target (the renderer's [`TargetFormat`], width x height, usable as `TEXTURE_BINDING` and `COPY_SRC`): bind it to
    /// draw the last frame on screen without reading it back.
    pub fn color_texture(&self) -> &wgpu::Texture {
        &self.targets.color
    }
}

/// Linear light in [0, 1] as an 8-bit sRGB value (the sRGB transfer function).
fn linear_to_srgb8(v: f32) -> u8 {
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// Median wall-clock milliseconds of `repeats` submissions of what `encode` records, each waited for.
#[cfg(not(target_arch = "wasm32"))]
fn time_alone(
    gpu: &Gpu,
    repeats: usize,
    encode: impl Fn(&mut wgpu::CommandEncoder) -> crate::Result<()>,
) -> crate::Result<f64> {
    let mut times = Vec::with_capacity(repeats.max(1));
    for _ in 0..repeats.max(1) {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encode(&mut encoder)?;
        let command = encoder.finish();
        let started = std::time::Instant::now();
        gpu.submit_and_wait([command])?;
        times.push(started.elapsed().as_secs_f64() * 1e3);
    }
    times.sort_by(f64::total_cmp);
    Ok(times[times.len() / 2])
}
