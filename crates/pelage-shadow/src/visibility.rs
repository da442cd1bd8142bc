//! Stage 2's hand-over to the hair pass: one light's shadow evaluated at every strand
//! vertex (`wgsl/shadow/probe.wgsl`), into that light's slice of a visibility buffer.

use pelage_contract::{PreparedFrame, StrandBuffers, StrandFrame, StrandLayout};
use pelage_gpu::{
    BindLayout, Gpu, GpuTimer, PassInfo, ShaderBinding, compute_pipeline_with_layouts,
    dispatch_size, wgpu, zeroed_storage,
};

/// Light `index`'s visibility at every strand vertex, written each frame at floats
/// `index * stride ..` of a buffer the hair pass reads ([`pelage_contract::Visibility`]).
#[derive(Debug)]
pub struct LightVisibility {
    pipeline: wgpu::ComputePipeline,
    own: wgpu::BindGroup,
    shadow: Option<wgpu::BindGroup>,
    /// The layout of the frame last prepared (packed, see [`StrandLayout::to_bits`]).
    layout: std::sync::atomic::AtomicU64,
    /// That frame.
    prepared: PreparedFrame,
    limits: wgpu::Limits,
    label: String,
}

impl LightVisibility {
    /// A zeroed visibility buffer for `lights` lights of `stride` floats.
    pub fn buffer(gpu: &Gpu, lights: u32, stride: u32) -> crate::Result<wgpu::Buffer> {
        Ok(zeroed_storage(
            gpu,
            "pelage light visibility",
            u64::from(lights) * u64::from(stride) * 4,
            wgpu::BufferUsages::STORAGE,
        )?)
    }

    /// Evaluates the shadow method behind `binding` at every vertex of `strands` into
    /// slice `index` of `out` (`stride` floats per light, from [`Visibility::stride_for`](pelage_contract::Visibility::stride_for)).
    pub fn new(
        gpu: &Gpu,
        binding: &ShaderBinding,
        strands: &StrandBuffers,
        out: &wgpu::Buffer,
        index: u32,
        stride: u32,
    ) -> crate::Result<Self> {
        let vertices = strands.vertices.size() / 16;
        let bytes = u64::from(stride) * 4;
        let offset = u64::from(index) * bytes;
        if u64::from(stride) < vertices || !stride.is_multiple_of(64) || offset + bytes > out.size()
        {
            return Err(pelage_scene::ParamError {
                name: "visibility.stride".into(),
                value: stride.to_string(),
                reason: format!(
                    "must be a multiple of 64 holding the {vertices} strand vertices, with light \
                     {index}'s slice inside the {}-byte buffer",
                    out.size()
                ),
            }
            .into());
        }
        let module = crate::SHADERS.library().module_redirected(
            gpu,
            "shadow/probe.wgsl",
            &[binding.redirect()],
        )?;
        let label = format!("shadow: light {index} visibility");
        let (pipeline, own, shadow) = gpu.scoped(|device| {
            // probe.wgsl: the strand vertices read, this light's slice written; the
            // method's resources at its own group.
            let own_layout = BindLayout::new(&label, wgpu::ShaderStages::COMPUTE)
                .storage(0)
                .storage_rw(1)
                .build(device);
            let shadow_layout = binding.layout(device, &label, wgpu::ShaderStages::COMPUTE);
            let mut layouts = vec![Some(&own_layout)];
            binding.place(&mut layouts, shadow_layout.as_ref());
            let pipeline = compute_pipeline_with_layouts(device, &label, &module, "main", &layouts);
            let own = pelage_gpu::create_bind_group(
                device,
                &wgpu::BindGroupDescriptor {
                    label: Some(&label),
                    layout: &own_layout,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: strands.vertices.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                                buffer: out,
                                offset,
                                size: wgpu::BufferSize::new(bytes),
                            }),
                        },
                    ],
                },
            );
            let shadow = shadow_layout
                .as_ref()
                .and_then(|l| binding.bind_group(device, &label, l));
            (pipeline, own, shadow)
        })?;
        Ok(Self {
            pipeline,
            own,
            shadow,
            layout: std::sync::atomic::AtomicU64::new(strands.full_layout().to_bits()),
            prepared: PreparedFrame::default(),
            limits: gpu.limits().clone(),
            label,
        })
    }

    /// The pass `encode` records: reads the strand vertices and the shadow method's
    /// `lookup` ([`ShadowMethod::lookup`](crate::ShadowMethod::lookup), under the
    /// frame's name for this light), writes [`VISIBILITY`](pelage_contract::VISIBILITY).
    pub fn passes(&self, lookup: &[String]) -> Vec<PassInfo> {
        vec![
            PassInfo::new(self.label.clone())
                .reads([pelage_contract::STRAND_VERTICES.to_string()])
                .reads(lookup.iter().cloned())
                .writes([pelage_contract::VISIBILITY]),
        ]
    }

    /// Takes the strands stage 1 grows in `strands`, for the next `encode` (the shape of
    /// every stage's `prepare`: the queue and the frame; this pass has no uniforms, its
    /// dispatch size is the frame's vertex count).
    pub fn prepare(&self, _queue: &wgpu::Queue, strands: &StrandFrame) -> crate::Result<()> {
        self.layout.store(
            strands.layout.to_bits(),
            std::sync::atomic::Ordering::Release,
        );
        self.prepared.set(strands);
        Ok(())
    }

    /// Records the evaluation (after the shadow method's own passes) for `strands`,
    /// the frame of the last `prepare`.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        strands: &StrandFrame,
        timer: Option<&mut GpuTimer>,
    ) -> crate::Result<()> {
        self.prepared.check(&self.label, strands)?;
        let layout =
            StrandLayout::from_bits(self.layout.load(std::sync::atomic::Ordering::Acquire));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&self.label),
            timestamp_writes: timer.and_then(|t| t.compute_pass(&self.label)),
        });
        pass.set_pipeline(&self.pipeline);
        pelage_gpu::set_bind_group(&mut pass, 0, &self.own);
        if let Some(group) = &self.shadow {
            pelage_gpu::set_bind_group(&mut pass, 1, group);
        }
        // Only the vertices stage 1 grew this frame.
        let groups = dispatch_size(&self.limits, layout.vertices(), 64);
        pass.dispatch_workgroups(groups.0, groups.1, 1);
        Ok(())
    }
}
