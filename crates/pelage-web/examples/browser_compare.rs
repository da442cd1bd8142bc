//! The native side of the browser test (`.ci/browser-test`): renders the page's scene
//! ([`pelage_web::scene`], the same function the page calls) natively at the size of
//! the browser's screenshot, for the same time, strand count, wind and method, writes
//! it, and compares the two by mean LDR-FLIP, over the whole frame and over the pixels
//! where either frame shows the creature (differs from the background). Exits 1 when
//! the frame's mean exceeds `--max` or the creature's exceeds `--creature-max` (by
//! default `--max`).
//!
//! ```text
//! browser_compare SCREENSHOT.png NATIVE_OUT.png [--t 0.5] [--strands N] [--wind 1]
//!                 [--method strand_raster] [--groom FILE] [--max 0.02] [--creature-max X]
//! ```
//!
//! `--groom FILE` draws the groom file as the page draws one it was given
//! ([`pelage_web::groom_scene`]; the strand count is the file's).

use std::process::ExitCode;

use pelage::Renderer;
use pelage::gpu::Gpu;
use pelage_reference::flip::{DEFAULT_PIXELS_PER_DEGREE, LinearImage, flip};
use pelage_web::Settings;

/// The options; see the module documentation.
struct Options {
    screenshot: std::path::PathBuf,
    native: std::path::PathBuf,
    t: f32,
    settings: Settings,
    groom: Option<std::path::PathBuf>,
    max: f64,
    creature_max: f64,
}

fn parse() -> Result<Options, String> {
    let mut positional = Vec::new();
    let mut t = 0.5;
    let mut settings = Settings::default();
    let mut max = 0.02;
    let mut creature_max = None;
    let mut groom = None;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        let mut value = |name: &str| args.next().ok_or(format!("{name} needs a value"));
        let number = |name: &str, text: String| {
            text.parse::<f64>()
                .map_err(|e| format!("{name} {text}: {e}"))
        };
        match arg.as_str() {
            "--t" => t = number("--t", value("--t")?)? as f32,
            "--strands" => {
                let text = value("--strands")?;
                settings.strands = text.parse().map_err(|e| format!("--strands {text}: {e}"))?;
            }
            "--wind" => settings.wind = number("--wind", value("--wind")?)? as f32,
            "--method" => settings.method = value("--method")?,
            "--groom" => groom = Some(std::path::PathBuf::from(value("--groom")?)),
            "--max" => max = number("--max", value("--max")?)?,
            "--creature-max" => {
                creature_max = Some(number("--creature-max", value("--creature-max")?)?);
            }
            other if other.starts_with("--") => return Err(format!("unknown option {other}")),
            _ => positional.push(std::path::PathBuf::from(arg)),
        }
    }
    let [screenshot, native] = <[_; 2]>::try_from(positional)
        .map_err(|_| "usage: browser_compare SCREENSHOT.png NATIVE_OUT.png [options]")?;
    Ok(Options {
        screenshot,
        native,
        t,
        settings,
        groom,
        max,
        creature_max: creature_max.unwrap_or(max),
    })
}

fn run(options: &Options) -> Result<bool, Box<dyn std::error::Error>> {
    let shot = image::open(&options.screenshot)
        .map_err(|e| format!("{}: {e}", options.screenshot.display()))?
        .to_rgba8();
    let (width, height) = shot.dimensions();
    let mut settings = options.settings.clone();
    let scene = match &options.groom {
        Some(path) => {
            let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
            let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
            let groom = pelage_web::read_groom(bytes, &name.unwrap_or_default())?;
            settings.strands = groom.strands;
            pelage_web::groom_scene(&groom, &settings)?
        }
        None => pelage_web::scene(&settings)?,
    };
    let gpu = Gpu::headless()?;
    let mut renderer = Renderer::new(&gpu, &scene, width, height)?;
    renderer.render(&gpu, options.t, &scene.camera)?;
    renderer.finish(&gpu)?;
    let native = renderer.image(&gpu)?;
    native.save(&options.native)?;

    let reference = LinearImage::from_srgb8_rgba(width, height, native.as_raw())?;
    let test = LinearImage::from_srgb8_rgba(width, height, shot.as_raw())?;
    let map = flip(&reference, &test, DEFAULT_PIXELS_PER_DEGREE)?;
    // The background is the colour of the top-left pixel in both frames.
    let background = |img: &image::RgbaImage, p: &image::Rgba<u8>| {
        let corner = img.get_pixel(0, 0);
        p.0.iter()
            .zip(corner.0)
            .take(3)
            .all(|(a, b)| a.abs_diff(b) <= 2)
    };
    let (mut sum, mut count) = (0.0f64, 0usize);
    for ((a, b), value) in native.pixels().zip(shot.pixels()).zip(&map.values) {
        if !background(&native, a) || !background(&shot, b) {
            sum += f64::from(*value);
            count += 1;
        }
    }
    let creature = if count > 0 { sum / count as f64 } else { 0.0 };
    println!(
        "native: {} ({}, {width}x{height}, t = {}, {} strands, wind x{}, {})",
        options.native.display(),
        gpu.describe(),
        options.t,
        settings.strands,
        settings.wind,
        settings.method
    );
    println!(
        "mean FLIP browser vs native: {:.4} over the frame, {creature:.4} over the {count} \
         pixels of the creature (bounds {} and {})",
        map.mean(),
        options.max,
        options.creature_max
    );
    // A frame without the creature would compare well over the frame: demand it.
    let enough = count * 20 >= (width * height) as usize;
    if !enough {
        println!("only {count} pixels differ from the background: the creature is missing");
    }
    Ok(enough && map.mean() <= options.max && creature <= options.creature_max)
}

fn main() -> ExitCode {
    let options = match parse() {
        Ok(options) => options,
        Err(e) => {
            eprintln!("browser_compare: {e}");
            return ExitCode::from(2);
        }
    };
    match run(&options) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("browser_compare: {e}");
            ExitCode::from(2)
        }
    }
}
