//! The machinery of the per-pixel-storage methods: slicing the screen into bands whose
//! buffers fit one storage binding, and recording each method's passes per band.

use encase::ShaderType;
use pelage_gpu::{BindLayout, Gpu, GpuError, GpuTimer, PassInfo, wgpu};

use crate::targets::TargetFormat;

use crate::draw::{
    Common, Draw, HairInputs, HairPipe, OIT_STORAGE, RasterDesc, TARGET_COLOR, TARGET_DEPTH,
    TargetViews, Vertices, depth_state, over_target, raster_pipeline,
};

/// One slice of the screen and the method's constants (`OitTile` in `shade/oit/common.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, ShaderType)]
pub struct OitTile {
    /// First row of the slice.
    pub y0: u32,
    /// Rows in the slice.
    pub rows: u32,
    /// Width of the target.
    pub width: u32,
    /// Fragments kept (k-buffer, subsets) or sorted at resolve (lists).
    pub k: u32,
    /// Node pool capacity (lists).
    pub capacity: u32,
    /// WBOIT weight function index.
    pub weight: u32,
    /// DBK layer thickness.
    pub depth_shift: f32,
    /// 1 when depth is reversed (nearer is larger), else 0.
    pub reverse_z: u32,
}

/// How a pass of a sliced method attaches the targets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PassKind {
    /// Hair into storage only: depth attached read-only, no colour.
    Storage,
    /// As `Storage`, for a pass that only records depths (does not shade, so does not
    /// bind the shading model).
    DepthOnly,
    /// Hair drawn opaque into colour and depth (DBK's fallback).
    OpaqueHair,
    /// The full-screen resolve, blended over the colour.
    Resolve,
}

/// One pass: its pipeline and which `@group(3)` bindings its entry point uses.
#[derive(Debug)]
pub(crate) struct SlicedPass {
    pub draw: Draw,
    pub kind: PassKind,
    pub bindings: &'static [u32],
    /// The pass's own `@group(3)` layout, exactly `bindings` (a pass that writes the
    /// depth cannot bind it, so passes do not share one layout of the union).
    pub layout: wgpu::BindGroupLayout,
}

/// The `@group(3)` layout of a pass of a sliced method using `bindings`, as
/// `shade/oit/*.wgsl` declares them: 0 the slice's `OitTile` uniform, 1 the opaque
/// depth (`texture_2d<f32>`, unfilterable: GL has no `textureLoad` of a depth texture), every other binding a per-pixel `read_write` storage
/// buffer (fragment stage only).
pub(crate) fn oit_layout(label: &str, bindings: &[u32]) -> BindLayout {
    bindings.iter().fold(
        BindLayout::new(label, wgpu::ShaderStages::VERTEX_FRAGMENT),
        |layout, &binding| match binding {
            0 => layout
                .visible(wgpu::ShaderStages::VERTEX_FRAGMENT)
                .uniform(0),
            1 => layout
                .visible(wgpu::ShaderStages::VERTEX_FRAGMENT)
                .texture_2d(1, wgpu::TextureSampleType::Float { filterable: false }),
            _ => layout
                .visible(wgpu::ShaderStages::FRAGMENT)
                .storage_rw(binding),
        },
    )
}

/// The slices and group-3 resources of a method.
#[derive(Debug)]
pub(crate) struct Sliced {
    width: u32,
    height: u32,
    pub rows: u32,
    pub capacity: u32,
    pub count: u32,
    tiles: wgpu::Buffer,
    stride: u64,
    /// `(binding, buffer)` of the method's storage.
    pub buffers: Vec<(u32, wgpu::Buffer)>,
    pub passes: Vec<SlicedPass>,
    /// The `@group(3)` bind groups per slice and pass, with the depth view they sample:
    /// built on the first `encode` and again only when the caller's depth view changes.
    groups: std::sync::Mutex<Option<(wgpu::TextureView, Vec<wgpu::BindGroup>)>>,
    /// The device the groups are (re)built on when the caller's depth view changes:
    /// recording takes no device, and in steady state builds nothing.
    gpu: Gpu,
}

