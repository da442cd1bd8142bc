//! Transparency methods on targets they cannot draw: the [`TargetBridge`] a [`Frame`]
//! puts around its hair pass when the caller's targets are multisampled (every
//! transparency method draws single-sampled) or have reversed depth that the method does
//! not draw ([`Transparency::draws_reverse_z`]: the k-buffer, A-buffer, DBK-buffer and
//! random subsets). The opaque method draws any target itself and is never bridged.
//!
//! Around the method's passes the frame records:
//!
//! 1. `bridge: resolve colour` (multisampled targets only): an empty render pass over the
//!    caller's multisampled colour whose resolve target is the bridge's single-sampled
//!    colour (the caller's picture so far, averaged as the caller's own resolve does);
//! 2. `bridge: resolve depth`: the caller's depth into the bridge's single-sampled depth
//!    (and a copy of it), each pixel the nearest of its samples (hair behind any sample
//!    of an opaque surface is hidden in that pixel), as `1 - depth` when the method draws
//!    standard depth for a reversed caller (its projection turned to match:
//!    [`TargetBridge::matrices`]);
//! 3. the method, on the bridge's targets (the caller's own colour when it is
//!    single-sampled), drawing over them as it draws over a caller's targets it can draw;
//! 4. `bridge: write back`: the single-sampled colour into every sample of the caller's
//!    colour (resolved into the caller's resolve target, if any), and the method's depth,
//!    turned back, into every sample of the caller's depth where the method changed it
//!    (its mesh or opaque hair): elsewhere the caller's own samples stay.
//!
//! The caller's resolved picture is then the one the method draws single-sampled over
//! the caller's resolved picture. Pixels drawn before the hair keep their antialiasing
//! (resolved, then written into every sample); the hair's edges are the method's own;
//! the mesh pelage draws itself is single-sampled. When the caller asks for cleared
//! targets (`TargetViews::load` false) passes 1 and 2 only clear the bridge's targets.
//!
//! The caller's depth must be sampleable (`TEXTURE_BINDING`, as the transparency methods
//! already ask of a depth they draw) and its colour a render attachment.
//!
//! [`Frame`]: crate::Frame
//! [`Transparency::draws_reverse_z`]: pelage_scene::Transparency::draws_reverse_z

use std::sync::Mutex;

use glam::Mat4;
use pelage_gpu::{BindLayout, Gpu, GpuTimer, PassInfo, audit, wgpu};
use pelage_scene::{CameraMatrices, Transparency};
use pelage_shade::{TARGET_COLOR, TARGET_DEPTH, TargetFormat, TargetViews};

/// The shaders of the facade crate (`src/wgsl/`): the target bridge's passes.
pub(crate) static SHADERS: pelage_gpu::ShaderSources = pelage_gpu::wgsl_sources!(
    in "src/wgsl";
    uses [&pelage_gpu::SHADERS];
    "bridge.wgsl",
);

/// The plan's name of the resolved depth's copy the write-back compares with.
pub(crate) const RESOLVED_DEPTH: &str = "bridge.resolved_depth";

/// Labels of the bridge's passes (the plan's and the GPU timer's names).
const RESOLVE_COLOR: &str = "bridge: resolve colour";
const RESOLVE_DEPTH: &str = "bridge: resolve depth";
const WRITE_BACK: &str = "bridge: write back";

/// Format of the resolved depth's copy (a colour target the write-back can load).
const RESOLVED_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;

/// A value no depth takes: the copy's clear value when the caller asks for cleared
/// targets, so that the write-back writes every pixel's depth.
const NO_DEPTH: f64 = -1.0;

/// Clip z turned into `w - z` (depth `1 - depth`): a reversed projection as a standard
/// one and back.
const FLIP_DEPTH: Mat4 = Mat4::from_cols_array(&[
    1.0, 0.0, 0.0, 0.0, //
    0.0, 1.0, 0.0, 0.0, //
    0.0, 0.0, -1.0, 0.0, //
    0.0, 0.0, 1.0, 1.0,
]);

