//! What every stage 3 method shares: the frame and style uniforms, the opaque mesh
//! draw, and building hair and full-screen pipelines with their bind groups.

use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};

use pelage_contract::{
    MeshBuffers, PreparedFrame, StrandBuffers, StrandFrame, StrandLayout, VISIBILITY, Visibility,
};
use pelage_gpu::{
    BindLayout, Gpu, GpuTimer, PassInfo, Redirect, ShaderBinding, UniformBuffer, bind_buffers,
    pipeline_layout, wgpu,
};
use pelage_scene::{CameraMatrices, Light, ParamError, ShadeParams};

use crate::hair_model::HairModel;
use crate::ribbons::{FrameUniforms, MeshStyle, RibbonStyle};
use crate::targets::TargetFormat;
use crate::volume::VolumeGrid;

/// The body's sky contract `shade/mesh.wgsl` imports (`shade/body_sky.wgsl`).
const BODY_SKY: &str = "shade/body_sky.wgsl";
/// The volume method's implementation of [`BODY_SKY`].
const BODY_SKY_VOLUME: &str = "shade/body_sky_volume.wgsl";
/// The frame resource naming the colour target a method draws into.
pub const TARGET_COLOR: &str = "target.color";
/// The frame resource naming the depth target a method draws into and tests against.
pub const TARGET_DEPTH: &str = "target.depth";
/// The frame resource naming a transparency method's own per-pixel storage.
pub const OIT_STORAGE: &str = "oit.storage";

/// The label of the mesh's pass (its draws, one per light with a shadow).
const MESH_LABEL: &str = "shade: mesh";

/// The inputs every method is built from.
#[derive(Clone, Copy, Debug)]
pub struct HairInputs<'a> {
    /// How to draw and shade.
    pub params: &'a ShadeParams,
    /// Stage 1's mesh buffers (the opaque surface).
    pub mesh: &'a MeshBuffers,
    /// Stage 1's strands (their widths and opacity come with them, in
    /// [`StrandBuffers::style`]).
    pub strands: &'a StrandBuffers,
    /// Stage 2's implementation of the shadow contract (`shadow/none.wgsl`) for each
    /// light, in light order (one method for every light): the mesh is drawn once per
    /// binding, each light shadowed by its own (a light past the end lights it
    /// unshadowed); empty draws the mesh unshadowed.
    pub shadows: &'a [ShaderBinding],
    /// Stage 2's per-vertex light visibility for the hair; `None` lights every vertex fully.
    pub visibility: Option<Visibility<'a>>,
    /// The formats of the targets the method will draw into (the caller's).
    pub target: TargetFormat,
    /// Whether the method draws `mesh` (flat coloured, shadowed by each light's shadow)
    /// before the hair; `false` for an engine that draws its own mesh into the targets first
    /// (then pass [`TargetViews::load`]). The strands still grow from `mesh`.
    pub draw_mesh: bool,
    /// With the volume method: the caller records the grid itself
    /// ([`HairPass::grid`](crate::HairPass::grid)'s `encode`, after stage 2 and before a
    /// mesh pass of its own that reads the body's sky from it,
    /// [`HairPass::body_sky_binding`](crate::HairPass::body_sky_binding)), and
    /// [`HairPass::encode`](crate::HairPass::encode) leaves it out. `false`: `encode`
    /// records it first. Nothing for the other models.
    pub grid_apart: bool,
}

