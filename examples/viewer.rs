//! An interactive viewer: pelage's fur in a window, every parameter and method in egui panels.
//!
//! ```text
//! cargo run --release --example viewer -- [--scene FILE.toml] [--size WxH]
//!                                         [--frames N] [--screenshot FILE.png]
//!                                         [--time-changes]
//! ```
//!
//! Mouse: left drag orbits, right or middle drag pans, the wheel zooms.
//! Keys: space plays or pauses the wind, F12 or P saves the window (panels included) as
//! `out/viewer/shot_NNN.png`, Escape quits.
//!
//! Flags: `--scene` loads a TOML scene file (see `scenes/default.toml`) instead of the
//! built-in creature; `--size` sets the window's inner size in pixels (default 1280x800);
//! `--frames N` renders N frames (the wind advancing 1/24 s each), saves the whole window
//! to `--screenshot FILE.png` (default `out/viewer/viewer.png`) and exits: the automated check.
//! `--time-changes` scripts a change of each uniform-only parameter (wind, hair colour, key
//! light, shading), once through a new renderer and once in place, prints the wall time
//! from the change to the presented frame (the GPU idle) for both, and exits.
//!
//! Each frame: pelage renders offscreen at the window's size ([`Renderer`]); a fullscreen
//! triangle copies its colour into a composition texture, egui draws its panels over it, and
//! the same triangle copies the composition to the window's surface. A changed parameter
//! goes to [`Frame::update`](pelage::Frame::update), which writes what lives in uniforms or small buffers
//! (wind, hair colour, lights, shading) in place, at once, even while a slider is dragged;
//! a change it answers with [`pelage::Error::NeedsRebuild`] (strand count, methods, ...) rebuilds the
//! renderer once the mouse button is up. If pelage refuses the parameters the panel says
//! why and the last good renderer keeps drawing.

use std::error::Error;
use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use egui::{CollapsingHeader, Slider};
use glam::Vec3;
use pelage::gpu::TimerReport;
use pelage::gpu::{Gpu, ShaderSources, wgpu};
use pelage::scene::sigma_a_from_color;
use pelage::scene::{
    Absorption, ChiangParams, DEFAULT_MELANIN_REDNESS, DynamicsParams, MAX_MELANIN, ShadowParams,
    Transparency, WindParams,
};
use pelage::scene::{Camera, HairParams, HairType, Light, Named, ShadeParams, ShadingModel};
use pelage::{Renderer, scene::Scene};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

/// The wind time wraps around after this many seconds.
const T_MAX: f32 = 60.0;

/// The viewer's own shader (`examples/wgsl/present/blit.wgsl`); tests/shaders.rs checks
/// that folder.
static VIEWER_SHADERS: ShaderSources =
    pelage::gpu::wgsl_sources!(in "examples/wgsl"; "present/blit.wgsl");

struct Args {
    scene: Option<PathBuf>,
    size: (u32, u32),
    frames: Option<u32>,
    screenshot: PathBuf,
    time_changes: bool,
}

fn parse_args() -> Result<Args, String> {
    let (mut scene, mut size, mut frames) = (None, (1280, 800), None);
    let mut time_changes = false;
    let mut screenshot = PathBuf::from("out/viewer/viewer.png");
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or(format!("{flag} needs a value"));
        match flag.as_str() {
            "--scene" => scene = Some(PathBuf::from(value()?)),
            "--screenshot" => screenshot = PathBuf::from(value()?),
            "--time-changes" => time_changes = true,
            "--frames" => frames = Some(value()?.parse::<u32>().map_err(|e| e.to_string())?.max(1)),
            "--size" => {
                let v = value()?;
                let wh = v
                    .split_once('x')
                    .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)));
                size = wh
                    .filter(|&(w, h)| w > 0 && h > 0)
                    .ok_or(format!("--size {v}: want WxH"))?;
            }
            _ => {
                return Err(format!(
                    "unknown argument {flag}; see the top of examples/viewer.rs"
                ));
            }
        }
    }
    Ok(Args {
        scene,
        size,
        frames,
        screenshot,
        time_changes,
    })
}

/// The orbit camera: yaw and pitch around a target, at a distance; the lens is the scene's.
struct Orbit {
    base: Camera,
    target: Vec3,
    yaw: f32,
    pitch: f32,
    distance: f32,
}

impl Orbit {
    fn new(camera: &Camera) -> Self {
        let d = camera.eye - camera.target;
        let distance = d.length().max(1e-3);
        let (yaw, pitch) = (d.x.atan2(d.z), (d.y / distance).clamp(-1.0, 1.0).asin());
        Self {
            base: camera.clone(),
            target: camera.target,
            yaw,
            pitch,
            distance,
        }
    }

    fn camera(&self) -> Camera {
        let ((sy, cy), (sp, cp)) = (self.yaw.sin_cos(), self.pitch.sin_cos());
        let eye = self.target + self.distance * Vec3::new(cp * sy, sp, cp * cy);
        Camera {
            eye,
            target: self.target,
            ..self.base.clone()
        }
    }

    /// The mouse moved by (`dx`, `dy`) pixels with `button` held, in a window `height` high.
    fn drag(&mut self, button: MouseButton, dx: f32, dy: f32, height: f32) {
        if button == MouseButton::Left {
            self.yaw -= dx * 0.008;
            self.pitch = (self.pitch + dy * 0.008).clamp(-1.5, 1.5);
            return;
        }
        // Pan in the view plane: the point under the mouse stays under it.
        let camera = self.camera();
        let forward = (camera.target - camera.eye).normalize();
        let right = forward.cross(Vec3::Y).normalize();
        let pixel = 2.0 * self.distance * (camera.fov_y * 0.5).tan() / height.max(1.0);
        self.target += (right.cross(forward) * dy - right * dx) * pixel;
    }

    fn zoom(&mut self, steps: f32) {
        let (near, far) = (self.base.near * 4.0, self.base.far * 0.7);
        self.distance = (self.distance * 0.9f32.powf(steps)).clamp(near, far);
    }
}