/// Rows per slice so that a per-pixel buffer of `bytes_per_pixel` (the method's
/// largest) fits the storage binding limit.
pub(crate) fn rows_per_slice(
    gpu: &Gpu,
    what: &str,
    width: u32,
    height: u32,
    bytes_per_pixel: u64,
) -> crate::Result<u32> {
    let limit = gpu
        .limits()
        .max_storage_buffer_binding_size
        .min(gpu.limits().max_buffer_size);
    let row = u64::from(width) * bytes_per_pixel.max(1);
    let rows = (limit / row).min(u64::from(height));
    if rows == 0 {
        return Err(GpuError::TooLarge {
            what: format!("{what} for one row of {width} pixels"),
            bytes: row,
            limit,
        }
        .into());
    }
    Ok(rows as u32)
}

impl Sliced {
    /// Uniforms for `height` rows in slices of `rows`, each a copy of `base` with its own rows.
    pub fn new(gpu: &Gpu, base: OitTile, height: u32, rows: u32) -> crate::Result<Self> {
        let rows = rows.clamp(1, height.max(1));
        let count = height.div_ceil(rows);
        let stride = u64::from(gpu.limits().min_uniform_buffer_offset_alignment)
            .max(OitTile::min_size().get());
        let mut bytes = vec![0u8; (stride * u64::from(count)) as usize];
        for i in 0..count {
            let tile = OitTile {
                y0: i * rows,
                rows: rows.min(height - i * rows),
                ..base
            };
            let mut one = encase::UniformBuffer::new(Vec::<u8>::new());
            one.write(&tile)
                .map_err(|e| GpuError::Validation(format!("laying out OitTile: {e}")))?;
            let one = one.into_inner();
            let at = (stride * u64::from(i)) as usize;
            bytes[at..at + one.len()].copy_from_slice(&one);
        }
        let tiles = gpu.scoped(|device| {
            pelage_gpu::create_buffer_init(
                device,
                &wgpu::util::BufferInitDescriptor {
                    label: Some("pelage oit slices"),
                    contents: &bytes,
                    usage: wgpu::BufferUsages::UNIFORM,
                },
            )
        })?;
        Ok(Self {
            width: base.width,
            height,
            rows,
            capacity: base.capacity,
            count,
            tiles,
            stride,
            buffers: Vec::new(),
            passes: Vec::new(),
            groups: std::sync::Mutex::new(None),
            gpu: gpu.clone(),
        })
    }

