//! The opaque method: depth-tested ribbons, alpha ignored (`shade/ribbons.wgsl`).

use pelage_contract::StrandFrame;
use pelage_gpu::{Gpu, GpuTimer, PassInfo, wgpu};
use pelage_scene::{CameraMatrices, Light};

use super::HairPass;
use crate::draw::{Common, Draw, HairInputs, HairPipe, TargetViews, depth_state};

/// The mesh, then the hair as opaque ribbons, depth tested; the only method that uses
/// MSAA (the targets' sample count; `ShadeParams::sample_count` for the facade's own).
#[derive(Debug)]
pub struct Opaque {
    common: Common,
    hair: Draw,
}

impl Opaque {
    /// Builds the pipelines for targets of [`HairInputs::target`]'s formats and sample
    /// count (any the device supports: MSAA hides the ribbons' aliasing).
    pub fn new(gpu: &Gpu, inputs: &HairInputs<'_>) -> crate::Result<Self> {
        let params = inputs.params;
        let common = Common::new(gpu, inputs, inputs.target.samples, params.min_pixels)?;
        let module = common.module(gpu, "shade/ribbons.wgsl")?;
        let hair = common.hair_draw(
            gpu,
            inputs,
            &HairPipe {
                module: &module,
                label: "shade: hair",
                fragment: "fs_main",
                targets: &[Some(inputs.target.color.into())],
                depth: depth_state(&inputs.target, true),
                shades: true,
                oit: None,
            },
        )?;
        Ok(Self { common, hair })
    }
}

impl HairPass for Opaque {
    fn name(&self) -> &'static str {
        "opaque"
    }

    fn prepare(
        &self,
        queue: &wgpu::Queue,
        strands: &StrandFrame,
        camera: &CameraMatrices,
        lights: &[Light],
        width: u32,
        height: u32,
    ) -> crate::Result<()> {
        self.common
            .prepare(queue, strands, camera, lights, width, height)
    }

    fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        strands: &StrandFrame,
        target: &TargetViews<'_>,
        mut timer: Option<&mut GpuTimer>,
    ) -> crate::Result<()> {
        self.common.check(self.name(), strands)?;
        // The mesh does not resolve: the hair pass that follows does.
        self.common.encode_volume(encoder, timer.as_deref_mut());
        self.common
            .encode_mesh(encoder, target, None, timer.as_deref_mut());
        let mut pass = pelage_gpu::audit::begin_render_pass(
            &mut *encoder,
            &wgpu::RenderPassDescriptor {
                label: Some(self.hair.label),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target.color,
                    depth_slice: None,
                    resolve_target: target.resolve,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: target.depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: timer.and_then(|t| t.render_pass(self.hair.label)),
                occlusion_query_set: None,
                multiview_mask: None,
            },
        );
        self.hair.record(&mut pass, None);
        Ok(())
    }

    fn set_params(&mut self, gpu: &Gpu, params: &pelage_scene::ShadeParams) -> crate::Result<()> {
        self.common.set_params(gpu, params)
    }

    fn passes(&self, lookup: &[String]) -> Vec<PassInfo> {
        let hair = self
            .common
            .hair_pass(self.hair.label)
            .writes([crate::draw::TARGET_COLOR, crate::draw::TARGET_DEPTH]);
        self.common
            .volume_pass()
            .into_iter()
            .chain(self.common.mesh_pass(lookup))
            .chain([hair])
            .collect()
    }

    fn grid(&self) -> Option<&crate::VolumeGrid> {
        self.common.grid()
    }

    fn body_sky_binding(&self) -> Option<pelage_gpu::ShaderBinding> {
        self.common.body_sky_binding()
    }

    fn memory_bytes(&self) -> u64 {
        0
    }
}