/// The views a method renders into, owned by the caller.
#[derive(Clone, Copy, Debug)]
pub struct TargetViews<'a> {
    /// Colour to render into, in [`HairInputs::target`]'s colour format and sample count.
    pub color: &'a wgpu::TextureView,
    /// The single-sample target `color` resolves into when it is multisampled.
    pub resolve: Option<&'a wgpu::TextureView>,
    /// Depth, in [`HairInputs::target`]'s depth format and sample count; the
    /// transparency methods also bind it as a texture, so it needs `TEXTURE_BINDING` usage.
    pub depth: &'a wgpu::TextureView,
    /// The depth aspect of `depth` alone, for the transparency methods to sample: needed
    /// when the depth format has a stencil (a view with `TextureAspect::DepthOnly`);
    /// `None` samples `depth` itself.
    pub depth_sampled: Option<&'a wgpu::TextureView>,
    /// Size of the targets in pixels.
    pub width: u32,
    /// Size of the targets in pixels.
    pub height: u32,
    /// Keep what the targets hold and draw over it, depth tested against it (an engine
    /// that drew its own content first); `false` clears colour to the background and
    /// depth to the far plane.
    pub load: bool,
}

impl TargetViews<'_> {
    /// The depth view to sample (see [`TargetViews::depth_sampled`]).
    pub fn depth_to_sample(&self) -> &wgpu::TextureView {
        self.depth_sampled.unwrap_or(self.depth)
    }
}

/// One render pipeline with its bind groups (index = group; `None` = unused).
#[derive(Debug)]
pub(crate) struct Draw {
    pub label: &'static str,
    pub pipeline: wgpu::RenderPipeline,
    pub groups: Vec<Option<wgpu::BindGroup>>,
    pub vertices: Vertices,
}

/// How many vertices a [`Draw`] draws.
#[derive(Clone, Debug)]
pub(crate) enum Vertices {
    /// Always this many.
    Fixed(u32),
    /// As many as the hair ribbons of the strands stage 1 grew this frame, as
    /// [`Common::prepare`] last saw them.
    Hair(Arc<AtomicU32>),
}

impl Vertices {
    fn get(&self) -> u32 {
        match self {
            Self::Fixed(n) => *n,
            Self::Hair(n) => n.load(Ordering::Acquire),
        }
    }
}

/// A colour attachment that draws over what `view` holds (loaded and stored): every
/// pass compositing hair onto the caller's target.
pub(crate) fn over_color(view: &wgpu::TextureView) -> wgpu::RenderPassColorAttachment<'_> {
    wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: wgpu::LoadOp::Load,
            store: wgpu::StoreOp::Store,
        },
    }
}

impl Draw {
    /// Binds the pipeline and its groups, then `extra` (group, bind group) pairs, and draws.
    pub fn record(&self, pass: &mut wgpu::RenderPass<'_>, extra: Option<(u32, &wgpu::BindGroup)>) {
        pass.set_pipeline(&self.pipeline);
        for (group, bind_group) in self.groups.iter().enumerate() {
            if let Some(bind_group) = bind_group {
                pelage_gpu::set_bind_group(pass, group as u32, bind_group);
            }
        }
        if let Some((group, bind_group)) = extra {
            pelage_gpu::set_bind_group(pass, group, bind_group);
        }
        pass.draw(0..self.vertices.get(), 0..1);
    }
}

/// A hair pipeline: `fragment` of `module` (a file importing `shade/hair.wgsl`).
pub(crate) struct HairPipe<'a> {
    pub module: &'a wgpu::ShaderModule,
    pub label: &'static str,
    pub fragment: &'a str,
    pub targets: &'a [Option<wgpu::ColorTargetState>],
    pub depth: wgpu::DepthStencilState,
    /// Whether `fragment` shades (calls `hair_radiance`), so binds the shading model.
    pub shades: bool,
    /// The layout of the method's `@group(3)`, if the module declares one.
    pub oit: Option<&'a wgpu::BindGroupLayout>,
}

