//! The main job: the built-in creature, furred, in gusting wind, rendered headless.
//!
//! Writes a PNG per frame and an animated GIF preview under `out/wind/`, shows a
//! progress bar, and ends with a summary of what it wrote and the GPU time per stage.
//!
//! ```text
//! cargo run --release --example wind -- [--frames N] [--size WxH] [--strands N] [--fps N]
//!     [--out DIR] [--shadow none|voxel|dom|map|adsm] [--shadow-res N]
//!     [--oit opaque|wboit|k_buffer|a_buffer|dbk|random_subsets]
//!     [--model kajiya_kay|marschner|marschner_lut|sadeghi] [--lights key|key_back]
//!     [--scene FILE]
//! ```

use std::path::PathBuf;
use std::time::Instant;

use pelage::scene::{Light, ShadingModel, ShadowParams, Transparency};
use pelage::{Renderer, Scene, gpu::Gpu, save_png, write_atomically};

struct Args {
    frames: u32,
    width: u32,
    height: u32,
    strands: Option<u32>,
    fps: u32,
    out: PathBuf,
    scene: Option<PathBuf>,
    // Scene settings given on the command line (they override the scene file's).
    shadow: Option<ShadowParams>,
    transparency: Option<Transparency>,
    key_and_back: Option<bool>,
    model: Option<ShadingModel>,
}

