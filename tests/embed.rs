//! The embed example's engine frame (its own HDR and depth-stencil targets, glam
//! matrices, mesh drawn by its own shader, pelage's stages recorded into its encoder)
//! gives the facade's picture of the same scene, both tone mapped by the engine.

// The example's engine, compiled into this test; its `main` goes unused here.
#[allow(dead_code)]
#[path = "../examples/embed.rs"]
mod embed;

use pelage::scene::Camera;
use pelage::{Renderer, scene::Scene};
use pelage_reference::flip::{DEFAULT_PIXELS_PER_DEGREE, LinearImage, flip};

#[test]
fn the_engine_frame_is_the_facades_picture() {
    let gpu = embed::device().unwrap_or_else(|e| {
        panic!("this test needs a GPU adapter (install mesa-vulkan-drivers for lavapipe): {e}")
    });

    // The engine's glam matrices are the default camera's.
    let engine_camera = embed::camera();
    let camera = Camera::default();
    let facade_camera = camera.matrices(embed::WIDTH, embed::HEIGHT);
    for (a, b) in [
        (engine_camera.view, facade_camera.view),
        (engine_camera.projection, facade_camera.projection),
    ] {
        assert!(a.abs_diff_eq(b, 1e-6), "engine {a} vs facade {b}");
    }

    // The engine's frame 0 (its rest pose), without the tip markers.
    let mut engine = embed::Engine::new(&gpu).unwrap();
    let engine_image = embed::tone_map(&engine.frame(&gpu, 0.0, false).unwrap()).unwrap();

    // The facade: the same scene into the same target formats, the same tone mapping.
    let scene = Scene {
        hair: embed::hair(),
        shade: embed::shade(),
        lights: embed::lights(),
        camera,
        ..Scene::default()
    };
    let mut renderer =
        Renderer::with_format(&gpu, &scene, embed::WIDTH, embed::HEIGHT, &embed::TARGET).unwrap();
    renderer.render(&gpu, 0.0, &scene.camera).unwrap();
    let facade_hdr = embed::read_hdr(&gpu, renderer.color_texture()).unwrap();
    let facade_image = embed::tone_map(&facade_hdr).unwrap();

    // Both pictures hold fur: most pixels differ from the background.
    let background = *facade_image.get_pixel(0, 0);
    let drawn = facade_image.pixels().filter(|p| **p != background).count();
    assert!(
        drawn > (embed::WIDTH * embed::HEIGHT / 10) as usize,
        "the facade drew {drawn} pixels"
    );

    let linear = |image: &image::RgbaImage| {
        LinearImage::from_srgb8_rgba(image.width(), image.height(), image.as_raw()).unwrap()
    };
    let map = flip(
        &linear(&facade_image),
        &linear(&engine_image),
        DEFAULT_PIXELS_PER_DEGREE,
    )
    .unwrap();
    let differing = (facade_image.pixels().zip(engine_image.pixels()))
        .filter(|(a, b)| a != b)
        .count();
    println!(
        "engine frame vs facade: mean FLIP {:.5}, {differing} of {} pixels differ",
        map.mean(),
        embed::WIDTH * embed::HEIGHT
    );
    // PELAGE_EMBED_OUT=DIR keeps both pictures for a look.
    if let Some(dir) = std::env::var_os("PELAGE_EMBED_OUT").map(std::path::PathBuf::from) {
        std::fs::create_dir_all(&dir).unwrap();
        engine_image.save(&dir.join("engine.png")).unwrap();
        facade_image.save(&dir.join("facade.png")).unwrap();
    }
    assert!(map.mean() <= 0.01, "mean FLIP {} > 0.01", map.mean());
    // The engine does pelage's arithmetic, so the pictures agree nearly pixel for pixel.
    // A mean FLIP alone would let a near miss through: the engine's mesh drawn without
    // the fur's shadow changes 3.4% of the pixels yet scores 0.0077.
    assert!(
        differing * 100 <= (embed::WIDTH * embed::HEIGHT) as usize,
        "{differing} pixels differ (more than 1%)"
    );
}
