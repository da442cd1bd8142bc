//! pelage-gpu on a real adapter (lavapipe on machines without a GPU).
//!
//! These tests fail, never skip, when no adapter is found: the error says
//! what to install.

use pelage_gpu::{
    Gpu, GpuError, GpuTimer, SHADERS, UniformBuffer, read_buffer, read_buffer_range, read_texture,
    storage_buffer, wgpu, zeroed_storage,
};

fn gpu() -> Gpu {
    Gpu::headless().unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn context_and_describe() {
    let gpu = gpu();
    let line = gpu.describe();
    println!("{line}");
    assert!(!line.is_empty() && line != "unknown adapter", "{line}");
    assert!(gpu.limits().max_storage_buffer_binding_size >= 128 << 20);
    gpu.check().unwrap();
}

#[test]
fn from_device_wraps_a_callers_device() {
    let engine = gpu();
    let wrapped = Gpu::from_device(engine.device.clone(), engine.queue.clone(), None);
    assert_eq!(wrapped.describe(), engine.describe());
    assert_eq!(wrapped.features(), engine.features());
    let values = vec![1u32, 2, 3];
    let buffer = storage_buffer(&wrapped, "v", &values, wgpu::BufferUsages::STORAGE).unwrap();
    assert_eq!(
        read_buffer(&wrapped, &buffer).unwrap(),
        bytemuck::cast_slice::<u32, u8>(&values)
    );
}

#[test]
fn buffer_round_trip() {
    let gpu = gpu();
    let values: Vec<u32> = (0..1000).map(|i| i * 7 + 3).collect();
    let buffer = storage_buffer(&gpu, "values", &values, wgpu::BufferUsages::STORAGE).unwrap();
    let bytes = read_buffer(&gpu, &buffer).unwrap();
    assert_eq!(bytemuck::cast_slice::<u8, u32>(&bytes), values.as_slice());

    // An unaligned window inside the buffer.
    let part = read_buffer_range(&gpu, &buffer, 5, 9).unwrap();
    assert_eq!(part, bytemuck::cast_slice::<u32, u8>(&values)[5..14]);
    assert!(matches!(
        read_buffer_range(&gpu, &buffer, 3990, 20),
        Err(GpuError::Map(_))
    ));

    let zeros = zeroed_storage(&gpu, "zeros", 10, wgpu::BufferUsages::empty()).unwrap();
    assert_eq!(read_buffer(&gpu, &zeros).unwrap(), vec![0; 12]);
}

#[derive(encase::ShaderType)]
struct Params {
    wind: glam::Vec3,
    time: f32,
    count: u32,
}

#[test]
fn uniform_buffer_layout_and_rewrite() {
    let gpu = gpu();
    let params = |t: f32| Params {
        wind: glam::Vec3::new(1.0, 2.0, 3.0),
        time: t,
        count: 7,
    };
    let uniform = UniformBuffer::new(&gpu, "params", &params(0.5)).unwrap();
    uniform.write(&gpu.queue, &params(9.0)).unwrap();
    let bytes = read_buffer(&gpu, &uniform.buffer).unwrap();
    // WGSL layout: vec3 at 0, f32 packed into its padding at 12, u32 at 16, size 32.
    assert_eq!(bytes.len(), 32);
    let floats: &[f32] = bytemuck::cast_slice(&bytes[..16]);
    assert_eq!(floats, [1.0, 2.0, 3.0, 9.0]);
    assert_eq!(u32::from_le_bytes(bytes[16..20].try_into().unwrap()), 7);

    // An array of f32 breaks uniform layout rules: an error, not a panic.
    assert!(matches!(
        UniformBuffer::new(&gpu, "bad", &[1.0f32, 2.0]),
        Err(GpuError::Validation(_))
    ));
}

const DOUBLE: &str = r"
@group(0) @binding(0) var<storage, read_write> values: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x < arrayLength(&values)) {
        values[id.x] = values[id.x] * 2u;
    }
}
";

