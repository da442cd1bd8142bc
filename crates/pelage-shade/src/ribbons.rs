//! The opaque raster pass: mesh, then hair ribbons (`wgsl/shade/mesh.wgsl`, `wgsl/shade/ribbons.wgsl`).

use encase::ShaderType;
use glam::{Mat4, Vec3};
use pelage_gpu::{Gpu, GpuTimer, ShaderBinding, ShaderLibrary, UniformBuffer, bind_buffers, wgpu};
use pelage_scene::{Camera, DirectionalLight, HairParams, ShadeParams};
use pelage_strands::{MeshBuffers, StrandBuffers};

use crate::targets::{COLOR_FORMAT, DEPTH_FORMAT};

/// Camera and light for one frame (`Frame` in `wgsl/shade/frame.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct FrameUniforms {
    /// World to clip.
    pub view_proj: Mat4,
    /// Eye position.
    pub eye: Vec3,
    /// World units per pixel at distance 1: `2 tan(fov_y / 2) / height`.
    pub pixel_scale: f32,
    /// Unit vector towards the light.
    pub to_light: Vec3,
    /// Ambient fraction.
    pub ambient: f32,
    /// Light colour times intensity.
    pub light_color: Vec3,
    /// Padding.
    pub _pad: f32,
}

/// Style of the hair ribbons (`RibbonStyle` in `ribbons.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct RibbonStyle {
    /// Segments per strand.
    pub segments: u32,
    /// Tip width as a fraction of the root width.
    pub tip_width: f32,
    /// Minimum ribbon width in pixels.
    pub min_pixels: f32,
    /// Root darkening.
    pub root_occlusion: f32,
    /// Kajiya-Kay diffuse weight.
    pub diffuse: f32,
    /// Kajiya-Kay specular weight.
    pub specular: f32,
    /// Kajiya-Kay exponent.
    pub shininess: f32,
    /// Padding.
    pub _pad: f32,
    /// Specular colour.
    pub specular_color: Vec3,
}

/// Style of the opaque mesh (`MeshStyle` in `mesh.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct MeshStyle {
    /// Albedo, linear RGB.
    pub color: Vec3,
    /// Padding.
    pub _pad: f32,
}

/// Stage 3's opaque method: the mesh and the hair as Kajiya-Kay shaded ribbons, depth tested.
#[derive(Debug)]
pub struct RibbonPass {
    params: ShadeParams,
    frame: UniformBuffer<FrameUniforms>,
    /// The mesh, then the hair.
    draws: [Draw; 2],
}

/// One render pass: a pipeline, its bind groups (index = group; `None` = unused), a vertex count.
#[derive(Debug)]
struct Draw {
    label: &'static str,
    pipeline: wgpu::RenderPipeline,
    groups: Vec<Option<wgpu::BindGroup>>,
    vertices: u32,
}

impl RibbonPass {
    /// Builds the pipelines for targets of `ShadeParams::sample_count` samples in
    /// [`COLOR_FORMAT`] and [`DEPTH_FORMAT`], bound to the given mesh and strand buffers.
    /// `shadow` is stage 2's implementation of the shadow contract (`shadow/none.wgsl`);
    /// `None` draws without shadows.
    pub fn new(
        gpu: &Gpu,
        params: &ShadeParams,
        hair: &HairParams,
        mesh: &MeshBuffers,
        strands: &StrandBuffers,
        shadow: Option<&ShaderBinding>,
    ) -> crate::Result<Self> {
        params.validate()?;
        hair.growth.validate()?;
        let hair_vertices = u64::from(strands.strand_count) * u64::from(strands.segments) * 6;
        let hair_vertices = u32::try_from(hair_vertices).map_err(|_| pelage_scene::ParamError {
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
                &Camera::default(),
                &DirectionalLight::default(),
                params,
                1,
                1,
            )?,
        )?;
        let ribbon_style = UniformBuffer::new(
            gpu,
            "pelage ribbon style",
            &RibbonStyle {
                segments: strands.segments,
                tip_width: hair.growth.tip_width,
                min_pixels: params.min_pixels,
                root_occlusion: params.root_occlusion,
                diffuse: params.diffuse,
                specular: params.specular,
                shininess: params.shininess,
                _pad: 0.0,
                specular_color: params.specular_color,
            },
        )?;
        let mesh_style = UniformBuffer::new(
            gpu,
            "pelage mesh style",
            &MeshStyle {
                color: params.mesh_color,
                _pad: 0.0,
            },
        )?;
        // The shadow contract: both passes import shadow/none.wgsl; a shadow method
        // redirects it to its own lookup and hands over the resources for group 1.
        let redirects: Vec<(&str, &str)> = shadow.iter().map(|b| b.redirect()).collect();
        let mesh_module = ShaderLibrary::module_redirected(gpu, "shade/mesh.wgsl", &redirects)?;
        let hair_module = ShaderLibrary::module_redirected(gpu, "shade/ribbons.wgsl", &redirects)?;
        let samples = params.sample_count;

        let (mesh, hair) = gpu.scoped(|device| {
            let mesh_pipeline = raster_pipeline(
                device,
                "pelage mesh",
                &mesh_module,
                samples,
                Some(wgpu::Face::Back),
            );
            // Ribbons face the camera by construction; either winding may reach the rasterizer.
            let hair_pipeline =
                raster_pipeline(device, "pelage ribbons", &hair_module, samples, None);
            let mesh_groups = [bind_buffers(
                device,
                "pelage mesh",
                &mesh_pipeline.get_bind_group_layout(0),
                &[
                    &frame.buffer,
                    &mesh.positions,
                    &mesh.normals,
                    &mesh.indices,
                    &mesh_style.buffer,
                ],
            )];
            let hair_groups = [bind_buffers(
                device,
                "pelage ribbons",
                &hair_pipeline.get_bind_group_layout(0),
                &[
                    &frame.buffer,
                    &strands.vertices,
                    &strands.roots,
                    &ribbon_style.buffer,
                ],
            )];
            let shadow_group = |pipeline: &wgpu::RenderPipeline, label: &str| {
                shadow.and_then(|b| {
                    b.bind_group(device, label, &pipeline.get_bind_group_layout(b.group))
                })
            };
            let mesh_shadow = shadow_group(&mesh_pipeline, "pelage mesh shadow");
            let hair_shadow = shadow_group(&hair_pipeline, "pelage ribbons shadow");
            (
                Draw {
                    label: "shade: mesh",
                    pipeline: mesh_pipeline,
                    groups: mesh_groups
                        .into_iter()
                        .map(Some)
                        .chain([mesh_shadow])
                        .collect(),
                    vertices: mesh.triangle_count.saturating_mul(3),
                },
                Draw {
                    label: "shade: hair",
                    pipeline: hair_pipeline,
                    groups: hair_groups
                        .into_iter()
                        .map(Some)
                        .chain([hair_shadow])
                        .collect(),
                    vertices: hair_vertices,
                },
            )
        })?;

        Ok(Self {
            params: params.clone(),
            frame,
            draws: [mesh, hair],
        })
    }

