//! Weighted blended OIT (McGuire and Bavoil 2013) (`shade/oit/wboit.wgsl`).

use pelage_contract::StrandFrame;
use pelage_gpu::{BindLayout, Gpu, GpuTimer, PassInfo, wgpu};
use pelage_scene::{CameraMatrices, Light, WboitWeight};

use super::HairPass;
use super::sliced::{OitTile, Sliced};
use crate::draw::{Common, Draw, HairInputs, HairPipe, TargetViews, depth_state};

const ACCUMULATION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
const REVEALAGE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R16Float;

/// Weighted blended OIT: an Rgba16Float accumulation and an R16Float revealage target
/// (10 bytes per pixel), no per-pixel lists.
#[derive(Debug)]
pub struct Wboit {
    common: Common,
    accum: Draw,
    resolve: Sliced,
    /// The accumulation target (a view made once: recording creates nothing).
    accumulation: wgpu::TextureView,
    /// The revealage target.
    revealage: wgpu::TextureView,
    bind_accum: wgpu::BindGroup,
    bind_resolve: wgpu::BindGroup,
    width: u32,
    height: u32,
}

impl Wboit {
    /// Builds WBOIT with the weight function `weight` for `width` x `height` targets.
    pub fn new(
        gpu: &Gpu,
        inputs: &HairInputs<'_>,
        weight: WboitWeight,
        width: u32,
        height: u32,
    ) -> crate::Result<Self> {
        let common = Common::new(gpu, inputs, 1, inputs.params.min_pixels.max(1.0))?;
        let module = common.module(gpu, "shade/oit/wboit.wgsl")?;
        let additive = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let reveal = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::Zero,
            dst_factor: wgpu::BlendFactor::OneMinusSrc,
            operation: wgpu::BlendOperation::Add,
        };
        let targets = [
            Some(wgpu::ColorTargetState {
                format: ACCUMULATION_FORMAT,
                blend: Some(wgpu::BlendState {
                    color: additive,
                    alpha: additive,
                }),
                write_mask: wgpu::ColorWrites::ALL,
            }),
            Some(wgpu::ColorTargetState {
                format: REVEALAGE_FORMAT,
                blend: Some(wgpu::BlendState {
                    color: reveal,
                    alpha: reveal,
                }),
                write_mask: wgpu::ColorWrites::ALL,
            }),
        ];
        // wboit.wgsl's @group(3): fs_accum reads the tile (its weight function), fs_resolve
        // loads the two targets; each pass has a layout of what it binds.
        let accum_layout = gpu.scoped(|device| {
            BindLayout::new(
                "pelage wboit accumulate",
                wgpu::ShaderStages::VERTEX_FRAGMENT,
            )
            .uniform(0)
            .build(device)
        })?;
        let accum = common.hair_draw(
            gpu,
            inputs,
            &HairPipe {
                module: &module,
                label: "shade: wboit accumulate",
                fragment: "fs_accum",
                targets: &targets,
                depth: depth_state(&inputs.target, false),
                shades: true,
                oit: Some(&accum_layout),
            },
        )?;
        let weight_index = match weight {
            WboitWeight::Eq7 => 0,
            WboitWeight::Eq8 => 1,
            WboitWeight::Eq9 => 2,
            WboitWeight::Eq10 => 3,
            WboitWeight::Constant => 4,
        };
        let base = OitTile {
            reverse_z: u32::from(inputs.target.reverse_z),
            width,
            weight: weight_index,
            ..Default::default()
        };
        let mut resolve = Sliced::new(gpu, base, height, height)?;
        let float = wgpu::TextureSampleType::Float { filterable: false };
        resolve.add_resolve_pass_with(
            gpu,
            &inputs.target,
            &module,
            "shade: wboit resolve",
            "fs_resolve",
            &[1, 2],
            &BindLayout::new("shade: wboit resolve", wgpu::ShaderStages::FRAGMENT)
                .texture_2d(1, float)
                .texture_2d(2, float),
        )?;
        let (accumulation, revealage, bind_accum, bind_resolve) = gpu.scoped(|device| {
            let texture = |label: &str, format| {
                device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width,
                        height,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                        | wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                })
            };
            let accumulation = texture("pelage wboit accumulation", ACCUMULATION_FORMAT);
            let revealage = texture("pelage wboit revealage", REVEALAGE_FORMAT);
            let (accumulation_view, revealage_view) = (
                accumulation.create_view(&Default::default()),
                revealage.create_view(&Default::default()),
            );
            pelage_gpu::audit::name_view(&accumulation_view, crate::OIT_STORAGE);
            pelage_gpu::audit::name_view(&revealage_view, crate::OIT_STORAGE);
            let bind = pelage_gpu::create_bind_group(
                device,
                &wgpu::BindGroupDescriptor {
                    label: Some("pelage wboit resolve"),
                    layout: &resolve.passes[0].layout,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: wgpu::BindingResource::TextureView(&accumulation_view),
                        },
                        wgpu::BindGroupEntry {
                            binding: 2,
                            resource: wgpu::BindingResource::TextureView(&revealage_view),
                        },
                    ],
                },
            );
            let bind_accum = pelage_gpu::create_bind_group(
                device,
                &wgpu::BindGroupDescriptor {
                    label: Some("pelage wboit accumulate"),
                    layout: &accum_layout,
                    entries: &[wgpu::BindGroupEntry {
                        binding: 0,
                        resource: resolve.tile_binding(0),
                    }],
                },
            );
            (accumulation_view, revealage_view, bind_accum, bind)
        })?;
        Ok(Self {
            common,
            accum,
            resolve,
            accumulation,
            revealage,
            bind_accum,
            bind_resolve,
            width,
            height,
        })
    }
}