#[test]
fn timed_compute_doubles_values() {
    let gpu = gpu();
    let n = 1u32 << 20;
    let values: Vec<u32> = (0..n).collect();
    let buffer = storage_buffer(&gpu, "values", &values, wgpu::BufferUsages::STORAGE).unwrap();
    let pipeline = gpu
        .scoped(|device| {
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("double"),
                source: wgpu::ShaderSource::Wgsl(DOUBLE.into()),
            });
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("double"),
                layout: None,
                module: &module,
                entry_point: Some("main"),
                compilation_options: Default::default(),
                cache: None,
            })
        })
        .unwrap();
    let bind_group = gpu
        .scoped(|device| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: None,
                layout: &pipeline.get_bind_group_layout(0),
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buffer.as_entire_binding(),
                }],
            })
        })
        .unwrap();

    let mut timer = GpuTimer::new(&gpu, 4)
        .unwrap()
        .expect("lavapipe supports timestamp queries");
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("double"),
            timestamp_writes: timer.compute_pass("double"),
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(n / 64, 1, 1);
    }
    timer.resolve(&mut encoder);
    gpu.submit_and_wait([encoder.finish()]).unwrap();

    let report = timer.read(&gpu).unwrap();
    println!("{report:?}");
    assert_eq!(report.scopes.len(), 1);
    let ms = report.scopes[0].1;
    assert!(ms.is_finite() && ms > 0.0, "{ms}");
    assert_eq!(report.by_label(), vec![("double".to_string(), ms)]);
    assert_eq!(report.total_ms(), ms);
    // The timer is reset for the next frame.
    assert!(timer.read(&gpu).unwrap().scopes.is_empty());

    let doubled = read_buffer(&gpu, &buffer).unwrap();
    let doubled: &[u32] = bytemuck::cast_slice(&doubled);
    assert!(doubled.iter().enumerate().all(|(i, &v)| v == 2 * i as u32));
}

#[test]
fn timer_capacity_and_missing_resolve() {
    let gpu = gpu();
    let mut timer = GpuTimer::new(&gpu, 1).unwrap().unwrap();
    assert!(timer.compute_pass("a").is_some());
    assert!(timer.compute_pass("b").is_none());
    // No resolve: an error, not garbage, and the timer resets.
    assert!(matches!(timer.read(&gpu), Err(GpuError::Validation(_))));
    assert!(timer.read(&gpu).unwrap().scopes.is_empty());
    assert!(GpuTimer::new(&gpu, 5000).is_err());
}

#[test]
fn texture_readback_removes_row_padding() {
    let gpu = gpu();
    let (width, height) = (300u32, 7u32);
    let texels: Vec<u8> = (0..width * height * 4)
        .map(|i| (i * 31 % 251) as u8)
        .collect();
    let size = wgpu::Extent3d {
        width,
        height,
        depth_or_array_layers: 1,
    };
    let texture = gpu
        .scoped(|device| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some("readback"),
                size,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba8Unorm,
                usage: wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            })
        })
        .unwrap();
    gpu.queue.write_texture(
        texture.as_image_copy(),
        &texels,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(width * 4),
            rows_per_image: Some(height),
        },
        size,
    );
    let data = read_texture(&gpu, &texture).unwrap();
    assert_eq!((data.width, data.height, data.bytes_per_texel), (300, 7, 4));
    assert_eq!(data.format, wgpu::TextureFormat::Rgba8Unorm);
    assert!(data.data == texels, "texels differ after readback");
}

#[test]
fn scoped_returns_validation_error_instead_of_panicking() {
    let gpu = gpu();
    let layout = gpu
        .device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: None,
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: false },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
    // A uniform buffer where a storage buffer is required.
    let wrong = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("wrong usage"),
        size: 16,
        usage: wgpu::BufferUsages::UNIFORM,
        mapped_at_creation: false,
    });
    let result = gpu.scoped(|device| {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wrong.as_entire_binding(),
            }],
        })
    });
    match result {
        Err(GpuError::Validation(message)) => println!("{message}"),
        other => panic!("expected a validation error, got {other:?}"),
    }
    // The device still works afterwards.
    gpu.check().unwrap();
}

#[test]
fn uncaptured_error_is_recorded_not_panicked() {
    let gpu = gpu();
    // Outside any scope: wgpu's default handler would panic here.
    let _ = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("mappable storage"),
        size: 16,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    assert!(matches!(gpu.check(), Err(GpuError::Validation(_))));
    gpu.check().unwrap();
}

#[test]
fn storage_size_limit_is_checked() {
    let gpu = gpu();
    let limit = gpu
        .limits()
        .max_storage_buffer_binding_size
        .min(gpu.limits().max_buffer_size);
    gpu.check_storage_size("strands", limit).unwrap();
    let err = gpu.check_storage_size("strands", limit + 1).unwrap_err();
    let message = err.to_string();
    assert!(matches!(err, GpuError::TooLarge { bytes, .. } if bytes == limit + 1));
    assert!(message.contains(&limit.to_string()), "{message}");
    assert!(message.contains("(1 over)"), "{message}");
    assert!(matches!(
        zeroed_storage(&gpu, "huge", limit + 4, wgpu::BufferUsages::empty()),
        Err(GpuError::TooLarge { .. })
    ));
}