/// The uniforms and the mesh draw every method has.
#[derive(Debug)]
pub(crate) struct Common {
    pub params: ShadeParams,
    pub frame: UniformBuffer<FrameUniforms>,
    pub style: UniformBuffer<RibbonStyle>,
    /// The mesh's draws: the first with the body's sky, light 0 and the lights without a
    /// shadow; one more per further light with a shadow, added over it.
    pub mesh_draws: Vec<Draw>,
    /// Ribbon vertices of this frame's strands (written by `prepare`).
    pub hair_vertices: Arc<AtomicU32>,
    /// The stage 1 frame `prepare` last wrote the uniforms for.
    pub prepared: PreparedFrame,
    /// The ribbon style as created; `prepare` rewrites its segment count.
    pub style_value: RibbonStyle,
    pub redirects: Vec<Redirect>,
    pub samples: u32,
    /// The targets' formats.
    pub target: TargetFormat,
    /// Whether `mesh_draws` are drawn.
    pub draw_mesh: bool,
    /// Whether the caller records the volume grid itself ([`HairInputs::grid_apart`]).
    pub grid_apart: bool,
    pub model: HairModel,
    /// The volume method's grid passes, when the model uses them.
    pub volume: Option<VolumeGrid>,
    /// Floats per light in the visibility buffer (0: none).
    pub visibility_stride: u32,
    /// The visibility buffer, or a small one that is never read.
    pub visibility: wgpu::Buffer,
    /// Each mesh draw's style (its colour rewritten by [`Common::set_params`]).
    pub mesh_styles: Vec<(UniformBuffer<MeshStyle>, MeshStyle)>,
}

