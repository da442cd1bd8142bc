//! pelage inside an engine that already runs on wgpu.
//!
//! ```text
//! cargo run --release --example embed -- [--frames N] [--out DIR]
//! ```
//!
//! The "engine" here owns everything pelage touches: the device and queue, the
//! encoder, an HDR colour target (`Rgba16Float`) and a depth-stencil target
//! (`Depth24PlusStencil8`), its camera matrices (built with glam, right-handed), its
//! lights, and the mesh: position, normal and index buffers it draws from as vertex
//! and index buffers and pelage reads as storage buffers. It skins the mesh on the CPU
//! every frame (a slow breath) and rewrites those buffers. Every frame it:
//! 1. lets pelage grow the strands from its mesh buffers and shadow them (voxel grid);
//! 2. draws its own mesh into its targets with its own shader, which imports pelage's
//!    shadow contract (`shadow/none.wgsl`, redirected to the voxel lookup) so the body
//!    is shadowed by the fur as pelage would shadow it, and its body-sky contract
//!    (`shade/body_sky.wgsl`, redirected to the volume grid pelage filled after its
//!    shadows) so the skin under the fur sees the sky and light the fur leaves it;
//! 3. lets pelage draw the hair over it (`draw_mesh = false`, `load = true`), depth
//!    tested against the engine's depth;
//! 4. binds pelage's strand buffer in a pass of its own, drawing every 40th strand's
//!    tip as a point;
//! 5. reads the HDR target back and tone maps it (Reinhard, then sRGB) on the CPU.
//!
//! pelage's stages are one `pelage::Frame` built from a `Scene` (the engine's mesh as
//! the rest pose, grown fur, a voxel shadow, `draw_mesh = false`) on the engine's mesh
//! buffers; it is prepared with the engine's matrices and recorded in two parts around
//! the engine's mesh pass, and the order of every pass, pelage's and the engine's, is
//! the frame's plan with the engine's pass inserted, checked once.
//!
//! Writes `DIR/embed_NNNN.png` (default `out/embed`) and checks the last frame.
//! `tests/embed.rs` renders frame 0 without the tips and compares it with the facade's
//! picture of the same scene (`pelage::Renderer`).

use std::path::PathBuf;

use glam::Vec3;
use pelage::gpu::{Gpu, PassInfo, ShaderSources, wgpu};
use pelage::scene::{
    CameraMatrices, HairParams, Light, Mesh, ShadeParams, ShadowParams, VoxelParams,
};
use pelage::shade::{TARGET_COLOR, TARGET_DEPTH, TargetFormat, TargetViews};
use pelage::strands::{MESH, MeshBuffers};
use pelage::{Frame, FrameTarget, scene::Scene};
use wgpu::util::DeviceExt;

type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

/// The engine's frame size.
pub const WIDTH: u32 = 320;
/// The engine's frame size.
pub const HEIGHT: u32 = 240;
/// The engine's targets, as pelage is told about them: HDR colour, a depth-stencil
/// depth, one sample, standard depth.
pub const TARGET: TargetFormat = TargetFormat {
    color: wgpu::TextureFormat::Rgba16Float,
    depth: wgpu::TextureFormat::Depth24PlusStencil8,
    samples: 1,
    reverse_z: false,
};

/// The engine's camera: the values of pelage's default camera, so that the test can
/// compare the frame with the facade's.
const EYE: Vec3 = Vec3::new(2.2, 0.9, 2.9);
const FOV_Y_DEGREES: f32 = 40.0;
const NEAR: f32 = 0.05;
const FAR: f32 = 20.0;

/// View and projection as the engine builds them: right-handed, y up, depth in [0, 1].
pub fn camera() -> CameraMatrices {
    CameraMatrices {
        view: glam::camera::rh::view::look_at_mat4(EYE, Vec3::ZERO, Vec3::Y),
        // glam's "directx" projections: wgpu's clip space, depth in [0, 1].
        projection: glam::camera::rh::proj::directx::perspective(
            FOV_Y_DEGREES.to_radians(),
            WIDTH as f32 / HEIGHT as f32,
            NEAR,
            FAR,
        ),
    }
}

