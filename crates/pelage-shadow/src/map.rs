//! The shadow-map methods: the hair rasterised from the light into a front-most depth
//! map (and, for deep opacity maps, layers of opacity behind it), looked up with PCF
//! (`wgsl/shadow/hair_light.wgsl`, `map_*.wgsl`, `dom_lookup.wgsl`, `adsm_lookup.wgsl`).

use encase::ShaderType;
use glam::{Vec3, Vec4};
use pelage_contract::{MeshBuffers, StrandBuffers, StrandFrame};
use pelage_gpu::{
    BindLayout, BoundResource, Gpu, GpuTimer, PassInfo, ShaderBinding, UniformBuffer, bind_buffers,
    pipeline_layout, wgpu,
};
use pelage_scene::{
    AdsmParams, DeepOpacityParams, DirectionalLight, LayerSpacing, MapParams, OpacityFormat,
    ShadowMapParams,
};

use crate::{LightFit, LightGridUniforms, MeshShadowMap, ShadowMethod};

/// `MapUniforms` in `wgsl/shadow/map_common.wgsl`.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct MapUniforms {
    /// Deep opacity layer ends (absolute, or fractions of the hair's depth).
    pub ends: [Vec4; 2],
    /// Deep opacity layers.
    pub layers: u32,
    /// 1 when `ends` are fractions of the hair's depth.
    pub ends_are_fractions: u32,
    /// PCF radius in texels.
    pub pcf_radius: i32,
    /// Shadow map depth bias, scene units.
    pub bias: f32,
    /// ADSM fibre spacing, scene units.
    pub fiber_spacing: f32,
    /// Minimum ribbon width from the light, texels.
    pub min_texels: f32,
    /// Padding.
    pub _pad0: f32,
    /// Padding.
    pub _pad1: f32,
}

impl MapUniforms {
    fn new(map: &MapParams) -> Self {
        Self {
            ends: [Vec4::ZERO; 2],
            layers: 1,
            ends_are_fractions: 0,
            pcf_radius: map.pcf_radius as i32,
            bias: 0.0,
            fiber_spacing: 1.0,
            // Wide enough that a ribbon always covers texel centres along its length.
            min_texels: 1.5,
            _pad0: 0.0,
            _pad1: 0.0,
        }
    }
}

const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The opacity layers of deep opacity maps.
#[derive(Debug)]
struct Layers {
    views: [wgpu::TextureView; 2],
    pipeline: wgpu::RenderPipeline,
    group: wgpu::BindGroup,
    two_targets: bool,
    bytes: u64,
}

/// The light-side machinery shared by the map methods: fit, depth pass, optional layers.
#[derive(Debug)]
struct LightMap {
    size: u32,
    fit: LightFit,
    uniforms: UniformBuffer<MapUniforms>,
    depth: wgpu::TextureView,
    depth_pipeline: wgpu::RenderPipeline,
    depth_group: wgpu::BindGroup,
    layers: Option<Layers>,
    mesh_map: MeshShadowMap,
}

impl LightMap {
    /// Ribbon vertices of the strands stage 1 grew this frame (see `LightFit::drawn`).
    fn drawn_vertices(&self) -> u32 {
        u32::try_from(self.fit.drawn().segment_count() * 6).unwrap_or(u32::MAX)
    }

