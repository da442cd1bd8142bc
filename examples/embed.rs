//! pelage inside an engine that already runs on wgpu.
//!
//! ```text
//! cargo run --release --example embed -- [--frames N] [--out DIR]
//! ```
//!
//! The "engine" here owns everything pelage touches: the device and queue, the
//! encoder, the mesh's position, normal and index storage buffers (it re-skins the
//! mesh on the CPU every frame, a slow breathing, and writes the new positions and
//! normals into its own buffers), and the colour and depth targets. Every frame it:
//! 1. draws its own content (a sky gradient and a ground plane) into its targets;
//! 2. lets pelage grow the strands from its mesh buffers, shadow them (voxel grid)
//!    and draw mesh and hair over its content, depth tested against it;
//! 3. binds pelage's strand buffer in a pass of its own, drawing each strand's tip
//!    as a point (any engine pass can read the strands, or the voxel grid through
//!    `VoxelShadow::volume` and `grid`).
//!
//! Writes `DIR/embed_NNNN.png` (default `out/embed`) and checks that the frame holds
//! the engine's content, pelage's hair and the engine's tip markers.

use std::path::PathBuf;

use glam::Vec3;
use pelage::gpu::{Gpu, wgpu};
use pelage::scene::{Camera, HairParams, Light, Mesh, ShadeParams, VoxelParams};
use pelage::shade::{
    COLOR_FORMAT, DEPTH_FORMAT, HairInputs, TargetFormat, TargetViews, Visibility,
};
use pelage::shadow::{LightVisibility, ShadowMethod, VoxelShadow};
use pelage::strands::{GrowStrands, MeshBuffers, StrandStage};
use wgpu::util::DeviceExt;

const WIDTH: u32 = 320;
const HEIGHT: u32 = 240;

/// The engine's own shaders: a background (sky gradient and ground) and tip markers.
const ENGINE_WGSL: &str = r#"
struct Camera { view_proj: mat4x4<f32>, per_strand: u32, tips: u32, _a: u32, _b: u32 }
@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<storage, read> strand_vertices: array<vec4<f32>>;

struct Sky { @builtin(position) clip: vec4<f32>, @location(0) uv: vec2<f32> }

@vertex
fn vs_sky(@builtin(vertex_index) i: u32) -> Sky {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    var out: Sky;
    // Far plane: pelage's depth test lets everything in front of it through.
    out.clip = vec4<f32>(uv * 2.0 - 1.0, 0.999999, 1.0);
    out.uv = uv;
    return out;
}

@fragment
fn fs_sky(in: Sky) -> @location(0) vec4<f32> {
    let y = in.uv.y;
    if (y < 0.42) {
        // Ground: a checkerboard.
        let c = (u32(in.clip.x / 24.0) + u32(in.clip.y / 24.0)) % 2u;
        return vec4<f32>(vec3<f32>(0.10, 0.14, 0.08) * (0.8 + 0.4 * f32(c)), 1.0);
    }
    return vec4<f32>(mix(vec3<f32>(0.35, 0.45, 0.6), vec3<f32>(0.08, 0.1, 0.2), y), 1.0);
}

@vertex
fn vs_tip(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // Every `tips`-th strand's last vertex, read straight from pelage's strand buffer.
    let strand = i * camera.tips;
    let p = strand_vertices[strand * camera.per_strand + camera.per_strand - 1u].xyz;
    return camera.view_proj * vec4<f32>(p, 1.0);
}

@fragment
fn fs_tip() -> @location(0) vec4<f32> {
    return vec4<f32>(1.0, 0.2, 0.1, 1.0);
}
"#;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct EngineCamera {
    view_proj: [f32; 16],
    per_strand: u32,
    tips: u32,
    _pad: [u32; 2],
}

