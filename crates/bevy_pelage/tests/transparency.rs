//! Every transparency method the adapter runs draws under Bevy's 4x MSAA (and Bevy's
//! reverse-Z depth): the plugin's frame of the fur example's scene equals pelage's own
//! single-sampled frame of it by mean FLIP, method by method. pelage's `Frame` draws a
//! method into targets of its own between Bevy's multisampled, reversed ones and writes
//! the picture back (`src/bridge.rs`).

// The example's app and scene, compiled into this test; its `main` goes unused here.
#[allow(dead_code)]
#[path = "../examples/fur.rs"]
mod fur;

use bevy::render::renderer::{RenderAdapterInfo, RenderDevice, RenderQueue};
use pelage::Renderer;
use pelage::gpu::{Gpu, wgpu};
use pelage::scene::Transparency;
use pelage::shade::TargetFormat;
use pelage_reference::flip::{DEFAULT_PIXELS_PER_DEGREE, LinearImage, flip};

fn linear(image: &image::RgbaImage) -> LinearImage {
    LinearImage::from_srgb8_rgba(image.width(), image.height(), image.as_raw()).unwrap()
}

/// Bevy's device as pelage sees it (its features decide the methods that run).
fn bevy_gpu(app: &bevy::app::App) -> Gpu {
    let render = app.sub_app(bevy::render::RenderApp).world();
    Gpu::from_device(
        render.resource::<RenderDevice>().wgpu_device().clone(),
        (**render.resource::<RenderQueue>()).clone(),
        Some((**render.resource::<RenderAdapterInfo>()).clone()),
    )
}

#[test]
fn every_transparency_method_draws_under_bevys_msaa_as_pelage_draws_it() {
    let own_gpu = Gpu::headless().unwrap();
    let format = TargetFormat {
        color: wgpu::TextureFormat::Rgba8UnormSrgb,
        depth: wgpu::TextureFormat::Depth32Float,
        samples: 1,
        reverse_z: true,
    };
    let pixels = (fur::WIDTH * fur::HEIGHT) as usize;
    let mut worst = (0.0f64, "");
    for method in Transparency::defaults() {
        let mut scene = fur::scene();
        scene.shade.transparency = method.clone();
        let view = fur::View {
            msaa: true,
            ..Default::default()
        };
        let (mut app, target) = fur::app_of(view, &scene).unwrap_or_else(|e| {
            panic!("this test needs a GPU adapter (install mesa-vulkan-drivers for lavapipe): {e}")
        });
        let supported = pelage::shade::supported_methods(&bevy_gpu(&app));
        if !supported.contains(&method.name()) {
            println!(
                "{}: skipped, Bevy's device lacks what it needs (runs: {supported:?})",
                method.name()
            );
            continue;
        }
        // Frame 1 builds pelage on Bevy's device; the fur is drawn from frame 2 on.
        for _ in 0..4 {
            app.update();
        }
        let t = fur::time(&app);
        let bevy_frame = fur::read(&mut app, &target).unwrap();
        let background = *bevy_frame.get_pixel(0, 0);
        let drawn = bevy_frame.pixels().filter(|p| **p != background).count();
        assert!(
            drawn > pixels / 10,
            "{}: Bevy's frame holds {drawn} drawn pixels",
            method.name()
        );

        // Opaque hair draws Bevy's samples itself (the plugin gives it the camera's
        // count): its reference is pelage's own 4x MSAA frame. The others draw
        // single-sampled wherever they draw.
        let mut own_scene = scene.clone();
        let mut own_format = format;
        if method == Transparency::Opaque {
            own_scene.shade.sample_count = 4;
            own_format.samples = 4;
        }
        let mut renderer =
            Renderer::with_format(&own_gpu, &own_scene, fur::WIDTH, fur::HEIGHT, &own_format)
                .unwrap();
        renderer.render(&own_gpu, t, &own_scene.camera).unwrap();
        let own = renderer.image(&own_gpu).unwrap();
        let map = flip(
            &linear(&own),
            &linear(&bevy_frame),
            DEFAULT_PIXELS_PER_DEGREE,
        )
        .unwrap();
        let differing = own
            .pixels()
            .zip(bevy_frame.pixels())
            .filter(|(a, b)| a != b)
            .count();
        println!(
            "{} under Bevy's 4x MSAA vs pelage's own frame at t = {t:.3} s: mean FLIP {:.5}, \
             {differing} of {pixels} pixels differ",
            method.name(),
            map.mean()
        );
        // PELAGE_BEVY_OUT=DIR keeps both pictures per method.
        if let Some(dir) = std::env::var_os("PELAGE_BEVY_OUT").map(std::path::PathBuf::from) {
            std::fs::create_dir_all(&dir).unwrap();
            bevy_frame
                .save(dir.join(format!("bevy_msaa_{}.png", method.name())))
                .unwrap();
            own.save(dir.join(format!("pelage_{}.png", method.name())))
                .unwrap();
        }
        if map.mean() > worst.0 {
            worst = (map.mean(), method.name());
        }
        // The bound for the plugin against the facade.
        assert!(
            map.mean() <= 0.005,
            "{}: mean FLIP {} > 0.005",
            method.name(),
            map.mean()
        );
    }
    println!("worst: {} (mean FLIP {:.5})", worst.1, worst.0);
}
