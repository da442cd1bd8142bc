//! The volume method of multiple scattering (after Moon, Walter and Marschner 2008): a
//! radiance grid over the hair, filled every frame by the compute passes of
//! `wgsl/shade/volume.wgsl` and read by `wgsl/shade/models/chiang_volume_common_model.wgsl`
//! (the `volume` and `dual_volume` models).
//! The grid, the phase function and the approximations are described in
//! `wgsl/shade/models/volume_common.wgsl`; the CPU mirror is `pelage_reference::volume`.
//!
//! Per frame: fit a cube of `volume_grid`³ cells to the hair's bounds; splat every segment's
//! optical depth, tangent and colour (u32 atomics, fixed point: it runs where 64-bit and
//! float atomics do not, the browser included); inject the light each cell scatters once
//! from each light and from the sky (`shade.ambient`, radiance `ambient/π` from every
//! direction, 15 directions), through the grid's own transmittance toward the light (so
//! it works with every shadow method), and add the sky's unscattered light to the fluence
//! (the hair's single scattering of the sky is read from the grid); propagate it
//! `volume_iterations` cells along the six axis directions (discrete ordinates, each
//! direction's light spreading to the four diagonal neighbours ahead as its cone of
//! directions does), scattering with Chiang's energies at each cell; keep the fluence and
//! flux per cell and channel (order-1 spherical harmonics, 4 coefficients per channel).

use encase::ShaderType;
use pelage_contract::{MeshBuffers, StrandBuffers, StrandLayout};
use pelage_gpu::{
    BindLayout, Gpu, GpuTimer, PassInfo, UniformBuffer, bind_numbered,
    compute_pipeline_with_layouts, dispatch_size, wgpu, zeroed_storage,
};
use pelage_scene::{ChiangParams, MAX_VOLUME_GRID, MIN_VOLUME_GRID, ParamError, mesh_albedo};

use crate::models::ChiangTables;

/// `VolumeUniforms` in `wgsl/shade/models/volume_common.wgsl`.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct VolumeUniforms {
    /// Cells per side.
    pub resolution: u32,
    /// Propagation steps.
    pub iterations: u32,
    /// Strand vertices this frame.
    pub vertex_count: u32,
    /// Segments per strand this frame.
    pub segments: u32,
    /// Strands this frame.
    pub strand_count: u32,
    /// Invocations of the fit pass.
    pub fit_invocations: u32,
    /// Tip width as a fraction of the root width.
    pub tip_width: f32,
    /// Fixed-point units per unit of optical depth.
    pub fixed_scale: f32,
    /// Its inverse.
    pub inv_fixed_scale: f32,
    /// Smallest cell edge, world units.
    pub min_cell: f32,
    /// Triangles of the mesh under the hair (0: none).
    pub triangle_count: u32,
    /// 1 when the grid carries the light the fibres scatter of the lights (`volume`), 0
    /// when dual scattering carries it (`dual_volume`): the injection's weight.
    pub light_fibres: f32,
    /// The mesh's Lambertian albedo per channel (π times `shade.mesh_color`, at most 1).
    pub mesh_albedo: glam::Vec3,
    /// Padding.
    pub _pad2: f32,
}

/// Fixed-point units per unit of optical depth in the splat (2^16: a cell saturates at an
/// optical depth of 65 536, and a sample of depth 1/131 072 still counts).
pub const VOLUME_FIXED_SCALE: f32 = 65_536.0;
/// Invocations of the fit pass.
const FIT_INVOCATIONS: u32 = 256 * 64;
/// Bytes per cell of the fluence and the medium (3 vec4: per channel fluence and flux).
const CELL_BYTES: u64 = 48;
/// Bytes per cell of a propagation state, the largest buffers (6 vec4: the light leaving
/// along each axis direction, rgb and an unused w).
const STATE_BYTES: u64 = 96;
/// u32 per cell of the splat accumulator (`VOLUME_ACCUM`).
const ACCUM_U32: u64 = 12;
/// The frame resource of the grid's fluence (what the hair passes read).
pub const VOLUME_FLUENCE: &str = "volume.fluence";

/// The grid pass's own buffers (bounds, splat accumulator, medium, propagation states):
/// written and read within the pass.
pub const VOLUME_SCRATCH: &str = "volume.scratch";

/// The grid's uniform and fluence: what the shading reads (bound by
/// [`HairModel`](crate::HairModel) at group 2, bindings 3 and 4).
#[derive(Debug)]
pub struct VolumeField {
    uniform: UniformBuffer<VolumeUniforms>,
    value: VolumeUniforms,
    fluence: wgpu::Buffer,
}