/// The fur pelage grows on the engine's mesh.
pub fn hair() -> HairParams {
    let mut hair = HairParams::default();
    hair.roots.count = 12_000;
    hair
}

/// Shading: pelage's defaults (Chiang's fibres, the volume grid's multiple scattering)
/// on a single-sampled target; the engine's mesh takes its colour, the ambient term and
/// the background from here too, and the sky on its skin from pelage's grid.
pub fn shade() -> ShadeParams {
    ShadeParams {
        sample_count: 1,
        ..Default::default()
    }
}

/// One key light.
pub fn lights() -> Vec<Light> {
    vec![Light::default()]
}

/// The engine's own shaders: its mesh (Lambert, the key light shadowed through pelage's
/// shadow contract, the sky through its body-sky contract) and the tip markers (read
/// from pelage's strand buffer).
const ENGINE_WGSL: &str = r#"
#import shadow/none.wgsl
#import shade/body_sky.wgsl

struct Engine {
    view_proj: mat4x4<f32>,
    to_light: vec4<f32>,
    // rgb: the light's colour times intensity; w: ambient.
    light: vec4<f32>,
    mesh_color: vec4<f32>,
    per_strand: u32,
    tips: u32,
}
@group(0) @binding(0) var<uniform> engine: Engine;
@group(0) @binding(1) var<storage, read> strand_vertices: array<vec4<f32>>;

struct MeshOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) world: vec3<f32>,
}

@vertex
fn vs_mesh(@location(0) p: vec3<f32>, @location(1) n: vec3<f32>) -> MeshOut {
    return MeshOut(engine.view_proj * vec4<f32>(p, 1.0), n, p);
}

@fragment
fn fs_mesh(in: MeshOut) -> @location(0) vec4<f32> {
    let n = normalize(in.normal);
    // body_sky: the sky (ambient) as pelage's shading leaves it on the body, through
    // the contract's redirect (the volume grid).
    var lit = body_sky(in.world, n, engine.light.w);
    // surface_visibility: pelage's shadow method at a point on the body, through the
    // contract's redirect.
    lit += engine.light.rgb * max(dot(n, engine.to_light.xyz), 0.0) * surface_visibility(in.world);
    return vec4<f32>(engine.mesh_color.rgb * lit, 1.0);
}

@vertex
fn vs_tip(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // Every `tips`-th strand's last vertex, read straight from pelage's strand buffer.
    let strand = i * engine.tips;
    let p = strand_vertices[strand * engine.per_strand + engine.per_strand - 1u].xyz;
    return engine.view_proj * vec4<f32>(p, 1.0);
}

@fragment
fn fs_tip() -> @location(0) vec4<f32> {
    return vec4<f32>(8.0, 0.2, 0.1, 1.0);
}
"#;

/// The engine's shader as a source pelage's shader library composes (for the import).
static ENGINE_SHADERS: ShaderSources = ShaderSources::new(
    "embed",
    "examples",
    &[("embed/engine.wgsl", ENGINE_WGSL)],
    &[&pelage::gpu::SHADERS, &pelage::shade::SHADERS],
);

/// `Engine` in `ENGINE_WGSL`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct EngineUniforms {
    view_proj: [f32; 16],
    to_light: [f32; 4],
    light: [f32; 4],
    mesh_color: [f32; 4],
    per_strand: u32,
    tips: u32,
    _pad: [u32; 2],
}

/// The mesh's vertex buffers: packed `f32` triples.
const POSITION: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![0 => Float32x3];
const NORMAL: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![1 => Float32x3];

/// Draw every 40th strand's tip.
const TIP_EVERY: u32 = 40;