/// Every scene parameter the panels edit; a change goes to [`Frame::update`](pelage::Frame::update).
#[derive(Clone, PartialEq)]
struct Controls {
    hair: HairParams,
    wind_on: bool,
    /// Strand dynamics (`SimulateStrands`) instead of the stateless wind: the scene's
    /// `[dynamics]`, or the default parameters when it has none.
    simulate: bool,
    shadow: ShadowParams,
    shade: ShadeParams,
    key_and_back: bool,
    /// The key light turned about the vertical axis, degrees.
    key_turn: f32,
    /// The key light's intensity as a multiple of the scene's.
    key_gain: f32,
}

impl Controls {
    /// The scene these controls describe, on `base`'s mesh and camera.
    fn scene(&self, base: &Scene) -> Scene {
        let mut scene = base.clone();
        scene.hair = self.hair.clone();
        if !self.wind_on {
            scene.hair.wind = WindParams::calm();
        }
        scene.dynamics = match self.simulate {
            true => base
                .dynamics
                .clone()
                .or_else(|| Some(DynamicsParams::default())),
            false => None,
        };
        scene.shadow = self.shadow.clone();
        scene.shade = self.shade.clone();
        scene.lights = match self.key_and_back {
            true => Light::key_and_back(&base.camera),
            false => base.lights.iter().take(1).cloned().collect(),
        };
        let turn = glam::Quat::from_rotation_y(self.key_turn.to_radians());
        match scene.lights.first_mut() {
            Some(Light::Directional(d)) => {
                d.direction = turn * d.direction;
                d.intensity *= self.key_gain;
            }
            Some(Light::Point(p)) => {
                p.position = turn * p.position;
                p.intensity *= self.key_gain;
            }
            None => {}
        }
        scene
    }
}

/// Playback, and what the panels show besides the parameters.
#[derive(Default)]
struct View {
    playing: bool,
    t: f32,
    stats: TimerReport,
    /// Strands and segments per strand drawn in the last frame (level of detail).
    drawn: (u32, u32),
    frame_ms: f64,
    error: Option<String>,
    status: String,
    screenshot_wanted: bool,
    adapter: String,
    /// Strands and segments of the scene's groom file, when it draws one (its shape is
    /// its own: the growth sliders do not apply).
    groom: Option<(u32, u32)>,
}

/// The window and everything on the GPU that is not pelage's.
struct Gfx {
    window: Arc<Window>,
    instance: wgpu::Instance,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    gpu: Gpu,
    /// wgpu errors raised outside any error scope (wgpu's default handler would panic).
    errors: Arc<Mutex<Vec<String>>>,
    blit: wgpu::RenderPipeline,
    /// The whole window (pelage's image, then egui's panels), sRGB. Screenshots read it
    /// back: a surface texture need not allow COPY_SRC (and reading it would race the
    /// presentation engine). It reaches the surface through the blit rather than
    /// `copy_texture_to_texture`, because some surfaces (OpenGL's) allow no COPY_DST either.
    composition: wgpu::Texture,
    egui_state: egui_winit::State,
    egui: egui_wgpu::Renderer,
    /// egui textures to free once the frame that last used them is submitted.
    egui_free: Vec<egui::TextureId>,
}

impl Gfx {
    fn new(event_loop: &ActiveEventLoop, (w, h): (u32, u32)) -> Result<Self, Box<dyn Error>> {
        let size = winit::dpi::PhysicalSize::new(w, h);
        let attributes = Window::default_attributes().with_title("pelage viewer");
        let window = Arc::new(event_loop.create_window(attributes.with_inner_size(size))?);
        let display = Box::new(event_loop.owned_display_handle());
        let desc = wgpu::InstanceDescriptor::new_with_display_handle_from_env(display);
        let instance = wgpu::Instance::new(desc);
        let surface = instance.create_surface(window.clone())?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            compatible_surface: Some(&surface),
            ..Default::default()
        }))?;
        // The optional features pelage uses when present: timing, float32 blending for
        // deep opacity maps, 64-bit atomics for the k-buffer.
        let wanted = pelage::gpu::WANTED_FEATURES;
        let (device, queue) =
            pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
                label: Some("viewer"),
                required_features: adapter.features() & wanted,
                required_limits: adapter.limits(),
                ..Default::default()
            }))?;
        let errors = Arc::new(Mutex::new(Vec::new()));
        let sink = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            sink.lock()
                .map(|mut list| list.push(e.to_string()))
                .unwrap_or_default()
        }));

        // An 8-bit RGBA or BGRA surface, sRGB preferred, drawn to through an sRGB view.
        let caps = surface.get_capabilities(&adapter);
        let eight_bit = [
            wgpu::TextureFormat::Bgra8Unorm,
            wgpu::TextureFormat::Rgba8Unorm,
        ];
        let format = (caps.formats.iter().copied())
            .filter(|f| eight_bit.contains(&f.remove_srgb_suffix()))
            .max_by_key(|f| f.is_srgb())
            .ok_or("the window's surface offers no 8-bit RGBA or BGRA format")?;
        let srgb = format.add_srgb_suffix();
        let mut config = (surface.get_default_config(&adapter, w, h))
            .ok_or("this adapter cannot present to the window")?;
        config.format = format;
        config.view_formats = if format == srgb { vec![] } else { vec![srgb] };
        surface.configure(&device, &config);

        let shaders = VIEWER_SHADERS.library();
        shaders.validate("present/blit.wgsl")?;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("blit"),
            source: wgpu::ShaderSource::Wgsl(shaders.compose("present/blit.wgsl")?.into()),
        });
        let blit = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("blit"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(srgb.into())],
            }),
            multiview_mask: None,
            cache: None,
        });

        let ctx = egui::Context::default();
        let (id, scale) = (ctx.viewport_id(), Some(window.scale_factor() as f32));
        let max_side = Some(device.limits().max_texture_dimension_2d as usize);
        let egui_state = egui_winit::State::new(ctx, id, &window, scale, None, max_side);
        let egui = egui_wgpu::Renderer::new(&device, srgb, Default::default());
        let composition = composition_texture(&device, srgb, w, h);
        let gpu = Gpu::from_device(device, queue, Some(adapter.get_info()));
        let egui_free = Vec::new();
        Ok(Self {
            window,
            instance,
            surface,
            config,
            gpu,
            errors,
            blit,
            composition,
            egui_state,
            egui,
            egui_free,
        })
    }

    fn resize(&mut self, w: u32, h: u32) {
        (self.config.width, self.config.height) = (w, h);
        self.surface.configure(&self.gpu.device, &self.config);
        let format = self.composition.format();
        self.composition = composition_texture(&self.gpu.device, format, w, h);
    }

    /// The wgpu errors raised outside a scope since the last call, as one line.
    fn take_errors(&self) -> Option<String> {
        let joined = self
            .errors
            .lock()
            .ok()?
            .drain(..)
            .collect::<Vec<_>>()
            .join("; ");
        (!joined.is_empty()).then_some(joined)
    }

    /// Draws `source` (the window's size) over all of `target` with the blit pipeline.
    fn blit(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        source: &wgpu::Texture,
        target: &wgpu::TextureView,
    ) {
        let mut pass = begin_pass(encoder, target);
        self.draw_blit(&mut pass, source, 0);
    }

    /// Draws `source` at its own size, `x` pixels from the target's left edge.
    fn draw_blit(&self, pass: &mut wgpu::RenderPass<'_>, source: &wgpu::Texture, x: u32) {
        let view = source.create_view(&Default::default());
        let group = self
            .gpu
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("blit"),
                layout: &self.blit.get_bind_group_layout(0),
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&view),
                }],
            });
        let (w, h) = (source.width() as f32, source.height() as f32);
        pass.set_viewport(x as f32, 0.0, w, h, 0.0, 1.0);
        pass.set_pipeline(&self.blit);
        pass.set_bind_group(0, &group, &[]);
        pass.draw(0..3, 0..1);
    }
}

