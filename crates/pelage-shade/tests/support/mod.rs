//! What the transparency tests share: small scenes grown on the GPU, rendering one
//! frame with a method, and the exact composite (every fragment captured from an
//! A-buffer whose pool holds them all, sorted and blended on the CPU).

#![allow(dead_code)]

use glam::Vec3;
use pelage_gpu::Gpu;
use pelage_reference::flip::{DEFAULT_PIXELS_PER_DEGREE, LinearImage, flip};
use pelage_reference::oit::{Fragment, composite_sorted, linear_to_srgb8, srgb8_to_linear};
use pelage_scene::{Camera, HairParams, Light, Mesh, ShadeParams, Transparency, WindParams};
use pelage_shade::{ABuffer, HairInputs, HairPass, OitStats, TargetFormat, Targets};
use pelage_strands::{GrowStrands, MeshBuffers, StrandFrame, StrandStage};

pub const W: u32 = 128;
pub const H: u32 = 96;

pub fn gpu() -> Gpu {
    Gpu::headless().unwrap_or_else(|e| panic!("these tests need a GPU adapter: {e}"))
}

pub struct Scene {
    pub mesh: Mesh,
    pub camera: Camera,
    pub buffers: MeshBuffers,
    pub strands: GrowStrands,
    /// The frame the strands were grown in.
    pub frame: StrandFrame,
}

/// The creature with `strands` strands of `opacity`, grown at t = 0.
pub fn scene(gpu: &Gpu, strands: u32, opacity: f32, camera: Camera) -> Scene {
    let mut hair = HairParams::default();
    hair.roots.count = strands;
    grown(gpu, Mesh::creature(), hair, opacity, camera)
}

/// Long hair on a head (a sphere), covering the whole screen, 16 fragments per pixel
/// on average at 128x96 and up to about 60.
pub fn long_hair(gpu: &Gpu, opacity: f32) -> Scene {
    let mut hair = HairParams::default();
    hair.roots.count = 6000;
    hair.growth.segments = 16;
    hair.growth.length = 0.9;
    hair.growth.force_weight = 0.12;
    hair.growth.direction_jitter = 0.15;
    let camera = Camera {
        eye: Vec3::new(1.6, 0.3, 2.0),
        target: Vec3::new(0.0, -0.15, 0.0),
        ..Default::default()
    };
    grown(gpu, Mesh::icosphere(0.5, 3).unwrap(), hair, opacity, camera)
}

pub fn grown(gpu: &Gpu, mesh: Mesh, mut hair: HairParams, opacity: f32, camera: Camera) -> Scene {
    hair.wind = WindParams::calm();
    hair.growth.opacity = opacity;
    let buffers = MeshBuffers::upload(gpu, &mesh).unwrap();
    let mut grown = GrowStrands::new(gpu, &mesh, &buffers, &hair).unwrap();
    let frame = grown.prepare(&gpu.queue, 0.0).unwrap();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    grown.encode(&mut encoder, &frame, None).unwrap();
    gpu.submit_and_wait([encoder.finish()]).unwrap();
    Scene {
        mesh,
        camera,
        buffers,
        strands: grown,
        frame,
    }
}

pub fn inputs<'a>(s: &'a Scene, params: &'a ShadeParams) -> HairInputs<'a> {
    HairInputs {
        params,
        mesh: &s.buffers,
        strands: s.strands.buffers(),
        shadows: &[],
        visibility: None,
        target: TargetFormat::for_params(params),
        draw_mesh: true,
        grid_apart: false,
    }
}

pub fn params(t: Transparency) -> ShadeParams {
    ShadeParams {
        transparency: t,
        // The OIT tests judge compositing; they were measured with Kajiya-Kay (the
        // default before the strand rasterizer and Chiang became the defaults).
        model: pelage_scene::ShadingModel::KajiyaKay(Default::default()),
        ..Default::default()
    }
}

/// Renders one frame with `method`; returns the RGBA8 sRGB image and the pool counters.
pub fn render_with(
    gpu: &Gpu,
    s: &Scene,
    method: &dyn HairPass,
    samples: u32,
) -> (Vec<u8>, OitStats) {
    render_lit(gpu, s, method, samples, &[Light::default()])
}

/// [`render_with`] lit by `lights`.
pub fn render_lit(
    gpu: &Gpu,
    s: &Scene,
    method: &dyn HairPass,
    samples: u32,
    lights: &[Light],
) -> (Vec<u8>, OitStats) {
    let targets = Targets::new(gpu, W, H, samples).unwrap();
    method
        .prepare(&gpu.queue, &s.frame, &s.camera.matrices(W, H), lights, W, H)
        .unwrap();
    let (color, resolve) = targets.color_views();
    let depth = targets.depth_view();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    method
        .encode(
            &mut encoder,
            &s.frame,
            &targets.views(&color, resolve.as_ref(), &depth),
            None,
        )
        .unwrap();
    gpu.submit_and_wait([encoder.finish()]).unwrap();
    // The frame's after-submit step: the pool grows here for the next frame.
    method.after_submit(gpu).unwrap();
    let stats = method.stats(gpu).unwrap();
    (targets.read_color(gpu).unwrap().data, stats)
}

pub fn render(gpu: &Gpu, s: &Scene, t: Transparency) -> (Vec<u8>, OitStats) {
    let p = params(t);
    let method = pelage_shade::build(gpu, &inputs(s, &p), W, H).unwrap();
    render_with(gpu, s, method.as_ref(), p.samples())
}

pub struct Exact {
    pub image: Vec<u8>,
    pub background: Vec<u8>,
    /// Fragments per pixel.
    pub depth: Vec<usize>,
}

/// The exact composite: every fragment, sorted, blended over the opaque colour.
pub fn exact(gpu: &Gpu, s: &Scene) -> Exact {
    let p = params(Transparency::a_buffer());
    let targets = Targets::new(gpu, W, H, 1).unwrap();
    let abuffer = ABuffer::new(gpu, &inputs(s, &p), 256.0, 64, W, H).unwrap();
    abuffer
        .prepare(
            &gpu.queue,
            &s.frame,
            &s.camera.matrices(W, H),
            &[Light::default()],
            W,
            H,
        )
        .unwrap();
    let capture = abuffer.capture(gpu, &targets).unwrap();
    assert_eq!(
        abuffer.stats(gpu).unwrap().dropped,
        0,
        "the reference pool overflowed"
    );
    let mut image = Vec::new();
    let mut depth = Vec::new();
    for (p, list) in capture.lists.iter().enumerate() {
        let bg = &capture.background[4 * p..4 * p + 3];
        let mut fragments: Vec<Fragment> = list
            .iter()
            .map(|f| Fragment {
                depth: f.depth,
                color: f.color,
                alpha: f.alpha,
            })
            .collect();
        depth.push(fragments.len());
        let c = composite_sorted(
            &mut fragments,
            [
                srgb8_to_linear(bg[0]),
                srgb8_to_linear(bg[1]),
                srgb8_to_linear(bg[2]),
            ],
        );
        image.extend([
            linear_to_srgb8(c[0]),
            linear_to_srgb8(c[1]),
            linear_to_srgb8(c[2]),
            255,
        ]);
    }
    Exact {
        image,
        background: capture.background,
        depth,
    }
}

pub fn mean_flip(reference: &[u8], test: &[u8]) -> f64 {
    let r = LinearImage::from_srgb8_rgba(W, H, reference).unwrap();
    let t = LinearImage::from_srgb8_rgba(W, H, test).unwrap();
    flip(&r, &t, DEFAULT_PIXELS_PER_DEGREE).unwrap().mean()
}