impl HairPass for Wboit {
    fn name(&self) -> &'static str {
        "wboit"
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
        self.resolve.check_target(target)?;
        self.common.encode_volume(encoder, timer.as_deref_mut());
        self.common
            .encode_mesh(encoder, target, None, timer.as_deref_mut());
        let (accumulation, revealage) = (&self.accumulation, &self.revealage);
        {
            let attachment = |view, clear| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(clear),
                        store: wgpu::StoreOp::Store,
                    },
                })
            };
            let mut pass = pelage_gpu::audit::begin_render_pass(
                &mut *encoder,
                &wgpu::RenderPassDescriptor {
                    label: Some(self.accum.label),
                    color_attachments: &[
                        attachment(accumulation, wgpu::Color::TRANSPARENT),
                        attachment(revealage, wgpu::Color::WHITE),
                    ],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: target.depth,
                        depth_ops: None,
                        stencil_ops: None,
                    }),
                    timestamp_writes: timer
                        .as_deref_mut()
                        .and_then(|t| t.render_pass(self.accum.label)),
                    occlusion_query_set: None,
                    multiview_mask: None,
                },
            );
            self.accum.record(&mut pass, Some((3, &self.bind_accum)));
        }
        let resolve = &self.resolve.passes[0].draw;
        let mut pass = pelage_gpu::audit::begin_render_pass(
            &mut *encoder,
            &wgpu::RenderPassDescriptor {
                label: Some(resolve.label),
                color_attachments: &[Some(crate::draw::over_color(target.color))],
                depth_stencil_attachment: None,
                timestamp_writes: timer.and_then(|t| t.render_pass(resolve.label)),
                occlusion_query_set: None,
                multiview_mask: None,
            },
        );
        resolve.record(&mut pass, Some((3, &self.bind_resolve)));
        Ok(())
    }

    fn set_params(&mut self, gpu: &Gpu, params: &pelage_scene::ShadeParams) -> crate::Result<()> {
        self.common.set_params(gpu, params)
    }

    fn passes(&self, lookup: &[String]) -> Vec<PassInfo> {
        let accumulate = self
            .common
            .hair_pass(self.accum.label)
            .writes([crate::draw::OIT_STORAGE]);
        let resolve = self.resolve.passes.iter().map(|pass| {
            PassInfo::new(pass.draw.label)
                .reads([crate::draw::OIT_STORAGE, crate::draw::TARGET_COLOR])
                .writes([crate::draw::TARGET_COLOR])
        });
        self.common
            .volume_pass()
            .into_iter()
            .chain(self.common.mesh_pass(lookup))
            .chain([accumulate])
            .chain(resolve)
            .collect()
    }

    fn grid(&self) -> Option<&crate::VolumeGrid> {
        self.common.grid()
    }

    fn body_sky_binding(&self) -> Option<pelage_gpu::ShaderBinding> {
        self.common.body_sky_binding()
    }

    fn memory_bytes(&self) -> u64 {
        10 * u64::from(self.width) * u64::from(self.height)
    }
}