impl VolumeField {
    /// The largest `volume_grid` this device holds (its storage binding and buffer size).
    pub fn max_resolution(gpu: &Gpu) -> u32 {
        let limit = gpu
            .limits()
            .max_storage_buffer_binding_size
            .min(gpu.limits().max_buffer_size);
        let cells = limit / STATE_BYTES;
        let mut n = (cells as f64).cbrt().floor() as u32;
        while n > 0 && u64::from(n).pow(3) > cells {
            n -= 1;
        }
        n.min(MAX_VOLUME_GRID)
    }

    /// Allocates the field for `params` (`volume_grid` cells per side); errors naming
    /// `shading.chiang.volume_grid` when the device cannot hold it.
    pub fn new(gpu: &Gpu, params: &ChiangParams) -> crate::Result<Self> {
        params.validate()?;
        let n = params.volume_grid;
        let max = Self::max_resolution(gpu);
        if n > max {
            return Err(ParamError::new(
                "shading.chiang.volume_grid",
                n,
                &format!(
                    "must be in [{MIN_VOLUME_GRID}, {max}] on this device (its storage binding \
                     limit holds {max}³ cells of {STATE_BYTES} bytes)"
                ),
            )
            .into());
        }
        let value = VolumeUniforms {
            resolution: n,
            iterations: params.volume_iterations,
            vertex_count: 0,
            segments: 0,
            strand_count: 0,
            fit_invocations: FIT_INVOCATIONS,
            tip_width: 1.0,
            fixed_scale: VOLUME_FIXED_SCALE,
            inv_fixed_scale: 1.0 / VOLUME_FIXED_SCALE,
            min_cell: 1e-6,
            triangle_count: 0,
            light_fibres: if params.multiple_scattering.grid_carries_lights() {
                1.0
            } else {
                0.0
            },
            mesh_albedo: glam::Vec3::ZERO,
            _pad2: 0.0,
        };
        let uniform = UniformBuffer::new(gpu, "pelage volume", &value)?;
        let fluence = zeroed_storage(
            gpu,
            "pelage volume fluence",
            16 + cells(n) * CELL_BYTES,
            wgpu::BufferUsages::STORAGE,
        )?;
        pelage_gpu::audit::name_buffer(&fluence, VOLUME_FLUENCE);
        Ok(Self {
            uniform,
            value,
            fluence,
        })
    }

    /// The uniform (binding 3 of the model's group).
    pub fn uniform_buffer(&self) -> &wgpu::Buffer {
        &self.uniform.buffer
    }

    /// The fluence: a header `(origin, cell edge)` and 3 vec4 per cell (binding 4).
    pub fn fluence_buffer(&self) -> &wgpu::Buffer {
        &self.fluence
    }

    /// The uniform's value as last written.
    pub fn uniforms(&self) -> &VolumeUniforms {
        &self.value
    }

    /// Cells per side.
    pub fn resolution(&self) -> u32 {
        self.value.resolution
    }
}

fn cells(n: u32) -> u64 {
    u64::from(n).pow(3)
}

/// The grid passes of one frame: fit, splat, occupy, describe, inject, propagate
/// (`wgsl/shade/volume.wgsl`).
#[derive(Debug)]
pub struct VolumeGrid {
    field_uniform: wgpu::Buffer,
    value: std::sync::Mutex<VolumeUniforms>,
    bounds: wgpu::Buffer,
    accum: wgpu::Buffer,
    medium: wgpu::Buffer,
    fit: [wgpu::ComputePipeline; 2],
    splat: wgpu::ComputePipeline,
    splat_mesh: wgpu::ComputePipeline,
    occupy: wgpu::ComputePipeline,
    mesh_group: wgpu::BindGroup,
    /// Writes the medium the later passes read without atomics.
    describe: wgpu::ComputePipeline,
    inject: wgpu::ComputePipeline,
    propagate: wgpu::ComputePipeline,
    /// The fluence over the clear share of cells the body partly fills (two passes).
    settle: [wgpu::ComputePipeline; 2],
    fit_group: wgpu::BindGroup,
    splat_group: wgpu::BindGroup,
    inject_group: wgpu::BindGroup,
    chiang_group: wgpu::BindGroup,
    propagate_groups: [wgpu::BindGroup; 2],
    max_segments: u64,
    bytes: u64,
    /// The device's limits (the dispatch sizes).
    limits: wgpu::Limits,
}