fn main() {
    if let Err(e) = run() {
        eprintln!("embed: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
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

    // The engine's device: its own instance, adapter and features.
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        force_fallback_adapter: false,
        ..Default::default()
    }))?;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("engine"),
        required_features: adapter.features() & wgpu::Features::TIMESTAMP_QUERY,
        required_limits: adapter.limits(),
        ..Default::default()
    }))?;
    // pelage borrows it.
    let gpu = Gpu::from_device(device, queue, Some(adapter.get_info()));
    let device = &gpu.device;

    // The engine's mesh, in storage buffers it owns and rewrites every frame.
    let rest = Mesh::creature();
    let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    let floats = |v: &[Vec3]| -> Vec<f32> { v.iter().flat_map(|p| p.to_array()).collect() };
    let make = |label: &str, bytes: &[u8]| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytes,
            usage: storage,
        })
    };
    let positions = make(
        "engine positions",
        bytemuck::cast_slice(&floats(&rest.positions)),
    );
    let normals = make(
        "engine normals",
        bytemuck::cast_slice(&floats(&rest.normals)),
    );
    let indices = make("engine indices", bytemuck::cast_slice(&rest.indices));
    // The box the skinned mesh stays in: the rest pose breathes by up to 6% in x and y.
    let bounds = {
        let (lo, hi) = rest.bounds();
        let breath = Vec3::new(1.06, 1.06, 1.0);
        (lo.min(lo * breath), hi.max(hi * breath))
    };
    let mesh = MeshBuffers::from_buffers(
        positions.clone(),
        normals.clone(),
        indices,
        rest.positions.len() as u32,
        (rest.indices.len() / 3) as u32,
        bounds,
    )?;

    // pelage's stages, one by one, on the engine's device.
    let mut hair = HairParams::default();
    hair.roots.count = 12_000;
    let mut strands = GrowStrands::new(&gpu, &rest, &mesh, &hair)?;
    let b = strands.buffers();
    // Everything later stages need to know about the strands travels with them (counts,
    // widths, the box they can reach), so a shadow sizes itself from `b` and the mesh.
    let voxel = VoxelShadow::new(
        &gpu,
        &VoxelParams::default(),
        b,
        &mesh,
        pelage::shadow::reach(b, &mesh),
    )?;
    let stride =
        LightVisibility::stride_for(u64::from(b.strand_count) * u64::from(b.segments + 1))?;
    let visibility = LightVisibility::buffer(&gpu, 1, stride)?;
    let hand_over = LightVisibility::new(&gpu, &voxel.binding(), b, &visibility, 0, stride)?;
    let shade = ShadeParams {
        sample_count: 1,
        ..Default::default()
    };
    let pass = pelage::shade::build(
        &gpu,
        &HairInputs {
            params: &shade,
            mesh: &mesh,
            strands: b,
            shadow: Some(&voxel.binding()),
            visibility: Some(Visibility {
                buffer: &visibility,
                stride,
            }),
            // The engine's targets: single-sampled, pelage's default formats.
            target: TargetFormat::default(),
            draw_mesh: true,
        },
        WIDTH,
        HEIGHT,
    )?;

    // The engine's targets and pipelines.
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
    let color = target(COLOR_FORMAT, attach | wgpu::TextureUsages::COPY_SRC);
    let depth = target(DEPTH_FORMAT, attach | wgpu::TextureUsages::TEXTURE_BINDING);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("engine"),
        source: wgpu::ShaderSource::Wgsl(ENGINE_WGSL.into()),
    });
    let pipeline = |vs: &str, fs: &str, topology, compare| {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(vs),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some(vs),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState {
                topology,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(compare),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some(fs),
                compilation_options: Default::default(),
                targets: &[Some(COLOR_FORMAT.into())],
            }),
            multiview_mask: None,
            cache: None,
        })
    };
    let sky = pipeline(
        "vs_sky",
        "fs_sky",
        wgpu::PrimitiveTopology::TriangleList,
        wgpu::CompareFunction::LessEqual,
    );
    // The markers are an overlay: drawn over everything.
    let tips = pipeline(
        "vs_tip",
        "fs_tip",
        wgpu::PrimitiveTopology::PointList,
        wgpu::CompareFunction::Always,
    );
    let camera_buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("engine camera"),
        size: std::mem::size_of::<EngineCamera>() as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let tip_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("engine tips"),
        layout: &tips.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: camera_buffer.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: b.vertices.as_entire_binding(),
            },
        ],
    });
    let tip_every = 40;
    let tip_count = b.strand_count / tip_every;
    let per_strand = b.segments + 1;

    let camera = Camera::default();
    let lights = [Light::default()];
    std::fs::create_dir_all(&out)?;
    for frame in 0..frames {
        let t = frame as f32 / 12.0;
        // Skinning, the engine's business: a slow breath along the body's width.
        let breath = 1.0 + 0.06 * (t * 3.0).sin();
        let skinned: Vec<Vec3> = rest
            .positions
            .iter()
            .map(|p| Vec3::new(p.x * breath, p.y * breath, p.z))
            .collect();
        gpu.queue
            .write_buffer(&positions, 0, bytemuck::cast_slice(&floats(&skinned)));
        gpu.queue
            .write_buffer(&normals, 0, bytemuck::cast_slice(&floats(&rest.normals)));
        // Stage 1 first: the frame it returns prepares and records every later stage.
        let strand_frame = strands.prepare(&gpu.queue, t)?;
        voxel.prepare(
            &gpu.queue,
            &strand_frame,
            &lights[0].as_directional(Vec3::ZERO),
        )?;
        hand_over.prepare(&strand_frame);
        pass.prepare(
            &gpu.queue,
            &strand_frame,
            &camera.matrices(WIDTH, HEIGHT),
            &lights,
            WIDTH,
            HEIGHT,
        )?;
        let view_proj = camera.view_projection(WIDTH as f32 / HEIGHT as f32);
        gpu.queue.write_buffer(
            &camera_buffer,
            0,
            bytemuck::bytes_of(&EngineCamera {
                view_proj: view_proj.to_cols_array(),
                per_strand,
                tips: tip_every,
                _pad: [0; 2],
            }),
        );

        let color_view = color.create_view(&Default::default());
        let depth_view = depth.create_view(&Default::default());
        let mut encoder = device.create_command_encoder(&Default::default());
        // 1. The engine's own content.
        {
            let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("engine background"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &color_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            rp.set_pipeline(&sky);
            rp.draw(0..3, 0..1);
        }
        // 2. pelage, into the same encoder and targets.
        strands.encode(&mut encoder, &strand_frame, None)?;
        voxel.encode(&mut encoder, &strand_frame, None)?;
        hand_over.encode(&mut encoder, &strand_frame, None)?;
        pass.encode(
            &gpu,
            &mut encoder,
            &strand_frame,
            &TargetViews {
                color: &color_view,
                resolve: None,
                depth: &depth_view,
                depth_sampled: None,
                width: WIDTH,
                height: HEIGHT,
                load: true,
            },
            None,
        )?;
        // 3. The engine reads pelage's strand buffer in a pass of its own.
        {
            let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("engine tips"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &color_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            rp.set_pipeline(&tips);
            rp.set_bind_group(0, &tip_group, &[]);
            rp.draw(0..tip_count, 0..1);
        }
        gpu.submit_and_wait([encoder.finish()])?;

        let data = pelage::gpu::read_texture(&gpu, &color)?;
        let image = image::RgbaImage::from_raw(data.width, data.height, data.data)
            .ok_or("colour readback has the wrong size")?;
        let path = out.join(format!("embed_{frame:04}.png"));
        pelage::save_png(&image, &path)?;
        if frame + 1 == frames {
            // The frame holds all three: engine sky or ground, pelage fur, engine tips.
            let px = |x: u32, y: u32| image.get_pixel(x, y).0;
            let sky_pixel = px(WIDTH / 2, 4);
            let ground_pixel = px(4, HEIGHT - 4);
            let centre = px(WIDTH / 2, HEIGHT / 2);
            let tips_drawn = image
                .pixels()
                .filter(|p| p[0] > 230 && p[1] < 150 && p[2] < 110)
                .count();
            println!(
                "sky {sky_pixel:?}, ground {ground_pixel:?}, fur at the centre {centre:?}, {tips_drawn} tip-marker pixels"
            );
            if sky_pixel[2] <= sky_pixel[0] || ground_pixel[1] <= ground_pixel[2] {
                return Err("the engine's own content is missing".into());
            }
            if centre == sky_pixel || centre == ground_pixel {
                return Err("pelage's fur is missing at the centre of the frame".into());
            }
            if tips_drawn == 0 {
                return Err("the engine's pass over pelage's strand buffer drew nothing".into());
            }
            println!("wrote {} and the frames before it", path.display());
        }
    }
    Ok(())
}
