//! Groom files as Bevy assets: `scenes/long_hair.hair` loaded through Bevy's asset
//! server and drawn by the plugin (the groom example's app) equals pelage's own frame of
//! `scenes/long_hair.toml` by mean FLIP; a file pelage refuses is the asset's load error
//! (Bevy's `LoadState::Failed`, with pelage's message), and its entity gets no fur.

// The example's app, compiled into this test; its `main` goes unused here.
#[allow(dead_code)]
#[path = "../examples/groom.rs"]
mod groom;

use bevy::asset::{AssetPlugin, LoadState};
use bevy::prelude::*;
use bevy_pelage::{GroomAsset, GroomLoader};
use pelage::Renderer;
use pelage::gpu::wgpu;
use pelage::shade::TargetFormat;
use pelage_reference::flip::{DEFAULT_PIXELS_PER_DEGREE, LinearImage, flip};

fn linear(image: &image::RgbaImage) -> LinearImage {
    LinearImage::from_srgb8_rgba(image.width(), image.height(), image.as_raw()).unwrap()
}

/// The groom's own strands in the wind (`long_hair.toml`) and interpolated from it as
/// guides onto the head (`guides.toml`).
#[test]
fn a_groom_asset_draws_as_pelage_draws_the_scene_file() {
    let scenes = groom::default_scene_file().with_file_name("");
    for name in ["long_hair.toml", "guides.toml"] {
        against_pelage(&scenes.join(name), true);
    }
}

/// The groom on an entity without a `Mesh3d`: pelage's groom-only scene (no head drawn
/// or shadowed).
#[test]
fn a_groom_alone_draws_as_pelage_draws_a_groom_only_scene() {
    against_pelage(&groom::default_scene_file(), false);
}

/// The plugin's frame of the scene file's groom (on its head, or alone) against pelage's
/// own frame of the same scene (its mesh left out without the head).
fn against_pelage(file: &std::path::Path, head: bool) {
    let name = file.file_name().unwrap().to_string_lossy();
    let name = if head {
        name.into_owned()
    } else {
        format!("{name} without its mesh")
    };
    let (mut app, target) = groom::app_with_groom(file, None, head).unwrap_or_else(|e| {
        panic!("this test needs a GPU adapter (install mesa-vulkan-drivers for lavapipe): {e}")
    });
    let waited = groom::until_drawn(&mut app, &target, 200).unwrap();
    // Two more frames: the strand rasterizer's pool and the k-buffer settle.
    app.update();
    app.update();
    let t = groom::time(&app);
    let bevy_frame = groom::read(&mut app, &target).unwrap();
    let pixels = (groom::WIDTH * groom::HEIGHT) as usize;

    let (mut scene, groom_file) = groom::scene(file).unwrap();
    if !head {
        scene.mesh = pelage::scene::Mesh::default();
    }
    assert!(scene.groom.is_some());
    let gpu = pelage::gpu::Gpu::headless().unwrap();
    let format = TargetFormat {
        color: wgpu::TextureFormat::Rgba8UnormSrgb,
        depth: wgpu::TextureFormat::Depth32Float,
        samples: 1,
        reverse_z: true,
    };
    let mut renderer =
        Renderer::with_format(&gpu, &scene, groom::WIDTH, groom::HEIGHT, &format).unwrap();
    renderer.render(&gpu, t, &scene.camera).unwrap();
    let own = renderer.image(&gpu).unwrap();
    let background = *own.get_pixel(0, 0);
    let drawn = own.pixels().filter(|p| **p != background).count();
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
        "{groom_file} as a Bevy asset (drawn after {waited} frames), Bevy's 4x MSAA, vs \
         pelage's frame of {name} at t = {t:.3} s: mean FLIP {:.5}, {differing} of \
         {pixels} pixels differ ({drawn} drawn)",
        map.mean()
    );
    if let Some(dir) = std::env::var_os("PELAGE_BEVY_OUT").map(std::path::PathBuf::from) {
        std::fs::create_dir_all(&dir).unwrap();
        bevy_frame
            .save(dir.join(format!("bevy_{name}.png")))
            .unwrap();
        own.save(dir.join(format!("pelage_{name}.png"))).unwrap();
    }
    assert!(
        drawn > pixels / 20,
        "{name}: pelage's frame holds {drawn} drawn pixels"
    );
    // The bound for the plugin against the facade.
    assert!(
        map.mean() <= 0.005,
        "{name}: mean FLIP {} > 0.005",
        map.mean()
    );
}

/// A broken groom file: the loader's error is Bevy's load error, naming pelage's reason.
#[test]
fn a_bad_groom_file_is_the_assets_load_error() {
    let dir = std::env::temp_dir().join(format!("bevy_pelage_groom_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A `.hair` file cut short in its header, and a `.tfx` file of the wrong size.
    std::fs::write(dir.join("short.hair"), b"HAIR\x01\x00").unwrap();
    std::fs::write(dir.join("bad.tfx"), [7u8; 10]).unwrap();
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        AssetPlugin {
            file_path: dir.to_string_lossy().into_owned(),
            ..default()
        },
    ))
    .init_asset::<GroomAsset>()
    .register_asset_loader(GroomLoader);
    let server = app.world().resource::<AssetServer>().clone();
    // pelage's reasons (HairFileError::Truncated, TfxFileError's header check).
    let cases = [
        ("short.hair", "shorter than the 128-byte header"),
        ("bad.tfx", "truncated at byte 10 while reading the header"),
    ];
    for (file, reason) in cases {
        let handle: Handle<GroomAsset> = server.load(file);
        let mut state = server.load_state(&handle);
        for _ in 0..500 {
            if matches!(state, LoadState::Failed(_) | LoadState::Loaded) {
                break;
            }
            app.update();
            std::thread::sleep(std::time::Duration::from_millis(5));
            state = server.load_state(&handle);
        }
        let LoadState::Failed(error) = state else {
            panic!("{file}: {state:?}, not failed");
        };
        let message = error.to_string();
        println!("{message}");
        assert!(
            message.contains(file) && message.contains(reason),
            "{file}: {message}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A groom file that is not there: the entity gets no fur (nor its mesh: pelage draws
/// none without a frame), nothing panics, frame after frame.
#[test]
fn an_entity_whose_groom_does_not_load_is_skipped() {
    let file = groom::default_scene_file();
    let (mut app, target) = groom::app_with_groom(&file, Some("missing.hair"), true).unwrap();
    assert!(groom::until_drawn(&mut app, &target, 12).is_err());
    let frame = groom::read(&mut app, &target).unwrap();
    let background = *frame.get_pixel(0, 0);
    assert!(frame.pixels().all(|p| *p == background));
}