impl VolumeGrid {
    /// The passes filling `field` from `strands`, lit by the lights of the `frame`
    /// uniform (`FrameUniforms`), scattering with `tables` (Chiang's, of the same
    /// parameters), over `mesh` (the body under the hair: it shadows the light and
    /// reflects it as a Lambertian of albedo `π · mesh_color`, at most 1 per channel;
    /// `None`: no body).
    pub fn new(
        gpu: &Gpu,
        field: &VolumeField,
        tables: &ChiangTables,
        frame: &wgpu::Buffer,
        strands: &StrandBuffers,
        mesh: Option<&MeshBuffers>,
        mesh_color: glam::Vec3,
    ) -> crate::Result<Self> {
        let n = cells(field.resolution());
        let usage = wgpu::BufferUsages::STORAGE;
        let empty = zeroed_storage(gpu, "pelage volume no mesh", 16, usage)?;
        pelage_gpu::audit::constant(&[&empty]);
        let (positions, indices, normals, triangle_count) = match mesh {
            Some(m) => (&m.positions, &m.indices, &m.normals, m.triangle_count),
            None => (&empty, &empty, &empty, 0),
        };
        let mut value = *field.uniforms();
        value.triangle_count = triangle_count;
        value.mesh_albedo = mesh_albedo(mesh_color);
        let bounds = zeroed_storage(gpu, "pelage volume bounds", 24, usage)?;
        let accum = zeroed_storage(gpu, "pelage volume accum", n * ACCUM_U32 * 4, usage)?;
        let medium = zeroed_storage(gpu, "pelage volume medium", n * CELL_BYTES, usage)?;
        let states = [
            zeroed_storage(gpu, "pelage volume state a", n * STATE_BYTES, usage)?,
            zeroed_storage(gpu, "pelage volume state b", n * STATE_BYTES, usage)?,
        ];
        for buffer in [&bounds, &accum, &medium, &states[0], &states[1]] {
            pelage_gpu::audit::name_buffer(buffer, VOLUME_SCRATCH);
        }
        let module = crate::SHADERS.library().module(gpu, "shade/volume.wgsl")?;
        let c = wgpu::ShaderStages::COMPUTE;
        let bytes = bounds.size()
            + accum.size()
            + medium.size()
            + states[0].size()
            + states[1].size()
            + field.fluence_buffer().size()
            + field.uniform_buffer().size();
        Ok(gpu.scoped(|device| {
            let fit_layout = BindLayout::new("pelage volume fit", c)
                .uniform(0)
                .storage(2)
                .storage_rw(4)
                .storage_rw(9)
                .build(device);
            let splat_layout = BindLayout::new("pelage volume splat", c)
                .uniform(0)
                .storage(2)
                .storage(3)
                .storage_rw(5)
                .storage_rw(9)
                .build(device);
            let inject_layout = BindLayout::new("pelage volume inject", c)
                .uniform(0)
                .uniform(1)
                .storage_rw(5)
                .storage_rw(6)
                .storage_rw(8)
                .storage_rw(9)
                .build(device);
            let chiang_layout = BindLayout::new("pelage volume chiang", c)
                .uniform(0)
                .storage(1)
                .storage(2)
                .build(device);
            let mesh_layout = BindLayout::new("pelage volume mesh", c)
                .uniform(0)
                .storage_rw(5)
                .storage_rw(9)
                .storage(10)
                .storage(11)
                .storage(12)
                .build(device);
            let propagate_layout = BindLayout::new("pelage volume propagate", c)
                .uniform(0)
                .storage_rw(5)
                .storage_rw(6)
                .storage(7)
                .storage_rw(8)
                .storage_rw(9)
                .build(device);
            let pipe = |label, entry, layouts: &[Option<&wgpu::BindGroupLayout>]| {
                compute_pipeline_with_layouts(device, label, &module, entry, layouts)
            };
            let fit = [
                pipe("pelage volume fit", "fit", &[Some(&fit_layout)]),
                pipe("pelage volume finalize", "finalize", &[Some(&fit_layout)]),
            ];
            let splat = pipe("pelage volume splat", "splat", &[Some(&splat_layout)]);
            let splat_mesh = pipe(
                "pelage volume splat mesh",
                "splat_mesh",
                &[Some(&mesh_layout)],
            );
            let occupy = pipe("pelage volume occupy", "occupy", &[Some(&mesh_layout)]);
            let describe = pipe(
                "pelage volume describe",
                "describe",
                &[Some(&inject_layout), None, Some(&chiang_layout)],
            );
            let inject = pipe(
                "pelage volume inject",
                "inject",
                &[Some(&inject_layout), None, Some(&chiang_layout)],
            );
            let propagate = pipe(
                "pelage volume propagate",
                "propagate",
                &[Some(&propagate_layout)],
            );
            let settle = [
                pipe("pelage volume settle", "settle", &[Some(&propagate_layout)]),
                pipe(
                    "pelage volume settled",
                    "settled",
                    &[Some(&propagate_layout)],
                ),
            ];
            let u = field.uniform_buffer();
            let fl = field.fluence_buffer();
            let fit_group = bind_numbered(
                device,
                "pelage volume fit",
                &fit_layout,
                &[(0, u), (2, &strands.vertices), (4, &bounds), (9, fl)],
            );
            let splat_group = bind_numbered(
                device,
                "pelage volume splat",
                &splat_layout,
                &[
                    (0, u),
                    (2, &strands.vertices),
                    (3, &strands.roots),
                    (5, &accum),
                    (9, fl),
                ],
            );
            let mesh_group = bind_numbered(
                device,
                "pelage volume mesh",
                &mesh_layout,
                &[
                    (0, u),
                    (5, &accum),
                    (9, fl),
                    (10, positions),
                    (11, indices),
                    (12, normals),
                ],
            );
            let inject_group = bind_numbered(
                device,
                "pelage volume inject",
                &inject_layout,
                &[
                    (0, u),
                    (1, frame),
                    (5, &accum),
                    (6, &medium),
                    (8, &states[0]),
                    (9, fl),
                ],
            );
            let chiang_group = bind_numbered(
                device,
                "pelage volume chiang",
                &chiang_layout,
                &[
                    (0, tables.model_buffer()),
                    (1, tables.n_buffer()),
                    (2, tables.dual_buffer()),
                ],
            );
            let propagate_group = |from: usize| {
                bind_numbered(
                    device,
                    "pelage volume propagate",
                    &propagate_layout,
                    &[
                        (0, u),
                        (5, &accum),
                        (6, &medium),
                        (7, &states[from]),
                        (8, &states[1 - from]),
                        (9, fl),
                    ],
                )
            };
            let propagate_groups = [propagate_group(0), propagate_group(1)];
            Self {
                field_uniform: field.uniform_buffer().clone(),
                value: std::sync::Mutex::new(value),
                bounds,
                accum,
                medium,
                fit,
                splat,
                splat_mesh,
                occupy,
                mesh_group,
                describe,
                inject,
                propagate,
                settle,
                fit_group,
                splat_group,
                inject_group,
                chiang_group,
                propagate_groups,
                max_segments: u64::from(strands.strand_count) * u64::from(strands.segments),
                bytes,
                limits: gpu.limits().clone(),
            }
        })?)
    }