impl Common {
    /// Uniforms and the mesh pipeline for targets of `samples` samples; ribbons are at
    /// least `min_pixels` wide.
    pub fn new(
        gpu: &Gpu,
        inputs: &HairInputs<'_>,
        samples: u32,
        min_pixels: f32,
    ) -> crate::Result<Self> {
        let HairInputs {
            params,
            mesh,
            strands,
            shadows,
            visibility,
            target,
            draw_mesh,
            grid_apart,
        } = *inputs;
        params.validate()?;
        target.validate(gpu)?;
        if target.samples != samples {
            return Err(ParamError {
                name: "target.samples".into(),
                value: target.samples.to_string(),
                reason: format!(
                    "this method draws {samples}-sample targets (the transparency methods draw single-sampled, \
                     opaque hair the shade sample_count); give targets of {samples} sample(s)"
                ),
            }
            .into());
        }
        strands.style.validate()?;
        // Every segment at full detail must fit one draw.
        let hair_vertices = u64::from(strands.strand_count) * u64::from(strands.segments) * 6;
        u32::try_from(hair_vertices).map_err(|_| ParamError {
            name: "roots.count".into(),
            value: strands.strand_count.to_string(),
            reason: format!(
                "{} strands x {} segments x 6 vertices exceeds one draw's u32 vertex count; use fewer strands or segments",
                strands.strand_count, strands.segments
            ),
        })?;
        let frame = UniformBuffer::new(
            gpu,
            "pelage frame",
            &FrameUniforms::new(
                &pelage_scene::Camera::default().matrices(1, 1),
                &[Light::default()],
                params,
                1,
                0,
            )?,
        )?;
        let style_value = RibbonStyle {
            segments: strands.segments,
            tip_width: strands.style.tip_width,
            min_pixels,
            root_occlusion: params.root_occlusion,
            opacity: strands.style.opacity,
        };
        let style = UniformBuffer::new(gpu, "pelage ribbon style", &style_value)?;
        // One mesh draw per light with a shadow (at least one: the body's sky).
        let mesh_styles = (0..shadows.len().max(1))
            .map(|i| {
                let style = MeshStyle {
                    color: params.mesh_color,
                    base: u32::from(i == 0),
                    shadowed: if i < shadows.len() {
                        i as u32
                    } else {
                        u32::MAX
                    },
                    unshadowed_from: shadows.len() as u32,
                };
                Ok((UniformBuffer::new(gpu, "pelage mesh style", &style)?, style))
            })
            .collect::<crate::Result<Vec<_>>>()?;
        // The shadow contract: every pass imports shadow/none.wgsl; a shadow method
        // redirects it to its own lookup and hands over the resources for group 1.
        let vertex_count = u64::from(strands.strand_count) * u64::from(strands.segments + 1);
        let (visibility_stride, visibility_buffer) = match visibility {
            Some(v) => {
                if u64::from(v.stride) < vertex_count || v.buffer.size() < u64::from(v.stride) * 4 {
                    return Err(ParamError {
                        name: "visibility.stride".into(),
                        value: v.stride.to_string(),
                        reason: format!(
                            "must hold the {vertex_count} strand vertices, in a buffer of at least stride x 4 bytes ({} given)",
                            v.buffer.size()
                        ),
                    }
                    .into());
                }
                (v.stride, v.buffer.clone())
            }
            None => {
                // Never written: every vertex lit (the shaders skip it without a shadow).
                let none = pelage_gpu::zeroed_storage(
                    gpu,
                    "pelage no visibility",
                    16,
                    wgpu::BufferUsages::STORAGE,
                )?;
                pelage_gpu::audit::constant(&[&none]);
                (0, none)
            }
        };
        let model = HairModel::new(gpu, &params.model)?;
        let volume = match (model.volume(), model.chiang()) {
            (Some(field), Some(tables)) => Some(VolumeGrid::new(
                gpu,
                field,
                tables,
                &frame.buffer,
                strands,
                Some(mesh),
                params.mesh_color,
            )?),
            _ => None,
        };
        // The body's sky: unoccluded, or with the volume method through the hair, read
        // from its grid in the model's group 2 (shade/body_sky_volume.wgsl).
        let body_sky = volume
            .is_some()
            .then_some(Redirect::new(BODY_SKY, BODY_SKY_VOLUME));
        let shadow = shadows.first();
        let redirects: Vec<Redirect> = shadow
            .iter()
            .map(|b| b.redirect())
            .chain(model.redirect())
            .chain(body_sky)
            .collect();
        let mesh_module =
            crate::SHADERS
                .library()
                .module_redirected(gpu, "shade/mesh.wgsl", &redirects)?;
        let mesh_draws = gpu.scoped(|device| {
            // mesh.wgsl: frame, positions, normals, indices, style; group 1 the shadow
            // method's; group 2 the hair model's when the body's sky reads the grid.
            let layout = BindLayout::new("pelage mesh", wgpu::ShaderStages::VERTEX_FRAGMENT)
                .uniform(0)
                .storage(1)
                .storage(2)
                .storage(3)
                .uniform(4)
                .build(device);
            let shadow_layout = shadow.and_then(|b| {
                b.layout(
                    device,
                    "pelage mesh shadow",
                    wgpu::ShaderStages::VERTEX_FRAGMENT,
                )
            });
            let sky_layout = body_sky.and_then(|_| {
                model
                    .binding()
                    .layout(device, "pelage mesh sky", wgpu::ShaderStages::FRAGMENT)
            });
            let mut layouts = vec![Some(&layout)];
            if let Some(b) = shadow {
                b.place(&mut layouts, shadow_layout.as_ref());
            }
            if sky_layout.is_some() {
                model.binding().place(&mut layouts, sky_layout.as_ref());
            }
            let pipeline = |label, color: wgpu::ColorTargetState, depth| {
                raster_pipeline(
                    device,
                    &RasterDesc {
                        label,
                        layouts: &layouts,
                        module: &mesh_module,
                        vertex: "vs_main",
                        fragment: Some("fs_main"),
                        targets: &[Some(color)],
                        depth: Some(depth),
                        samples,
                        cull: Some(wgpu::Face::Back),
                    },
                )
            };
            // The first draw writes colour and depth; each further light is added
            // (one + one) where the first draw's depth is, exactly (the same vertex
            // shader, so the same depths), without writing it.
            let first = pipeline(
                "pelage mesh",
                target.color.into(),
                depth_state(&target, true),
            );
            let added = (shadows.len() > 1).then(|| {
                let add = wgpu::BlendComponent {
                    src_factor: wgpu::BlendFactor::One,
                    dst_factor: wgpu::BlendFactor::One,
                    operation: wgpu::BlendOperation::Add,
                };
                pipeline(
                    "pelage mesh, a further light",
                    wgpu::ColorTargetState {
                        format: target.color,
                        blend: Some(wgpu::BlendState {
                            color: add,
                            alpha: add,
                        }),
                        write_mask: wgpu::ColorWrites::COLOR,
                    },
                    wgpu::DepthStencilState {
                        depth_compare: Some(wgpu::CompareFunction::Equal),
                        ..depth_state(&target, false)
                    },
                )
            });
            let sky_group = sky_layout
                .as_ref()
                .and_then(|l| model.binding().bind_group(device, "pelage mesh sky", l));
            mesh_styles
                .iter()
                .enumerate()
                .map(|(i, (style, _))| {
                    let group0 = bind_buffers(
                        device,
                        "pelage mesh",
                        &layout,
                        &[
                            &frame.buffer,
                            &mesh.positions,
                            &mesh.normals,
                            &mesh.indices,
                            &style.buffer,
                        ],
                    );
                    let shadow_group = shadows
                        .get(i)
                        .zip(shadow_layout.as_ref())
                        .and_then(|(b, l)| b.bind_group(device, "pelage mesh shadow", l));
                    let pipeline = match (i, &added) {
                        (0, _) | (_, None) => first.clone(),
                        (_, Some(added)) => added.clone(),
                    };
                    Draw {
                        label: MESH_LABEL,
                        pipeline,
                        groups: vec![Some(group0), shadow_group, sky_group.clone()],
                        vertices: Vertices::Fixed(mesh.triangle_count.saturating_mul(3)),
                    }
                })
                .collect::<Vec<_>>()
        })?;
        Ok(Self {
            params: params.clone(),
            frame,
            style,
            mesh_draws,
            hair_vertices: Arc::new(AtomicU32::new(ribbon_vertices(strands.full_layout()))),
            prepared: PreparedFrame::default(),
            style_value,
            redirects,
            samples,
            target,
            draw_mesh,
            grid_apart,
            model,
            volume,
            visibility_stride,
            visibility: visibility_buffer,
            mesh_styles,
        })
    }

