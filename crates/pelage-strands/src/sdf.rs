//! A signed distance field of the body the strands grow on, built on the GPU
//! (`wgsl/strands/sdf.wgsl`), which the simulation's collision step samples.

use encase::ShaderType;
use glam::{UVec3, Vec3};
use pelage_gpu::{
    BindLayout, Gpu, GpuTimer, PassInfo, UniformBuffer, compute_pipeline_with_layouts,
    dispatch_size, read_buffer, wgpu, zeroed_storage,
};
use pelage_scene::{ParamError, SDF_BAND_CELLS, SdfGrid};

use crate::{MESH, MeshBuffers};

/// Workgroup size of `sdf.wgsl`.
const WORKGROUP: u32 = 64;

/// The timestamp label of the field's build (one compute pass of several dispatches).
pub const SDF_LABEL: &str = "strands: sdf";

/// The frame resource of the body's distance field (a 3D `r32float` texture).
pub const BODY_SDF: &str = "strands.sdf";

/// The uniforms of `sdf.wgsl` (`SdfUniforms` there).
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct SdfUniforms {
    /// Position of node (0, 0, 0).
    pub origin: Vec3,
    /// Edge of a cell.
    pub cell: f32,
    /// Nodes per axis.
    pub dims: UVec3,
    /// Triangles of the mesh.
    pub triangle_count: u32,
    /// Cells around each triangle's box it writes exactly ([`SDF_BAND_CELLS`]).
    pub band: u32,
    /// The distance written where no triangle reached (every triangle non-finite).
    pub far: f32,
}

