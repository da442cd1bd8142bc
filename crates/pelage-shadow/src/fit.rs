//! Fitting a light-space grid to the hair on the GPU (`wgsl/shadow/light_fit.wgsl`),
//! shared by every method that sees the hair from the light.

use encase::ShaderType;
use glam::Vec3;
use pelage_contract::{PreparedFrame, StrandBuffers, StrandFrame, StrandLayout};
use pelage_gpu::{
    BindLayout, Gpu, GpuTimer, PassInfo, UniformBuffer, bind_buffers,
    compute_pipeline_with_layouts, wgpu, zeroed_storage,
};
use pelage_scene::DirectionalLight;

use crate::LightSpace;

/// Invocations of the fit pass (a grid-stride loop covers every vertex).
const FIT_INVOCATIONS: u32 = 64 * 256;

/// `LightGridUniforms` in `wgsl/shadow/light_common.wgsl`.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct LightGridUniforms {
    /// First light-space axis.
    pub axis_x: Vec3,
    /// Voxels along x.
    pub resolution_x: u32,
    /// Second light-space axis.
    pub axis_y: Vec3,
    /// Voxels along y.
    pub resolution_y: u32,
    /// Direction the light travels.
    pub axis_z: Vec3,
    /// Voxels along z (the volume holds one more layer: the column totals).
    pub resolution_z: u32,
    /// Strand vertices.
    pub vertex_count: u32,
    /// Segments per strand.
    pub segments: u32,
    /// Strands.
    pub strand_count: u32,
    /// 0 = nearest, 1 = trilinear.
    pub splat: u32,
    /// Padding around the fitted bounds, world units.
    pub padding: f32,
    /// Hair opacity.
    pub opacity: f32,
    /// Tip width as a fraction of the root width.
    pub tip_width: f32,
    /// Lookup offset toward the light, voxels.
    pub bias_voxels: f32,
    /// Fixed-point units per unit of optical depth, `2^VoxelParams::fixed_point_bits`.
    pub fixed_scale: f32,
    /// `1 / fixed_scale`.
    pub inv_fixed_scale: f32,
    /// Invocations of the fit pass.
    pub fit_invocations: u32,
    /// Smallest cell edge, world units.
    pub min_cell: f32,
}

/// `LightGrid` in `wgsl/shadow/light_common.wgsl`: the grid fitted this frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, ShaderType)]
pub struct LightGrid {
    /// Light-space position of the grid's corner.
    pub origin: Vec3,
    /// Padding.
    pub _pad0: f32,
    /// Cell size, world units.
    pub cell: Vec3,
    /// Padding.
    pub _pad1: f32,
    /// `1 / cell`.
    pub inv_cell: Vec3,
    /// Padding.
    pub _pad2: f32,
}

impl LightGridUniforms {
    /// The uniforms for `strands` (padded by their widest width), on a grid of
    /// `resolution` cells no smaller than `min_cell`; the voxel-only fields (`splat`,
    /// `bias_voxels`, the fixed point) take neutral values for the caller to override.
    pub fn for_hair(strands: &StrandBuffers, resolution: [u32; 3], min_cell: f32) -> Self {
        Self {
            axis_x: Vec3::X,
            resolution_x: resolution[0],
            axis_y: Vec3::Y,
            resolution_y: resolution[1],
            axis_z: Vec3::Z,
            resolution_z: resolution[2],
            vertex_count: strands.strand_count.saturating_mul(strands.segments + 1),
            segments: strands.segments,
            strand_count: strands.strand_count,
            splat: 0,
            padding: strands.style.max_width,
            opacity: strands.style.opacity,
            tip_width: strands.style.tip_width,
            bias_voxels: 0.0,
            fixed_scale: 1.0,
            inv_fixed_scale: 1.0,
            fit_invocations: FIT_INVOCATIONS,
            min_cell,
        }
    }

    /// These uniforms aimed along `light`.
    pub fn aimed(&self, light: &DirectionalLight) -> crate::Result<Self> {
        let space = LightSpace::new(light.to_light()?);
        Ok(Self {
            axis_x: space.x,
            axis_y: space.y,
            axis_z: space.z,
            ..*self
        })
    }
}

/// The fit pass: a reduction of the strand vertices' light-space bounds into a
/// [`LightGrid`], every frame, with no readback.
#[derive(Debug)]
pub struct LightFit {
    base: LightGridUniforms,
    /// The layout the uniforms were last written for (packed strands << 32 | segments).
    drawn: std::sync::atomic::AtomicU64,
    /// The stage 1 frame they were written for.
    prepared: PreparedFrame,
    uniforms: UniformBuffer<LightGridUniforms>,
    bounds: wgpu::Buffer,
    grid: wgpu::Buffer,
    pipelines: [wgpu::ComputePipeline; 2],
    groups: [wgpu::BindGroup; 2],
}

