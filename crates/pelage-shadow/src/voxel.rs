//! Voxel shadows: fit, splat, scan (`wgsl/shadow/voxel_*.wgsl`).

use glam::Vec3;
use pelage_contract::{MeshBuffers, StrandBuffers, StrandFrame};
use pelage_gpu::{
    BindLayout, BoundResource, Gpu, GpuTimer, PassInfo, ShaderBinding, bind_buffers,
    compute_pipeline_with_layouts, dispatch_size, wgpu, zeroed_storage,
};
use pelage_scene::{DirectionalLight, Splat, VoxelParams};

use crate::{LightFit, LightGridUniforms, MeshShadowMap, ShadowMethod};

/// Stage 2's voxel method: a light-space density grid fitted to the hair every frame,
/// splatted with atomics and integrated along the light.
///
/// Per frame, all on the GPU and into the caller's encoder: fit (reduction of the
/// strand vertices' light-space bounds), clear, splat (one invocation per segment),
/// scan (one per column), and the mesh shadow map. The shading pass reads the result
/// through [`ShadowMethod::binding`].
#[derive(Debug)]
pub struct VoxelShadow {
    params: VoxelParams,
    fit: LightFit,
    volume: wgpu::Buffer,
    splat: wgpu::ComputePipeline,
    splat_group: wgpu::BindGroup,
    limits: wgpu::Limits,
    scan: wgpu::ComputePipeline,
    scan_group: wgpu::BindGroup,
    mesh_map: MeshShadowMap,
}

impl VoxelShadow {
    /// Allocates the grid and builds the passes for `strands` on `mesh`.
    /// `reach` is the world box the hair and mesh stay in: the mesh map covers it,
    /// and `VoxelParams::voxel_size` derives the resolution from it.
    pub fn new(
        gpu: &Gpu,
        params: &VoxelParams,
        strands: &StrandBuffers,
        mesh: &MeshBuffers,
        reach: (Vec3, Vec3),
    ) -> crate::Result<Self> {
        params.validate()?;
        strands.style.validate()?;
        let resolution = params.resolution_for(reach);
        let [rx, ry, rz] = resolution;
        let voxels = u64::from(rx) * u64::from(ry) * u64::from(rz + 1);
        gpu.check_storage_size("voxel shadow grid", voxels * 4)?;
        // A power of two, so the scale and its inverse are exact. At the default 2^16 a
        // sample's share of a trilinear splat keeps three significant digits.
        let fixed_scale = (1u32 << params.fixed_point_bits) as f32;
        let base = LightGridUniforms {
            splat: match params.splat {
                Splat::Nearest => 0,
                Splat::Trilinear => 1,
            },
            bias_voxels: params.bias_voxels,
            fixed_scale,
            inv_fixed_scale: 1.0 / fixed_scale,
            // A cell a few strand widths across is the finest that estimates density
            // (and a flat groom must not get an infinitely thin grid).
            ..LightGridUniforms::for_hair(strands, resolution, 4.0 * strands.style.width)
        };
        let fit = LightFit::new(gpu, base, strands)?;
        let volume = zeroed_storage(
            gpu,
            "pelage voxel volume",
            voxels * 4,
            wgpu::BufferUsages::STORAGE,
        )?;
        pelage_gpu::audit::name_buffer(&volume, crate::SHADOW_VOLUME);
        let mesh_map = MeshShadowMap::new(
            gpu,
            mesh,
            params.mesh_map_size,
            params.mesh_pcf_radius,
            reach,
        )?;

        let splat_module = crate::SHADERS
            .library()
            .module(gpu, "shadow/voxel_splat.wgsl")?;
        let scan_module = crate::SHADERS
            .library()
            .module(gpu, "shadow/voxel_scan.wgsl")?;
        let (splat, splat_group, scan, scan_group) = gpu.scoped(|device| {
            // voxel_splat.wgsl: grid uniforms and grid, vertices, roots, the volume written.
            let splat_layout = BindLayout::new("pelage voxel splat", wgpu::ShaderStages::COMPUTE)
                .uniform(0)
                .storage(1)
                .storage(2)
                .storage(3)
                .storage_rw(4)
                .build(device);
            let splat = compute_pipeline_with_layouts(
                device,
                "pelage voxel splat",
                &splat_module,
                "main",
                &[Some(&splat_layout)],
            );
            let splat_group = bind_buffers(
                device,
                "pelage voxel splat",
                &splat_layout,
                &[
                    fit.uniforms(),
                    fit.grid(),
                    &strands.vertices,
                    &strands.roots,
                    &volume,
                ],
            );
            // voxel_scan.wgsl: grid uniforms, the volume scanned in place.
            let scan_layout = BindLayout::new("pelage voxel scan", wgpu::ShaderStages::COMPUTE)
                .uniform(0)
                .storage_rw(1)
                .build(device);
            let scan = compute_pipeline_with_layouts(
                device,
                "pelage voxel scan",
                &scan_module,
                "main",
                &[Some(&scan_layout)],
            );
            let scan_group = bind_buffers(
                device,
                "pelage voxel scan",
                &scan_layout,
                &[fit.uniforms(), &volume],
            );
            (splat, splat_group, scan, scan_group)
        })?;
        Ok(Self {
            params: params.clone(),
            fit,
            volume,
            splat,
            splat_group,
            limits: gpu.limits().clone(),
            scan,
            scan_group,
            mesh_map,
        })
    }