fn composition_texture(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
    w: u32,
    h: u32,
) -> wgpu::Texture {
    use wgpu::TextureUsages as U;
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some("composition"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC,
        view_formats: &[],
    })
}

/// A render pass that clears `target` to black and draws over it.
fn begin_pass(
    encoder: &mut wgpu::CommandEncoder,
    target: &wgpu::TextureView,
) -> wgpu::RenderPass<'static> {
    let ops = wgpu::Operations {
        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
        store: wgpu::StoreOp::Store,
    };
    let attachment = wgpu::RenderPassColorAttachment {
        view: target,
        depth_slice: None,
        resolve_target: None,
        ops,
    };
    let desc = wgpu::RenderPassDescriptor {
        color_attachments: &[Some(attachment)],
        ..Default::default()
    };
    // egui-wgpu draws into a RenderPass<'static>: the pass keeps what it uses alive itself.
    encoder.begin_render_pass(&desc).forget_lifetime()
}

struct App {
    args: Args,
    base: Scene,
    controls: Controls,
    /// The controls and size of the last build attempt, good or refused (a refused one
    /// is not retried until something changes).
    attempted: Option<(Controls, u32, u32)>,
    renderer: Option<Renderer>,
    /// `--time-changes`: the scripted changes, and the one whose frame is being timed.
    timing: Option<Timing>,
    orbit: Orbit,
    view: View,
    gfx: Option<Gfx>,
    drag: Option<MouseButton>,
    cursor: Option<(f64, f64)>,
    last_frame: Instant,
    started: Instant,
    frames: u32,
    shots: u32,
    failure: Option<String>,
}