    /// Sets the body's colour (`shade.mesh_color`) for the frames that follow (the next
    /// [`VolumeGrid::prepare`] writes it).
    pub fn set_mesh_color(&self, mesh_color: glam::Vec3) {
        let albedo = mesh_albedo(mesh_color);
        match self.value.lock() {
            Ok(mut v) => v.mesh_albedo = albedo,
            Err(poisoned) => poisoned.into_inner().mesh_albedo = albedo,
        }
    }

    /// Writes the uniform for this frame's strands (`layout`, of strands whose tips are
    /// `tip_width` of their roots' width).
    pub fn prepare(
        &self,
        queue: &wgpu::Queue,
        layout: StrandLayout,
        tip_width: f32,
    ) -> crate::Result<()> {
        let segments = layout.segment_count().min(self.max_segments);
        let mut v = self.uniforms();
        v.strand_count = layout.strands;
        v.segments = layout.segments;
        v.vertex_count = u32::try_from(layout.vertices()).unwrap_or(u32::MAX);
        v.tip_width = tip_width;
        if segments < layout.segment_count() || layout.segments == 0 {
            v.strand_count = 0;
            v.vertex_count = 0;
        }
        pelage_gpu::write_storage(queue, "pelage volume", &self.field_uniform, &v)?;
        if let Ok(mut held) = self.value.lock() {
            *held = v;
        }
        Ok(())
    }

