//! Explicit bind group layouts (issue 17, item 3): every pipeline of every shadow and
//! transparency method (and every shading model) is built and renders a frame on a
//! device created with `wgpu::Limits::default()`, the limits WebGPU guarantees; only
//! the 64-bit atomics some transparency methods declare are requested beyond them.
//! And no library pipeline asks wgpu for an automatic layout (a scan of the sources).

use pelage::gpu::{Gpu, wgpu};
use pelage::scene::{ShadingModel, ShadowParams, Transparency};
use pelage::{Renderer, scene::Scene};

/// The features the k-buffer and random subsets declare (64-bit atomics); nothing else.
const INT64: wgpu::Features = wgpu::Features::SHADER_INT64
    .union(wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX)
    .union(wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS);

/// A device with the default limits (and the adapter's 64-bit atomics, if any), wrapped
/// as an engine would ([`Gpu::from_device`]: wgpu's default handler panics on any error
/// outside a scope, which fails the test).
fn default_limits_gpu() -> Gpu {
    gpu_with(|adapter| adapter.features() & INT64)
}

/// A device with WebGPU's default limits and the features `features` picks from the
/// adapter's.
fn gpu_with(features: impl FnOnce(&wgpu::Adapter) -> wgpu::Features) -> Gpu {
    pollster::block_on(async {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let mut adapter = None;
        for force_fallback_adapter in [false, true] {
            let options = wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter,
                compatible_surface: None,
                apply_limit_buckets: false,
            };
            if let Ok(found) = instance.request_adapter(&options).await {
                adapter = Some(found);
                break;
            }
        }
        let adapter = adapter.unwrap_or_else(|| panic!("this test needs a GPU adapter"));
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("pelage default limits"),
                required_features: features(&adapter),
                required_limits: wgpu::Limits::default(),
                ..Default::default()
            })
            .await
            .unwrap_or_else(|e| panic!("a device with the default limits: {e}"));
        Gpu::from_device(device, queue, Some(adapter.get_info()))
    })
}

fn scene(shadow: ShadowParams, transparency: Transparency, model: ShadingModel) -> Scene {
    let mut scene = Scene::default();
    scene.hair.roots.count = 500;
    scene.shadow = shadow;
    scene.shade.transparency = transparency;
    scene.shade.model = model;
    scene.shade.sample_count = 1;
    scene
}

#[test]
fn every_method_renders_on_a_device_with_default_limits() {
    let gpu = default_limits_gpu();
    assert_eq!(
        gpu.limits().max_storage_buffers_per_shader_stage,
        wgpu::Limits::default().max_storage_buffers_per_shader_stage
    );
    println!("{}, features {:?}", gpu.describe(), gpu.features() & INT64);
    let shadows = [
        ShadowParams::None,
        ShadowParams::default(),
        ShadowParams::DeepOpacity(Default::default()),
        ShadowParams::ShadowMap(Default::default()),
        ShadowParams::Adsm(Default::default()),
    ];
    let methods = [
        Transparency::Opaque,
        Transparency::wboit(),
        Transparency::KBuffer { k: 8 },
        Transparency::a_buffer(),
        Transparency::Dbk {
            depth_shift: 0.05,
            nodes_per_pixel: 8.0,
            resolve_k: 16,
        },
        Transparency::RandomSubsets { k: 8 },
        Transparency::strand_raster(),
    ];
    // The models with the most bindings (tables in storage buffers), with the method
    // binding the most storage in the fragment stage (DBK's hair pass: four buffers).
    let models = [
        ShadingModel::Marschner {
            params: Default::default(),
            lut: true,
        },
        ShadingModel::Chiang(Default::default()),
        ShadingModel::Sadeghi(Default::default()),
    ];
    let dbk = methods[4].clone();
    let cases = shadows
        .iter()
        .map(|s| (s.clone(), Transparency::Opaque, ShadingModel::default()))
        .chain(
            methods
                .iter()
                .map(|m| (ShadowParams::default(), m.clone(), ShadingModel::default())),
        )
        .chain(
            models
                .iter()
                .map(|model| (ShadowParams::default(), dbk.clone(), model.clone())),
        );
    for (shadow, method, model) in cases {
        let s = scene(shadow.clone(), method.clone(), model.clone());
        let mut renderer = match Renderer::new(&gpu, &s, 64, 48) {
            Ok(r) => r,
            Err(pelage::Error::Shade(pelage::shade::ShadeError::Unsupported(why))) => {
                // Only a method declaring a feature this adapter lacks may refuse.
                assert!(
                    !gpu.features().contains(INT64),
                    "{method:?} refused although the 64-bit atomics are enabled: {why}"
                );
                println!("{method:?}: skipped, this adapter cannot run it: {why}");
                continue;
            }
            Err(e) => panic!("{shadow:?} / {method:?} / {model:?}: {e}"),
        };
        renderer
            .render(&gpu, 0.0, &s.camera)
            .unwrap_or_else(|e| panic!("{shadow:?} / {method:?} / {model:?}: {e}"));
        renderer
            .finish(&gpu)
            .unwrap_or_else(|e| panic!("{shadow:?} / {method:?} / {model:?}: {e}"));
        println!("{shadow:?} / {method:?} / {model:?}: rendered");
    }
}