impl winit::application::ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_none() {
            match Gfx::new(event_loop, self.args.size) {
                Ok(gfx) => {
                    self.view.adapter = gfx.gpu.describe();
                    println!("adapter: {}", self.view.adapter);
                    self.gfx = Some(gfx);
                }
                Err(e) => self.fail(event_loop, format!("cannot open the window: {e}")),
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(gfx) = &mut self.gfx else { return };
        // egui sees every event first; what it consumes (clicks on panels, typing) stops there.
        let consumed = gfx.egui_state.on_window_event(&gfx.window, &event).consumed;
        let height = gfx.config.height as f32;
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(_) => gfx.window.request_redraw(),
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.frame(event_loop) {
                    self.fail(event_loop, e.to_string());
                }
            }
            WindowEvent::MouseInput { state, button, .. } => match state {
                ElementState::Pressed if !consumed => self.drag = Some(button),
                _ => self.drag = None,
            },
            WindowEvent::CursorMoved { position, .. } => {
                if let (Some(button), Some((x, y))) = (self.drag, self.cursor) {
                    let (dx, dy) = ((position.x - x) as f32, (position.y - y) as f32);
                    self.orbit.drag(button, dx, dy, height);
                }
                self.cursor = Some((position.x, position.y));
            }
            WindowEvent::MouseWheel { delta, .. } if !consumed => self.orbit.zoom(match delta {
                MouseScrollDelta::LineDelta(_, y) => y,
                MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
            }),
            WindowEvent::KeyboardInput { event, .. } if !consumed && event.state.is_pressed() => {
                match event.logical_key.as_ref() {
                    Key::Named(NamedKey::Space) => self.view.playing = !self.view.playing,
                    Key::Named(NamedKey::F12) | Key::Character("p" | "P") => {
                        self.view.screenshot_wanted = true
                    }
                    Key::Named(NamedKey::Escape) => event_loop.exit(),
                    _ => {}
                }
            }
            _ => {}
        }
    }
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, message: String) {
        self.failure = Some(message);
        event_loop.exit();
    }

    /// One frame: panels, a rebuild if needed, pelage, composition, present, screenshot.
    fn frame(&mut self, event_loop: &ActiveEventLoop) -> Result<(), Box<dyn Error>> {
        let Some(gfx) = &mut self.gfx else {
            return Ok(());
        };
        let size = gfx.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return Ok(()); // minimised: draw nothing until the window comes back
        }
        if (size.width, size.height) != (gfx.config.width, gfx.config.height) {
            gfx.resize(size.width, size.height);
        }
        let (w, h) = (gfx.config.width, gfx.config.height);

        // 1. The panels: egui runs the UI code, which edits the controls and the view. The
        //    3-D view is the window right of the parameter panel.
        let ctx = gfx.egui_state.egui_ctx().clone();
        let input = gfx.egui_state.take_egui_input(&gfx.window);
        let (controls, view) = (&mut self.controls, &mut self.view);
        let mut x0 = 0.0;
        let mut out = ctx.run_ui(input, |ui| x0 = panels(ui, controls, view));
        gfx.egui_state
            .handle_platform_output(&gfx.window, out.platform_output);
        let x0 = ((x0 * out.pixels_per_point).round() as u32).min(w - 1);

        // 2. After a change: in place when the renderer can take it (at once, even while a
        //    slider is dragged), otherwise a new renderer once no slider is being dragged.
        let mut rebuild_anyway = false;
        if let Some(timing) = &mut self.timing {
            rebuild_anyway = timing.next(&mut self.controls, self.frames);
        }
        let wanted = Some((self.controls.clone(), w - x0, h));
        let mut rebuild = self.attempted != wanted;
        let applying = Instant::now();
        let same_size = |r: &Renderer| {
            let t = r.color_texture();
            (t.width(), t.height()) == (w - x0, h)
        };
        if let Some(renderer) = self
            .renderer
            .as_mut()
            .filter(|r| rebuild && !rebuild_anyway && same_size(r))
        {
            let scene = self.controls.scene(&self.base);
            let update = match renderer.frame_mut().update(&gfx.gpu, &scene) {
                Err(pelage::Error::NeedsRebuild(_)) => Ok(false),
                other => other.map(|()| true).map_err(|e| e.to_string()),
            };
            match update.and_then(|applied| gfx.take_errors().map_or(Ok(applied), Err)) {
                Ok(true) => (rebuild, self.view.error) = (false, None),
                Ok(false) => {}
                Err(e) => {
                    self.view.error = Some(format!("kept the last good parameters: {e}"));
                    rebuild = false;
                }
            }
            if !rebuild {
                self.attempted = wanted.clone();
            }
        }
        if rebuild && !ctx.input(|i| i.pointer.any_down()) {
            let scene = self.controls.scene(&self.base);
            let built = Renderer::new(&gfx.gpu, &scene, w - x0, h).map_err(|e| e.to_string());
            match built.and_then(|r| gfx.take_errors().map_or(Ok(r), Err)) {
                Ok(renderer) => (self.renderer, self.view.error) = (Some(renderer), None),
                Err(e) => {
                    let kept = match self.renderer {
                        Some(_) => "kept the last good renderer",
                        None => "nothing to draw",
                    };
                    self.view.error = Some(format!("{kept}: {e}"));
                }
            }
            self.attempted = wanted;
        }
        if let Some(timing) = self.timing.as_mut().filter(|t| t.started.is_some()) {
            timing.apply_ms = applying.elapsed().as_secs_f64() * 1e3;
        }

        // 3. Advance the wind (fixed steps for --frames, the clock otherwise) and render.
        let dt = std::mem::replace(&mut self.last_frame, Instant::now())
            .elapsed()
            .as_secs_f32();
        self.view.frame_ms = 0.8 * self.view.frame_ms + 0.2 * f64::from(dt) * 1e3;
        if self.view.playing {
            let step = if self.args.frames.is_some() {
                1.0 / 24.0
            } else {
                dt
            };
            self.view.t = (self.view.t + step) % T_MAX;
        }
        if let Some(renderer) = &mut self.renderer {
            match renderer.render(&gfx.gpu, self.view.t, &self.orbit.camera()) {
                Ok(stats) => {
                    // Timings arrive a frame or more late: keep the last ones until then.
                    if !stats.scopes.is_empty() {
                        self.view.stats = stats;
                    }
                    self.view.drawn = (
                        renderer.frame().strands().lod().strands,
                        renderer.frame().strands().lod().segments,
                    );
                }
                Err(e) => self.view.error = Some(format!("render: {e}")),
            }
        }

        // 4. egui's textures: upload this frame's, free those the last frame let go of.
        let (device, queue) = (&gfx.gpu.device, &gfx.gpu.queue);
        for (id, deltas) in out.textures_delta.set.drain() {
            deltas
                .iter()
                .for_each(|d| gfx.egui.update_texture(device, queue, id, d));
        }
        let freed = out.textures_delta.free.drain().collect();
        std::mem::replace(&mut gfx.egui_free, freed)
            .iter()
            .for_each(|id| gfx.egui.free_texture(id));
        let paint = ctx.tessellate(out.shapes, out.pixels_per_point);

        // 5. The surface's next texture; an outdated or lost surface is set up again.
        use wgpu::CurrentSurfaceTexture as Next;
        let frame = match gfx.surface.get_current_texture() {
            Next::Success(frame) | Next::Suboptimal(frame) => frame,
            Next::Validation => return Err("the surface refused to hand out a frame".into()),
            next => {
                if matches!(next, Next::Lost) {
                    gfx.surface = gfx.instance.create_surface(gfx.window.clone())?;
                }
                if matches!(next, Next::Lost | Next::Outdated) {
                    gfx.surface.configure(&gfx.gpu.device, &gfx.config);
                }
                gfx.window.request_redraw(); // timed out or occluded: try again later
                return Ok(());
            }
        };

        // 6. Compose pelage's image and the panels, then copy the composition to the surface.
        let px = out.pixels_per_point;
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [w, h],
            pixels_per_point: px,
        };
        let mut encoder = device.create_command_encoder(&Default::default());
        let mut commands = gfx
            .egui
            .update_buffers(device, queue, &mut encoder, &paint, &screen);
        {
            let mut pass = begin_pass(
                &mut encoder,
                &gfx.composition.create_view(&Default::default()),
            );
            // pelage's image, unless a refused rebuild left one of another size.
            let image = self.renderer.as_ref().map(|r| r.color_texture());
            if let Some(image) = image.filter(|t| (t.width(), t.height()) == (w - x0, h)) {
                gfx.draw_blit(&mut pass, image, x0);
            }
            gfx.egui.render(&mut pass, &paint, &screen);
        }
        let format = Some(gfx.composition.format());
        let view = frame.texture.create_view(&wgpu::TextureViewDescriptor {
            format,
            ..Default::default()
        });
        gfx.blit(&mut encoder, &gfx.composition, &view);
        commands.push(encoder.finish());
        queue.submit(commands);
        queue.present(frame);
        if let Some(e) = gfx.take_errors() {
            self.view.error = Some(e);
        }
        if let Some(timing) = &mut self.timing {
            gfx.gpu.device.poll(wgpu::PollType::wait_indefinitely())?;
            if timing.presented() {
                timing.report();
                event_loop.exit();
                return Ok(());
            }
        }

        // 7. Screenshots: on request, and at the end of a --frames run.
        self.frames += 1;
        let last = self.args.frames.is_some_and(|n| self.frames >= n);
        if std::mem::take(&mut self.view.screenshot_wanted) || last {
            let path = match last {
                true => self.args.screenshot.clone(),
                false => PathBuf::from(format!("out/viewer/shot_{:03}.png", self.shots)),
            };
            self.shots += 1;
            self.view.status = match screenshot(gfx, &path) {
                Ok(()) => format!("saved {}", path.display()),
                Err(e) => format!("screenshot failed: {e}"),
            };
            println!("{}", self.view.status);
        }
        if !last {
            gfx.window.request_redraw(); // keep animating
            return Ok(());
        }
        let seconds = self.started.elapsed().as_secs_f64();
        let fps = f64::from(self.frames) / seconds;
        let gpu_ms = self.view.stats.total_ms();
        println!(
            "{} frames of {w}x{h} in {seconds:.1} s ({fps:.2} frames/s), the last {gpu_ms:.1} ms on the GPU",
            self.frames
        );
        if let Some(e) = self.view.error.take() {
            return Err(e.into());
        }
        event_loop.exit();
        Ok(())
    }
}

