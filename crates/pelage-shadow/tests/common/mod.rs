//! Helpers shared by the shadow tests: grooms, hand-made strands, the ray-traced
//! reference, and any method's transmittance at the strand vertices.

#![allow(dead_code)] // each test file uses its own subset

use glam::{Vec2, Vec3, Vec4};
use pelage_gpu::{Gpu, read_buffer, storage_buffer, wgpu, zeroed_storage};
use pelage_reference::transmittance::{
    SegmentBvh, rmse_p95, segments_from_strands, transmittance_at_every_nth_vertex,
};
use pelage_scene::{DirectionalLight, GrowthParams, HairParams, Mesh, WindParams};
use pelage_shadow::{ShadowMethod, TransmittanceProbe};
use pelage_strands::{
    GrowStrands, MeshBuffers, StrandBuffers, StrandFrame, StrandRoot, StrandStyle,
};
// The per-frame calls of stage 1, for every test that uses this module.
pub use pelage_strands::StrandStage;

pub fn gpu() -> Gpu {
    Gpu::headless().unwrap_or_else(|e| panic!("these tests need a GPU adapter: {e}"))
}

pub fn light() -> DirectionalLight {
    DirectionalLight::default()
}

/// Strand buffers holding exactly `strands` (each the same vertex count), all of `width`.
pub fn strand_buffers(gpu: &Gpu, strands: &[Vec<Vec3>], width: f32) -> StrandBuffers {
    let per = strands[0].len();
    let segments = (per - 1) as u32;
    let vertices: Vec<Vec4> = strands
        .iter()
        .flat_map(|s| {
            s.iter()
                .enumerate()
                .map(move |(i, p)| p.extend(i as f32 / segments as f32))
        })
        .collect();
    let roots: Vec<StrandRoot> = (0..strands.len())
        .map(|i| StrandRoot {
            triangle: 0,
            seed: i as u32,
            bary: Vec2::ZERO,
            length: 1.0,
            width,
            phase: 0.0,
            tilt: 0.0,
            azimuth: 0.0,
            color: Vec3::ONE,
            region: 0,
        })
        .collect();
    let usage = wgpu::BufferUsages::STORAGE;
    let points = strands.iter().flatten();
    let lo = points.clone().fold(Vec3::INFINITY, |a, p| a.min(*p)) - Vec3::splat(width);
    let hi = points.fold(Vec3::NEG_INFINITY, |a, p| a.max(*p)) + Vec3::splat(width);
    StrandBuffers::new(
        storage_buffer(gpu, "test vertices", &vertices, usage).unwrap(),
        storage_buffer(gpu, "test roots", &roots, usage).unwrap(),
        strands.len() as u32,
        segments,
        StrandStyle::of(&growth(width, 1.0)),
        (lo, hi),
    )
    .unwrap()
}

/// The same buffers as `strands`, styled as strands grown with `growth` (width, tip
/// width, opacity).
pub fn styled(strands: &StrandBuffers, growth: &GrowthParams) -> StrandBuffers {
    StrandBuffers {
        vertices: strands.vertices.clone(),
        roots: strands.roots.clone(),
        strand_count: strands.strand_count,
        segments: strands.segments,
        style: StrandStyle::of(growth),
        reach: strands.reach,
    }
}

/// A stage 1 frame holding every strand of `strands` (what hand-made buffers, or grown
/// ones at full detail, hold).
pub fn full_frame(strands: &StrandBuffers) -> StrandFrame {
    StrandFrame::next(strands.full_layout())
}

/// A one-triangle mesh out of the way (every method needs a mesh for its mesh map).
pub fn dummy_mesh(gpu: &Gpu) -> MeshBuffers {
    let mesh = Mesh {
        positions: vec![
            Vec3::new(50.0, 0.0, 0.0),
            Vec3::new(51.0, 0.0, 0.0),
            Vec3::new(50.0, 0.0, 1.0),
        ],
        normals: vec![Vec3::Y; 3],
        indices: vec![0, 2, 1],
        uvs: Vec::new(),
    };
    MeshBuffers::upload(gpu, &mesh).unwrap()
}

pub fn growth(width: f32, opacity: f32) -> GrowthParams {
    GrowthParams {
        width,
        tip_width: 1.0,
        opacity,
        ..GrowthParams::default()
    }
}

/// Runs `method` aimed at the default light and returns its `light_visibility` at every
/// strand vertex (the tests' methods have no mesh map, so this is the hair's transmittance).
pub fn transmittance(gpu: &Gpu, method: &dyn ShadowMethod, strands: &StrandBuffers) -> Vec<f32> {
    transmittance_from(gpu, method, strands, &light())
}