/// One jump-flooding step's distance in nodes (`JfaStep` in `sdf.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
struct JfaStep {
    step: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

/// The jump-flooding steps for a grid whose longest axis has `longest` nodes: halving
/// from the largest power of two below it to 1, then 1 again (JFA+1, Rong and Tan 2006).
pub fn flood_steps(longest: u32) -> Vec<u32> {
    let mut steps = Vec::new();
    let mut s = (longest.max(2) - 1).next_power_of_two() / 2;
    while s >= 1 {
        steps.push(s);
        s /= 2;
    }
    steps.push(1);
    steps
}

/// A signed distance field of a mesh on a grid ([`SdfGrid`]: the mesh's box plus a
/// margin, `resolution` nodes along its longest axis), negative inside, built on the GPU
/// from [`MeshBuffers`] in one compute pass ([`SDF_LABEL`]) and held in a 3D `r32float`
/// texture ([`BodySdf::view`]) that the simulation reads with `textureLoad` and
/// trilinear interpolation (`r32float` is not filterable without a device feature,
/// `r16float` cannot be written as a storage texture on WebGPU, and the simulation's
/// pass already binds WebGPU's 8 storage buffers, so a texture it is).
///
/// **Build.** Each triangle writes its exact distance into the nodes of its box grown by
/// [`SDF_BAND_CELLS`] cells (an `atomicMin` on the distance's bits, then the triangle
/// index where its distance is the minimum), then jump flooding
/// ([`flood_steps`]: about `log2(resolution) + 1` passes over the nodes, each looking at
/// 26 neighbours) carries the nearest triangle to the far nodes, and a last pass writes
/// the exact distance to the triangle each node holds, signed by the mesh's normal at the
/// nearest point (the vertex normals interpolated there). Nodes within the band are exact
/// (to float rounding); farther ones may hold a triangle slightly farther than the
/// nearest (jump flooding's known error), measured against the CPU mirror
/// (`pelage_reference::sdf`).
///
/// **Holes, NaN.** The sign is the side of the nearest surface point's normal: an open
/// mesh is "inside" only behind its surface near a node, never flooded from a hole.
/// Triangles with a non-finite corner are skipped; if none is left, every node reads
/// far outside (no collision) rather than a wrong inside.
#[derive(Debug)]
pub struct BodySdf {
    grid: SdfGrid,
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    clear: wgpu::ComputePipeline,
    splat_distance: wgpu::ComputePipeline,
    splat_nearest: wgpu::ComputePipeline,
    flood: wgpu::ComputePipeline,
    finish: wgpu::ComputePipeline,
    /// Clear and splats (writing buffer A); then one per flood step; then the finish.
    groups: Vec<wgpu::BindGroup>,
    steps: Vec<u32>,
    triangle_count: u32,
    limits: wgpu::Limits,
}

impl BodySdf {
    /// The field of `mesh` over the box `bounds` (where the mesh stays in every pose it
    /// will be built in) with `resolution` nodes along the box's longest axis. Nothing
    /// is computed until [`BodySdf::encode`] (or [`BodySdf::build`]) runs. Refuses a
    /// resolution outside `[MIN_SDF_RESOLUTION, MAX_SDF_RESOLUTION]` or past the device's
    /// `max_texture_dimension_3d` (named `dynamics.sdf_resolution`), a mesh without
    /// triangles (`mesh.indices`), and a grid whose buffers the device cannot bind.
    pub fn new(
        gpu: &Gpu,
        mesh: &MeshBuffers,
        bounds: (Vec3, Vec3),
        resolution: u32,
    ) -> crate::Result<Self> {
        let device_max = gpu.limits().max_texture_dimension_3d;
        if resolution > device_max {
            return Err(ParamError::new(
                "dynamics.sdf_resolution",
                resolution,
                &format!("must be at most {device_max} on this device (max_texture_dimension_3d)"),
            )
            .into());
        }
        if mesh.triangle_count == 0 {
            return Err(ParamError::new(
                "mesh.indices",
                0,
                "a body's distance field needs at least one triangle",
            )
            .into());
        }
        let grid = SdfGrid::new(bounds, resolution)?;
        let nodes = grid.nodes() as u64;
        let storage = wgpu::BufferUsages::STORAGE;
        let bits = zeroed_storage(gpu, "pelage sdf distance bits", nodes * 4, storage)?;
        let near_a = zeroed_storage(gpu, "pelage sdf nearest A", nodes * 4, storage)?;
        let near_b = zeroed_storage(gpu, "pelage sdf nearest B", nodes * 4, storage)?;
        // Scratch of the build: written and read inside its one pass.
        for b in [&bits, &near_a, &near_b] {
            pelage_gpu::audit::name_buffer(b, BODY_SDF);
        }
        let diagonal = (grid.dims - UVec3::ONE).as_vec3().length() * grid.cell;
        let uniforms = UniformBuffer::new(
            gpu,
            "pelage sdf uniforms",
            &SdfUniforms {
                origin: grid.origin,
                cell: grid.cell,
                dims: grid.dims,
                triangle_count: mesh.triangle_count,
                band: SDF_BAND_CELLS,
                far: 2.0 * diagonal,
            },
        )?;
        let steps = flood_steps(grid.dims.max_element());
        let step_buffers = std::iter::once(0)
            .chain(steps.iter().copied())
            .map(|step| {
                let value = JfaStep {
                    step,
                    pad0: 0,
                    pad1: 0,
                    pad2: 0,
                };
                UniformBuffer::new(gpu, "pelage sdf flood step", &value)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let module = crate::SHADERS.library().module(gpu, "strands/sdf.wgsl")?;
        let built = gpu.scoped(|device| {
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("pelage body sdf"),
                size: wgpu::Extent3d {
                    width: grid.dims.x,
                    height: grid.dims.y,
                    depth_or_array_layers: grid.dims.z,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D3,
                format: wgpu::TextureFormat::R32Float,
                usage: wgpu::TextureUsages::STORAGE_BINDING
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            });
            let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
            pelage_gpu::audit::name_view(&view, BODY_SDF);
            let layout = BindLayout::new(SDF_LABEL, wgpu::ShaderStages::COMPUTE)
                .uniform(0)
                .storage(1)
                .storage(2)
                .storage(3)
                .storage_rw(4)
                .storage(5)
                .storage_rw(6)
                .entry(
                    7,
                    wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: wgpu::TextureFormat::R32Float,
                        view_dimension: wgpu::TextureViewDimension::D3,
                    },
                )
                .uniform(8)
                .build(device);
            let pipeline = |entry: &str| {
                compute_pipeline_with_layouts(device, SDF_LABEL, &module, entry, &[Some(&layout)])
            };
            let pipelines = [
                pipeline("clear"),
                pipeline("splat_distance"),
                pipeline("splat_nearest"),
                pipeline("flood"),
                pipeline("finish"),
            ];
            fn buffer(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
                wgpu::BindGroupEntry {
                    binding,
                    resource: b.as_entire_binding(),
                }
            }
            let group = |near_in: &wgpu::Buffer, near_out: &wgpu::Buffer, step: &wgpu::Buffer| {
                pelage_gpu::create_bind_group(
                    device,
                    &wgpu::BindGroupDescriptor {
                        label: Some(SDF_LABEL),
                        layout: &layout,
                        entries: &[
                            buffer(0, &uniforms.buffer),
                            buffer(1, &mesh.positions),
                            buffer(2, &mesh.normals),
                            buffer(3, &mesh.indices),
                            buffer(4, &bits),
                            buffer(5, near_in),
                            buffer(6, near_out),
                            wgpu::BindGroupEntry {
                                binding: 7,
                                resource: wgpu::BindingResource::TextureView(&view),
                            },
                            buffer(8, step),
                        ],
                    },
                )
            };
            // Splats write A; flood step k reads A and writes B when k is even.
            let mut groups = vec![group(&near_b, &near_a, &step_buffers[0].buffer)];
            for (k, step) in step_buffers[1..].iter().enumerate() {
                let (from, to) = if k % 2 == 0 {
                    (&near_a, &near_b)
                } else {
                    (&near_b, &near_a)
                };
                groups.push(group(from, to, &step.buffer));
            }
            let last = if steps.len() % 2 == 1 {
                &near_b
            } else {
                &near_a
            };
            let other = if steps.len() % 2 == 1 {
                &near_a
            } else {
                &near_b
            };
            groups.push(group(last, other, &step_buffers[0].buffer));
            (texture, view, pipelines, groups)
        })?;
        let (texture, view, [clear, splat_distance, splat_nearest, flood, finish], groups) = built;
        Ok(Self {
            grid,
            texture,
            view,
            clear,
            splat_distance,
            splat_nearest,
            flood,
            finish,
            groups,
            steps,
            triangle_count: mesh.triangle_count,
            limits: gpu.limits().clone(),
        })
    }