#[test]
fn library_shaders_compile_on_the_device() {
    let gpu = gpu();
    let library = SHADERS.library();
    for name in SHADERS.names() {
        library.module(&gpu, name).unwrap_or_else(|e| panic!("{e}"));
    }
}

const SCALE: &str = r"
@group(0) @binding(0) var<uniform> factor: vec4<u32>;
@group(0) @binding(1) var<storage, read> input: array<u32>;
@group(0) @binding(2) var<storage, read_write> output: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x < arrayLength(&output)) {
        output[id.x] = input[id.x] * factor.x;
    }
}
";

#[test]
fn explicit_layouts_run_and_a_mismatch_is_a_validation_error() {
    use pelage_gpu::{BindLayout, bind_buffers, compute_pipeline_with_layouts};
    let gpu = gpu();
    let module = gpu
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("scale"),
            source: wgpu::ShaderSource::Wgsl(SCALE.into()),
        });
    let layout = BindLayout::new("scale", wgpu::ShaderStages::COMPUTE)
        .uniform(0)
        .storage(1)
        .storage_rw(2);
    assert_eq!(layout.layout_entries().len(), 3);
    let usage = wgpu::BufferUsages::STORAGE;
    let factor = storage_buffer(
        &gpu,
        "factor",
        &[3u32, 0, 0, 0],
        wgpu::BufferUsages::UNIFORM,
    )
    .unwrap();
    let input = storage_buffer(&gpu, "input", &[1u32, 2, 3, 4], usage).unwrap();
    let output = zeroed_storage(&gpu, "output", 16, usage).unwrap();
    let (pipeline, group) = gpu
        .scoped(|device| {
            let layout = layout.build(device);
            let pipeline =
                compute_pipeline_with_layouts(device, "scale", &module, "main", &[Some(&layout)]);
            let group = bind_buffers(device, "scale", &layout, &[&factor, &input, &output]);
            (pipeline, group)
        })
        .unwrap();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    }
    gpu.submit_and_wait([encoder.finish()]).unwrap();
    let out = read_buffer(&gpu, &output).unwrap();
    assert_eq!(bytemuck::cast_slice::<u8, u32>(&out), &[3, 6, 9, 12]);

    // The output declared read-only where the shader writes it: a validation error.
    let wrong = BindLayout::new("scale wrong", wgpu::ShaderStages::COMPUTE)
        .uniform(0)
        .storage(1)
        .storage(2);
    let result = gpu.scoped(|device| {
        let layout = wrong.build(device);
        compute_pipeline_with_layouts(device, "scale wrong", &module, "main", &[Some(&layout)])
    });
    match result {
        Err(GpuError::Validation(message)) => println!("{message}"),
        other => panic!("expected a validation error, got {other:?}"),
    }
    gpu.check().unwrap();
}

#[test]
fn a_shader_binding_describes_its_layout() {
    use pelage_gpu::{BoundResource, ShaderBinding};
    let gpu = gpu();
    let buffer = zeroed_storage(&gpu, "b", 16, wgpu::BufferUsages::STORAGE).unwrap();
    let binding = ShaderBinding {
        contract: "shared/math.wgsl",
        module: "shared/math.wgsl",
        sources: &SHADERS,
        group: 2,
        resources: vec![
            BoundResource::Uniform(buffer.clone()),
            BoundResource::Storage(buffer.clone()),
        ],
        reads: vec!["b".into()],
    };
    let entries = binding.layout_entries(wgpu::ShaderStages::FRAGMENT);
    assert_eq!(entries.len(), 2);
    assert_eq!(entries[1].binding, 1);
    assert!(matches!(
        entries[1].ty,
        wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            ..
        }
    ));
    let layout = binding
        .layout(&gpu.device, "b", wgpu::ShaderStages::FRAGMENT)
        .unwrap();
    let mut layouts = Vec::new();
    binding.place(&mut layouts, Some(&layout));
    assert_eq!(layouts.len(), 3);
    assert!(layouts[0].is_none() && layouts[1].is_none() && layouts[2].is_some());
    let empty = ShaderBinding {
        resources: Vec::new(),
        ..binding
    };
    assert!(
        empty
            .layout(&gpu.device, "none", wgpu::ShaderStages::FRAGMENT)
            .is_none()
    );
}