    /// A pipeline drawing the hair with `fragment` of `module` (a file importing
    /// `shade/hair.wgsl`), with groups 0 (strands, uniforms, visibility) and 2 (the
    /// shading model) bound.
    pub fn hair_draw(
        &self,
        gpu: &Gpu,
        inputs: &HairInputs<'_>,
        pipe: &HairPipe<'_>,
    ) -> crate::Result<Draw> {
        let HairPipe {
            module,
            label,
            fragment,
            targets,
            ref depth,
            shades,
            oit,
        } = *pipe;
        Ok(gpu.scoped(|device| {
            // hair.wgsl: the vertex stage reads the strands and visibility, both stages
            // the frame and style uniforms.
            let layout = BindLayout::new(label, wgpu::ShaderStages::VERTEX_FRAGMENT)
                .uniform(0)
                .visible(wgpu::ShaderStages::VERTEX)
                .storage(1)
                .storage(2)
                .visible(wgpu::ShaderStages::VERTEX_FRAGMENT)
                .uniform(3)
                .visible(wgpu::ShaderStages::VERTEX)
                .storage(4)
                .build(device);
            let model = self.model.binding();
            let model_layout = shades
                .then(|| model.layout(device, label, wgpu::ShaderStages::VERTEX_FRAGMENT))
                .flatten();
            // Group 1 stays empty: the hair reads its shadows from the visibility buffer.
            let mut layouts = vec![Some(&layout), None];
            model.place(&mut layouts, model_layout.as_ref());
            if let Some(oit) = oit {
                layouts.resize(4, None);
                layouts[3] = Some(oit);
            }
            let pipeline = raster_pipeline(
                device,
                &RasterDesc {
                    label,
                    layouts: &layouts,
                    module,
                    vertex: "vs_main",
                    fragment: Some(fragment),
                    targets,
                    depth: Some(depth.clone()),
                    samples: self.samples,
                    // Ribbons face the camera by construction; either winding may reach the rasterizer.
                    cull: None,
                },
            );
            let group0 = bind_buffers(
                device,
                label,
                &layout,
                &[
                    &self.frame.buffer,
                    &inputs.strands.vertices,
                    &inputs.strands.roots,
                    &self.style.buffer,
                    &self.visibility,
                ],
            );
            let model_group = model_layout
                .as_ref()
                .and_then(|l| model.bind_group(device, label, l));
            Draw {
                label,
                pipeline,
                groups: vec![Some(group0), None, model_group],
                vertices: Vertices::Hair(self.hair_vertices.clone()),
            }
        })?)
    }

