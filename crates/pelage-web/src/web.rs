//! The page's side of the demo: a WebGPU device with the default limits, the canvas,
//! and a [`pelage::Renderer`] whose frame is copied into the canvas's texture.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use pelage::gpu::{Gpu, wgpu};
use pelage::scene::Resampled;
use pelage::{Error, Renderer, scene::Scene};

/// Frames the demo lets the GPU fall behind by before it skips an animation frame (as
/// many as pelage's `Renderer::render` queues before it waits, which the web must never).
const FRAMES_IN_FLIGHT: usize = 2;
use wasm_bindgen::prelude::*;

use crate::{DemoError, Settings};

/// The optional feature the demo asks for when the browser offers it: timestamp
/// queries in passes, for the GPU time per pass. Nothing else beyond WebGPU's defaults.
const FEATURES: wgpu::Features = wgpu::Features::TIMESTAMP_QUERY;

/// The canvas format: `rgba8unorm`, which every browser's canvas takes; the renderer's
/// `Rgba8UnormSrgb` target is copied into it byte for byte (the formats differ only in
/// their sRGB view, which a texture copy allows), so the canvas shows the sRGB values
/// pelage wrote, as the native PNG holds them.
const CANVAS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

impl From<DemoError> for JsValue {
    fn from(e: DemoError) -> Self {
        JsError::new(&e.to_string()).into()
    }
}

/// The demo: a device, the canvas and the renderer of the current [`Settings`].
#[wasm_bindgen]
pub struct Demo {
    gpu: Gpu,
    surface: wgpu::Surface<'static>,
    width: u32,
    height: u32,
    settings: Settings,
    /// The groom shown instead of the creature, once one was loaded.
    groom: Option<Resampled>,
    scene: Scene,
    renderer: Renderer,
    /// The newest GPU time per pass the renderer read back (a frame or more late).
    passes: Vec<(String, f64)>,
    /// Errors the device raised outside any scope since the last frame.
    errors: Arc<Mutex<Vec<String>>>,
    /// Frames submitted that the GPU has not finished (`on_submitted_work_done`
    /// answers in the event loop): the web's form of the renderer's wait, which is a
    /// no-op there.
    in_flight: Arc<AtomicUsize>,
}