/// Saves what the window shows (the composition) as an RGB PNG.
fn screenshot(gfx: &Gfx, path: &Path) -> Result<(), Box<dyn Error>> {
    let data = pelage::gpu::read_texture(&gfx.gpu, &gfx.composition)?;
    let bgra = data.format.remove_srgb_suffix() == wgpu::TextureFormat::Bgra8Unorm;
    let (r, b) = if bgra { (2, 0) } else { (0, 2) };
    let rgb = data
        .data
        .chunks_exact(4)
        .flat_map(|p| [p[r], p[1], p[b]])
        .collect();
    let image = image::RgbImage::from_raw(data.width, data.height, rgb).ok_or("short readback")?;
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    let mut png = Vec::new();
    let encoder =
        PngEncoder::new_with_quality(&mut png, CompressionType::Best, FilterType::Adaptive);
    image.write_with_encoder(encoder)?;
    pelage_lab::write_file_atomically(path, &png)?;
    Ok(())
}

/// A slider, logarithmic when its range spans two decades or more.
fn slider<N: egui::emath::Numeric>(ui: &mut egui::Ui, v: &mut N, r: RangeInclusive<N>, text: &str) {
    let (lo, hi) = (r.start().to_f64(), r.end().to_f64());
    ui.add(
        Slider::new(v, r)
            .logarithmic(lo > 0.0 && hi >= 100.0 * lo)
            .text(text),
    );
}

/// A combo box over `names`; returns the new index when the user picks another one.
fn pick(ui: &mut egui::Ui, label: &str, names: &[&str], current: usize) -> Option<usize> {
    let mut index = current;
    egui::ComboBox::from_label(label)
        .selected_text(names[current])
        .show_ui(ui, |ui| {
            for (i, name) in names.iter().enumerate() {
                ui.selectable_value(&mut index, i, *name);
            }
        });
    (index != current).then_some(index)
}

/// A combo box over a method table ([`Named::NAMES`], the names every surface uses): the
/// method picked, at its defaults, when it changed.
fn pick_method<T: Named>(ui: &mut egui::Ui, label: &str, current: &T) -> Option<T> {
    let names: Vec<&str> = T::NAMES.iter().map(|m| m.name).collect();
    pick(ui, label, &names, current.row()).and_then(T::default_of)
}

/// The parameter panel on the left and the GPU times top right; returns the panel's right
/// edge in points.
fn panels(ui: &mut egui::Ui, c: &mut Controls, v: &mut View) -> f32 {
    let panel = egui::Panel::left("parameters").exact_size(300.0);
    let right = panel.show(ui, |ui| {
        egui::ScrollArea::vertical().show(ui, |ui| {
            ui.heading("pelage viewer");
            ui.horizontal(|ui| {
                let play = if v.playing {
                    "Pause (space)"
                } else {
                    "Play (space)"
                };
                if ui.button(play).clicked() {
                    v.playing = !v.playing;
                }
                v.screenshot_wanted |= ui.button("Screenshot (F12)").clicked();
            });
            slider(ui, &mut v.t, 0.0..=T_MAX, "time (s)");
            if let Some(e) = &v.error {
                ui.colored_label(egui::Color32::LIGHT_RED, e);
            }
            if !v.status.is_empty() {
                ui.label(&v.status);
            }
            let section = |ui: &mut egui::Ui, title: &str, body: &mut dyn FnMut(&mut egui::Ui)| {
                CollapsingHeader::new(title)
                    .default_open(true)
                    .show(ui, body);
            };
            section(ui, "Hair", &mut |ui| hair_ui(ui, c, v.groom));
            section(ui, "Wind", &mut |ui| wind_ui(ui, c));
            section(ui, "Shadow", &mut |ui| shadow_ui(ui, c));
            section(ui, "Transparency", &mut |ui| transparency_ui(ui, c));
            section(ui, "Shading", &mut |ui| shading_ui(ui, c));
            section(ui, "Lights", &mut |ui| {
                ui.radio_value(&mut c.key_and_back, false, "key (the scene's first light)");
                ui.radio_value(&mut c.key_and_back, true, "key + warm back light");
                slider(ui, &mut c.key_turn, -180.0..=180.0, "key light turn (°)");
                slider(ui, &mut c.key_gain, 0.0..=4.0, "key light intensity (x)");
            });
        });
    });
    // GPU time per pass (timestamp queries), then the frame's totals, top right.
    let corner = egui::Window::new("GPU time").anchor(egui::Align2::RIGHT_TOP, [-8.0, 8.0]);
    corner.auto_sized().show(ui.ctx(), |ui| {
        egui::Grid::new("passes").striped(true).show(ui, |ui| {
            let by_label = v.stats.by_label();
            let passes = by_label.iter().map(|(l, ms)| (l.as_str(), *ms, "ms"));
            let totals = [
                ("frame total", v.stats.total_ms(), "ms"),
                ("wall clock", v.frame_ms, "ms"),
                ("frames per second", 1000.0 / v.frame_ms.max(1e-3), "/s"),
            ];
            for (label, value, unit) in passes.chain(totals) {
                ui.label(label);
                ui.monospace(format!("{value:7.2} {unit}"));
                ui.end_row();
            }
            ui.label("strands x segments drawn");
            ui.monospace(format!("{} x {}", v.drawn.0, v.drawn.1));
            ui.end_row();
        });
        if v.stats.scopes.is_empty() {
            ui.label("(no pass timings: nothing rendered, or no timestamp queries)");
        }
        ui.small(&v.adapter);
    });
    right.response.rect.right()
}