#[test]
fn the_strand_rasterizer_needs_no_feature_and_no_more_than_webgpu_limits() {
    // Issue 18: no 64-bit atomics, no timestamp queries, WebGPU's limits (128 MiB per
    // binding, 8 storage buffers per stage, 16 KiB of workgroup memory): every pipeline
    // validates (an error outside a scope panics through wgpu's default handler) and
    // the picture has hair, with every shading model and both tile sizes.
    let gpu = gpu_with(|_| wgpu::Features::empty());
    assert!(gpu.features().is_empty());
    assert!(pelage::shade::supported_methods(&gpu).contains(&"strand_raster"));
    let models = [
        ShadingModel::default(),
        ShadingModel::Marschner {
            params: Default::default(),
            lut: true,
        },
        ShadingModel::Chiang(Default::default()),
    ];
    for (tile, model) in [(16, &models[0]), (8, &models[1]), (16, &models[2])] {
        let transparency = Transparency::StrandRaster {
            tile,
            bins: 16,
            pool: 4.0,
        };
        let s = scene(ShadowParams::default(), transparency, model.clone());
        let mut renderer = Renderer::new(&gpu, &s, 64, 48)
            .unwrap_or_else(|e| panic!("tile {tile}, {model:?}: {e}"));
        renderer.render(&gpu, 0.0, &s.camera).unwrap();
        renderer.finish(&gpu).unwrap();
        let (_, _, pixels) = renderer.rgba8(&gpu).unwrap();
        let background = &pixels[..4];
        let hair = pixels.chunks(4).filter(|p| *p != background).count();
        println!("tile {tile}, {model:?}: {hair} pixels differ from the background");
        assert!(hair > 100, "tile {tile}: no hair drawn");
    }
}

#[test]
fn the_simulation_renders_on_a_device_with_default_limits_and_repeats_bit_for_bit() {
    // Issue 20: the simulation binds 8 storage buffers (WebGPU's default), on a head
    // that turns (the mesh rewritten every frame): two renderers given the same frames
    // draw the same pictures, and the picture changes as the head turns.
    let gpu = gpu_with(|_| wgpu::Features::empty());
    let mut s = scene(
        ShadowParams::default(),
        Transparency::Opaque,
        ShadingModel::default(),
    );
    s.mesh = pelage::scene::Mesh::icosphere(0.5, 2).unwrap();
    s.hair.growth.length = 0.6;
    s.camera.eye = glam::Vec3::new(0.0, 0.3, 2.5);
    s.camera.target = glam::Vec3::ZERO;
    s.dynamics = Some(pelage::scene::DynamicsParams {
        colliders: vec![pelage::scene::Collider::sphere(glam::Vec3::ZERO, 0.45)],
        ..Default::default()
    });
    s.motion = Some(pelage::scene::MeshMotion::default());
    let frames = |renderer: &mut Renderer| {
        (0..6)
            .map(|f| {
                renderer.render(&gpu, f as f32 * 0.25, &s.camera).unwrap();
                renderer.finish(&gpu).unwrap();
                renderer.rgba8(&gpu).unwrap().2
            })
            .collect::<Vec<_>>()
    };
    let a = frames(&mut Renderer::new(&gpu, &s, 64, 48).unwrap());
    let b = frames(&mut Renderer::new(&gpu, &s, 64, 48).unwrap());
    assert!(a == b, "two renderers of the same frames differ");
    assert!(a[0] != a[5], "the head did not move");
}

#[test]
fn no_library_pipeline_has_an_automatic_layout() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let dirs = [
        "src",
        "crates/pelage-gpu/src",
        "crates/pelage-scene/src",
        "crates/pelage-strands/src",
        "crates/pelage-shadow/src",
        "crates/pelage-shade/src",
    ];
    let mut found = Vec::new();
    let mut stack: Vec<_> = dirs.iter().map(|d| root.join(d)).collect();
    while let Some(path) = stack.pop() {
        if path.is_dir() {
            for entry in std::fs::read_dir(&path).unwrap() {
                stack.push(entry.unwrap().path());
            }
            continue;
        }
        if path.extension().is_none_or(|e| e != "rs") {
            continue;
        }
        // pelage-gpu's `compute_pipeline` (automatic) stays for tools and benchmarks.
        let allowed = path.ends_with("crates/pelage-gpu/src/pipelines.rs");
        let text = std::fs::read_to_string(&path).unwrap();
        for (i, line) in text.lines().enumerate() {
            let automatic = line.contains("layout: None")
                || line.contains(".get_bind_group_layout(")
                || (line.contains("compute_pipeline(") && !line.contains("fn compute_pipeline("));
            if automatic && !allowed && !line.trim_start().starts_with("//") {
                found.push(format!("{}:{}: {}", path.display(), i + 1, line.trim()));
            }
        }
    }
    assert!(
        found.is_empty(),
        "automatic layouts in the library:\n{}",
        found.join("\n")
    );
}
