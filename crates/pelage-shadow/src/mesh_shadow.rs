//! The opaque mesh's own shadow: a depth map from the light, sampled with PCF
//! (`wgsl/shadow/mesh_depth.wgsl`, `wgsl/shadow/mesh_shadow.wgsl`).

use encase::ShaderType;
use glam::{Mat4, Vec3};
use pelage_contract::MeshBuffers;
use pelage_gpu::{
    BindLayout, BoundResource, Gpu, GpuTimer, PassInfo, UniformBuffer, bind_buffers,
    pipeline_layout, wgpu,
};
use pelage_scene::DirectionalLight;

use crate::LightSpace;

const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// `MeshShadowUniforms` in `wgsl/shadow/mesh_shadow.wgsl`.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct MeshShadowUniforms {
    /// World to the light's clip space.
    pub view_proj: Mat4,
    /// One texel in uv units.
    pub texel: f32,
    /// PCF radius in texels.
    pub pcf_radius: i32,
    /// Depth bias in clip-space z.
    pub bias: f32,
    /// 0 = no mesh shadows.
    pub enabled: u32,
}

/// A depth map of the mesh from a directional light.
#[derive(Debug)]
pub struct MeshShadowMap {
    size: u32,
    pcf_radius: u32,
    uniforms: UniformBuffer<MeshShadowUniforms>,
    view: wgpu::TextureView,
    sampler: wgpu::Sampler,
    /// `None` when `size` is 0 (no mesh shadows) or the mesh has no triangles.
    draw: Option<(wgpu::RenderPipeline, wgpu::BindGroup, u32)>,
    bounds: (Vec3, Vec3),
}

impl MeshShadowMap {
    /// A `size` x `size` map (0 = disabled) with a PCF kernel of radius `pcf_radius`,
    /// covering the world box `bounds` (the mesh and everything that grows on it). A mesh
    /// without triangles disables it too: everything is lit by the mesh.
    pub fn new(
        gpu: &Gpu,
        mesh: &MeshBuffers,
        size: u32,
        pcf_radius: u32,
        bounds: (Vec3, Vec3),
    ) -> crate::Result<Self> {
        let max = gpu.limits().max_texture_dimension_2d;
        if size > max {
            return Err(pelage_scene::ParamError {
                name: "shadow.mesh_map_size".into(),
                value: size.to_string(),
                reason: format!("this adapter's textures are at most {max} texels wide"),
            }
            .into());
        }
        let uniforms = UniformBuffer::new(gpu, "pelage mesh shadow", &Self::disabled_uniforms())?;
        let module = crate::SHADERS
            .library()
            .module(gpu, "shadow/mesh_depth.wgsl")?;
        let (view, sampler, draw) = gpu.scoped(|device| {
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("pelage mesh shadow map"),
                size: wgpu::Extent3d {
                    width: size.max(1),
                    height: size.max(1),
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: DEPTH_FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            });
            let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("pelage mesh shadow"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                compare: Some(wgpu::CompareFunction::LessEqual),
                ..Default::default()
            });
            // A mesh without triangles (a groom-only scene) casts nothing: no pass.
            let draw = (size > 0 && mesh.triangle_count > 0).then(|| {
                // mesh_depth.wgsl (vertex stage only): the light, positions, indices.
                let layout = BindLayout::new("pelage mesh shadow map", wgpu::ShaderStages::VERTEX)
                    .uniform(0)
                    .storage(1)
                    .storage(2)
                    .build(device);
                let pipeline_layout =
                    pipeline_layout(device, "pelage mesh shadow map", &[Some(&layout)]);
                let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("pelage mesh shadow map"),
                    layout: Some(&pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_main"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: Default::default(),
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: DEPTH_FORMAT,
                        depth_write_enabled: Some(true),
                        depth_compare: Some(wgpu::CompareFunction::Less),
                        stencil: Default::default(),
                        bias: wgpu::DepthBiasState {
                            constant: 2,
                            slope_scale: 2.0,
                            clamp: 0.0,
                        },
                    }),
                    multisample: Default::default(),
                    fragment: None,
                    multiview_mask: None,
                    cache: None,
                });
                let bind_group = bind_buffers(
                    device,
                    "pelage mesh shadow map",
                    &layout,
                    &[&uniforms.buffer, &mesh.positions, &mesh.indices],
                );
                (pipeline, bind_group, mesh.triangle_count.saturating_mul(3))
            });
            (texture.create_view(&Default::default()), sampler, draw)
        })?;
        pelage_gpu::audit::name_view(&view, crate::SHADOW_MESH_MAP);
        Ok(Self {
            size,
            pcf_radius,
            uniforms,
            view,
            sampler,
            draw,
            bounds,
        })
    }

    fn disabled_uniforms() -> MeshShadowUniforms {
        MeshShadowUniforms {
            view_proj: Mat4::IDENTITY,
            texel: 1.0,
            pcf_radius: 0,
            bias: 0.0,
            enabled: 0,
        }
    }

    /// Aims the map along `light` (fitted to the bounds given at creation).
    pub fn set_light(&self, queue: &wgpu::Queue, light: &DirectionalLight) -> crate::Result<()> {
        let light = LightSpace::new(light.to_light()?);
        let u = if self.draw.is_some() {
            let (lo, hi) = light.bounds_of(self.bounds.0, self.bounds.1);
            MeshShadowUniforms {
                view_proj: light.orthographic(lo, hi),
                texel: 1.0 / self.size as f32,
                pcf_radius: self.pcf_radius as i32,
                // A few texels' worth of depth along the light; the pipeline adds slope bias.
                bias: 2e-3,
                enabled: 1,
            }
        } else {
            Self::disabled_uniforms()
        };
        Ok(self.uniforms.write(queue, &u)?)
    }

    /// Records the depth pass (nothing when disabled).
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        let Some((pipeline, bind_group, vertices)) = &self.draw else {
            return;
        };
        let mut pass = pelage_gpu::audit::begin_render_pass(
            &mut *encoder,
            &wgpu::RenderPassDescriptor {
                label: Some("pelage mesh shadow map"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: timer.and_then(|t| t.render_pass("shadow: mesh map")),
                occlusion_query_set: None,
                multiview_mask: None,
            },
        );
        pass.set_pipeline(pipeline);
        pelage_gpu::set_bind_group(&mut pass, 0, bind_group);
        pass.draw(0..*vertices, 0..1);
    }

    /// The depth pass as `encode` records it (none when disabled): reads the mesh,
    /// writes `shadow.mesh_map`.
    pub fn passes(&self) -> Vec<PassInfo> {
        self.draw
            .iter()
            .map(|_| {
                PassInfo::new("shadow: mesh map")
                    .reads([pelage_contract::MESH])
                    .writes([crate::SHADOW_MESH_MAP])
            })
            .collect()
    }

    /// The resources `wgsl/shadow/mesh_shadow.wgsl` binds at 3, 4 and 5.
    pub fn resources(&self) -> [BoundResource; 3] {
        [
            BoundResource::Uniform(self.uniforms.buffer.clone()),
            BoundResource::Texture(self.view.clone(), wgpu::TextureSampleType::Depth),
            BoundResource::Sampler(self.sampler.clone(), wgpu::SamplerBindingType::Comparison),
        ]
    }

    /// Bytes of GPU memory the map holds.
    pub fn memory_bytes(&self) -> u64 {
        u64::from(self.size.max(1)).pow(2) * 4
    }
}
