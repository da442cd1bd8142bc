//! What the stage 1 tests share: an adapter, growing on it with a readback, and the roots
//! as the CPU mirrors take them.

use glam::Vec4;
use pelage_gpu::{Gpu, read_buffer, wgpu};
use pelage_reference::strands::Root;
use pelage_strands::{StrandRoot, StrandStage};

/// The adapter, or a failure saying what to install.
pub fn gpu() -> Gpu {
    Gpu::headless().unwrap_or_else(|e| panic!("these tests need a GPU adapter: {e}"))
}

/// The strand vertices in `buffer`.
pub fn read_vertices(gpu: &Gpu, buffer: &wgpu::Buffer) -> Vec<Vec4> {
    let bytes = read_buffer(gpu, buffer).expect("read back strand vertices");
    bytemuck::cast_slice::<u8, [f32; 4]>(&bytes)
        .iter()
        .map(|v| Vec4::from_array(*v))
        .collect()
}

/// Runs a stage 1 method for time `t` on the GPU and returns the vertices.
pub fn grow_on_gpu(gpu: &Gpu, strands: &mut dyn StrandStage, t: f32) -> Vec<Vec4> {
    let frame = strands.prepare(&gpu.queue, t).unwrap();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    strands.encode(&mut encoder, &frame, None).unwrap();
    gpu.submit_and_wait([encoder.finish()]).unwrap();
    read_vertices(gpu, &strands.buffers().vertices)
}

/// The roots a stage 1 method sampled on the CPU (an input of its GPU pass, as of the
/// mirror), as the CPU mirrors take them.
#[allow(dead_code)] // not every test binary runs a mirror
pub fn mirror_roots(roots: &[StrandRoot]) -> Vec<Root> {
    roots
        .iter()
        .map(|r| Root {
            triangle: r.triangle,
            seed: r.seed,
            bary: r.bary,
            length: r.length,
            width: r.width,
            phase: r.phase,
            tilt: r.tilt,
            azimuth: r.azimuth,
            color: r.color,
            region: r.region,
        })
        .collect()
}
