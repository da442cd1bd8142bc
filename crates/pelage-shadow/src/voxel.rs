//! Voxel shadows: fit, splat, scan (`wgsl/shadow/voxel_*.wgsl`).

use encase::ShaderType;
use glam::Vec3;
use pelage_gpu::{
    BoundResource, Gpu, GpuTimer, ShaderBinding, ShaderLibrary, UniformBuffer, bind_buffers,
    bind_numbered, compute_pipeline, dispatch_size, wgpu, zeroed_storage,
};
use pelage_scene::{DirectionalLight, GrowthParams, Splat, VoxelParams};
use pelage_strands::{MeshBuffers, StrandBuffers};

use crate::{LightSpace, MeshShadowMap};

/// Invocations of the fit pass (a grid-stride loop covers every vertex).
const FIT_INVOCATIONS: u32 = 64 * 256;

/// `VoxelUniforms` in `wgsl/shadow/voxel_common.wgsl`.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct VoxelUniforms {
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

/// `VoxelGrid` in `wgsl/shadow/voxel_common.wgsl`: the grid fitted this frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, ShaderType)]
pub struct VoxelGrid {
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

/// Stage 2's voxel method: a light-space density grid fitted to the hair every frame,
/// splatted with atomics and integrated along the light.
///
/// Per frame, all on the GPU and into the caller's encoder: clear, fit (reduction of
/// the strand vertices' light-space bounds), splat (one invocation per segment), scan
/// (one per column), and the mesh shadow map. The shading pass reads the result
/// through [`VoxelShadow::binding`].
#[derive(Debug)]
pub struct VoxelShadow {
    base: VoxelUniforms,
    uniforms: UniformBuffer<VoxelUniforms>,
    bounds: wgpu::Buffer,
    grid: wgpu::Buffer,
    volume: wgpu::Buffer,
    fit: [wgpu::ComputePipeline; 2],
    fit_groups: [wgpu::BindGroup; 2],
    splat: wgpu::ComputePipeline,
    splat_group: wgpu::BindGroup,
    splat_groups: (u32, u32),
    scan: wgpu::ComputePipeline,
    scan_group: wgpu::BindGroup,
    sample: wgpu::ComputePipeline,
    mesh_map: MeshShadowMap,
}

impl VoxelShadow {
    /// Allocates the grid and builds the passes for `strands` (grown with `growth`) on `mesh`.
    /// `mesh_bounds` is the world box the hair and mesh stay in: the mesh map covers it,
    /// and `VoxelParams::voxel_size` derives the resolution from it.
    pub fn new(
        gpu: &Gpu,
        params: &VoxelParams,
        growth: &GrowthParams,
        strands: &StrandBuffers,
        mesh: &MeshBuffers,
        mesh_bounds: (Vec3, Vec3),
    ) -> crate::Result<Self> {
        params.validate()?;
        growth.validate()?;
        let [rx, ry, rz] = params.resolution_for(mesh_bounds);
        let voxels = u64::from(rx) * u64::from(ry) * u64::from(rz + 1);
        gpu.check_storage_size("voxel shadow grid", voxels * 4)?;
        let vertex_count = strands.strand_count.saturating_mul(strands.segments + 1);
        let base = VoxelUniforms {
            axis_x: Vec3::X,
            resolution_x: rx,
            axis_y: Vec3::Y,
            resolution_y: ry,
            axis_z: Vec3::Z,
            resolution_z: rz,
            vertex_count,
            segments: strands.segments,
            strand_count: strands.strand_count,
            splat: match params.splat {
                Splat::Nearest => 0,
                Splat::Trilinear => 1,
            },
            padding: growth.width,
            opacity: growth.opacity,
            tip_width: growth.tip_width,
            bias_voxels: params.bias_voxels,
            // A power of two, so the scale and its inverse are exact. At the default 2^16 a
            // sample's share of a trilinear splat keeps three significant digits.
            fixed_scale: (1u32 << params.fixed_point_bits) as f32,
            inv_fixed_scale: 1.0 / (1u32 << params.fixed_point_bits) as f32,
            fit_invocations: FIT_INVOCATIONS,
            // A cell a few strand widths across is the finest that estimates density
            // (and a flat groom must not get an infinitely thin grid).
            min_cell: 4.0 * growth.width,
        };
        let uniforms = UniformBuffer::new(gpu, "pelage voxel uniforms", &base)?;
        let usage = wgpu::BufferUsages::STORAGE;
        let bounds = zeroed_storage(gpu, "pelage voxel bounds", 24, usage)?;
        let grid = zeroed_storage(gpu, "pelage voxel grid", VoxelGrid::min_size().get(), usage)?;
        let volume = zeroed_storage(gpu, "pelage voxel volume", voxels * 4, usage)?;
        let mesh_map = MeshShadowMap::new(
            gpu,
            mesh,
            params.mesh_map_size,
            params.mesh_pcf_radius,
            mesh_bounds,
        )?;

        let fit_module = ShaderLibrary::module(gpu, "shadow/voxel_fit.wgsl")?;
        let splat_module = ShaderLibrary::module(gpu, "shadow/voxel_splat.wgsl")?;
        let scan_module = ShaderLibrary::module(gpu, "shadow/voxel_scan.wgsl")?;
        let sample_module = ShaderLibrary::module(gpu, "shadow/voxel_sample.wgsl")?;
        let splat_groups = dispatch_size(
            gpu.limits(),
            u64::from(strands.strand_count) * u64::from(strands.segments),
            64,
        );
        let built = gpu.scoped(|device| {
            let fit = [
                compute_pipeline(device, "pelage voxel fit", &fit_module, "fit"),
                compute_pipeline(device, "pelage voxel finalize", &fit_module, "finalize"),
            ];
            // Each entry point binds only what it uses: fit reads vertices, finalize writes the grid.
            let fit_groups = [
                bind_numbered(
                    device,
                    "pelage voxel fit",
                    &fit[0].get_bind_group_layout(0),
                    &[(0, &uniforms.buffer), (1, &strands.vertices), (2, &bounds)],
                ),
                bind_numbered(
                    device,
                    "pelage voxel finalize",
                    &fit[1].get_bind_group_layout(0),
                    &[(0, &uniforms.buffer), (2, &bounds), (3, &grid)],
                ),
            ];
            let splat = compute_pipeline(device, "pelage voxel splat", &splat_module, "main");
            let splat_group = bind_buffers(
                device,
                "pelage voxel splat",
                &splat.get_bind_group_layout(0),
                &[
                    &uniforms.buffer,
                    &grid,
                    &strands.vertices,
                    &strands.roots,
                    &volume,
                ],
            );
            let scan = compute_pipeline(device, "pelage voxel scan", &scan_module, "main");
            let scan_group = bind_buffers(
                device,
                "pelage voxel scan",
                &scan.get_bind_group_layout(0),
                &[&uniforms.buffer, &volume],
            );
            let sample = compute_pipeline(device, "pelage voxel sample", &sample_module, "main");
            (
                fit,
                fit_groups,
                splat,
                splat_group,
                scan,
                scan_group,
                sample,
            )
        })?;
        let (fit, fit_groups, splat, splat_group, scan, scan_group, sample) = built;
        Ok(Self {
            base,
            uniforms,
            bounds,
            grid,
            volume,
            fit,
            fit_groups,
            splat,
            splat_group,
            splat_groups,
            scan,
            scan_group,
            sample,
            mesh_map,
        })
    }