/// The hair panel; `groom` holds the strands and segments of a groom file, whose count
/// and shape are its own.
fn hair_ui(ui: &mut egui::Ui, c: &mut Controls, groom: Option<(u32, u32)>) {
    if let Some((strands, segments)) = groom {
        ui.label(format!(
            "groom file: {strands} strands x {segments} segments"
        ));
        let g = &mut c.hair.growth;
        slider(ui, &mut g.width, 0.0002..=0.02, "width");
        slider(ui, &mut g.opacity, 0.0..=1.0, "opacity");
        slider(ui, &mut g.force_weight, 0.0..=0.5, "wind force weight");
        return;
    }
    slider(ui, &mut c.hair.roots.count, 100..=200_000, "strands");
    let g = &mut c.hair.growth;
    slider(ui, &mut g.length, 0.01..=0.5, "length");
    slider(ui, &mut g.segments, 1..=32, "segments");
    slider(ui, &mut g.width, 0.0002..=0.02, "width");
    slider(ui, &mut g.opacity, 0.0..=1.0, "opacity");
    let current = match g.hair_type {
        HairType::Straight => 0,
        HairType::Wavy { .. } => 1,
        HairType::Curly { .. } => 2,
    };
    if let Some(i) = pick(ui, "hair type", &["straight", "wavy", "curly"], current) {
        g.hair_type = match i {
            1 => HairType::Wavy {
                amplitude: 0.01,
                frequency: 20.0,
            },
            2 => HairType::Curly {
                radius: 0.008,
                pitch: 0.03,
            },
            _ => HairType::Straight,
        };
    }
    match &mut g.hair_type {
        HairType::Straight => {}
        HairType::Wavy {
            amplitude,
            frequency,
        } => {
            slider(ui, amplitude, 0.0..=0.05, "amplitude");
            slider(ui, frequency, 0.0..=60.0, "waves per unit");
        }
        HairType::Curly { radius, pitch } => {
            slider(ui, radius, 0.0..=0.03, "radius");
            slider(ui, pitch, 0.005..=0.1, "pitch");
        }
    }
    ui.horizontal(|ui| {
        let mut rgb = g.color.to_array();
        ui.color_edit_button_rgb(&mut rgb); // linear RGB, as pelage wants it
        g.color = Vec3::from_array(rgb);
        ui.label("colour");
    });
    // Stochastic simplification and segment reduction, re-evaluated every frame from the
    // hair's size on screen: zoom out to see strands thin out (stats show how many).
    let lod = &mut c.hair.lod;
    ui.checkbox(&mut lod.enabled, "level of detail");
    if lod.enabled {
        slider(
            ui,
            &mut lod.start_pixels,
            1_000.0..=2_000_000.0,
            "B0 (pixels)",
        );
        slider(ui, &mut lod.half_at, 0.05..=0.5, "h");
        slider(
            ui,
            &mut lod.segment_error_pixels,
            0.0..=2.0,
            "segment error (px)",
        );
    }
}

fn wind_ui(ui: &mut egui::Ui, c: &mut Controls) {
    ui.checkbox(&mut c.wind_on, "wind on");
    ui.checkbox(&mut c.simulate, "simulate (dynamics)")
        .on_hover_text(
            "SimulateStrands: inertia, shape constraints, colliders; off: the stateless wind",
        );
    let w = &mut c.hair.wind;
    ui.add_enabled_ui(c.wind_on, |ui| {
        slider(ui, &mut w.strength, 0.0..=5.0, "strength");
        slider(ui, &mut w.gust_strength, 0.0..=1.0, "gust strength");
        slider(ui, &mut w.gust_frequency, 0.0..=3.0, "gusts / second");
        slider(ui, &mut w.turbulence, 0.0..=3.0, "turbulence");
    });
}

fn shadow_ui(ui: &mut egui::Ui, c: &mut Controls) {
    if let Some(method) = pick_method(ui, "method", &c.shadow) {
        c.shadow = method;
    }
    let size = "map size (texels)";
    match &mut c.shadow {
        ShadowParams::None => {}
        ShadowParams::Voxel(p) => {
            let mut n = p.resolution[0];
            slider(ui, &mut n, 4..=512, "voxels per axis");
            if n != p.resolution[0] {
                (p.resolution, p.voxel_size) = ([n; 3], None);
            }
        }
        ShadowParams::DeepOpacity(p) => slider(ui, &mut p.map.size, 16..=4096, size),
        ShadowParams::ShadowMap(p) => slider(ui, &mut p.map.size, 16..=4096, size),
        ShadowParams::Adsm(p) => slider(ui, &mut p.map.size, 16..=4096, size),
    }
}

