//! The default scene against a golden image rendered on lavapipe.
//!
//! Re-bless after an intended change with `PELAGE_BLESS=1 cargo test --test golden`;
//! the new image is written to `tests/golden/default_scene.png` (commit it) and the
//! differences of the old one are printed.

use std::path::Path;

use pelage::{Renderer, Scene, gpu::Gpu};

const GOLDEN: &str = "tests/golden/default_scene.png";

#[test]
fn default_scene_matches_golden_image() {
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
    let scene = Scene::default();
    let mut renderer = Renderer::new(&gpu, &scene, 240, 180).unwrap();
    renderer.render(&gpu, 1.0, &scene.camera).unwrap();
    let image = renderer.image(&gpu).unwrap();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(GOLDEN);
    if std::env::var_os("PELAGE_BLESS").is_some() {
        pelage::save_png(&image, &path).unwrap();
        println!("blessed {}", path.display());
        return;
    }
    let golden = image::open(&path)
        .unwrap_or_else(|e| {
            panic!(
                "cannot open {}: {e}; bless it with PELAGE_BLESS=1",
                path.display()
            )
        })
        .to_rgba8();
    assert_eq!(golden.dimensions(), image.dimensions());

    // Per-channel differences in 8-bit sRGB: small everywhere, large almost nowhere.
    let diffs: Vec<u8> = golden
        .as_raw()
        .iter()
        .zip(image.as_raw())
        .map(|(a, b)| a.abs_diff(*b))
        .collect();
    let mean = diffs.iter().map(|&d| f64::from(d)).sum::<f64>() / diffs.len() as f64;
    let large = diffs.iter().filter(|&&d| d > 32).count() as f64 / diffs.len() as f64;
    println!(
        "golden: mean abs difference {mean:.3}/255, {:.3}% of channels off by more than 32",
        large * 100.0
    );
    if mean > 1.5 || large > 0.005 {
        let failed = path.with_file_name("default_scene.failed.png");
        pelage::save_png(&image, &failed).unwrap();
        panic!(
            "image differs from {GOLDEN}: mean {mean:.3}/255, {:.3}% large; wrote {}",
            large * 100.0,
            failed.display()
        );
    }
}

#[test]
fn renderer_refuses_a_bad_scene_with_a_named_parameter() {
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
    let mut scene = Scene::default();
    scene.hair.growth.length = f32::NAN;
    let err = Renderer::new(&gpu, &scene, 64, 64).unwrap_err().to_string();
    assert!(err.contains("growth.length"), "{err}");
    let scene = Scene::default();
    let err = Renderer::new(&gpu, &scene, 0, 64).unwrap_err().to_string();
    assert!(err.contains("image size"), "{err}");
}