    /// The uniform of slice `slice`, for binding 0 of `@group(3)`.
    pub fn tile_binding(&self, slice: u32) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.tiles,
            offset: self.stride * u64::from(slice),
            size: Some(OitTile::min_size()),
        })
    }

    /// Errors unless `target` has the size the buffers were made for.
    pub fn check_target(&self, target: &TargetViews<'_>) -> crate::Result<()> {
        if (target.width, target.height) != (self.width, self.height) {
            return Err(crate::ShadeError::TargetSize {
                built: (self.width, self.height),
                given: (target.width, target.height),
            });
        }
        Ok(())
    }

    /// Bytes of the method's storage buffers.
    pub fn memory_bytes(&self) -> u64 {
        self.buffers.iter().map(|(_, b)| b.size()).sum::<u64>() + self.tiles.size()
    }

    /// The storage buffer at `binding`.
    pub fn buffer(&self, binding: u32) -> Option<&wgpu::Buffer> {
        self.buffers
            .iter()
            .find(|(b, _)| *b == binding)
            .map(|(_, b)| b)
    }

    /// Adds a hair pass drawing `fragment` of the method's module.
    pub fn add_hair_pass(
        &mut self,
        ctx: &PassContext<'_>,
        label: &'static str,
        fragment: &str,
        kind: PassKind,
        bindings: &'static [u32],
    ) -> crate::Result<()> {
        let (targets, depth) = match kind {
            PassKind::OpaqueHair => (
                vec![Some(ctx.inputs.target.color.into())],
                depth_state(&ctx.inputs.target, true),
            ),
            _ => (Vec::new(), depth_state(&ctx.inputs.target, false)),
        };
        let layout = ctx
            .gpu
            .scoped(|device| oit_layout(label, bindings).build(device))?;
        let draw = ctx.common.hair_draw(
            ctx.gpu,
            ctx.inputs,
            &HairPipe {
                module: ctx.module,
                label,
                fragment,
                targets: &targets,
                depth,
                shades: kind != PassKind::DepthOnly,
                oit: Some(&layout),
            },
        )?;
        self.passes.push(SlicedPass {
            draw,
            kind,
            bindings,
            layout,
        });
        Ok(())
    }

    /// Adds the full-screen resolve `fragment` of `module`, binding `bindings` of
    /// `@group(3)` ([`oit_layout`]).
    pub fn add_resolve_pass(
        &mut self,
        gpu: &Gpu,
        target: &TargetFormat,
        module: &wgpu::ShaderModule,
        label: &'static str,
        fragment: &str,
        bindings: &'static [u32],
    ) -> crate::Result<()> {
        let layout = oit_layout(label, bindings);
        self.add_resolve_pass_with(gpu, target, module, label, fragment, bindings, &layout)
    }

    /// As [`Sliced::add_resolve_pass`], with the `@group(3)` layout `layout` (declaring
    /// `bindings`).
    #[allow(clippy::too_many_arguments)]
    pub fn add_resolve_pass_with(
        &mut self,
        gpu: &Gpu,
        target: &TargetFormat,
        module: &wgpu::ShaderModule,
        label: &'static str,
        fragment: &str,
        bindings: &'static [u32],
        layout: &BindLayout,
    ) -> crate::Result<()> {
        let (draw, layout) = gpu.scoped(|device| {
            let layout = layout.build(device);
            // Only group 3: groups 0 to 2 are left out of the layout, so need no bind group.
            let layouts = [None, None, None, Some(&layout)];
            let pipeline = raster_pipeline(
                device,
                &RasterDesc {
                    label,
                    layouts: &layouts,
                    module,
                    vertex: "vs_fullscreen",
                    fragment: Some(fragment),
                    targets: &[Some(over_target(target))],
                    depth: None,
                    samples: 1,
                    cull: None,
                },
            );
            let draw = Draw {
                label,
                pipeline,
                groups: Vec::new(),
                vertices: Vertices::Fixed(3),
            };
            (draw, layout)
        })?;
        self.passes.push(SlicedPass {
            draw,
            kind: PassKind::Resolve,
            bindings,
            layout,
        });
        Ok(())
    }

    /// The passes `encode` records: every pass of the method for each slice in turn.
    /// Storage passes write the method's storage ([`OIT_STORAGE`]; the first of a slice
    /// starts it, later ones read it too), the resolve reads it and blends over the
    /// colour, the opaque fallback draws into the targets.
    pub fn pass_infos(&self, common: &Common) -> Vec<PassInfo> {
        let mut infos = Vec::new();
        for _ in 0..self.count {
            let mut started = false;
            for pass in &self.passes {
                let label = pass.draw.label;
                let info = match pass.kind {
                    PassKind::Storage | PassKind::DepthOnly => {
                        // A depth-only pass shades nothing: no model resources.
                        let info = match pass.kind {
                            PassKind::DepthOnly => common.hair_geometry_pass(label),
                            _ => common.hair_pass(label),
                        };
                        let info = info.writes([OIT_STORAGE]);
                        let info = if started {
                            info.reads([OIT_STORAGE])
                        } else {
                            info
                        };
                        started = true;
                        info
                    }
                    PassKind::OpaqueHair => {
                        let info = common.hair_pass(label).writes([TARGET_COLOR, TARGET_DEPTH]);
                        // Per-pixel storage it binds (read_write, as every binding of
                        // shade/oit/*.wgsl: the DBK fallback only reads its nearest depth).
                        if pass.bindings.iter().any(|&b| b >= 2) {
                            info.reads([OIT_STORAGE]).writes([OIT_STORAGE])
                        } else {
                            info
                        }
                    }
                    // The resolve also clears what it composited (slots, heads, the
                    // nearest depths) for the next frame: it writes the storage too.
                    PassKind::Resolve => PassInfo::new(label)
                        .reads([OIT_STORAGE, TARGET_COLOR])
                        .writes([TARGET_COLOR, OIT_STORAGE]),
                };
                infos.push(info);
            }
        }
        infos
    }

    /// The `@group(3)` bind groups of every slice and pass, sampling `depth`.
    fn bind_groups(
        &self,
        gpu: &Gpu,
        depth: &wgpu::TextureView,
    ) -> crate::Result<Vec<wgpu::BindGroup>> {
        for (_, buffer) in &self.buffers {
            pelage_gpu::audit::name_buffer(buffer, crate::OIT_STORAGE);
        }
        Ok(gpu.scoped(|device| {
            let mut groups = Vec::new();
            for slice in 0..self.count {
                for pass in &self.passes {
                    let entries: Vec<wgpu::BindGroupEntry<'_>> = pass
                        .bindings
                        .iter()
                        .filter_map(|&binding| {
                            let resource = match binding {
                                0 => self.tile_binding(slice),
                                1 => wgpu::BindingResource::TextureView(depth),
                                _ => self.buffer(binding)?.as_entire_binding(),
                            };
                            Some(wgpu::BindGroupEntry { binding, resource })
                        })
                        .collect();
                    groups.push(pelage_gpu::create_bind_group(
                        device,
                        &wgpu::BindGroupDescriptor {
                            label: Some(pass.draw.label),
                            layout: &pass.layout,
                            entries: &entries,
                        },
                    ));
                }
            }
            groups
        })?)
    }

    /// Records every pass for every slice.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &TargetViews<'_>,
        timer: Option<&mut GpuTimer>,
    ) -> crate::Result<()> {
        self.encode_with(encoder, target, timer, &mut |_, _| {})
    }

    /// As [`Sliced::encode`], calling `between(encoder, pass index)` after each pass of the
    /// first slice (the lab copies the lists out before the resolve empties them).
    pub fn encode_with(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &TargetViews<'_>,
        mut timer: Option<&mut GpuTimer>,
        between: &mut dyn FnMut(&mut wgpu::CommandEncoder, usize),
    ) -> crate::Result<()> {
        self.check_target(target)?;
        // Bind groups per slice and pass hold the depth view the passes sample: built
        // once, and again only when the caller hands a different view.
        let depth = target.depth_to_sample();
        let mut cache = self.groups.lock().map_err(|_| {
            GpuError::Validation("a thread panicked while recording this method".into())
        })?;
        if cache.as_ref().is_none_or(|(view, _)| view != depth) {
            *cache = Some((depth.clone(), self.bind_groups(&self.gpu, depth)?));
        }
        let groups = cache
            .as_ref()
            .map_or(&[][..], |(_, groups)| groups.as_slice());
        let mut groups = groups.iter();
        for slice in 0..self.count {
            let y0 = slice * self.rows;
            let rows = self.rows.min(target.height.saturating_sub(y0));
            for (index, pass) in self.passes.iter().enumerate() {
                if slice == 0 && index > 0 {
                    between(encoder, index - 1);
                }
                let Some(group) = groups.next() else {
                    break;
                };
                let label = pass.draw.label;
                let timestamp_writes = timer.as_deref_mut().and_then(|t| t.render_pass(label));
                let color = crate::draw::over_color(target.color);
                let color_attachments = match pass.kind {
                    PassKind::Storage | PassKind::DepthOnly => Vec::new(),
                    PassKind::OpaqueHair | PassKind::Resolve => vec![Some(color)],
                };
                let depth_stencil_attachment = match pass.kind {
                    // Read-only: the same texture is bound for the shader's own depth test.
                    PassKind::Storage | PassKind::DepthOnly => {
                        Some(wgpu::RenderPassDepthStencilAttachment {
                            view: target.depth,
                            depth_ops: None,
                            stencil_ops: None,
                        })
                    }
                    PassKind::OpaqueHair => Some(wgpu::RenderPassDepthStencilAttachment {
                        view: target.depth,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    PassKind::Resolve => None,
                };
                let mut render = pelage_gpu::audit::begin_render_pass(
                    &mut *encoder,
                    &wgpu::RenderPassDescriptor {
                        label: Some(label),
                        color_attachments: &color_attachments,
                        depth_stencil_attachment,
                        timestamp_writes,
                        occlusion_query_set: None,
                        multiview_mask: None,
                    },
                );
                render.set_scissor_rect(0, y0, target.width, rows.max(1));
                pass.draw.record(&mut render, Some((3, group)));
            }
        }
        Ok(())
    }
}

/// What a sliced method's hair passes are built from.
pub(crate) struct PassContext<'a> {
    pub gpu: &'a Gpu,
    pub common: &'a Common,
    pub inputs: &'a HairInputs<'a>,
    pub module: &'a wgpu::ShaderModule,
}

