//! The Bevy plugin, headless on the test machine's adapter (lavapipe in CI): frames of
//! the fur example's scene rendered into an `Image` hold fur, the fur moves with the
//! wind from frame to frame, and a frame equals pelage's own picture of the same scene
//! (same camera, light, fur and size) by mean FLIP.

// The example's app and scene, compiled into this test; its `main` goes unused here.
#[allow(dead_code)]
#[path = "../examples/fur.rs"]
mod fur;

use pelage::Renderer;
use pelage::gpu::wgpu;
use pelage::shade::TargetFormat;
use pelage_reference::flip::{DEFAULT_PIXELS_PER_DEGREE, LinearImage, flip};

/// Pixels that differ between two pictures.
fn differing(a: &image::RgbaImage, b: &image::RgbaImage) -> usize {
    a.pixels().zip(b.pixels()).filter(|(p, q)| p != q).count()
}

fn linear(image: &image::RgbaImage) -> LinearImage {
    LinearImage::from_srgb8_rgba(image.width(), image.height(), image.as_raw()).unwrap()
}

#[test]
fn bevy_frames_hold_moving_fur_equal_to_pelages_own() {
    let (mut app, target) = fur::app(fur::View::default()).unwrap_or_else(|e| {
        panic!("this test needs a GPU adapter (install mesa-vulkan-drivers for lavapipe): {e}")
    });
    // Frame 1 builds pelage on Bevy's device; the fur is drawn from frame 2 on.
    let mut frames = Vec::new();
    for _ in 0..4 {
        app.update();
        frames.push((fur::time(&app), fur::read(&mut app, &target).unwrap()));
    }
    let (t, bevy_frame) = frames.last().unwrap().clone();
    let (t_before, before) = frames[frames.len() - 2].clone();
    assert!(
        t > t_before,
        "Bevy's clock did not advance ({t_before} then {t})"
    );

    // Fur is there: most pixels differ from the cleared background.
    let background = *bevy_frame.get_pixel(0, 0);
    let drawn = bevy_frame.pixels().filter(|p| **p != background).count();
    let pixels = (fur::WIDTH * fur::HEIGHT) as usize;
    assert!(
        drawn > pixels / 10,
        "Bevy's frame holds {drawn} drawn pixels"
    );
    // It moves with the wind between consecutive frames.
    let moved = differing(&before, &bevy_frame);
    println!("t = {t_before:.3} s to {t:.3} s: {moved} of {pixels} pixels changed");
    assert!(
        moved > pixels / 200,
        "only {moved} pixels changed between frames"
    );

    // pelage's own frame of the scene at the same time: the same camera (pelage's,
    // reverse-Z as Bevy's), light, fur and size, into an sRGB target like Bevy's.
    let gpu = pelage::gpu::Gpu::headless().unwrap();
    let scene = fur::scene();
    let format = TargetFormat {
        color: wgpu::TextureFormat::Rgba8UnormSrgb,
        depth: wgpu::TextureFormat::Depth32Float,
        samples: 1,
        reverse_z: true,
    };
    let mut renderer =
        Renderer::with_format(&gpu, &scene, fur::WIDTH, fur::HEIGHT, &format).unwrap();
    renderer.render(&gpu, t, &scene.camera).unwrap();
    let own = renderer.image(&gpu).unwrap();

    let map = flip(
        &linear(&own),
        &linear(&bevy_frame),
        DEFAULT_PIXELS_PER_DEGREE,
    )
    .unwrap();
    println!(
        "Bevy frame vs pelage's own frame at t = {t:.3} s: mean FLIP {:.5}, {} of {pixels} pixels differ",
        map.mean(),
        differing(&own, &bevy_frame)
    );
    // PELAGE_BEVY_OUT=DIR keeps both pictures (docs/src/images/bevy.png is Bevy's frame).
    if let Some(dir) = std::env::var_os("PELAGE_BEVY_OUT").map(std::path::PathBuf::from) {
        std::fs::create_dir_all(&dir).unwrap();
        bevy_frame.save(dir.join("bevy.png")).unwrap();
        own.save(dir.join("pelage.png")).unwrap();
    }
    // Bevy records the same `Frame` as the facade, so the bound is the embed test's
    // (tests/embed.rs): mean FLIP <= 0.01 and at most 1% of the pixels differing. Measured:
    // 0.00002, 9 of 76 800 pixels. A mean alone would let a near miss through (a mesh
    // drawn without the fur's shadow changes 3.4% of the pixels and scores 0.0077).
    assert!(map.mean() <= 0.01, "mean FLIP {} > 0.01", map.mean());
    let differing = differing(&own, &bevy_frame);
    assert!(
        differing * 100 <= pixels,
        "{differing} of {pixels} pixels differ (more than 1%)"
    );
}