/// Targets a transparency method can draw, between it and a caller's targets it cannot,
/// and the passes between them (see the module docs).
#[derive(Debug)]
pub(crate) struct TargetBridge {
    gpu: Gpu,
    /// The targets the method draws into: single-sampled, standard depth when flipped.
    inner: TargetFormat,
    /// The method draws standard depth for a reversed caller.
    flip: bool,
    /// The single-sampled colour (multisampled callers only; otherwise the method draws
    /// into the caller's colour).
    color: Option<wgpu::TextureView>,
    depth: wgpu::TextureView,
    resolved: wgpu::TextureView,
    resolve_depth: wgpu::RenderPipeline,
    resolve_layout: wgpu::BindGroupLayout,
    /// The colour write-back with its bind group (multisampled callers only).
    write_color: Option<(wgpu::RenderPipeline, wgpu::BindGroup)>,
    write_depth: (wgpu::RenderPipeline, wgpu::BindGroup),
    /// The resolve pass's bind group for the caller's depth view it was made for (made
    /// again only when the caller hands another view).
    resolve_group: Mutex<Option<(wgpu::TextureView, wgpu::BindGroup)>>,
}

impl TargetBridge {
    /// Whether `method` needs a bridge to draw into `outer` targets.
    pub fn needed(outer: &TargetFormat, method: &Transparency) -> bool {
        *method != Transparency::Opaque
            && (outer.samples > 1 || (outer.reverse_z && !method.draws_reverse_z()))
    }