    /// Aims the grid and the mesh map along `light`; takes effect at the next `encode`.
    pub fn set_light(&self, queue: &wgpu::Queue, light: &DirectionalLight) -> crate::Result<()> {
        let space = LightSpace::new(light.to_light()?);
        let u = VoxelUniforms {
            axis_x: space.x,
            axis_y: space.y,
            axis_z: space.z,
            ..self.base
        };
        self.uniforms.write(queue, &u)?;
        self.mesh_map.set_light(queue, &space)
    }

    /// Records the whole method: fit, splat, scan and the mesh shadow map.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, mut timer: Option<&mut GpuTimer>) {
        self.encode_density(encoder, timer.as_deref_mut());
        self.encode_scan(encoder, timer.as_deref_mut());
        self.mesh_map.encode(encoder, timer);
    }

    /// Records the first half: clear, fit the grid, splat the density (u32 fixed point
    /// in [`VoxelShadow::volume`]).
    pub fn encode_density(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        mut timer: Option<&mut GpuTimer>,
    ) {
        encoder.clear_buffer(&self.bounds, 0, None);
        encoder.clear_buffer(&self.volume, 0, None);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("pelage voxel fit"),
                timestamp_writes: timer
                    .as_deref_mut()
                    .and_then(|t| t.compute_pass("shadow: fit")),
            });
            pass.set_pipeline(&self.fit[0]);
            pass.set_bind_group(0, &self.fit_groups[0], &[]);
            pass.dispatch_workgroups(FIT_INVOCATIONS / 256, 1, 1);
            pass.set_pipeline(&self.fit[1]);
            pass.set_bind_group(0, &self.fit_groups[1], &[]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("pelage voxel splat"),
            timestamp_writes: timer.and_then(|t| t.compute_pass("shadow: splat")),
        });
        pass.set_pipeline(&self.splat);
        pass.set_bind_group(0, &self.splat_group, &[]);
        pass.dispatch_workgroups(self.splat_groups.0, self.splat_groups.1, 1);
    }

    /// Records the scan alone: turns the u32 densities in [`VoxelShadow::volume`] into
    /// f32 optical depths in place (what `encode` runs after the splat).
    pub fn encode_scan(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("pelage voxel scan"),
            timestamp_writes: timer.and_then(|t| t.compute_pass("shadow: scan")),
        });
        pass.set_pipeline(&self.scan);
        pass.set_bind_group(0, &self.scan_group, &[]);
        pass.dispatch_workgroups(
            self.base.resolution_x.div_ceil(8),
            self.base.resolution_y.div_ceil(8),
            1,
        );
    }

    /// Records a measurement: the hair's transmittance (mesh excluded) at each `vec4`
    /// point of `points` into the `f32`s of `out` (as many as `out` holds). Builds a
    /// bind group per call: for tests and labs, not the frame loop.
    pub fn encode_sample(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        points: &wgpu::Buffer,
        out: &wgpu::Buffer,
    ) -> crate::Result<()> {
        let groups = dispatch_size(gpu.limits(), out.size() / 4, 64);
        let (own, lookup) = gpu.scoped(|device| {
            let own = bind_buffers(
                device,
                "pelage voxel sample",
                &self.sample.get_bind_group_layout(0),
                &[points, out],
            );
            let lookup = bind_buffers(
                device,
                "pelage voxel sample lookup",
                &self.sample.get_bind_group_layout(1),
                &[&self.uniforms.buffer, &self.grid, &self.volume],
            );
            (own, lookup)
        })?;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("pelage voxel sample"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.sample);
        pass.set_bind_group(0, &own, &[]);
        pass.set_bind_group(1, &lookup, &[]);
        pass.dispatch_workgroups(groups.0, groups.1, 1);
        Ok(())
    }

    /// The shadow contract's implementation for the shading passes.
    pub fn binding(&self) -> ShaderBinding {
        let [map_uniforms, map_view, map_sampler] = self.mesh_map.resources();
        ShaderBinding {
            contract: "shadow/none.wgsl",
            module: "shadow/voxel_lookup.wgsl",
            group: 1,
            resources: vec![
                BoundResource::Buffer(self.uniforms.buffer.clone()),
                BoundResource::Buffer(self.grid.clone()),
                BoundResource::Buffer(self.volume.clone()),
                map_uniforms,
                map_view,
                map_sampler,
            ],
        }
    }

    /// The volume: `resolution_x * resolution_y * (resolution_z + 1)` cells, index
    /// `(z * ry + y) * rx + x`; u32 fixed-point density after the splat, f32 optical
    /// depth in front of each voxel after the scan (the last layer: column totals).
    pub fn volume(&self) -> &wgpu::Buffer {
        &self.volume
    }

    /// The grid fitted by the last `encode` (a [`VoxelGrid`]).
    pub fn grid(&self) -> &wgpu::Buffer {
        &self.grid
    }

    /// The uniforms as last set (light axes included after `set_light`).
    pub fn base_uniforms(&self) -> VoxelUniforms {
        self.base
    }

    /// Bytes of GPU memory the method holds (grid volume, mesh map, small buffers).
    pub fn memory_bytes(&self) -> u64 {
        self.volume.size() + self.mesh_map.memory_bytes() + self.bounds.size() + self.grid.size()
    }
}