/// The engine's device: its own instance, adapter and features; pelage borrows it.
pub fn device() -> Result<Gpu> {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&Default::default()))?;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("engine"),
        required_features: adapter.features() & wgpu::Features::TIMESTAMP_QUERY,
        required_limits: adapter.limits(),
        ..Default::default()
    }))?;
    Ok(Gpu::from_device(device, queue, Some(adapter.get_info())))
}

/// Everything the engine holds across frames.
pub struct Engine {
    rest: Mesh,
    positions: wgpu::Buffer,
    normals: wgpu::Buffer,
    indices: wgpu::Buffer,
    /// pelage's stages.
    pelage: Frame,
    color: wgpu::Texture,
    depth: wgpu::Texture,
    uniforms: wgpu::Buffer,
    mesh_pipeline: wgpu::RenderPipeline,
    /// The engine's own group 0, the shadow's and the body sky's groups (index, bind group).
    mesh_groups: [(u32, wgpu::BindGroup); 3],
    tip_pipeline: wgpu::RenderPipeline,
    tip_group: wgpu::BindGroup,
    tip_count: u32,
}

impl Engine {
    /// Uploads the mesh, builds pelage's stages for the engine's targets and the
    /// engine's own pipelines.
    pub fn new(gpu: &Gpu) -> Result<Self> {
        let device = &gpu.device;
        // The engine's mesh, in buffers it owns: vertex and index buffers for its own
        // draw, storage buffers for pelage.
        let rest = Mesh::creature();
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let make = |label: &str, bytes: &[u8], extra: wgpu::BufferUsages| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytes,
                usage: usage | extra,
            })
        };
        let vertex = wgpu::BufferUsages::VERTEX;
        let positions = make("engine positions", &floats(&rest.positions), vertex);
        let normals = make("engine normals", &floats(&rest.normals), vertex);
        let indices = make(
            "engine indices",
            bytemuck::cast_slice(&rest.indices),
            wgpu::BufferUsages::INDEX,
        );
        // The skinned mesh only ever shrinks from its rest pose, so the rest bounds hold it.
        let mesh = MeshBuffers::from_buffers(
            positions.clone(),
            normals.clone(),
            indices.clone(),
            rest.positions.len() as u32,
            (rest.indices.len() / 3) as u32,
            rest.bounds(),
        )?;

        // pelage's stages on the engine's device and mesh buffers: its mesh as the rest
        // pose, grown fur, a voxel shadow; the engine draws the mesh itself.
        let scene = Scene {
            mesh: rest.clone(),
            hair: hair(),
            groom: None,
            guides: None,
            dynamics: None,
            motion: None,
            skin: None,
            shadow: ShadowParams::Voxel(VoxelParams::default()),
            shade: shade(),
            camera: Default::default(),
            lights: lights(),
        };
        let target = FrameTarget {
            draw_mesh: false,
            ..FrameTarget::new(TARGET, WIDTH, HEIGHT)
        };
        let pelage = Frame::with_mesh_buffers(gpu, &scene, mesh, &target)?;
        // What the engine's mesh shader imports from pelage: the key light's shadow (the
        // voxel method's lookup) and the body's sky (the volume grid), each a contract
        // read as the method's file, with the resources the method hands over.
        let shadow = pelage.shadow_binding(0).ok_or("the scene has no shadow")?;
        let sky = pelage
            .body_sky_binding()
            .ok_or("the scene's shading has no volume grid")?;

        // The frame's passes in order, with the engine's own mesh pass between pelage's
        // shadows and grid (which it samples) and pelage's hair (drawn over it), checked
        // once.
        pelage.plan([PassInfo::new("engine mesh")
            .reads([MESH])
            .reads(shadow.reads.clone())
            .reads(sky.reads.clone())
            .writes([TARGET_COLOR, TARGET_DEPTH])])?;

        // The engine's targets.
        let target = |format, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some("engine target"),
                size: wgpu::Extent3d {
                    width: WIDTH,
                    height: HEIGHT,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let attach = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let color = target(TARGET.color, attach | wgpu::TextureUsages::COPY_SRC);
        let depth = target(TARGET.depth, attach | wgpu::TextureUsages::TEXTURE_BINDING);

        // The engine's pipelines. Its shader imports pelage's contracts, redirected.
        let module = ENGINE_SHADERS.library().module_redirected(
            gpu,
            "embed/engine.wgsl",
            &[shadow.redirect(), sky.redirect()],
        )?;
        // The mesh pipeline's layout is explicit: the body-sky group is the hair model's
        // (the grid beside the model's tables), of which the contract reads two bindings.
        let fragment = wgpu::ShaderStages::FRAGMENT;
        let engine_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("engine mesh"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let shadow_layout = shadow
            .layout(device, "engine mesh shadow", fragment)
            .ok_or("the voxel shadow binds no resources")?;
        let sky_layout = sky
            .layout(device, "engine mesh sky", fragment)
            .ok_or("the body's sky binds no resources")?;
        let mut layouts = vec![None; 1 + shadow.group.max(sky.group) as usize];
        layouts[0] = Some(&engine_layout);
        layouts[shadow.group as usize] = Some(&shadow_layout);
        layouts[sky.group as usize] = Some(&sky_layout);
        let mesh_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("engine mesh"),
            bind_group_layouts: &layouts,
            immediate_size: 0,
        });
        let pipeline = |vertex, buffers: &[_], fragment, topology, depth, layout| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(vertex),
                layout,
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(vertex),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState {
                    topology,
                    cull_mode: (topology == wgpu::PrimitiveTopology::TriangleList)
                        .then_some(wgpu::Face::Back),
                    ..Default::default()
                },
                depth_stencil: depth,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fragment),
                    compilation_options: Default::default(),
                    targets: &[Some(TARGET.color.into())],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let vec3 = |attributes| wgpu::VertexBufferLayout {
            array_stride: 12,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes,
        };
        let mesh_pipeline = pipeline(
            "vs_mesh",
            &[Some(vec3(&POSITION)), Some(vec3(&NORMAL))],
            "fs_mesh",
            wgpu::PrimitiveTopology::TriangleList,
            Some(wgpu::DepthStencilState {
                format: TARGET.depth,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            Some(&mesh_layout),
        );
        // The markers are an overlay: no depth test.
        let tip_pipeline = pipeline(
            "vs_tip",
            &[],
            "fs_tip",
            wgpu::PrimitiveTopology::PointList,
            None,
            None,
        );
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("engine uniforms"),
            size: std::mem::size_of::<EngineUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let group = |label, layout: &wgpu::BindGroupLayout, buffers: &[&wgpu::Buffer]| {
            let entries: Vec<_> = (buffers.iter().enumerate())
                .map(|(i, b)| wgpu::BindGroupEntry {
                    binding: i as u32,
                    resource: b.as_entire_binding(),
                })
                .collect();
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(label),
                layout,
                entries: &entries,
            })
        };
        let mesh_groups = [
            (0, group("engine mesh", &engine_layout, &[&uniforms])),
            (
                shadow.group,
                shadow
                    .bind_group(device, "engine mesh shadow", &shadow_layout)
                    .ok_or("the voxel shadow binds no resources")?,
            ),
            (
                sky.group,
                sky.bind_group(device, "engine mesh sky", &sky_layout)
                    .ok_or("the body's sky binds no resources")?,
            ),
        ];
        let b = pelage.strands().buffers();
        let tip_group = group(
            "engine tips",
            &tip_pipeline.get_bind_group_layout(0),
            &[&uniforms, &b.vertices],
        );
        let tip_count = b.strand_count / TIP_EVERY;
        Ok(Self {
            rest,
            positions,
            normals,
            indices,
            pelage,
            color,
            depth,
            uniforms,
            mesh_pipeline,
            mesh_groups,
            tip_pipeline,
            tip_group,
            tip_count,
        })
    }

    /// Renders the frame at time `t` (with the tip markers when `tips`) and returns the
    /// HDR target, linear RGBA, row-major.
    pub fn frame(&mut self, gpu: &Gpu, t: f32, tips: bool) -> Result<Vec<[f32; 4]>> {
        // Skinning, the engine's business: a slow breath along the body's width (the
        // rest pose at t = 0).
        let breath = 1.0 - 0.03 * (1.0 - (t * 3.0).cos());
        let skinned: Vec<Vec3> = (self.rest.positions.iter())
            .map(|p| Vec3::new(p.x * breath, p.y * breath, p.z))
            .collect();
        let queue = &gpu.queue;
        queue.write_buffer(&self.positions, 0, &floats(&skinned));
        queue.write_buffer(&self.normals, 0, &floats(&self.rest.normals));

        // Per-frame uniforms: every pelage stage, with the engine's matrices.
        let (camera, lights, shade) = (camera(), lights(), shade());
        self.pelage.prepare(queue, t, &camera)?;
        let key = lights[0].as_directional(Vec3::ZERO);
        let b = self.pelage.strands().buffers();
        let uniforms = EngineUniforms {
            view_proj: camera.view_projection().to_cols_array(),
            to_light: (-key.direction.normalize()).extend(0.0).to_array(),
            light: (key.color * key.intensity).extend(shade.ambient).to_array(),
            mesh_color: shade.mesh_color.extend(1.0).to_array(),
            per_strand: b.segments + 1,
            tips: TIP_EVERY,
            _pad: [0; 2],
        };
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));

        let color = self.color.create_view(&Default::default());
        let depth = self.depth.create_view(&Default::default());
        // pelage samples depth through a view without the stencil (its transparency
        // methods do; the opaque one does not need it).
        let depth_only = self.depth.create_view(&wgpu::TextureViewDescriptor {
            aspect: wgpu::TextureAspect::DepthOnly,
            ..Default::default()
        });
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        // 1. pelage's strands and shadow (the engine's mesh pass samples the shadow).
        self.pelage.record_before_shade(&mut encoder, None)?;
        // 2. The engine's mesh, into its cleared targets.
        {
            let bg = shade.background.as_dvec3();
            let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("engine mesh"),
                color_attachments: &[color_attachment(
                    &color,
                    wgpu::LoadOp::Clear(wgpu::Color {
                        r: bg.x,
                        g: bg.y,
                        b: bg.z,
                        a: 1.0,
                    }),
                )],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0),
                        store: wgpu::StoreOp::Store,
                    }),
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            rp.set_pipeline(&self.mesh_pipeline);
            for (index, group) in &self.mesh_groups {
                rp.set_bind_group(*index, group, &[]);
            }
            rp.set_vertex_buffer(0, self.positions.slice(..));
            rp.set_vertex_buffer(1, self.normals.slice(..));
            rp.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
            rp.draw_indexed(0..self.rest.indices.len() as u32, 0, 0..1);
        }
        // 3. pelage's hair over it, depth tested against the engine's depth.
        let views = TargetViews {
            color: &color,
            resolve: None,
            depth: &depth,
            depth_sampled: Some(&depth_only),
            width: WIDTH,
            height: HEIGHT,
            load: true,
        };
        self.pelage.record_shade(&mut encoder, &views, None)?;
        // 4. The engine reads pelage's strand buffer in a pass of its own.
        if tips {
            let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("engine tips"),
                color_attachments: &[color_attachment(&color, wgpu::LoadOp::Load)],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            rp.set_pipeline(&self.tip_pipeline);
            rp.set_bind_group(0, &self.tip_group, &[]);
            rp.draw(0..self.tip_count, 0..1);
        }
        gpu.submit_and_wait([encoder.finish()])?;
        self.pelage.after_submit(gpu)?;
        read_hdr(gpu, &self.color)
    }
}