#[wasm_bindgen]
impl Demo {
    /// Asks the browser for a WebGPU adapter and a device with the default limits
    /// (and timestamp queries if offered), configures `canvas` (its `width` x `height`
    /// attributes are the frame's size) and builds the renderer of `strands`, `wind`
    /// and `method`.
    pub async fn create(
        canvas: web_sys::HtmlCanvasElement,
        strands: u32,
        wind: f32,
        method: String,
    ) -> Result<Demo, JsValue> {
        let settings = Settings {
            strands,
            wind,
            method,
        };
        let scene = crate::scene(&settings)?;
        let (width, height) = (canvas.width(), canvas.height());
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::BROWSER_WEBGPU,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let surface = instance
            .create_surface(wgpu::SurfaceTarget::Canvas(canvas))
            .map_err(|e| DemoError::Web(format!("the canvas: {e}")))?;
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface: Some(&surface),
                apply_limit_buckets: false,
            })
            .await
            .map_err(|e| DemoError::Web(format!("no WebGPU adapter: {e}")))?;
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("pelage web"),
                required_features: adapter.features() & FEATURES,
                required_limits: wgpu::Limits::default(),
                ..Default::default()
            })
            .await
            .map_err(|e| DemoError::Web(format!("no WebGPU device: {e}")))?;
        // Errors outside a scope (pelage pushes none on the web): to the console, where
        // the browser test looks, and to the next frame's result.
        let errors = Arc::new(Mutex::new(Vec::new()));
        let sink = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            let message = format!("WebGPU error: {e}");
            web_sys::console::error_1(&message.clone().into());
            if let Ok(mut list) = sink.lock() {
                list.push(message);
            }
        }));
        let mut config = surface
            .get_default_config(&adapter, width, height)
            .ok_or_else(|| DemoError::Web("the canvas cannot be drawn by this adapter".into()))?;
        config.format = CANVAS_FORMAT;
        config.usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_DST;
        config.alpha_mode = wgpu::CompositeAlphaMode::Opaque;
        config.view_formats = Vec::new();
        surface.configure(&device, &config);
        let gpu = Gpu::from_device(device, queue, Some(adapter.get_info()));
        let renderer = Renderer::new(&gpu, &scene, width, height).map_err(DemoError::from)?;
        Ok(Demo {
            gpu,
            surface,
            width,
            height,
            settings,
            groom: None,
            scene,
            renderer,
            passes: Vec::new(),
            errors,
            in_flight: Arc::new(AtomicUsize::new(0)),
        })
    }

    /// The transparency methods this device can run (pelage's
    /// [`supported_methods`](pelage::shade::supported_methods)), comma-separated.
    pub fn methods(&self) -> String {
        pelage::shade::supported_methods(&self.gpu).join(",")
    }

    /// Why each known method this device cannot run refuses: pelage's own error,
    /// one line each (empty when every method runs).
    pub fn refusals(&self) -> String {
        let supported = pelage::shade::supported_methods(&self.gpu);
        let mut lines = Vec::new();
        for name in crate::methods() {
            if supported.contains(&name) {
                continue;
            }
            let settings = Settings {
                strands: 100,
                method: name.into(),
                ..self.settings.clone()
            };
            let outcome = crate::scene(&settings)
                .and_then(|scene| Ok(Renderer::new(&self.gpu, &scene, 8, 8)?));
            if let Err(e) = outcome {
                lines.push(format!("{name}: {e}"));
            }
        }
        lines.join("\n")
    }

    /// The adapter, as pelage names it.
    pub fn adapter(&self) -> String {
        self.gpu.describe()
    }

    /// Whether the device times its passes.
    pub fn has_timestamps(&self) -> bool {
        self.gpu.has_timestamps()
    }

    /// Applies the controls: the wind in place, a new renderer for a new strand count or
    /// method. A refused setting keeps the renderer drawing what it drew. While a groom
    /// is shown the strand count must be the groom's ([`Demo::strands`]).
    pub fn set(&mut self, strands: u32, wind: f32, method: String) -> Result<(), JsValue> {
        let settings = Settings {
            strands,
            wind,
            method,
        };
        let scene = match &self.groom {
            Some(groom) => crate::groom_scene(groom, &settings)?,
            None => crate::scene(&settings)?,
        };
        self.show(settings, scene)
    }

    /// Shows the groom file `bytes` (`.hair` or `.tfx`, by `name`'s extension) instead
    /// of the creature, with the current wind and method ([`crate::groom_scene`]), and
    /// answers what it shows: `name: N strands x S segments`. A file that cannot be read
    /// or drawn is an error naming it, and the page keeps drawing what it drew.
    pub fn load_groom(&mut self, bytes: Vec<u8>, name: String) -> Result<String, JsValue> {
        let groom = crate::read_groom(bytes, &name)?;
        let settings = Settings {
            strands: groom.strands,
            ..self.settings.clone()
        };
        let scene = crate::groom_scene(&groom, &settings)?;
        let said = format!(
            "{name}: {} strands x {} segments{}",
            groom.strands,
            groom.segments,
            match groom.skipped {
                0 => String::new(),
                n => format!(" ({n} degenerate strands skipped)"),
            }
        );
        let previous = self.groom.replace(groom);
        if let Err(e) = self.show(settings, scene) {
            self.groom = previous;
            return Err(e);
        }
        Ok(said)
    }

    /// Goes back to the creature with `strands` strands (and the current wind and
    /// method).
    pub fn show_creature(&mut self, strands: u32) -> Result<(), JsValue> {
        let settings = Settings {
            strands,
            ..self.settings.clone()
        };
        let scene = crate::scene(&settings)?;
        let previous = self.groom.take();
        if let Err(e) = self.show(settings, scene) {
            self.groom = previous;
            return Err(e);
        }
        Ok(())
    }

    /// The strands drawn: the groom's when one is shown, else the slider's.
    pub fn strands(&self) -> u32 {
        self.settings.strands
    }

    /// Whether a groom is shown (the strand slider does not apply).
    pub fn has_groom(&self) -> bool {
        self.groom.is_some()
    }

    /// Takes `settings` and `scene`: the renderer updated in place, or rebuilt when the
    /// change shapes its buffers (a refused scene keeps the old renderer and settings).
    fn show(&mut self, settings: Settings, scene: Scene) -> Result<(), JsValue> {
        match self.renderer.frame_mut().update(&self.gpu, &scene) {
            Ok(()) => {}
            Err(Error::NeedsRebuild(_)) => {
                self.renderer = Renderer::new(&self.gpu, &scene, self.width, self.height)
                    .map_err(DemoError::from)?;
                self.passes.clear();
            }
            Err(e) => return Err(DemoError::from(e).into()),
        }
        self.settings = settings;
        self.scene = scene;
        self.take_errors()
    }

    /// Draws the frame of time `t` (seconds) and shows it in the canvas, and answers
    /// true; or, while [`FRAMES_IN_FLIGHT`] frames are still on the GPU, draws nothing
    /// and answers false (a slow GPU, SwiftShader's among them, would otherwise queue
    /// a frame per animation frame without bound). Submits and returns; nothing waits.
    pub fn frame(&mut self, t: f32) -> Result<bool, JsValue> {
        if self.in_flight.load(Ordering::Acquire) >= FRAMES_IN_FLIGHT {
            self.take_errors()?;
            return Ok(false);
        }
        let stats = self
            .renderer
            .render(&self.gpu, t, &self.scene.camera)
            .map_err(DemoError::from)?;
        if !stats.scopes.is_empty() {
            self.passes = stats.by_label();
        }
        let texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(texture)
            | wgpu::CurrentSurfaceTexture::Suboptimal(texture) => texture,
            other => {
                return Err(
                    DemoError::Web(format!("the canvas gave no texture: {other:?}")).into(),
                );
            }
        };
        let mut encoder = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("pelage web: to the canvas"),
            });
        encoder.copy_texture_to_texture(
            self.renderer.color_texture().as_image_copy(),
            texture.texture.as_image_copy(),
            wgpu::Extent3d {
                width: self.width,
                height: self.height,
                depth_or_array_layers: 1,
            },
        );
        self.gpu.queue.submit([encoder.finish()]);
        self.gpu.queue.present(texture);
        self.in_flight.fetch_add(1, Ordering::AcqRel);
        let done = self.in_flight.clone();
        self.gpu.queue.on_submitted_work_done(move || {
            done.fetch_sub(1, Ordering::AcqRel);
        });
        self.take_errors()?;
        Ok(true)
    }

    /// The newest GPU time per pass, one `label<TAB>milliseconds` line each; empty
    /// before the first timings arrive or without timestamp queries. Takes the
    /// timings that arrived since the last frame ([`Renderer::finish`], which on the web
    /// collects what the browser has answered and waits for nothing).
    pub fn timings(&mut self) -> Result<String, JsValue> {
        let stats = self.renderer.finish(&self.gpu).map_err(DemoError::from)?;
        if !stats.scopes.is_empty() {
            self.passes = stats.by_label();
        }
        Ok(self
            .passes
            .iter()
            .map(|(label, ms)| format!("{label}\t{ms:.3}"))
            .collect::<Vec<_>>()
            .join("\n"))
    }
}

impl Demo {
    /// The first error the device raised since the last call, as the frame's error.
    fn take_errors(&mut self) -> Result<(), JsValue> {
        let first = match self.errors.lock() {
            Ok(mut list) => std::mem::take(&mut *list).into_iter().next(),
            Err(_) => Some("the error list was poisoned".to_string()),
        };
        match first {
            Some(message) => Err(DemoError::Web(message).into()),
            None => Ok(()),
        }
    }
}
