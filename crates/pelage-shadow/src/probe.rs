//! Measuring a shadow method: its `light_visibility` at given points (`wgsl/shadow/probe.wgsl`).

use pelage_gpu::{Gpu, ShaderBinding, bind_buffers, compute_pipeline, dispatch_size, wgpu};

/// Evaluates a method's shadow contract at arbitrary points, for tests and labs.
///
/// With the method's mesh map disabled this is the hair's transmittance alone. Builds
/// its pipeline once; `encode` makes a small bind group per call (not for the frame loop).
#[derive(Debug)]
pub struct TransmittanceProbe {
    pipeline: wgpu::ComputePipeline,
    shadow_group: Option<wgpu::BindGroup>,
}

impl TransmittanceProbe {
    /// A probe of the method behind `binding`.
    pub fn new(gpu: &Gpu, binding: &ShaderBinding) -> crate::Result<Self> {
        let module = crate::SHADERS.library().module_redirected(
            gpu,
            "shadow/probe.wgsl",
            &[binding.redirect()],
        )?;
        let (pipeline, shadow_group) = gpu.scoped(|device| {
            let pipeline = compute_pipeline(device, "pelage transmittance probe", &module, "main");
            let layout = pipeline.get_bind_group_layout(binding.group);
            let group = binding.bind_group(device, "pelage transmittance probe shadow", &layout);
            (pipeline, group)
        })?;
        Ok(Self {
            pipeline,
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
                &self.pipeline.get_bind_group_layout(0),
                &[points, out],
            )
        })?;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("pelage transmittance probe"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &own, &[]);
        if let Some(group) = &self.shadow_group {
            pass.set_bind_group(1, group, &[]);
        }
        pass.dispatch_workgroups(groups.0, groups.1, 1);
        Ok(())
    }
}