    /// The bridge for `method` on `outer` targets of `width` x `height`.
    pub fn new(
        gpu: &Gpu,
        outer: TargetFormat,
        method: &Transparency,
        width: u32,
        height: u32,
    ) -> crate::Result<Self> {
        outer.validate(gpu)?;
        let flip = outer.reverse_z && !method.draws_reverse_z();
        let multisampled = outer.samples > 1;
        let inner = TargetFormat {
            samples: 1,
            depth: pelage_shade::DEPTH_FORMAT,
            reverse_z: outer.reverse_z && !flip,
            ..outer
        };
        let module = SHADERS.library().module(gpu, "bridge.wgsl")?;
        gpu.scoped(|device| {
            let texture = |label: &str, format| {
                device
                    .create_texture(&wgpu::TextureDescriptor {
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
                    .create_view(&Default::default())
            };
            let color = multisampled.then(|| texture("pelage bridge: colour", inner.color));
            let depth = texture("pelage bridge: depth", inner.depth);
            let resolved = texture("pelage bridge: resolved depth", RESOLVED_FORMAT);
            audit::name_view(&resolved, RESOLVED_DEPTH);
            let float = wgpu::TextureSampleType::Float { filterable: false };
            let resolve_layout = BindLayout::new(RESOLVE_DEPTH, wgpu::ShaderStages::FRAGMENT);
            let resolve_layout = if multisampled {
                resolve_layout.entry(
                    0,
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Depth,
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: true,
                    },
                )
            } else {
                resolve_layout.depth_2d(4)
            }
            .build(device);
            let color_layout = BindLayout::new(WRITE_BACK, wgpu::ShaderStages::FRAGMENT)
                .texture_2d(1, float)
                .build(device);
            let depth_layout = BindLayout::new(WRITE_BACK, wgpu::ShaderStages::FRAGMENT)
                .depth_2d(2)
                .texture_2d(3, float)
                .build(device);
            let constants = [
                ("REVERSE_Z", f64::from(u8::from(outer.reverse_z))),
                ("FLIP", f64::from(u8::from(flip))),
            ];
            let pipeline = |layout: &wgpu::BindGroupLayout,
                            fragment: &str,
                            targets: &[Option<wgpu::ColorTargetState>],
                            depth: wgpu::DepthStencilState,
                            samples: u32| {
                let label = fragment;
                let layout = pelage_gpu::pipeline_layout(device, label, &[Some(layout)]);
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
                    layout: Some(&layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_full"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: Default::default(),
                    depth_stencil: Some(depth),
                    multisample: wgpu::MultisampleState {
                        count: samples,
                        ..Default::default()
                    },
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(fragment),
                        compilation_options: wgpu::PipelineCompilationOptions {
                            constants: &constants,
                            ..Default::default()
                        },
                        targets,
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            };
            let depth_state = |format, write| wgpu::DepthStencilState {
                format,
                depth_write_enabled: Some(write),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: Default::default(),
                bias: Default::default(),
            };
            let resolve_depth = pipeline(
                &resolve_layout,
                if multisampled {
                    "fs_resolve_depth_ms"
                } else {
                    "fs_resolve_depth"
                },
                &[Some(RESOLVED_FORMAT.into())],
                depth_state(inner.depth, true),
                1,
            );
            let group = |layout: &wgpu::BindGroupLayout, views: &[(u32, &wgpu::TextureView)]| {
                let entries: Vec<_> = views
                    .iter()
                    .map(|&(binding, view)| wgpu::BindGroupEntry {
                        binding,
                        resource: wgpu::BindingResource::TextureView(view),
                    })
                    .collect();
                pelage_gpu::create_bind_group(
                    device,
                    &wgpu::BindGroupDescriptor {
                        label: Some(WRITE_BACK),
                        layout,
                        entries: &entries,
                    },
                )
            };
            let write_color = color.as_ref().map(|color| {
                (
                    pipeline(
                        &color_layout,
                        "fs_write_color",
                        &[Some(outer.color.into())],
                        depth_state(outer.depth, false),
                        outer.samples,
                    ),
                    group(&color_layout, &[(1, color)]),
                )
            });
            // The depth write-back shares the pass of the colour's (its colour untouched).
            let masked = [Some(wgpu::ColorTargetState {
                format: outer.color,
                blend: None,
                write_mask: wgpu::ColorWrites::empty(),
            })];
            let write_depth = (
                pipeline(
                    &depth_layout,
                    "fs_write_depth",
                    if multisampled { &masked } else { &[] },
                    depth_state(outer.depth, true),
                    outer.samples,
                ),
                group(&depth_layout, &[(2, &depth), (3, &resolved)]),
            );
            Self {
                gpu: gpu.clone(),
                inner,
                flip,
                color,
                depth,
                resolved,
                resolve_depth,
                resolve_layout,
                write_color,
                write_depth,
                resolve_group: Mutex::new(None),
            }
        })
        .map_err(Into::into)
    }

    /// The targets the method is built for.
    pub fn inner(&self) -> TargetFormat {
        self.inner
    }

    /// The caller's view and projection as the method draws them: the projection turned
    /// to standard depth when the bridge flips the depth direction.
    pub fn matrices(&self, camera: &CameraMatrices) -> CameraMatrices {
        if !self.flip {
            return *camera;
        }
        CameraMatrices {
            view: camera.view,
            projection: FLIP_DEPTH * camera.projection,
        }
    }

    /// The passes recorded before the method's.
    pub fn passes_before(&self) -> Vec<PassInfo> {
        let resolve_color = PassInfo::new(RESOLVE_COLOR)
            .reads([TARGET_COLOR])
            .writes([TARGET_COLOR]);
        let resolve_depth = PassInfo::new(RESOLVE_DEPTH)
            .reads([TARGET_DEPTH])
            .writes([TARGET_DEPTH, RESOLVED_DEPTH]);
        self.color
            .as_ref()
            .map(|_| resolve_color)
            .into_iter()
            .chain([resolve_depth])
            .collect()
    }

    /// The pass recorded after the method's (the colour is written back only into a
    /// multisampled caller's: a single-sampled one is the method's own target).
    pub fn passes_after(&self) -> Vec<PassInfo> {
        let written: &[&str] = if self.color.is_some() {
            &[TARGET_COLOR, TARGET_DEPTH]
        } else {
            &[TARGET_DEPTH]
        };
        vec![
            PassInfo::new(WRITE_BACK)
                .reads(written.iter().copied().chain([RESOLVED_DEPTH]))
                .writes(written.iter().copied()),
        ]
    }

    /// The views the method draws into: the bridge's depth, its colour or (single-sampled)
    /// the caller's; drawn over when `outer.load`.
    pub fn views<'a>(&'a self, outer: &TargetViews<'a>) -> TargetViews<'a> {
        TargetViews {
            color: self.color.as_ref().unwrap_or(outer.color),
            resolve: None,
            depth: &self.depth,
            depth_sampled: None,
            width: outer.width,
            height: outer.height,
            load: outer.load,
        }
    }

    /// Records passes 1 and 2 (module docs): the caller's colour and depth resolved into
    /// the bridge's targets, or (without `outer.load`) the copy cleared.
    pub fn encode_before(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        outer: &TargetViews<'_>,
        mut timer: Option<&mut GpuTimer>,
    ) -> crate::Result<()> {
        fn ops<V>(load: wgpu::LoadOp<V>) -> wgpu::Operations<V> {
            wgpu::Operations {
                load,
                store: wgpu::StoreOp::Store,
            }
        }
        let copy = |clear: f64| {
            Some(wgpu::RenderPassColorAttachment {
                view: &self.resolved,
                depth_slice: None,
                resolve_target: None,
                ops: ops(wgpu::LoadOp::Clear(wgpu::Color {
                    r: clear,
                    g: clear,
                    b: clear,
                    a: clear,
                })),
            })
        };
        if let Some(color) = &self.color {
            // An empty pass whose end resolves the caller's samples into the bridge's
            // colour, or (the caller asks for cleared targets) clears it.
            let attachment = if outer.load {
                wgpu::RenderPassColorAttachment {
                    view: outer.color,
                    depth_slice: None,
                    resolve_target: Some(color),
                    ops: ops(wgpu::LoadOp::Load),
                }
            } else {
                wgpu::RenderPassColorAttachment {
                    view: color,
                    depth_slice: None,
                    resolve_target: None,
                    ops: ops(wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)),
                }
            };
            drop(audit::begin_render_pass(
                encoder,
                &wgpu::RenderPassDescriptor {
                    label: Some(RESOLVE_COLOR),
                    color_attachments: &[Some(attachment)],
                    depth_stencil_attachment: None,
                    timestamp_writes: timer
                        .as_deref_mut()
                        .and_then(|t| t.render_pass(RESOLVE_COLOR)),
                    occlusion_query_set: None,
                    multiview_mask: None,
                },
            ));
        }
        let depth = Some(wgpu::RenderPassDepthStencilAttachment {
            view: &self.depth,
            depth_ops: Some(ops(wgpu::LoadOp::Clear(self.inner.far_depth()))),
            stencil_ops: None,
        });
        if !outer.load {
            // Nothing to resolve: the method clears its targets, and every pixel's depth
            // is written back.
            drop(audit::begin_render_pass(
                encoder,
                &wgpu::RenderPassDescriptor {
                    label: Some(RESOLVE_DEPTH),
                    color_attachments: &[copy(NO_DEPTH)],
                    depth_stencil_attachment: depth,
                    timestamp_writes: timer.and_then(|t| t.render_pass(RESOLVE_DEPTH)),
                    occlusion_query_set: None,
                    multiview_mask: None,
                },
            ));
            return Ok(());
        }
        let group = self.resolve_group(outer.depth_to_sample())?;
        let mut pass = audit::begin_render_pass(
            encoder,
            &wgpu::RenderPassDescriptor {
                label: Some(RESOLVE_DEPTH),
                color_attachments: &[copy(0.0)],
                depth_stencil_attachment: depth,
                timestamp_writes: timer.and_then(|t| t.render_pass(RESOLVE_DEPTH)),
                occlusion_query_set: None,
                multiview_mask: None,
            },
        );
        pass.set_pipeline(&self.resolve_depth);
        audit::set_bind_group(&mut pass, 0, &group);
        pass.draw(0..3, 0..1);
        Ok(())
    }

    /// Records pass 4 (module docs): the method's picture into every sample of the
    /// caller's colour (multisampled callers), its depth where it changed into the
    /// caller's depth.
    pub fn encode_after(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        outer: &TargetViews<'_>,
        timer: Option<&mut GpuTimer>,
    ) {
        fn load<V>() -> wgpu::Operations<V> {
            wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            }
        }
        let color: Vec<_> = (self.color.as_ref())
            .map(|_| {
                Some(wgpu::RenderPassColorAttachment {
                    view: outer.color,
                    depth_slice: None,
                    resolve_target: outer.resolve,
                    ops: load(),
                })
            })
            .into_iter()
            .collect();
        // A depth format with a stencil keeps its stencil (read-only here).
        let mut pass = audit::begin_render_pass(
            encoder,
            &wgpu::RenderPassDescriptor {
                label: Some(WRITE_BACK),
                color_attachments: &color,
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: outer.depth,
                    depth_ops: Some(load()),
                    stencil_ops: None,
                }),
                timestamp_writes: timer.and_then(|t| t.render_pass(WRITE_BACK)),
                occlusion_query_set: None,
                multiview_mask: None,
            },
        );
        if let Some((pipeline, group)) = &self.write_color {
            pass.set_pipeline(pipeline);
            audit::set_bind_group(&mut pass, 0, group);
            pass.draw(0..3, 0..1);
        }
        let (pipeline, group) = &self.write_depth;
        pass.set_pipeline(pipeline);
        audit::set_bind_group(&mut pass, 0, group);
        pass.draw(0..3, 0..1);
    }

    /// The resolve pass's bind group for the caller's depth view `depth`.
    fn resolve_group(&self, depth: &wgpu::TextureView) -> crate::Result<wgpu::BindGroup> {
        let mut cache = self.resolve_group.lock().map_err(|_| {
            pelage_gpu::GpuError::Validation("a thread panicked while recording the frame".into())
        })?;
        if let Some((view, group)) = cache.as_ref()
            && view == depth
        {
            return Ok(group.clone());
        }
        let binding = if self.color.is_some() { 0 } else { 4 };
        let group = self.gpu.scoped(|device| {
            pelage_gpu::create_bind_group(
                device,
                &wgpu::BindGroupDescriptor {
                    label: Some(RESOLVE_DEPTH),
                    layout: &self.resolve_layout,
                    entries: &[wgpu::BindGroupEntry {
                        binding,
                        resource: wgpu::BindingResource::TextureView(depth),
                    }],
                },
            )
        })?;
        *cache = Some((depth.clone(), group.clone()));
        Ok(group)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bridge_shader_is_listed_and_validates() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/src/wgsl");
        let count = SHADERS
            .check_against_dir(dir)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(count, SHADERS.files().len());
    }

    /// The turned projection maps depth d to 1 - d and keeps x, y and w.
    #[test]
    fn the_flipped_projection_turns_depth() {
        let camera = pelage_scene::Camera::default();
        let reversed = camera.matrices_reverse_z(64, 48);
        let flipped = FLIP_DEPTH * reversed.projection;
        for z in [-0.5f32, -1.0, -3.0, -40.0] {
            let p = glam::Vec4::new(0.1, -0.2, z, 1.0);
            let (a, b) = (reversed.projection * p, flipped * p);
            assert_eq!((a.x, a.y, a.w), (b.x, b.y, b.w));
            assert!((b.z / b.w - (1.0 - a.z / a.w)).abs() < 1e-6, "{z}");
        }
        let standard = CameraMatrices {
            view: reversed.view,
            projection: flipped,
        };
        assert!(reversed.reverse_z() && !standard.reverse_z());
    }
}