/// A method made of the mesh pass and sliced passes: what the k-buffer, the A-buffer,
/// the DBK-buffer and random subsets have in common.
#[derive(Debug)]
pub(crate) struct SlicedMethod {
    pub name: &'static str,
    pub common: Common,
    pub sliced: Sliced,
}

impl SlicedMethod {
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &TargetViews<'_>,
        mut timer: Option<&mut GpuTimer>,
    ) -> crate::Result<()> {
        self.sliced.check_target(target)?;
        self.common.encode_volume(encoder, timer.as_deref_mut());
        self.common
            .encode_mesh(encoder, target, None, timer.as_deref_mut());
        self.sliced.encode(encoder, target, timer)
    }
}

/// Implements [`HairPass`](super::HairPass) for a newtype around [`SlicedMethod`].
macro_rules! sliced_hair_pass {
    ($method:ident) => {
        impl $crate::methods::HairPass for $method {
            fn name(&self) -> &'static str {
                self.0.name
            }

            fn prepare(
                &self,
                queue: &pelage_gpu::wgpu::Queue,
                strands: &pelage_contract::StrandFrame,
                camera: &pelage_scene::CameraMatrices,
                lights: &[pelage_scene::Light],
                width: u32,
                height: u32,
            ) -> $crate::Result<()> {
                self.0
                    .common
                    .prepare(queue, strands, camera, lights, width, height)
            }

            fn encode(
                &self,
                encoder: &mut pelage_gpu::wgpu::CommandEncoder,
                strands: &pelage_contract::StrandFrame,
                target: &$crate::TargetViews<'_>,
                timer: Option<&mut pelage_gpu::GpuTimer>,
            ) -> $crate::Result<()> {
                self.0.common.check(self.0.name, strands)?;
                self.0.encode(encoder, target, timer)
            }

            fn passes(&self, lookup: &[String]) -> Vec<pelage_gpu::PassInfo> {
                self.0
                    .common
                    .volume_pass()
                    .into_iter()
                    .chain(self.0.common.mesh_pass(lookup))
                    .chain(self.0.sliced.pass_infos(&self.0.common))
                    .collect()
            }

            fn memory_bytes(&self) -> u64 {
                self.0.sliced.memory_bytes()
            }

            fn grid(&self) -> Option<&$crate::VolumeGrid> {
                self.0.common.grid()
            }

            fn body_sky_binding(&self) -> Option<pelage_gpu::ShaderBinding> {
                self.0.common.body_sky_binding()
            }

            fn set_params(
                &mut self,
                gpu: &pelage_gpu::Gpu,
                params: &pelage_scene::ShadeParams,
            ) -> $crate::Result<()> {
                self.0.common.set_params(gpu, params)
            }

            fn slices(&self) -> u32 {
                self.0.sliced.count
            }

            fn stats(&self, gpu: &pelage_gpu::Gpu) -> $crate::Result<$crate::OitStats> {
                $crate::methods::a_buffer::list_stats(gpu, &self.0.sliced)
            }
        }
    };
}
pub(crate) use sliced_hair_pass;