    /// Records the build ([`SDF_LABEL`]: one compute pass, every dispatch reading the
    /// mesh buffers as they are when it runs).
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        let timestamp_writes = timer.and_then(|t| t.compute_pass(SDF_LABEL));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(SDF_LABEL),
            timestamp_writes,
        });
        let nodes = dispatch_size(&self.limits, self.grid.nodes() as u64, WORKGROUP);
        let triangles = dispatch_size(&self.limits, u64::from(self.triangle_count), WORKGROUP);
        let first = &self.groups[0];
        pelage_gpu::set_bind_group(&mut pass, 0, first);
        for (pipeline, size) in [
            (&self.clear, nodes),
            (&self.splat_distance, triangles),
            (&self.splat_nearest, triangles),
        ] {
            pass.set_pipeline(pipeline);
            pass.dispatch_workgroups(size.0, size.1, 1);
        }
        pass.set_pipeline(&self.flood);
        for group in &self.groups[1..=self.steps.len()] {
            pelage_gpu::set_bind_group(&mut pass, 0, group);
            pass.dispatch_workgroups(nodes.0, nodes.1, 1);
        }
        pass.set_pipeline(&self.finish);
        if let Some(last) = self.groups.last() {
            pelage_gpu::set_bind_group(&mut pass, 0, last);
        }
        pass.dispatch_workgroups(nodes.0, nodes.1, 1);
    }

    /// Records the build and submits it (a field built once: a still or rigid mesh).
    pub fn build(&self, gpu: &Gpu) -> crate::Result<()> {
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some(SDF_LABEL),
            });
        self.encode(&mut encoder, None);
        gpu.queue.submit([encoder.finish()]);
        Ok(())
    }

    /// The pass [`BodySdf::encode`] records: it reads [`MESH`] and writes [`BODY_SDF`].
    pub fn pass(&self) -> PassInfo {
        PassInfo::new(SDF_LABEL).reads([MESH]).writes([BODY_SDF])
    }

    /// The grid.
    pub fn grid(&self) -> &SdfGrid {
        &self.grid
    }

    /// The jump-flooding steps the build runs.
    pub fn flood_steps(&self) -> &[u32] {
        &self.steps
    }

    /// The field (`texture_3d<f32>`, `r32float`, one texel per node).
    pub fn view(&self) -> &wgpu::TextureView {
        &self.view
    }

    /// Bytes the field and its build buffers take on the GPU.
    pub fn bytes(&self) -> u64 {
        self.grid.nodes() as u64 * 16
    }

    /// Reads the field back, one value per node in [`SdfGrid::index`] order. Waits for
    /// the GPU: for tests and tools.
    pub fn read(&self, gpu: &Gpu) -> crate::Result<Vec<f32>> {
        let dims = self.grid.dims;
        let row = u64::from(dims.x) * 4;
        let padded = row.next_multiple_of(u64::from(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT));
        let size = padded * u64::from(dims.y) * u64::from(dims.z);
        let staging = gpu.scoped(|device| {
            pelage_gpu::create_buffer(
                device,
                &wgpu::BufferDescriptor {
                    label: Some("pelage sdf readback"),
                    size,
                    usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                },
            )
        })?;
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("pelage sdf readback"),
            });
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &staging,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded as u32),
                    rows_per_image: Some(dims.y),
                },
            },
            wgpu::Extent3d {
                width: dims.x,
                height: dims.y,
                depth_or_array_layers: dims.z,
            },
        );
        gpu.queue.submit([encoder.finish()]);
        let bytes = read_buffer(gpu, &staging)?;
        let mut out = Vec::with_capacity(self.grid.nodes());
        for r in bytes.chunks(padded as usize) {
            out.extend(
                r[..row as usize]
                    .chunks_exact(4)
                    .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            );
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flood_steps_halve_to_one_then_repeat_it() {
        assert_eq!(flood_steps(64), vec![32, 16, 8, 4, 2, 1, 1]);
        assert_eq!(flood_steps(65), vec![32, 16, 8, 4, 2, 1, 1]);
        assert_eq!(flood_steps(66), vec![64, 32, 16, 8, 4, 2, 1, 1]);
        assert_eq!(flood_steps(2), vec![1]);
    }
}