impl LightFit {
    /// The fit of `strands`' vertices under `base` (whose axes `prepare` replaces).
    pub fn new(gpu: &Gpu, base: LightGridUniforms, strands: &StrandBuffers) -> crate::Result<Self> {
        let uniforms = UniformBuffer::new(gpu, "pelage light grid uniforms", &base)?;
        let usage = wgpu::BufferUsages::STORAGE;
        let bounds = zeroed_storage(gpu, "pelage light bounds", 24, usage)?;
        let grid = zeroed_storage(gpu, "pelage light grid", LightGrid::min_size().get(), usage)?;
        pelage_gpu::audit::name_buffer(&bounds, crate::SHADOW_BOUNDS);
        pelage_gpu::audit::name_buffer(&grid, crate::SHADOW_GRID);
        let module = crate::SHADERS
            .library()
            .module(gpu, "shadow/light_fit.wgsl")?;
        let (pipelines, groups) = gpu.scoped(|device| {
            // One layout for both entry points, the union of what they use: fit reads the
            // vertices and widens the bounds, finalize reads the bounds and writes the grid.
            let layout = BindLayout::new("pelage light fit", wgpu::ShaderStages::COMPUTE)
                .uniform(0)
                .storage(1)
                .storage_rw(2)
                .storage_rw(3)
                .build(device);
            let layouts = [Some(&layout)];
            let pipelines = [
                compute_pipeline_with_layouts(device, "pelage light fit", &module, "fit", &layouts),
                compute_pipeline_with_layouts(
                    device,
                    "pelage light fit finalize",
                    &module,
                    "finalize",
                    &layouts,
                ),
            ];
            let group = bind_buffers(
                device,
                "pelage light fit",
                &layout,
                &[&uniforms.buffer, &strands.vertices, &bounds, &grid],
            );
            let groups = [group.clone(), group];
            (pipelines, groups)
        })?;
        Ok(Self {
            base,
            drawn: std::sync::atomic::AtomicU64::new(strands.full_layout().to_bits()),
            prepared: PreparedFrame::default(),
            uniforms,
            bounds,
            grid,
            pipelines,
            groups,
        })
    }

    /// Aims the grid along `light` and takes `strands`' [`StrandLayout`] (the strands
    /// and segments grown this frame); both take effect at the next `encode`, which
    /// must be for the same frame ([`LightFit::check`]).
    pub fn prepare(
        &self,
        queue: &wgpu::Queue,
        strands: &StrandFrame,
        light: &DirectionalLight,
    ) -> crate::Result<()> {
        let layout = strands.layout;
        let uniforms = LightGridUniforms {
            vertex_count: u32::try_from(layout.vertices()).unwrap_or(u32::MAX),
            segments: layout.segments,
            strand_count: layout.strands,
            ..self.base.aimed(light)?
        };
        self.uniforms.write(queue, &uniforms)?;
        self.drawn
            .store(layout.to_bits(), std::sync::atomic::Ordering::Release);
        self.prepared.set(strands);
        Ok(())
    }

    /// Errors unless the last [`LightFit::prepare`] was for `strands` (`stage` names the
    /// method in the error).
    pub fn check(&self, stage: &str, strands: &StrandFrame) -> crate::Result<()> {
        Ok(self.prepared.check(stage, strands)?)
    }

    /// The strands and segments the last `prepare` took: what every pass of this
    /// light draws or splats.
    pub fn drawn(&self) -> StrandLayout {
        StrandLayout::from_bits(self.drawn.load(std::sync::atomic::Ordering::Acquire))
    }

    /// Records the fit (clears the bounds first), timed as `label`.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
        label: &str,
    ) {
        encoder.clear_buffer(&self.bounds, 0, None);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("pelage light fit"),
            timestamp_writes: timer.and_then(|t| t.compute_pass(label)),
        });
        pass.set_pipeline(&self.pipelines[0]);
        pelage_gpu::set_bind_group(&mut pass, 0, &self.groups[0]);
        pass.dispatch_workgroups(FIT_INVOCATIONS / 256, 1, 1);
        pass.set_pipeline(&self.pipelines[1]);
        pelage_gpu::set_bind_group(&mut pass, 0, &self.groups[1]);
        pass.dispatch_workgroups(1, 1, 1);
    }

    /// The fit pass as `encode(.., label)` records it: reads the strand vertices, writes
    /// the grid (`shadow.grid`).
    pub fn pass_info(&self, label: &str) -> PassInfo {
        PassInfo::new(label)
            .reads([pelage_contract::STRAND_VERTICES])
            .writes([crate::SHADOW_BOUNDS, crate::SHADOW_GRID])
    }

    /// The uniforms (binding 0 of every light-space pass).
    pub fn uniforms(&self) -> &wgpu::Buffer {
        &self.uniforms.buffer
    }

    /// The fitted grid, a [`LightGrid`] written by the last `encode`.
    pub fn grid(&self) -> &wgpu::Buffer {
        &self.grid
    }

    /// The uniforms as created (axes are set per frame by `prepare`).
    pub fn base(&self) -> LightGridUniforms {
        self.base
    }

    /// Bytes of GPU memory held.
    pub fn memory_bytes(&self) -> u64 {
        self.uniforms.buffer.size() + self.bounds.size() + self.grid.size()
    }
}
