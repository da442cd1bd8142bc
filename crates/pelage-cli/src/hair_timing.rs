//! Wall-clock timing of a stage 3 method's hair passes, the same way for every method:
//! the method is built without the mesh (`draw_mesh: false`) and recorded over targets
//! it loads (`TargetViews::load`), so an encoder holds its hair passes alone; each frame
//! is submitted alone and waited for. Timestamp queries cannot be used for this on
//! lavapipe: it misplaces the timestamps of compute passes recorded after a render pass
//! (the strand rasterizer's passes read 0.1 ms for work that takes 250).

use std::time::Instant;

use pelage::gpu::Gpu;
use pelage::scene::{Camera, HairParams, Light, Mesh, ShadeParams};
use pelage::shade::{HairInputs, TargetFormat, Targets};
use pelage::strands::{GrowStrands, MeshBuffers, StrandStage};

/// What [`hair_wall_ms`] draws.
pub struct HairCase<'a> {
    /// The surface the strands grow from.
    pub mesh: &'a Mesh,
    /// The strands (grown once, at t = 0).
    pub hair: &'a HairParams,
    /// The method and shading.
    pub shade: &'a ShadeParams,
    /// The view.
    pub camera: &'a Camera,
}

/// Median wall-clock milliseconds of `frames` frames of the hair passes of `case` at
/// `width` x `height`, after two of warm-up.
pub fn hair_wall_ms(
    gpu: &Gpu,
    case: &HairCase<'_>,
    width: u32,
    height: u32,
    frames: usize,
) -> Result<f64, Box<dyn std::error::Error>> {
    let mesh = MeshBuffers::upload(gpu, case.mesh)?;
    let mut strands = GrowStrands::new(gpu, case.mesh, &mesh, case.hair)?;
    let frame = strands.prepare(&gpu.queue, 0.0)?;
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    strands.encode(&mut encoder, &frame, None)?;
    gpu.submit_and_wait([encoder.finish()])?;
    let inputs = HairInputs {
        params: case.shade,
        mesh: &mesh,
        strands: strands.buffers(),
        shadows: &[],
        visibility: None,
        target: TargetFormat::for_params(case.shade),
        draw_mesh: false,
        grid_apart: false,
    };
    let method = pelage::shade::build(gpu, &inputs, width, height)?;
    let targets = Targets::new(gpu, width, height, case.shade.samples())?;
    let (color, resolve) = targets.color_views();
    let depth = targets.depth_view();
    let views = pelage::shade::TargetViews {
        load: true,
        ..targets.views(&color, resolve.as_ref(), &depth)
    };
    method.prepare(
        &gpu.queue,
        &frame,
        &case.camera.matrices(width, height),
        &[Light::default()],
        width,
        height,
    )?;
    let mut times = Vec::new();
    for i in 0..frames + 2 {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        method.encode(&mut encoder, &frame, &views, None)?;
        let commands = encoder.finish();
        let started = Instant::now();
        gpu.submit_and_wait([commands])?;
        method.after_submit(gpu)?;
        if i >= 2 {
            times.push(started.elapsed().as_secs_f64() * 1e3);
        }
    }
    times.sort_by(f64::total_cmp);
    Ok(times[times.len() / 2])
}