fn transparency_ui(ui: &mut egui::Ui, c: &mut Controls) {
    let t = &mut c.shade.transparency;
    if let Some(method) = pick_method(ui, "method", t) {
        *t = method;
    }
    let max_k = pelage::scene::MAX_OIT_K;
    match t {
        Transparency::Opaque => {
            ui.horizontal(|ui| {
                ui.label("MSAA");
                ui.radio_value(&mut c.shade.sample_count, 1, "1x");
                ui.radio_value(&mut c.shade.sample_count, 4, "4x");
            });
        }
        Transparency::Wboit { .. } => {}
        Transparency::KBuffer { k } | Transparency::RandomSubsets { k } => {
            slider(ui, k, 1..=max_k, "k");
        }
        Transparency::ABuffer {
            nodes_per_pixel,
            resolve_k,
        }
        | Transparency::Dbk {
            nodes_per_pixel,
            resolve_k,
            ..
        } => {
            slider(ui, nodes_per_pixel, 1.0..=64.0, "node pool per pixel");
            slider(ui, resolve_k, 1..=max_k, "resolve k");
        }
        Transparency::StrandRaster { tile, bins, pool } => {
            ui.horizontal(|ui| {
                ui.label("tile");
                ui.radio_value(tile, 8, "8 px");
                ui.radio_value(tile, 16, "16 px");
            });
            slider(ui, bins, 1..=256, "depth bins");
            slider(ui, pool, 1.0..=64.0, "pool per segment");
        }
    }
}

fn shading_ui(ui: &mut egui::Ui, c: &mut Controls) {
    if let Some(model) = pick_method(ui, "model", &c.shade.model) {
        // Marschner and its lookup tables share the parameters.
        c.shade.model = match (model, &c.shade.model) {
            (ShadingModel::Marschner { lut, .. }, ShadingModel::Marschner { params, .. }) => {
                ShadingModel::Marschner {
                    params: params.clone(),
                    lut,
                }
            }
            (model, _) => model,
        };
    }
    match &mut c.shade.model {
        ShadingModel::KajiyaKay(p) => {
            slider(ui, &mut p.diffuse, 0.0..=2.0, "diffuse");
            slider(ui, &mut p.specular, 0.0..=2.0, "specular");
            slider(ui, &mut p.shininess, 1.0..=500.0, "shininess");
            slider(ui, &mut p.shift_primary, -0.5..=0.5, "highlight shift");
            slider(
                ui,
                &mut p.secondary_specular,
                0.0..=2.0,
                "secondary specular",
            );
        }
        ShadingModel::Marschner { params: p, .. } => {
            slider(ui, &mut p.alpha_r_deg, -20.0..=0.0, "α_R shift (°)");
            slider(ui, &mut p.beta_r_deg, 1.0..=30.0, "β_R width (°)");
            slider(ui, &mut p.eta, 1.01..=2.5, "η index");
            slider(ui, &mut p.eccentricity, 0.85..=1.0, "eccentricity");
            slider(ui, &mut p.glint_scale, 0.0..=10.0, "glints k_G");
            slider(ui, &mut p.diffuse, 0.0..=1.0, "diffuse");
            if ui.button("absorption σ_a from the hair colour").clicked() {
                p.sigma_a = sigma_a_from_color(c.hair.growth.color);
            }
        }
        ShadingModel::Sadeghi(p) => {
            slider(ui, &mut p.intensity_r, 0.0..=2.0, "I_R highlight");
            slider(ui, &mut p.intensity_tt, 0.0..=2.0, "I_TT transmission");
            slider(ui, &mut p.intensity_trt, 0.0..=2.0, "I_TRT secondary");
            slider(ui, &mut p.glint_intensity, 0.0..=5.0, "I_G glints");
            slider(ui, &mut p.diffuse, 0.0..=1.0, "diffuse");
        }
        ShadingModel::Chiang(p) => chiang_ui(ui, p, c.hair.growth.color),
    }
    slider(ui, &mut c.shade.ambient, 0.0..=1.0, "ambient");
    slider(ui, &mut c.shade.root_occlusion, 0.0..=1.0, "root occlusion");
    ui.horizontal(|ui| {
        let mut rgb = c.shade.mesh_color.to_array();
        ui.color_edit_button_rgb(&mut rgb); // linear RGB
        c.shade.mesh_color = Vec3::from_array(rgb);
        ui.label("mesh colour");
    });
}

/// Chiang et al. 2016: roughness, tilt, index, where the absorption comes from (the hair
/// colour, melanin concentrations, or σ_a itself) and dual scattering.
fn chiang_ui(ui: &mut egui::Ui, p: &mut ChiangParams, hair_color: Vec3) {
    slider(ui, &mut p.beta_m, 0.02..=1.0, "β_m longitudinal roughness");
    slider(ui, &mut p.beta_n, 0.02..=1.0, "β_n azimuthal roughness");
    slider(ui, &mut p.alpha_deg, -10.0..=10.0, "α cuticle tilt (°)");
    slider(ui, &mut p.eta, 1.01..=2.5, "η index");
    let pigments = [
        "from the hair colour",
        "melanin (pbrt)",
        "σ_a",
        "melanin (Blender, Unreal)",
    ];
    let pigment = |p: &ChiangParams| match p.absorption() {
        _ if p.sigma_a.is_some() => 2,
        _ if p.melanin.is_some() => 3,
        Absorption::Fixed(_) => 1,
        Absorption::FromColor => 0,
    };
    if let Some(i) = pick(ui, "pigment", &pigments, pigment(p)) {
        // The absorption now, so that switching to σ_a keeps the look.
        let now = p.sigma_a_for(hair_color);
        p.sigma_a = None;
        p.eumelanin = None;
        p.pheomelanin = None;
        p.melanin = None;
        p.melanin_redness = None;
        p.tint = None;
        match i {
            1 => {
                p.eumelanin = Some(1.3);
                p.pheomelanin = Some(0.0);
            }
            2 => p.sigma_a = Some(now),
            3 => {
                p.melanin = Some(0.5);
                p.melanin_redness = Some(0.0);
                p.tint = Some(Vec3::ONE);
            }
            _ => {}
        }
    }
    let log_slider = |ui: &mut egui::Ui, v: &mut f32, hi: f32, text: &str| {
        ui.add(Slider::new(v, 0.0..=hi).logarithmic(true).text(text));
    };
    match pigment(p) {
        2 => {
            let mut s = p.sigma_a.unwrap_or_default();
            log_slider(ui, &mut s.x, 20.0, "σ_a red");
            log_slider(ui, &mut s.y, 20.0, "σ_a green");
            log_slider(ui, &mut s.z, 20.0, "σ_a blue");
            p.sigma_a = Some(s);
        }
        1 => {
            let mut eumelanin = p.eumelanin.unwrap_or(0.0);
            let mut pheomelanin = p.pheomelanin.unwrap_or(0.0);
            log_slider(
                ui,
                &mut eumelanin,
                MAX_MELANIN,
                "eumelanin (0.3 blond, 8 black)",
            );
            log_slider(ui, &mut pheomelanin, MAX_MELANIN, "pheomelanin (red)");
            p.eumelanin = Some(eumelanin);
            p.pheomelanin = Some(pheomelanin);
        }
        3 => {
            let mut melanin = p.melanin.unwrap_or(0.0);
            let mut redness = p.melanin_redness.unwrap_or(DEFAULT_MELANIN_REDNESS);
            let mut tint = p.tint.unwrap_or(Vec3::ONE).to_array();
            slider(
                ui,
                &mut melanin,
                0.0..=1.0,
                "melanin (0.25 blond, 0.9 black)",
            );
            slider(ui, &mut redness, 0.0..=1.0, "melanin redness");
            ui.horizontal(|ui| {
                ui.color_edit_button_rgb(&mut tint);
                ui.label("tint (linear)");
            });
            p.melanin = Some(melanin);
            p.melanin_redness = Some(redness);
            p.tint = Some(Vec3::from_array(tint));
        }
        _ => {
            ui.label("absorption from each strand's colour (hair panel)");
        }
    }
    if let Some(method) = pick_method(ui, "multiple scattering", &p.multiple_scattering) {
        p.multiple_scattering = method;
    }
}