    /// The shader `name` with the shadow contract redirected to this frame's method.
    pub fn module(&self, gpu: &Gpu, name: &str) -> crate::Result<wgpu::ShaderModule> {
        Ok(crate::SHADERS
            .library()
            .module_redirected(gpu, name, &self.redirects)?)
    }

    /// Writes the frame uniforms, and takes the layout of `strands` (the strands and
    /// segments stage 1 grows this frame) for the ribbon style and the hair draws.
    pub fn prepare(
        &self,
        queue: &wgpu::Queue,
        strands: &StrandFrame,
        camera: &CameraMatrices,
        lights: &[Light],
        width: u32,
        height: u32,
    ) -> crate::Result<()> {
        if width == 0 || height == 0 {
            return Err(ParamError::new(
                "target size",
                (width, height),
                "both sides must be at least 1 pixel",
            )
            .into());
        }
        if camera.reverse_z() != self.target.reverse_z {
            return Err(ParamError {
                name: "camera.projection".into(),
                value: if camera.reverse_z() { "reverse-Z" } else { "standard depth" }.into(),
                reason: format!(
                    "the targets were declared with reverse_z = {}; make the projection and TargetFormat::reverse_z agree",
                    self.target.reverse_z
                ),
            }
            .into());
        }
        let u = FrameUniforms::new(camera, lights, &self.params, height, self.visibility_stride)?;

        self.frame.write(queue, &u)?;
        let layout = strands.layout;
        self.style.write(
            queue,
            &RibbonStyle {
                segments: layout.segments,
                ..self.style_value
            },
        )?;
        if let Some(volume) = &self.volume {
            volume.prepare(queue, layout, self.style_value.tip_width)?;
        }
        self.hair_vertices
            .store(ribbon_vertices(layout), Ordering::Release);
        self.prepared.set(strands);
        Ok(())
    }

    /// What [`HairPass::set_params`](crate::HairPass::set_params) does for every method:
    /// refuses what shapes pipelines or buffers (naming it; nothing changes then), then
    /// rewrites the shading model's uniform or tables and the mesh colour, and keeps the
    /// rest (background, ambient, root occlusion) for the next `prepare` and `encode`.
    pub fn set_params(&mut self, gpu: &Gpu, params: &ShadeParams) -> crate::Result<()> {
        params.validate()?;
        let old = &self.params;
        let rebuild = |what: String| Err(crate::ShadeError::NeedsRebuild(what));
        if params.transparency != old.transparency {
            return rebuild(format!(
                "shade.transparency ({} to {})",
                old.transparency.name(),
                params.transparency.name()
            ));
        }
        if params.sample_count != old.sample_count {
            return rebuild(format!(
                "shade.sample_count ({} to {})",
                old.sample_count, params.sample_count
            ));
        }
        if params.min_pixels != old.min_pixels {
            return rebuild(format!(
                "shade.min_pixels ({} to {})",
                old.min_pixels, params.min_pixels
            ));
        }
        self.model.check_update(&params.model)?;
        self.model.update(gpu, &params.model)?;
        for (buffer, style) in &mut self.mesh_styles {
            style.color = params.mesh_color;
            buffer.write(&gpu.queue, style)?;
        }
        if let Some(volume) = &self.volume {
            volume.set_mesh_color(params.mesh_color);
        }
        self.style_value.root_occlusion = params.root_occlusion;
        self.params = params.clone();
        Ok(())
    }