    /// Records the first half: fit the grid, clear, splat the density (u32 fixed point
    /// in [`VoxelShadow::volume`]).
    pub fn encode_density(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        mut timer: Option<&mut GpuTimer>,
    ) {
        self.fit
            .encode(encoder, timer.as_deref_mut(), "shadow: fit");
        encoder.clear_buffer(&self.volume, 0, None);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("pelage voxel splat"),
            timestamp_writes: timer.and_then(|t| t.compute_pass("shadow: splat")),
        });
        pass.set_pipeline(&self.splat);
        pelage_gpu::set_bind_group(&mut pass, 0, &self.splat_group);
        // The segments stage 1 grew this frame (see LightFit::drawn).
        let groups = dispatch_size(&self.limits, self.fit.drawn().segment_count(), 64);
        pass.dispatch_workgroups(groups.0, groups.1, 1);
    }

    /// Records the scan alone: turns the u32 densities in [`VoxelShadow::volume`] into
    /// f32 optical depths in place (what `encode` runs after the splat).
    pub fn encode_scan(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("pelage voxel scan"),
            timestamp_writes: timer.and_then(|t| t.compute_pass("shadow: scan")),
        });
        pass.set_pipeline(&self.scan);
        pelage_gpu::set_bind_group(&mut pass, 0, &self.scan_group);
        let base = self.fit.base();
        pass.dispatch_workgroups(
            base.resolution_x.div_ceil(8),
            base.resolution_y.div_ceil(8),
            1,
        );
    }

    /// The volume: `resolution_x * resolution_y * (resolution_z + 1)` cells, index
    /// `(z * ry + y) * rx + x`; u32 fixed-point density after the splat, f32 optical
    /// depth in front of each voxel after the scan (the last layer: column totals).
    pub fn volume(&self) -> &wgpu::Buffer {
        &self.volume
    }

    /// The grid fitted by the last `encode` (a [`crate::LightGrid`]).
    pub fn grid(&self) -> &wgpu::Buffer {
        self.fit.grid()
    }

    /// The uniforms as created (the light's axes are set per frame).
    pub fn base_uniforms(&self) -> LightGridUniforms {
        self.fit.base()
    }
}

impl ShadowMethod for VoxelShadow {
    fn name(&self) -> String {
        let [x, y, z] = [
            self.fit.base().resolution_x,
            self.fit.base().resolution_y,
            self.fit.base().resolution_z,
        ];
        let splat = match self.params.splat {
            Splat::Nearest => "nearest",
            Splat::Trilinear => "trilinear",
        };
        format!("voxel {x}x{y}x{z} {splat}")
    }

    fn prepare(
        &self,
        queue: &wgpu::Queue,
        strands: &StrandFrame,
        light: &DirectionalLight,
    ) -> crate::Result<()> {
        self.fit.prepare(queue, strands, light)?;
        self.mesh_map.set_light(queue, light)
    }

    fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        strands: &StrandFrame,
        mut timer: Option<&mut GpuTimer>,
    ) -> crate::Result<()> {
        self.fit.check("shadow: voxel", strands)?;
        self.encode_density(encoder, timer.as_deref_mut());
        self.encode_scan(encoder, timer.as_deref_mut());
        self.mesh_map.encode(encoder, timer);
        Ok(())
    }

    fn passes(&self) -> Vec<PassInfo> {
        use pelage_contract::{STRAND_ROOTS, STRAND_VERTICES};
        let mut passes = vec![
            self.fit.pass_info("shadow: fit"),
            PassInfo::new("shadow: splat")
                .reads([crate::SHADOW_GRID, STRAND_VERTICES, STRAND_ROOTS])
                .writes([crate::SHADOW_VOLUME]),
            PassInfo::new("shadow: scan")
                .reads([crate::SHADOW_VOLUME])
                .writes([crate::SHADOW_VOLUME]),
        ];
        passes.extend(self.mesh_map.passes());
        passes
    }

    fn binding(&self) -> ShaderBinding {
        let mut resources = vec![
            BoundResource::Uniform(self.fit.uniforms().clone()),
            BoundResource::Storage(self.fit.grid().clone()),
            BoundResource::Storage(self.volume.clone()),
        ];
        resources.extend(self.mesh_map.resources());
        ShaderBinding {
            contract: crate::CONTRACT,
            module: "shadow/voxel_lookup.wgsl",
            sources: &crate::SHADERS,
            group: 1,
            resources,
            reads: self.lookup(),
        }
    }

    fn memory_bytes(&self) -> u64 {
        self.volume.size() + self.mesh_map.memory_bytes() + self.fit.memory_bytes()
    }
}