/// A colour attachment of `view`, loaded with `load` and stored.
fn color_attachment(
    view: &wgpu::TextureView,
    load: wgpu::LoadOp<wgpu::Color>,
) -> Option<wgpu::RenderPassColorAttachment<'_>> {
    Some(wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load,
            store: wgpu::StoreOp::Store,
        },
    })
}

/// The mesh's vectors as the bytes of packed `f32` triples.
fn floats(v: &[Vec3]) -> Vec<u8> {
    bytemuck::cast_slice(&v.iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>()).to_vec()
}

/// An `Rgba16Float` texture read back as linear RGBA.
pub fn read_hdr(gpu: &Gpu, texture: &wgpu::Texture) -> Result<Vec<[f32; 4]>> {
    let data = pelage::gpu::read_texture(gpu, texture)?;
    if data.format != wgpu::TextureFormat::Rgba16Float {
        return Err(format!("expected an Rgba16Float target, got {:?}", data.format).into());
    }
    let half = |h: &[u8]| pelage::gpu::f16_to_f32(u16::from_le_bytes([h[0], h[1]]));
    Ok(data
        .data
        .chunks_exact(8)
        .map(|px| std::array::from_fn(|c| half(&px[2 * c..])))
        .collect())
}

/// The engine's tone mapping: Reinhard per channel, then the sRGB transfer function.
pub fn tone_map(hdr: &[[f32; 4]]) -> Result<image::RgbaImage> {
    let srgb = |v: f32| {
        let v = (v.max(0.0) / (1.0 + v.max(0.0))).min(1.0);
        let s = if v <= 0.003_130_8 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0).round() as u8
    };
    let bytes = (hdr.iter())
        .flat_map(|p| [srgb(p[0]), srgb(p[1]), srgb(p[2]), 255])
        .collect();
    Ok(image::RgbaImage::from_raw(WIDTH, HEIGHT, bytes).ok_or("the frame has the wrong size")?)
}