    /// The mesh pass as `encode_mesh` records it when the method draws the mesh (reads
    /// the mesh, every light's shadow `lookup` and, with the volume method, the grid's
    /// fluence for the body's sky; clears and writes the targets); `None` when the
    /// engine draws its own.
    pub fn mesh_pass(&self, lookup: &[String]) -> Option<PassInfo> {
        self.draw_mesh.then(|| {
            // The body's sky is the model's group (the grid, with the volume method): the
            // frame resources it reads are the model binding's.
            PassInfo::new(MESH_LABEL)
                .reads([pelage_contract::MESH.to_string()])
                .reads(lookup.iter().cloned())
                .reads(self.model.binding().reads.iter().cloned())
                .writes([TARGET_COLOR, TARGET_DEPTH])
        })
    }

    /// The volume method's grid pass as the method records it (by
    /// [`Common::encode_volume`], before the mesh): `None` for the other models and when
    /// the caller records the grid apart.
    pub fn volume_pass(&self) -> Option<PassInfo> {
        self.grid()
            .map(VolumeGrid::pass_info)
            .filter(|_| !self.grid_apart)
    }

    /// Records the volume method's grid passes (nothing for the other models, nor when
    /// the caller records the grid apart).
    pub fn encode_volume(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        if let Some(volume) = self.grid().filter(|_| !self.grid_apart) {
            volume.encode(encoder, timer);
        }
    }

    /// The volume method's grid (`None` for the other models).
    pub fn grid(&self) -> Option<&VolumeGrid> {
        self.volume.as_ref()
    }

    /// The body's sky contract (`shade/body_sky.wgsl`) as the volume method implements
    /// it (`shade/body_sky_volume.wgsl`: the grid, read in the hair model's group), for a
    /// caller's own mesh shader; `None` for the other models (the open sky: `ambient`).
    pub fn body_sky_binding(&self) -> Option<ShaderBinding> {
        self.volume.as_ref()?;
        let model = self.model.binding();
        Some(ShaderBinding {
            contract: BODY_SKY,
            module: BODY_SKY_VOLUME,
            sources: &crate::SHADERS,
            group: model.group,
            resources: model.resources.clone(),
            reads: model.reads.clone(),
        })
    }

    /// A hair pass labelled `label`: reads the strands, the visibility (when bound), the
    /// volume grid's fluence (when the model reads it) and the depth target.
    pub fn hair_pass(&self, label: &str) -> PassInfo {
        self.hair_shading(label, true).reads([TARGET_DEPTH])
    }

    /// A depth-tested hair pass that binds no model (a depth-only pass):
    /// [`Common::hair_pass`] without the volume grid.
    pub fn hair_geometry_pass(&self, label: &str) -> PassInfo {
        self.hair_shading(label, false).reads([TARGET_DEPTH])
    }

    /// A compute pass shading the strands (no depth target): the strands, the
    /// visibility when bound, and the volume grid's fluence when `model` and the model
    /// reads it.
    pub fn hair_shading(&self, label: &str, model: bool) -> PassInfo {
        let mut pass = PassInfo::new(label).reads([
            pelage_contract::STRAND_VERTICES,
            pelage_contract::STRAND_ROOTS,
        ]);
        if model {
            pass = pass.reads(self.model.binding().reads.iter().cloned());
        }
        if self.visibility_stride > 0 {
            pass.reads([VISIBILITY])
        } else {
            pass
        }
    }