    #[allow(clippy::too_many_arguments)]
    fn new(
        gpu: &Gpu,
        map: &MapParams,
        values: MapUniforms,
        layers: Option<OpacityFormat>,
        strands: &StrandBuffers,
        mesh: &MeshBuffers,
        reach: (Vec3, Vec3),
    ) -> crate::Result<Self> {
        strands.style.validate()?;
        let max = gpu.limits().max_texture_dimension_2d;
        if map.size > max {
            return Err(pelage_scene::ParamError {
                name: "shadow map size".into(),
                value: map.size.to_string(),
                reason: format!("this adapter's textures are at most {max} texels wide"),
            }
            .into());
        }
        let vertices = u64::from(strands.strand_count) * u64::from(strands.segments) * 6;
        // Every segment drawn at once must fit one draw (checked at full detail).
        u32::try_from(vertices).map_err(|_| pelage_scene::ParamError {
            name: "roots.count".into(),
            value: strands.strand_count.to_string(),
            reason: "too many strand segments for one draw from the light; use fewer strands or segments".into(),
        })?;
        if layers == Some(OpacityFormat::Float32)
            && !gpu.features().contains(wgpu::Features::FLOAT32_BLENDABLE)
        {
            return Err(pelage_scene::ParamError {
                name: "shadow.deep_opacity.format".into(),
                value: "float32".into(),
                reason: "this adapter cannot blend 32-bit float targets; use float16".into(),
            }
            .into());
        }
        let base = LightGridUniforms::for_hair(
            strands,
            [map.size, map.size, 1],
            0.25 * strands.style.width,
        );
        let fit = LightFit::new(gpu, base, strands)?;
        let uniforms = UniformBuffer::new(gpu, "pelage light map uniforms", &values)?;
        let mesh_map = MeshShadowMap::new(gpu, mesh, map.mesh_map_size, map.pcf_radius, reach)?;
        let module = crate::SHADERS
            .library()
            .module(gpu, "shadow/hair_light.wgsl")?;
        let size = map.size;

        let built = gpu.scoped(|device| {
            let texture = |label: &str, format: wgpu::TextureFormat, side: u32| {
                device
                    .create_texture(&wgpu::TextureDescriptor {
                        label: Some(label),
                        size: wgpu::Extent3d {
                            width: side,
                            height: side,
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
            let depth = texture("pelage hair depth from the light", DEPTH_FORMAT, size);
            pelage_gpu::audit::name_view(&depth, crate::SHADOW_DEPTH);
            // hair_light.wgsl: grid uniforms and grid, vertices, roots, map uniforms; the
            // opacity pass also reads the front depth (5), which the depth pass writes, so
            // each pass has its own layout.
            let common_layout =
                BindLayout::new("pelage hair depth", wgpu::ShaderStages::VERTEX_FRAGMENT)
                    .uniform(0)
                    .storage(1)
                    .storage(2)
                    .storage(3)
                    .uniform(4);
            let depth_layout = common_layout.build(device);
            let pipeline = |label: &str,
                            layout: &wgpu::BindGroupLayout,
                            fragment: Option<wgpu::FragmentState<'_>>,
                            depth_write: bool| {
                let layout = pipeline_layout(device, label, &[Some(layout)]);
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
                    layout: Some(&layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_main"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: Default::default(),
                    depth_stencil: depth_write.then(|| wgpu::DepthStencilState {
                        format: DEPTH_FORMAT,
                        depth_write_enabled: Some(true),
                        depth_compare: Some(wgpu::CompareFunction::Less),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: Default::default(),
                    fragment,
                    multiview_mask: None,
                    cache: None,
                })
            };
            let depth_pipeline = pipeline(
                "pelage hair depth from the light",
                &depth_layout,
                None,
                true,
            );
            let common = [
                fit.uniforms(),
                fit.grid(),
                &strands.vertices,
                &strands.roots,
                &uniforms.buffer,
            ];
            let depth_group = bind_buffers(device, "pelage hair depth", &depth_layout, &common);
            let layers = layers.map(|format| {
                let format = match format {
                    OpacityFormat::Unorm8 => wgpu::TextureFormat::Rgba8Unorm,
                    OpacityFormat::Float16 => wgpu::TextureFormat::Rgba16Float,
                    OpacityFormat::Float32 => wgpu::TextureFormat::Rgba32Float,
                };
                let two_targets = values.layers > 4;
                let add = wgpu::BlendComponent {
                    src_factor: wgpu::BlendFactor::One,
                    dst_factor: wgpu::BlendFactor::One,
                    operation: wgpu::BlendOperation::Add,
                };
                let target = Some(wgpu::ColorTargetState {
                    format,
                    blend: Some(wgpu::BlendState {
                        color: add,
                        alpha: add,
                    }),
                    write_mask: wgpu::ColorWrites::ALL,
                });
                let targets = [target.clone(), if two_targets { target } else { None }];
                let fragment = wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_opacity"),
                    compilation_options: Default::default(),
                    targets: &targets,
                };
                let opacity_layout = common_layout
                    .clone()
                    .visible(wgpu::ShaderStages::FRAGMENT)
                    .texture_2d(5, wgpu::TextureSampleType::Float { filterable: false })
                    .build(device);
                let pipeline = pipeline(
                    "pelage deep opacity layers",
                    &opacity_layout,
                    Some(fragment),
                    false,
                );
                // The unused second layer texture is 1x1: the lookup binds it but never reads it.
                let second_side = if two_targets { size } else { 1 };
                let views = [
                    texture("pelage deep opacity layers 0-3", format, size),
                    texture("pelage deep opacity layers 4-7", format, second_side),
                ];
                for view in &views {
                    pelage_gpu::audit::name_view(view, crate::SHADOW_LAYERS);
                }
                let mut entries: Vec<wgpu::BindGroupEntry<'_>> = common
                    .iter()
                    .zip(0..)
                    .map(|(buffer, binding)| wgpu::BindGroupEntry {
                        binding,
                        resource: buffer.as_entire_binding(),
                    })
                    .collect();
                entries.push(wgpu::BindGroupEntry {
                    binding: 5,
                    resource: wgpu::BindingResource::TextureView(&depth),
                });
                let group = pelage_gpu::create_bind_group(
                    device,
                    &wgpu::BindGroupDescriptor {
                        label: Some("pelage deep opacity layers"),
                        layout: &opacity_layout,
                        entries: &entries,
                    },
                );
                let texel_bytes = u64::from(format.block_copy_size(None).unwrap_or(16));
                let bytes = texel_bytes * (u64::from(size).pow(2) + u64::from(second_side).pow(2));
                Layers {
                    views,
                    pipeline,
                    group,
                    two_targets,
                    bytes,
                }
            });
            (depth, depth_pipeline, depth_group, layers)
        })?;
        let (depth, depth_pipeline, depth_group, layers) = built;
        Ok(Self {
            size,
            fit,
            uniforms,
            depth,
            depth_pipeline,
            depth_group,
            layers,
            mesh_map,
        })
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
        self.fit.check("shadow: light map", strands)?;
        self.fit
            .encode(encoder, timer.as_deref_mut(), "shadow: fit");
        {
            let mut pass = pelage_gpu::audit::begin_render_pass(
                &mut *encoder,
                &wgpu::RenderPassDescriptor {
                    label: Some("pelage hair depth from the light"),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &self.depth,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(1.0),
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: timer
                        .as_deref_mut()
                        .and_then(|t| t.render_pass("shadow: depth")),
                    occlusion_query_set: None,
                    multiview_mask: None,
                },
            );
            pass.set_pipeline(&self.depth_pipeline);
            pelage_gpu::set_bind_group(&mut pass, 0, &self.depth_group);
            pass.draw(0..self.drawn_vertices(), 0..1);
        }
        if let Some(layers) = &self.layers {
            let attachment = |view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })
            };
            let attachments = [
                attachment(&layers.views[0]),
                if layers.two_targets {
                    attachment(&layers.views[1])
                } else {
                    None
                },
            ];
            let mut pass = pelage_gpu::audit::begin_render_pass(
                &mut *encoder,
                &wgpu::RenderPassDescriptor {
                    label: Some("pelage deep opacity layers"),
                    color_attachments: &attachments,
                    depth_stencil_attachment: None,
                    timestamp_writes: timer
                        .as_deref_mut()
                        .and_then(|t| t.render_pass("shadow: opacity")),
                    occlusion_query_set: None,
                    multiview_mask: None,
                },
            );
            pass.set_pipeline(&layers.pipeline);
            pelage_gpu::set_bind_group(&mut pass, 0, &layers.group);
            pass.draw(0..self.drawn_vertices(), 0..1);
        }
        self.mesh_map.encode(encoder, timer);
        Ok(())
    }

    /// The passes `encode` records: the fit, the front-most depth (`shadow.depth`), the
    /// opacity layers (`shadow.layers`, deep opacity maps only), the mesh map.
    fn passes(&self) -> Vec<PassInfo> {
        use pelage_contract::{STRAND_ROOTS, STRAND_VERTICES};
        let mut passes = vec![
            self.fit.pass_info("shadow: fit"),
            PassInfo::new("shadow: depth")
                .reads([crate::SHADOW_GRID, STRAND_VERTICES, STRAND_ROOTS])
                .writes([crate::SHADOW_DEPTH]),
        ];
        if self.layers.is_some() {
            passes.push(
                PassInfo::new("shadow: opacity")
                    .reads([
                        crate::SHADOW_GRID,
                        crate::SHADOW_DEPTH,
                        STRAND_VERTICES,
                        STRAND_ROOTS,
                    ])
                    .writes([crate::SHADOW_LAYERS]),
            );
        }
        passes.extend(self.mesh_map.passes());
        passes
    }

    /// The shadow contract's implementation `module` over this map's resources, which
    /// the method names `reads` (its `ShadowMethod::lookup`).
    fn binding(&self, module: &'static str, reads: Vec<String>) -> ShaderBinding {
        let mut resources = vec![
            BoundResource::Uniform(self.fit.uniforms().clone()),
            BoundResource::Storage(self.fit.grid().clone()),
            BoundResource::Uniform(self.uniforms.buffer.clone()),
        ];
        resources.extend(self.mesh_map.resources());
        resources.push(BoundResource::Texture(
            self.depth.clone(),
            // Read with textureLoad as `texture_2d<f32>` (GL cannot load a texture_depth_2d).
            wgpu::TextureSampleType::Float { filterable: false },
        ));
        if let Some(layers) = &self.layers {
            // Read with textureLoad: float32 layers need no filtering.
            resources.extend(layers.views.iter().map(|v| {
                BoundResource::Texture(
                    v.clone(),
                    wgpu::TextureSampleType::Float { filterable: false },
                )
            }));
        }
        ShaderBinding {
            contract: crate::CONTRACT,
            module,
            sources: &crate::SHADERS,
            group: 1,
            resources,
            reads,
        }
    }

    fn memory_bytes(&self) -> u64 {
        u64::from(self.size).pow(2) * 4
            + self.layers.as_ref().map_or(0, |l| l.bytes)
            + self.mesh_map.memory_bytes()
            + self.fit.memory_bytes()
            + self.uniforms.buffer.size()
    }
}

/// Deep opacity maps (Yuksel and Keyser 2008): the front-most hair depth from the
/// light, then 2 to 8 layers of opacity accumulated behind it with additive blending;
/// the lookup interpolates between the layers around a point.
#[derive(Debug)]
pub struct DeepOpacityMaps {
    params: DeepOpacityParams,
    map: LightMap,
}

impl DeepOpacityMaps {
    /// Builds the maps for `strands` on `mesh`; `reach` is the
    /// world box hair and mesh stay in (the mesh map covers it).
    pub fn new(
        gpu: &Gpu,
        params: &DeepOpacityParams,
        strands: &StrandBuffers,
        mesh: &MeshBuffers,
        reach: (Vec3, Vec3),
    ) -> crate::Result<Self> {
        pelage_scene::ShadowParams::DeepOpacity(params.clone()).validate()?;
        let mut ends = [0.0f32; 8];
        let fractions = match &params.spacing {
            LayerSpacing::Linear { depth } => {
                for (k, end) in ends.iter_mut().enumerate() {
                    *end = depth * (k + 1) as f32;
                }
                0
            }
            LayerSpacing::Fractions { ends: given } => {
                for (end, g) in ends.iter_mut().zip(given) {
                    *end = *g;
                }
                1
            }
        };
        let values = MapUniforms {
            ends: [Vec4::from_slice(&ends[..4]), Vec4::from_slice(&ends[4..])],
            layers: params.layers,
            ends_are_fractions: fractions,
            ..MapUniforms::new(&params.map)
        };
        let map = LightMap::new(
            gpu,
            &params.map,
            values,
            Some(params.format),
            strands,
            mesh,
            reach,
        )?;
        Ok(Self {
            params: params.clone(),
            map,
        })
    }
}

/// Implements [`ShadowMethod`] for a method built on a [`LightMap`] (a `map` field) and
/// described by its own `describe`, sampled through `$lookup`.
macro_rules! light_map_method {
    ($method:ident, $lookup:literal) => {
        impl ShadowMethod for $method {
            fn name(&self) -> String {
                self.describe()
            }

            fn prepare(
                &self,
                queue: &wgpu::Queue,
                strands: &StrandFrame,
                light: &DirectionalLight,
            ) -> crate::Result<()> {
                self.map.prepare(queue, strands, light)
            }

            fn encode(
                &self,
                encoder: &mut wgpu::CommandEncoder,
                strands: &StrandFrame,
                timer: Option<&mut GpuTimer>,
            ) -> crate::Result<()> {
                self.map.encode(encoder, strands, timer)
            }

            fn passes(&self) -> Vec<PassInfo> {
                self.map.passes()
            }

            fn binding(&self) -> ShaderBinding {
                self.map.binding($lookup, self.lookup())
            }

            fn memory_bytes(&self) -> u64 {
                self.map.memory_bytes()
            }
        }
    };
}

impl DeepOpacityMaps {
    /// A short description with its parameters (the [`ShadowMethod::name`]).
    fn describe(&self) -> String {
        let format = match self.params.format {
            OpacityFormat::Unorm8 => "unorm8",
            OpacityFormat::Float16 => "float16",
            OpacityFormat::Float32 => "float32",
        };
        let spacing = match &self.params.spacing {
            LayerSpacing::Linear { depth } => format!("every {depth}"),
            LayerSpacing::Fractions { ends } => format!("at {ends:?}"),
        };
        format!(
            "deep opacity {} layers {spacing} {}^2 {format}",
            self.params.layers, self.params.map.size
        )
    }
}

light_map_method!(DeepOpacityMaps, "shadow/dom_lookup.wgsl");

/// A hair shadow map with percentage-closer filtering: the hair is treated as opaque,
/// so anything behind the front-most hair (by more than a bias) is in shadow.
#[derive(Debug)]
pub struct HairShadowMap {
    params: ShadowMapParams,
    map: LightMap,
}

impl HairShadowMap {
    /// Builds the map for `strands` on `mesh`.
    pub fn new(
        gpu: &Gpu,
        params: &ShadowMapParams,
        strands: &StrandBuffers,
        mesh: &MeshBuffers,
        reach: (Vec3, Vec3),
    ) -> crate::Result<Self> {
        pelage_scene::ShadowParams::ShadowMap(params.clone()).validate()?;
        let values = MapUniforms {
            bias: params.bias,
            ..MapUniforms::new(&params.map)
        };
        let map = LightMap::new(gpu, &params.map, values, None, strands, mesh, reach)?;
        Ok(Self {
            params: params.clone(),
            map,
        })
    }
}

impl HairShadowMap {
    /// A short description with its parameters (the [`ShadowMethod::name`]).
    fn describe(&self) -> String {
        let r = self.params.map.pcf_radius;
        format!(
            "shadow map {}^2 pcf {}x{}",
            self.params.map.size,
            2 * r + 1,
            2 * r + 1
        )
    }
}

light_map_method!(HairShadowMap, "shadow/map_lookup.wgsl");

/// Approximated deep shadow maps (TressFX): one depth map; the fibres in front of a
/// point are estimated from its depth behind the front-most hair and a fibre spacing.
#[derive(Debug)]
pub struct Adsm {
    params: AdsmParams,
    map: LightMap,
}

impl Adsm {
    /// Builds the map for `strands` on `mesh`.
    pub fn new(
        gpu: &Gpu,
        params: &AdsmParams,
        strands: &StrandBuffers,
        mesh: &MeshBuffers,
        reach: (Vec3, Vec3),
    ) -> crate::Result<Self> {
        pelage_scene::ShadowParams::Adsm(params.clone()).validate()?;
        let values = MapUniforms {
            fiber_spacing: params.fiber_spacing,
            ..MapUniforms::new(&params.map)
        };
        let map = LightMap::new(gpu, &params.map, values, None, strands, mesh, reach)?;
        Ok(Self {
            params: params.clone(),
            map,
        })
    }
}

impl Adsm {
    /// A short description with its parameters (the [`ShadowMethod::name`]).
    fn describe(&self) -> String {
        let r = self.params.map.pcf_radius;
        format!(
            "adsm {}^2 pcf {}x{} spacing {}",
            self.params.map.size,
            2 * r + 1,
            2 * r + 1,
            self.params.fiber_spacing
        )
    }
}

light_map_method!(Adsm, "shadow/adsm_lookup.wgsl");