/// `--time-changes`: each uniform-only parameter changed twice, first through a new
/// renderer (what the viewer did before `Frame::update`), then in place, each change
/// timed from the moment the controls change to the frame presented with the GPU idle.
#[derive(Default)]
struct Timing {
    /// Changes made so far; change `i` is kind `i / 2`, through a new renderer when even.
    step: usize,
    /// When the change being timed was made.
    started: Option<Instant>,
    /// Milliseconds the change being timed took to apply (the update or the new renderer).
    apply_ms: f64,
    /// Per kind: milliseconds to the frame and to apply, through a new renderer, then in place.
    results: Vec<(&'static str, [f64; 4])>,
}

impl Timing {
    /// The kinds of change scripted, each flipping its parameter between two values.
    const KINDS: [&'static str; 4] = ["wind", "hair colour", "key light", "shading"];
    /// Frames drawn before the first change (the first renderer built and warm).
    const WARM_UP: u32 = 3;

    /// Before frame `frame`: makes the next change when the last one was presented and the
    /// warm-up is over; returns whether it must go through a new renderer.
    fn next(&mut self, c: &mut Controls, frame: u32) -> bool {
        if frame < Self::WARM_UP || self.started.is_some() || self.step >= 2 * Self::KINDS.len() {
            return false;
        }
        let flip = self.step.is_multiple_of(2);
        match self.step / 2 {
            0 => c.hair.wind.strength = if flip { 2.5 } else { 0.4 },
            1 => {
                c.hair.growth.color = if flip {
                    Vec3::new(0.7, 0.55, 0.3)
                } else {
                    Vec3::new(0.15, 0.1, 0.08)
                }
            }
            2 => c.key_turn = if flip { 60.0 } else { -45.0 },
            _ => c.shade.ambient = if flip { 0.5 } else { 0.05 },
        }
        self.started = Some(Instant::now());
        flip
    }

    /// After a frame was presented and the GPU went idle: records the change it showed;
    /// returns whether every change has been timed.
    fn presented(&mut self) -> bool {
        if let Some(started) = self.started.take() {
            let ms = started.elapsed().as_secs_f64() * 1e3;
            let kind = Self::KINDS[self.step / 2];
            if self.step.is_multiple_of(2) {
                let nan = f64::NAN;
                self.results.push((kind, [ms, self.apply_ms, nan, nan]));
            } else if let Some((_, last)) = self.results.last_mut() {
                (last[2], last[3]) = (ms, self.apply_ms);
            }
            self.step += 1;
        }
        self.step >= 2 * Self::KINDS.len()
    }

    fn report(&self) {
        println!("time from a change to its frame presented, and of that to apply it (ms):");
        println!(
            "{:<12} {:>16} {:>16} {:>16} {:>16}",
            "change", "new: to frame", "new: to apply", "in place: frame", "in place: apply"
        );
        for (kind, [rebuild, new_ms, in_place, update_ms]) in &self.results {
            println!(
                "{kind:<12} {rebuild:>16.1} {new_ms:>16.1} {in_place:>16.1} {update_ms:>16.2}"
            );
        }
    }
}

fn main() {
    let run = || -> Result<(), Box<dyn Error>> {
        let args = parse_args()?;
        let base = match &args.scene {
            Some(path) => Scene::from_file(path)?,
            None => Scene::default(),
        };
        let controls = Controls {
            hair: base.hair.clone(),
            wind_on: true,
            simulate: base.dynamics.is_some(),
            shadow: base.shadow.clone(),
            shade: base.shade.clone(),
            key_and_back: false,
            key_turn: 0.0,
            key_gain: 1.0,
        };
        let event_loop = EventLoop::new()?;
        let mut app = App {
            orbit: Orbit::new(&base.camera),
            view: View {
                playing: true,
                groom: base.groom.as_ref().map(|g| (g.strands, g.segments)),
                ..Default::default()
            },
            timing: args.time_changes.then(Timing::default),
            args,
            base,
            controls,
            attempted: None,
            renderer: None,
            gfx: None,
            drag: None,
            cursor: None,
            last_frame: Instant::now(),
            started: Instant::now(),
            frames: 0,
            shots: 0,
            failure: None,
        };
        event_loop.run_app(&mut app)?;
        app.failure.map_or(Ok(()), |e| Err(e.into()))
    };
    if let Err(e) = run() {
        eprintln!("viewer: {e}");
        std::process::exit(1);
    }
}
