//! Measuring a shadow method: its `light_visibility` (or `surface_visibility`) at given
//! points (`wgsl/shadow/probe.wgsl`).

use pelage_gpu::{
    BindLayout, Gpu, ShaderBinding, bind_buffers, compute_pipeline_with_layouts, dispatch_size,
    wgpu,
};

/// Evaluates a method's shadow contract at arbitrary points, for tests and labs.
///
/// With the method's mesh map disabled this is the hair's transmittance alone. Builds
/// its pipeline once; `encode` makes a small bind group per call (not for the frame loop).
#[derive(Debug)]
pub struct TransmittanceProbe {
    pipeline: wgpu::ComputePipeline,
    /// Group 0 (probe.wgsl's points and results), bound per `encode`.
    layout: wgpu::BindGroupLayout,
    shadow_group: Option<wgpu::BindGroup>,
}

impl TransmittanceProbe {
    /// A probe of the method behind `binding`: `light_visibility` (at a fibre).
    pub fn new(gpu: &Gpu, binding: &ShaderBinding) -> crate::Result<Self> {
        Self::with_entry(gpu, binding, "main")
    }

    /// A probe of `surface_visibility` (a point on the body) of the method behind
    /// `binding`.
    pub fn surface(gpu: &Gpu, binding: &ShaderBinding) -> crate::Result<Self> {
        Self::with_entry(gpu, binding, "surface")
    }

    fn with_entry(gpu: &Gpu, binding: &ShaderBinding, entry: &str) -> crate::Result<Self> {
        let module = crate::SHADERS.library().module_redirected(
            gpu,
            "shadow/probe.wgsl",
            &[binding.redirect()],
        )?;
        let (pipeline, layout, shadow_group) = gpu.scoped(|device| {
            let label = "pelage transmittance probe";
            let layout = BindLayout::new(label, wgpu::ShaderStages::COMPUTE)
                .storage(0)
                .storage_rw(1)
                .build(device);
            let shadow_label = "pelage transmittance probe shadow";
            let shadow_layout = binding.layout(device, shadow_label, wgpu::ShaderStages::COMPUTE);
            let mut layouts = vec![Some(&layout)];
            binding.place(&mut layouts, shadow_layout.as_ref());
            let pipeline = compute_pipeline_with_layouts(device, label, &module, entry, &layouts);
            let group = shadow_layout
                .as_ref()
                .and_then(|l| binding.bind_group(device, shadow_label, l));
            (pipeline, layout, group)
        })?;
        Ok(Self {
            pipeline,
            layout,
            shadow_group,
        })
    }

    /// Records the evaluation at each `vec4` point of `points` (xyz) into the `f32`s of
    /// `out` (as many as `out` holds; `points` must hold at least as many).
    pub fn encode(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        points: &wgpu::Buffer,
        out: &wgpu::Buffer,
    ) -> crate::Result<()> {
        let count = out.size() / 4;
        if points.size() < count * 16 {
            return Err(pelage_scene::ParamError {
                name: "points".into(),
                value: format!("{} bytes", points.size()),
                reason: format!("needs a vec4 for each of the {count} outputs"),
            }
            .into());
        }
        let groups = dispatch_size(gpu.limits(), count, 64);
        let own = gpu.scoped(|device| {
            bind_buffers(
                device,
                "pelage transmittance probe",
                &self.layout,
                &[points, out],
            )
        })?;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("pelage transmittance probe"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pelage_gpu::set_bind_group(&mut pass, 0, &own);
        if let Some(group) = &self.shadow_group {
            pelage_gpu::set_bind_group(&mut pass, 1, group);
        }
        pass.dispatch_workgroups(groups.0, groups.1, 1);
        Ok(())
    }
}
