//! A groom file as a Bevy asset: `scenes/long_hair.hair` (3 000 strands of long wavy
//! hair) loaded through Bevy's `AssetServer` and put on a head with a
//! [`bevy_pelage::Groom`], in the wind, drawn under Bevy's default 4x MSAA by the scene's
//! k-buffer, rendered headless into an `Image`.
//!
//! ```text
//! cargo run -p bevy_pelage --example groom -- [--frames N] [--out DIR] [--scene FILE]
//! ```
//!
//! Renders N frames (default 8, 1/12 s apart) of 320 x 240 of the scene file (default
//! `scenes/long_hair.toml`: its mesh, `[groom]` file, segments and guides, `[dynamics]`,
//! hair, shading, camera and key light) and writes `DIR/groom_NNNN.png` (default
//! `out/bevy`). The groom is loaded by the asset server from the scene file's folder.
//! `tests/groom.rs` renders the same scene and compares it with pelage's own frame.

use std::path::{Path, PathBuf};

use bevy::asset::AssetPlugin;
use bevy::image::Image;
use bevy::prelude::*;
use bevy::render::view::Msaa;
use bevy::time::TimeUpdateStrategy;
use bevy_pelage::{Groom, PelagePlugin};

#[path = "headless/mod.rs"]
mod headless;
use headless::Result;
pub use headless::{FRAME_STEP, HEIGHT, WIDTH, read, time};

/// The default scene file: long hair from `long_hair.hair` on a head.
pub fn default_scene_file() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/long_hair.toml")
}

/// The scene file at `path` as pelage's renderer takes it, and its groom file's name
/// relative to the scene's folder (what the asset server loads).
pub fn scene(path: &Path) -> Result<(pelage::scene::Scene, String)> {
    let scene = pelage::scene::Scene::from_file(path)?;
    let file = pelage::scene::SceneFile::load(path)?;
    let groom = file
        .groom
        .ok_or_else(|| format!("{} has no [groom]", path.display()))?;
    // The scene file names the groom relative to its folder (read back as a path there).
    let folder = path.parent().unwrap_or(Path::new(""));
    let relative = groom.path.strip_prefix(folder).unwrap_or(&groom.path);
    Ok((scene, relative.to_string_lossy().into_owned()))
}

/// A Bevy app, headless, whose asset server reads the folder of `scene_file`: a camera
/// (Bevy's default 4x MSAA), the key light, and the scene's mesh with [`Fur`] and a
/// [`Groom`] of the scene's groom file loaded as an asset. Returns the app and the image
/// it renders into.
///
/// [`Fur`]: bevy_pelage::Fur
pub fn app(scene_file: &Path) -> Result<(App, Handle<Image>)> {
    app_with_groom(scene_file, None, true)
}

/// [`app`] with another groom file than the scene's (a name in the scene's folder), and
/// without the scene's mesh unless `head` (the groom alone: no `Mesh3d`).
pub fn app_with_groom(
    scene_file: &Path,
    groom: Option<&str>,
    head: bool,
) -> Result<(App, Handle<Image>)> {
    let (scene, scene_groom) = scene(scene_file)?;
    let groom_file = groom.map_or(scene_groom, str::to_owned);
    let folder = scene_file
        .parent()
        .ok_or("the scene file has no folder")?
        .canonicalize()?;
    let mut app = App::new();
    app.add_plugins(headless::plugins().set(AssetPlugin {
        file_path: folder.to_string_lossy().into_owned(),
        ..default()
    }))
    .add_plugins(PelagePlugin)
    .insert_resource(TimeUpdateStrategy::ManualDuration(FRAME_STEP));
    let bg = scene.shade.background;
    app.insert_resource(ClearColor(Color::linear_rgb(bg.x, bg.y, bg.z)));

    let world = app.world_mut();
    let image = headless::target(world);
    let mesh = world
        .resource_mut::<Assets<Mesh>>()
        .add(bevy_pelage::bevy_mesh(&scene.mesh));
    world.spawn(headless::camera(
        &scene,
        &image,
        Transform::default(),
        Msaa::default(),
    ));
    world.spawn(headless::key_light(&scene, Quat::IDENTITY)?);
    let asset = world.resource::<AssetServer>().load(groom_file);
    let segments = scene.groom.as_ref().map_or(16, |g| g.segments);
    let mut entity = world.spawn((
        headless::fur(&scene, None),
        Groom {
            asset,
            segments,
            guides: scene.guides.clone(),
            dynamics: scene.dynamics.clone(),
        },
        Transform::default(),
    ));
    if head {
        entity.insert(Mesh3d(mesh));
    }
    headless::finish(&mut app);
    Ok((app, image))
}

/// Updates `app` until the fur has been drawn (the groom loads asynchronously): at most
/// `limit` frames. Returns the frames it took.
pub fn until_drawn(app: &mut App, image: &Handle<Image>, limit: u32) -> Result<u32> {
    for frame in 0..limit {
        app.update();
        let picture = read(app, image)?;
        // The corner is background; the head and its hair cover a fifth of the frame.
        let background = *picture.get_pixel(0, 0);
        let drawn = picture.pixels().filter(|p| **p != background).count();
        if drawn * 20 > picture.pixels().len() {
            return Ok(frame + 1);
        }
    }
    Err(format!("no fur after {limit} frames (did the groom load?)").into())
}

fn main() {
    if let Err(e) = run() {
        eprintln!("groom: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<()> {
    let mut frames = 8u32;
    let mut out = PathBuf::from("out/bevy");
    let mut scene_file = default_scene_file();
    let mut args = std::env::args().skip(1);
    while let Some(flag) = args.next() {
        match flag.as_str() {
            "--frames" => frames = args.next().ok_or("--frames needs a value")?.parse()?,
            "--out" => out = PathBuf::from(args.next().ok_or("--out needs a value")?),
            "--scene" => scene_file = PathBuf::from(args.next().ok_or("--scene needs a file")?),
            other => {
                return Err(format!("unknown argument {other} (--frames, --out, --scene)").into());
            }
        }
    }
    let (mut app, image) = app(&scene_file)?;
    let waited = until_drawn(&mut app, &image, 200)?;
    println!("the groom loaded and was drawn after {waited} frames");
    std::fs::create_dir_all(&out)?;
    for frame in 0..frames {
        app.update();
        let picture = read(&mut app, &image)?;
        let path = out.join(format!("groom_{frame:04}.png"));
        picture.save(&path)?;
        println!("t = {:.3} s: wrote {}", time(&app), path.display());
    }
    Ok(())
}