    /// Records the passes: clears, fit, splat, inject, the propagation steps and the
    /// settling of the fluence where the body fills part of a cell.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        let limits = &self.limits;
        let v = self.uniforms();
        encoder.clear_buffer(&self.bounds, 0, None);
        encoder.clear_buffer(&self.accum, 0, None);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(PASS),
            timestamp_writes: timer.and_then(|t| t.compute_pass(PASS)),
        });
        pelage_gpu::set_bind_group(&mut pass, 0, &self.fit_group);
        pass.set_pipeline(&self.fit[0]);
        pass.dispatch_workgroups(FIT_INVOCATIONS / 256, 1, 1);
        pass.set_pipeline(&self.fit[1]);
        pass.dispatch_workgroups(1, 1, 1);
        let segments = u64::from(v.strand_count) * u64::from(v.segments);
        if segments > 0 {
            let (x, y) = dispatch_size(limits, segments, 64);
            pelage_gpu::set_bind_group(&mut pass, 0, &self.splat_group);
            pass.set_pipeline(&self.splat);
            pass.dispatch_workgroups(x, y, 1);
        }
        if v.triangle_count > 0 {
            let (x, y) = dispatch_size(limits, u64::from(v.triangle_count), 64);
            pelage_gpu::set_bind_group(&mut pass, 0, &self.mesh_group);
            pass.set_pipeline(&self.splat_mesh);
            pass.dispatch_workgroups(x, y, 1);
        }
        let (x, y) = dispatch_size(limits, cells(v.resolution), 64);
        if v.triangle_count > 0 {
            // Without a mesh every cell's solid share is the cleared 0.
            pelage_gpu::set_bind_group(&mut pass, 0, &self.mesh_group);
            pass.set_pipeline(&self.occupy);
            pass.dispatch_workgroups(x, y, 1);
        }
        pelage_gpu::set_bind_group(&mut pass, 0, &self.inject_group);
        pelage_gpu::set_bind_group(&mut pass, 2, &self.chiang_group);
        pass.set_pipeline(&self.describe);
        pass.dispatch_workgroups(x, y, 1);
        pass.set_pipeline(&self.inject);
        pass.dispatch_workgroups(x, y, 1);
        pass.set_pipeline(&self.propagate);
        let steps = v.iterations as usize;
        for step in 0..steps {
            pelage_gpu::set_bind_group(&mut pass, 0, &self.propagate_groups[step % 2]);
            pass.dispatch_workgroups(x, y, 1);
        }
        if v.triangle_count > 0 {
            // `settle` writes the state the next step would, `settled` reads it back
            // (without a mesh no cell is solid and the fluence stays as it is).
            pelage_gpu::set_bind_group(&mut pass, 0, &self.propagate_groups[steps % 2]);
            pass.set_pipeline(&self.settle[0]);
            pass.dispatch_workgroups(x, y, 1);
            pelage_gpu::set_bind_group(&mut pass, 0, &self.propagate_groups[(steps + 1) % 2]);
            pass.set_pipeline(&self.settle[1]);
            pass.dispatch_workgroups(x, y, 1);
        }
    }

    /// The pass as the frame plan lists it: reads the strands and the mesh, writes the
    /// fluence.
    pub fn pass_info(&self) -> PassInfo {
        PassInfo::new(PASS)
            .reads([
                pelage_contract::STRAND_VERTICES,
                pelage_contract::STRAND_ROOTS,
                pelage_contract::MESH,
            ])
            .writes([VOLUME_SCRATCH, VOLUME_FLUENCE])
    }

    /// The uniform as last written by [`VolumeGrid::prepare`].
    pub fn uniforms(&self) -> VolumeUniforms {
        match self.value.lock() {
            Ok(v) => *v,
            Err(poisoned) => *poisoned.into_inner(),
        }
    }

    /// Bytes of GPU memory a grid of `resolution`³ cells holds (what
    /// [`VolumeGrid::memory_bytes`] reports): 336 bytes per cell and 104 more.
    pub fn bytes_for(resolution: u32) -> u64 {
        let n = cells(resolution);
        24 + n * ACCUM_U32 * 4
            + n * CELL_BYTES
            + 2 * n * STATE_BYTES
            + (16 + n * CELL_BYTES)
            + VolumeUniforms::min_size().get()
    }

    /// Bytes of GPU memory (every buffer of the grid, the fluence included).
    pub fn memory_bytes(&self) -> u64 {
        self.bytes
    }

    /// The per-cell scratch buffers, for tests: the accumulator (8 u32 per cell) and the
    /// medium (3 vec4 per cell).
    pub fn scratch_buffers(&self) -> (&wgpu::Buffer, &wgpu::Buffer) {
        (&self.accum, &self.medium)
    }
}

/// The label of the grid's compute pass (and its GPU timer scope).
pub const PASS: &str = "shade: volume grid";