/// [`transmittance`] for a given light.
pub fn transmittance_from(
    gpu: &Gpu,
    method: &dyn ShadowMethod,
    strands: &StrandBuffers,
    light: &DirectionalLight,
) -> Vec<f32> {
    let frame = full_frame(strands);
    method.prepare(&gpu.queue, &frame, light).unwrap();
    let out = zeroed_storage(
        gpu,
        "transmittance",
        strands.vertices.size() / 4,
        wgpu::BufferUsages::STORAGE,
    )
    .unwrap();
    let probe = TransmittanceProbe::new(gpu, &method.binding()).unwrap();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    method.encode(&mut encoder, &frame, None).unwrap();
    probe
        .encode(gpu, &mut encoder, &strands.vertices, &out)
        .unwrap();
    gpu.submit_and_wait([encoder.finish()]).unwrap();
    bytemuck::cast_slice(&read_buffer(gpu, &out).unwrap()).to_vec()
}

pub fn read_vec4(gpu: &Gpu, buffer: &wgpu::Buffer) -> Vec<Vec4> {
    bytemuck::cast_slice::<u8, [f32; 4]>(&read_buffer(gpu, buffer).unwrap())
        .iter()
        .map(|v| Vec4::from_array(*v))
        .collect()
}

/// Grows `hair` on `mesh` at t = 0 and returns the stage and its mesh buffers.
pub fn grow(gpu: &Gpu, mesh: &Mesh, hair: &HairParams) -> (GrowStrands, MeshBuffers) {
    let buffers = MeshBuffers::upload(gpu, mesh).unwrap();
    let mut strands = GrowStrands::new(gpu, mesh, &buffers, hair).unwrap();
    let frame = strands.prepare(&gpu.queue, 0.0).unwrap();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    strands.encode(&mut encoder, &frame, None).unwrap();
    gpu.submit_and_wait([encoder.finish()]).unwrap();
    (strands, buffers)
}

pub fn long_hair() -> (Mesh, HairParams) {
    let mut hair = HairParams::default();
    hair.roots.count = 6000;
    hair.growth.segments = 16;
    hair.growth.length = 0.9;
    hair.growth.force_weight = 0.12;
    hair.growth.direction_jitter = 0.15;
    hair.wind = WindParams::calm();
    (Mesh::icosphere(0.5, 3).unwrap(), hair)
}

/// A groom grown at t = 0 and the ray-traced transmittance at every `stride`-th one of
/// its vertices (every one for [`reference`]).
pub struct Reference {
    pub light: DirectionalLight,
    pub strands: GrowStrands,
    pub mesh_buffers: MeshBuffers,
    pub truth: Vec<f32>,
    pub stride: usize,
}

pub fn reference(gpu: &Gpu, mesh: &Mesh, hair: &HairParams) -> Reference {
    reference_from(gpu, mesh, hair, &light())
}

/// [`reference`] for a given light.
pub fn reference_from(
    gpu: &Gpu,
    mesh: &Mesh,
    hair: &HairParams,
    light: &DirectionalLight,
) -> Reference {
    reference_sampled(gpu, mesh, hair, light, 1)
}

/// [`reference_from`] at every `stride`-th vertex only (a dense groom's reference costs
/// a ray bundle per vertex; the errors are statistics over the vertices).
pub fn reference_sampled(
    gpu: &Gpu,
    mesh: &Mesh,
    hair: &HairParams,
    light: &DirectionalLight,
    stride: usize,
) -> Reference {
    let (strands, mesh_buffers) = grow(gpu, mesh, hair);
    let buffers = strands.buffers();
    let vertices = read_vec4(gpu, &buffers.vertices);
    let widths: Vec<f32> = strands.roots().iter().map(|r| r.width).collect();
    let per = (buffers.segments + 1) as usize;
    let g = &hair.growth;
    let bvh = SegmentBvh::build(segments_from_strands(
        &vertices,
        per,
        &widths,
        g.tip_width,
        g.opacity,
    ));
    let to_light = light.to_light().unwrap();
    let truth = transmittance_at_every_nth_vertex(
        &bvh,
        &vertices,
        per,
        to_light,
        REFERENCE_DISC,
        REFERENCE_RAYS,
        stride,
    );
    Reference {
        light: light.clone(),
        strands,
        mesh_buffers,
        truth,
        stride: stride.max(1),
    }
}

/// Radius of the disc of rays the reference averages over per sample, scene units
/// (the default creature is about 2.5 units across), and the rays per sample.
pub const REFERENCE_DISC: f32 = 0.01;
pub const REFERENCE_RAYS: u32 = 16;

/// RMSE and p95 of `method`'s transmittance against the reference.
pub fn error(gpu: &Gpu, r: &Reference, method: &dyn ShadowMethod) -> (f32, f32) {
    let t: Vec<f32> = transmittance_from(gpu, method, r.strands.buffers(), &r.light)
        .into_iter()
        .step_by(r.stride)
        .collect();
    rmse_p95(&t, &r.truth).unwrap()
}

/// Mean of a slice.
pub fn mean(v: &[f32]) -> f32 {
    v.iter().sum::<f32>() / v.len().max(1) as f32
}