fn parse_args() -> Result<Args, String> {
    let mut args = Args {
        frames: 48,
        width: 480,
        height: 360,
        strands: None,
        fps: 24,
        out: PathBuf::from("out/wind"),
        scene: None,
        shadow: None,
        transparency: None,
        key_and_back: None,
        model: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or(format!("{flag} needs a value"));
        let number = |v: String| v.parse::<u32>().map_err(|e| format!("{flag} {v}: {e}"));
        match flag.as_str() {
            "--frames" => args.frames = number(value()?)?,
            "--strands" => args.strands = Some(number(value()?)?),
            "--fps" => args.fps = number(value()?)?.max(1),
            "--out" => args.out = PathBuf::from(value()?),
            "--shadow" => {
                args.shadow = Some(match value()?.as_str() {
                    "none" => ShadowParams::None,
                    "voxel" => ShadowParams::Voxel(Default::default()),
                    "dom" => ShadowParams::DeepOpacity(Default::default()),
                    "map" => ShadowParams::ShadowMap(Default::default()),
                    "adsm" => ShadowParams::Adsm(Default::default()),
                    other => {
                        return Err(format!(
                            "--shadow {other}: expected none, voxel, dom, map or adsm"
                        ));
                    }
                })
            }
            "--scene" => args.scene = Some(PathBuf::from(value()?)),
            "--lights" => {
                args.key_and_back = Some(match value()?.as_str() {
                    "key" => false,
                    "key_back" => true,
                    other => return Err(format!("--lights {other}: expected key or key_back")),
                })
            }
            "--model" => {
                args.model = Some(match value()?.as_str() {
                    "kajiya_kay" => ShadingModel::default(),
                    "marschner" => ShadingModel::Marschner {
                        params: Default::default(),
                        lut: false,
                    },
                    "marschner_lut" => ShadingModel::Marschner {
                        params: Default::default(),
                        lut: true,
                    },
                    "sadeghi" => ShadingModel::Sadeghi(Default::default()),
                    other => {
                        return Err(format!(
                            "--model {other}: expected kajiya_kay, marschner, marschner_lut or sadeghi"
                        ));
                    }
                })
            }
            "--oit" => {
                args.transparency = Some(match value()?.as_str() {
                    "opaque" => Transparency::Opaque,
                    "wboit" => Transparency::wboit(),
                    "k_buffer" => Transparency::k_buffer(8),
                    "a_buffer" => Transparency::a_buffer(),
                    "dbk" => Transparency::dbk(0.05),
                    "random_subsets" => Transparency::random_subsets(8),
                    other => {
                        return Err(format!(
                            "--oit {other}: expected opaque, wboit, k_buffer, a_buffer, dbk or random_subsets"
                        ));
                    }
                })
            }
            "--shadow-res" => {
                let n = number(value()?)?;
                match args.shadow.get_or_insert_with(ShadowParams::default) {
                    ShadowParams::Voxel(v) => v.resolution = [n; 3],
                    ShadowParams::DeepOpacity(d) => d.map.size = n,
                    ShadowParams::ShadowMap(m) => m.map.size = n,
                    ShadowParams::Adsm(a) => a.map.size = n,
                    ShadowParams::None => {
                        return Err("--shadow-res needs a --shadow method before it".into());
                    }
                }
            }
            "--size" => {
                let v = value()?;
                let (w, h) = v
                    .split_once('x')
                    .ok_or(format!("--size {v}: expected WxH, e.g. 480x360"))?;
                args.width = number(w.to_string())?;
                args.height = number(h.to_string())?;
            }
            "-h" | "--help" => {
                println!(
                    "wind: render the built-in creature in gusting wind.\n\n\
                     --scene FILE   a scene file (TOML; scenes/default.toml lists every key);\n\
                     \x20              the options below override it\n\
                     --frames N     frames to render (48)\n\
                     --size WxH     image size (480x360)\n\
                     --strands N    strand count (the scene's default, 20000)\n\
                     --fps N        frames per second of the animation (24)\n\
                     --out DIR      output folder (out/wind)\n\
                     --shadow M     shadow method: none, voxel, dom (deep opacity maps),\n\
                     \x20              map (shadow map with PCF) or adsm; default voxel\n\
                     --shadow-res N voxels per axis, or map side in texels (128 / 1024)\n\
                     --oit M        transparency: opaque (4x MSAA, the default), wboit,\n\
                     \x20              k_buffer (k = 8), a_buffer, dbk or random_subsets (k = 8)\n\
                     --model M      shading: kajiya_kay (default), marschner, marschner_lut\n\
                     \x20              (from lookup tables) or sadeghi\n\
                     --lights L     key (one directional light, default) or key_back (a key\n\
                     \x20              light and a warm back light, each with its own shadow)"
                );
                std::process::exit(0);
            }
            other => return Err(format!("unknown argument {other}; try --help")),
        }
    }
    if args.frames == 0 {
        return Err("--frames must be at least 1".into());
    }
    Ok(args)
}

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args = parse_args()?;
    let started = Instant::now();
    let gpu = Gpu::headless()?;
    println!("adapter: {}", gpu.describe());

    let mut scene = match &args.scene {
        Some(path) => Scene::from_file(path)?,
        None => Scene::default(),
    };
    if let Some(shadow) = &args.shadow {
        scene.shadow = shadow.clone();
    }
    if let Some(transparency) = &args.transparency {
        scene.shade.transparency = transparency.clone();
    }
    if let Some(model) = &args.model {
        scene.shade.model = model.clone();
    }
    if args.key_and_back == Some(true) {
        scene.lights = Light::key_and_back(&scene.camera);
    }
    if let Some(n) = args.strands {
        scene.hair.roots.count = n;
    }
    let mut renderer = Renderer::new(&gpu, &scene, args.width, args.height)?;

    let bar = indicatif::ProgressBar::new(u64::from(args.frames)).with_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} frames, {elapsed} elapsed, eta {eta}",
        )?,
    );
    let mut frames = Vec::with_capacity(args.frames as usize);
    let mut per_pass: Vec<(String, Vec<f64>)> = Vec::new();
    for f in 0..args.frames {
        let t = f as f32 / args.fps as f32;
        // A slow quarter orbit over the animation, so the wind is seen from several sides.
        let camera = scene
            .camera
            .orbited(-0.5 * t / (args.frames as f32 / args.fps as f32));
        let stats = renderer.render(&gpu, t, &camera)?;
        for (label, ms) in stats.passes {
            match per_pass.iter_mut().find(|(l, _)| *l == label) {
                Some((_, v)) => v.push(ms),
                None => per_pass.push((label, vec![ms])),
            }
        }
        let image = renderer.image(&gpu)?;
        save_png(&image, &args.out.join(format!("frame_{f:04}.png")))?;
        frames.push(image);
        bar.inc(1);
    }
    bar.finish_and_clear();

    // Animated preview: every frame, at the animation's frame rate.
    let gif_path = args.out.join("wind.gif");
    let delay = image::Delay::from_numer_denom_ms(1000, args.fps);
    write_atomically(&gif_path, |w| {
        let mut encoder = image::codecs::gif::GifEncoder::new_with_speed(w, 20);
        encoder
            .set_repeat(image::codecs::gif::Repeat::Infinite)
            .map_err(|e| e.to_string())?;
        for img in frames {
            encoder
                .encode_frame(image::Frame::from_parts(img, 0, 0, delay))
                .map_err(|e| e.to_string())?;
        }
        Ok(())
    })?;

    println!(
        "wrote {} frames of {}x{} ({} strands x {} segments) to {}/frame_*.png and {}",
        args.frames,
        args.width,
        args.height,
        scene.hair.roots.count,
        scene.hair.growth.segments,
        args.out.display(),
        gif_path.display()
    );
    if per_pass.is_empty() {
        println!("GPU time per stage: n/a (the adapter has no timestamp queries)");
    } else {
        println!("GPU time per stage (median over {} frames):", args.frames);
        let mut total = 0.0;
        for (label, mut v) in per_pass {
            v.sort_by(f64::total_cmp);
            let median = v[v.len() / 2];
            total += median;
            println!("  {label:<16} {median:8.3} ms");
        }
        println!("  {:<16} {total:8.3} ms", "frame");
    }
    // Cross-check that does not rely on the driver's timestamps: each stage alone, wall clock.
    let last = args.frames.saturating_sub(1) as f32 / args.fps as f32;
    println!("wall clock per stage, submitted alone (median of 5):");
    for (stage, ms) in renderer.stage_wall_times(&gpu, last, &scene.camera, 5)? {
        println!("  {stage:<16} {ms:8.3} ms");
    }
    println!("wall time: {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}