    /// Errors unless the last [`Common::prepare`] was for `strands`.
    pub fn check(&self, method: &str, strands: &StrandFrame) -> crate::Result<()> {
        Ok(self.prepared.check(method, strands)?)
    }

    /// Records the mesh pass: clears colour (to the background) and depth unless
    /// `target.load`, then draws the mesh (unless built without it). Records nothing
    /// when there is neither a clear nor a mesh to draw.
    pub fn encode_mesh(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &TargetViews<'_>,
        resolve: Option<&wgpu::TextureView>,
        timer: Option<&mut GpuTimer>,
    ) {
        if target.load && !self.draw_mesh {
            return;
        }
        let far = self.target.far_depth();
        let bg = self.params.background;
        let mut pass = pelage_gpu::audit::begin_render_pass(
            &mut *encoder,
            &wgpu::RenderPassDescriptor {
                label: Some(MESH_LABEL),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target.color,
                    depth_slice: None,
                    resolve_target: resolve,
                    ops: wgpu::Operations {
                        load: if target.load {
                            wgpu::LoadOp::Load
                        } else {
                            wgpu::LoadOp::Clear(wgpu::Color {
                                r: f64::from(bg.x),
                                g: f64::from(bg.y),
                                b: f64::from(bg.z),
                                a: 1.0,
                            })
                        },
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: target.depth,
                    depth_ops: Some(wgpu::Operations {
                        load: if target.load {
                            wgpu::LoadOp::Load
                        } else {
                            wgpu::LoadOp::Clear(far)
                        },
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: timer.and_then(|t| t.render_pass(MESH_LABEL)),
                occlusion_query_set: None,
                multiview_mask: None,
            },
        );
        if self.draw_mesh {
            for draw in &self.mesh_draws {
                draw.record(&mut pass, None);
            }
        }
    }
}

/// Depth state for `target`'s depth format and direction: test nearer, write when `write`.
pub(crate) fn depth_state(target: &TargetFormat, write: bool) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: target.depth,
        depth_write_enabled: Some(write),
        depth_compare: Some(target.depth_compare()),
        stencil: Default::default(),
        bias: Default::default(),
    }
}

/// Premultiplied "over": what a resolve pass writes, `(colour, 1 - transmittance)`,
/// lands as `colour + transmittance * destination`.
pub(crate) fn over_target(target: &TargetFormat) -> wgpu::ColorTargetState {
    wgpu::ColorTargetState {
        format: target.color,
        blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
        write_mask: wgpu::ColorWrites::ALL,
    }
}

pub(crate) struct RasterDesc<'a> {
    pub label: &'a str,
    /// The explicit bind group layouts, group `i` = `layouts[i]`.
    pub layouts: &'a [Option<&'a wgpu::BindGroupLayout>],
    pub module: &'a wgpu::ShaderModule,
    pub vertex: &'a str,
    pub fragment: Option<&'a str>,
    pub targets: &'a [Option<wgpu::ColorTargetState>],
    pub depth: Option<wgpu::DepthStencilState>,
    pub samples: u32,
    pub cull: Option<wgpu::Face>,
}

pub(crate) fn raster_pipeline(device: &wgpu::Device, d: &RasterDesc<'_>) -> wgpu::RenderPipeline {
    let layout = pipeline_layout(device, d.label, d.layouts);
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(d.label),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: d.module,
            entry_point: Some(d.vertex),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState {
            cull_mode: d.cull,
            ..Default::default()
        },
        depth_stencil: d.depth.clone(),
        multisample: wgpu::MultisampleState {
            count: d.samples,
            ..Default::default()
        },
        fragment: d.fragment.map(|entry| wgpu::FragmentState {
            module: d.module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            targets: d.targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// Ribbon vertices of `layout`'s strands: 6 per segment (checked to fit a `u32` at full
/// detail by `Common::new`).
fn ribbon_vertices(layout: StrandLayout) -> u32 {
    u32::try_from(layout.segment_count() * 6).unwrap_or(u32::MAX)
}