fn main() {
    if let Err(e) = run() {
        eprintln!("embed: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<()> {
    let mut frames = 4u32;
    let mut out = PathBuf::from("out/embed");
    let mut args = std::env::args().skip(1);
    while let Some(flag) = args.next() {
        let value = args.next().ok_or(format!("{flag} needs a value"))?;
        match flag.as_str() {
            "--frames" => frames = value.parse()?,
            "--out" => out = PathBuf::from(value),
            other => return Err(format!("unknown argument {other} (--frames, --out)").into()),
        }
    }

    let gpu = device()?;
    let mut engine = Engine::new(&gpu)?;
    std::fs::create_dir_all(&out)?;
    for frame in 0..frames {
        let image = tone_map(&engine.frame(&gpu, frame as f32 / 12.0, true)?)?;
        let path = out.join(format!("embed_{frame:04}.png"));
        image.save(&path)?;
        if frame + 1 == frames {
            // The frame holds the engine's background, pelage's fur and the engine's tips.
            let px = |x: u32, y: u32| image.get_pixel(x, y).0;
            let corner = px(2, 2);
            let centre = px(WIDTH / 2, HEIGHT / 2);
            let tips_drawn = (image.pixels())
                .filter(|p| p[0] > 230 && p[1] < 150 && p[2] < 110)
                .count();
            println!(
                "background {corner:?}, fur at the centre {centre:?}, {tips_drawn} tip-marker pixels"
            );
            if centre == corner {
                return Err("nothing was drawn at the centre of the frame".into());
            }
            if tips_drawn == 0 {
                return Err("the engine's pass over pelage's strand buffer drew nothing".into());
            }
            println!("wrote {} and the frames before it", path.display());
        }
    }
    Ok(())
}
