//! pelage's creature with fur in wind, in a Bevy app: a camera, a directional light
//! and an entity with a `Mesh3d` and [`Fur`], rendered headless into an `Image`.
//!
//! ```text
//! cargo run -p bevy_pelage --example fur -- [--frames N] [--out DIR] [--msaa] [--hdr] [--transparency NAME] [--without-plugin]
//! ```
//!
//! `--transparency` names pelage's transparency method (`opaque`, `wboit`, `k_buffer`,
//! `a_buffer`, `dbk`, `random_subsets`, `strand_raster`, the default); every one draws
//! under `--msaa` too. Renders N frames (default 8, 1/12 s apart) of 320 x 240 and writes
//! `DIR/fur_NNNN.png` (default `out/bevy`), then the median time of Bevy's whole frame
//! (`App::update`) after the first two; `--without-plugin` times the same app without
//! `PelagePlugin`. No window: Bevy is built without winit,
//! so the example runs on a machine without a display (lavapipe included).
//! `tests/fur.rs` renders the same scene and compares it with pelage's own frame.

use std::path::PathBuf;

use bevy::camera::Hdr;
use bevy::image::Image;
use bevy::prelude::*;
use bevy::render::view::{Msaa, Tonemapping};
use bevy::time::TimeUpdateStrategy;
use bevy_pelage::PelagePlugin;

#[path = "headless/mod.rs"]
mod headless;
use headless::Result;
pub use headless::{FRAME_STEP, HEIGHT, WIDTH, read, time};

/// The scene, as pelage's own renderer takes it: the creature, 12,000 strands in
/// pelage's default gusting wind, one directional key light, pelage's default camera,
/// single-sampled shading.
pub fn scene() -> pelage::scene::Scene {
    let mut scene = pelage::scene::Scene::default();
    scene.hair.roots.count = 12_000;
    scene.shade.sample_count = 1;
    scene.lights = vec![pelage::scene::Light::Directional(
        pelage::scene::DirectionalLight::default(),
    )];
    scene
}

/// The camera options the Bevy app renders with.
#[derive(Clone, Copy, Debug, Default)]
pub struct View {
    /// 4x MSAA instead of none.
    pub msaa: bool,
    /// An HDR main target (Bevy then tone maps it; pelage's own frame does not).
    pub hdr: bool,
    /// Leave `PelagePlugin` out (the same app without fur: Bevy's own frame time).
    pub without_plugin: bool,
}

/// A Bevy app, headless, that renders `scene()` into an image each `update`: returns
/// the app and the image.
pub fn app(view: View) -> Result<(App, Handle<Image>)> {
    app_of(view, &scene())
}

/// [`app`] of another scene (`scene()` with another transparency method, say).
pub fn app_of(view: View, scene: &pelage::scene::Scene) -> Result<(App, Handle<Image>)> {
    let mut app = App::new();
    app.add_plugins(headless::plugins())
        .insert_resource(TimeUpdateStrategy::ManualDuration(FRAME_STEP));
    if !view.without_plugin {
        app.add_plugins(PelagePlugin);
    }
    let bg = scene.shade.background;
    app.insert_resource(ClearColor(Color::linear_rgb(bg.x, bg.y, bg.z)));

    let world = app.world_mut();
    let image = headless::target(world);
    let mesh = world
        .resource_mut::<Assets<Mesh>>()
        .add(bevy_pelage::bevy_mesh(&scene.mesh));

    let msaa = if view.msaa { Msaa::Sample4 } else { Msaa::Off };
    let mut camera = world.spawn(headless::camera(scene, &image, Transform::default(), msaa));
    if view.hdr {
        camera.insert((Hdr, Tonemapping::Reinhard));
    }

    // pelage's key light as a Bevy directional light.
    world.spawn(headless::key_light(scene, Quat::IDENTITY)?);

    world.spawn((
        Mesh3d(mesh),
        headless::fur(scene, None),
        Transform::default(),
    ));

    headless::finish(&mut app);
    Ok((app, image))
}

fn main() {
    if let Err(e) = run() {
        eprintln!("fur: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<()> {
    let mut frames = 8u32;
    let mut out = PathBuf::from("out/bevy");
    let mut view = View::default();
    let mut scene = scene();
    let mut args = std::env::args().skip(1);
    while let Some(flag) = args.next() {
        match flag.as_str() {
            "--msaa" => view.msaa = true,
            "--hdr" => view.hdr = true,
            "--without-plugin" => view.without_plugin = true,
            "--transparency" => {
                let name = args.next().ok_or("--transparency needs a name")?;
                scene.shade.transparency = pelage::scene::Transparency::by_name(&name)
                    .ok_or_else(|| format!("--transparency: no method {name}"))?;
            }
            "--frames" => frames = args.next().ok_or("--frames needs a value")?.parse()?,
            "--out" => out = PathBuf::from(args.next().ok_or("--out needs a value")?),
            other => {
                return Err(format!(
                    "unknown argument {other} (--frames, --out, --msaa, --hdr, --transparency, --without-plugin)"
                )
                .into());
            }
        }
    }
    let (mut app, image) = app_of(view, &scene)?;
    std::fs::create_dir_all(&out)?;
    let mut update_ms = Vec::new();
    let mut plugin_ms = Vec::new();
    for frame in 0..frames {
        let start = std::time::Instant::now();
        app.update();
        update_ms.push(start.elapsed().as_secs_f64() * 1e3);
        let render = app.sub_app(bevy::render::RenderApp).world();
        if let Some(cpu) = render.get_resource::<bevy_pelage::PelageCpuTime>() {
            plugin_ms.push((cpu.extract + cpu.prepare + cpu.record).as_secs_f64() * 1e3);
        }
        let picture = read(&mut app, &image)?;
        let path = out.join(format!("fur_{frame:04}.png"));
        picture.save(&path)?;
        println!("t = {:.3} s: wrote {}", time(&app), path.display());
    }
    // Bevy's whole frame (`App::update`: main world, extraction, render schedule,
    // submit), the first two frames (pipelines, pelage's set-up) left out.
    let median = |mut ms: Vec<f64>| {
        let mut steady = ms.split_off(ms.len().min(2));
        steady.sort_by(f64::total_cmp);
        steady.get(steady.len() / 2).copied()
    };
    let which = if view.without_plugin {
        "without"
    } else {
        "with"
    };
    if let Some(update) = median(update_ms) {
        println!("App::update: median {update:.2} ms ({which} the plugin)");
    }
    // The plugin's own systems (PelageCpuTime: extracting, preparing and recording).
    if let Some(plugin) = median(plugin_ms) {
        println!("the plugin's systems: median {plugin:.3} ms of CPU per frame");
    }
    Ok(())
}