    /// Sets camera and light for the next `encode`, for a `width` x `height` target.
    pub fn set_frame(
        &self,
        queue: &wgpu::Queue,
        camera: &Camera,
        light: &DirectionalLight,
        width: u32,
        height: u32,
    ) -> crate::Result<()> {
        let u = FrameUniforms::new(camera, light, &self.params, width, height)?;
        Ok(self.frame.write(queue, &u)?)
    }

    /// Records two render passes into the caller's views: the mesh (clearing colour and
    /// depth), then the hair. `resolve` is the single-sample target when `color` is multisampled.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        color: &wgpu::TextureView,
        resolve: Option<&wgpu::TextureView>,
        depth: &wgpu::TextureView,
        mut timer: Option<&mut GpuTimer>,
    ) {
        let bg = self.params.background;
        for (i, draw) in self.draws.iter().enumerate() {
            let first = i == 0;
            let label = draw.label;
            let timestamp_writes = timer.as_deref_mut().and_then(|t| t.render_pass(label));
            let load_color = if first {
                wgpu::LoadOp::Clear(wgpu::Color {
                    r: f64::from(bg.x),
                    g: f64::from(bg.y),
                    b: f64::from(bg.z),
                    a: 1.0,
                })
            } else {
                wgpu::LoadOp::Load
            };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(label),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: color,
                    depth_slice: None,
                    resolve_target: if first { None } else { resolve },
                    ops: wgpu::Operations {
                        load: load_color,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: depth,
                    depth_ops: Some(wgpu::Operations {
                        load: if first {
                            wgpu::LoadOp::Clear(1.0)
                        } else {
                            wgpu::LoadOp::Load
                        },
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&draw.pipeline);
            for (group, bind_group) in draw.groups.iter().enumerate() {
                if let Some(bind_group) = bind_group {
                    pass.set_bind_group(group as u32, bind_group, &[]);
                }
            }
            pass.draw(0..draw.vertices, 0..1);
        }
    }
}

impl FrameUniforms {
    /// Frame uniforms for `camera` and `light` on a `width` x `height` target.
    pub fn new(
        camera: &Camera,
        light: &DirectionalLight,
        params: &ShadeParams,
        width: u32,
        height: u32,
    ) -> crate::Result<Self> {
        camera.validate()?;
        let to_light = light.to_light()?;
        let height = height.max(1) as f32;
        Ok(Self {
            view_proj: camera.view_projection(width.max(1) as f32 / height),
            eye: camera.eye,
            pixel_scale: 2.0 * (camera.fov_y * 0.5).tan() / height,
            to_light,
            ambient: params.ambient,
            light_color: light.color * light.intensity,
            _pad: 0.0,
        })
    }
}

fn raster_pipeline(
    device: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    samples: u32,
    cull: Option<wgpu::Face>,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: None,
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState {
            cull_mode: cull,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: wgpu::MultisampleState {
            count: samples,
            ..Default::default()
        },
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[Some(COLOR_FORMAT.into())],
        }),
        multiview_mask: None,
        cache: None,
    })
}
