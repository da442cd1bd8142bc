//! `pelage`: the command line of the pelage hair renderer.
//!
//! `render` and `animate` run the frame pipeline on a scene (a TOML scene file or the
//! built-in creature), `lab` and `bench` chart every method's speed against its
//! accuracy, and `info` says what the adapter can do. Run `pelage --help` or
//! `pelage <command> --help`.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod animate;
mod auto;
mod bench;
mod error;
mod info;
mod lab;
mod progress;
mod render;
mod report;
mod scene_opts;

use error::CliError;

const AFTER_HELP: &str = "\
Examples:
  pelage render --size 640x480 --oit k_buffer -o out/fur.png
  pelage animate --scene scenes/default.toml --frames 24 --shadow dom
  pelage lab shadows --quick --out /tmp/lab
  pelage info

Without a GPU, install Mesa's software Vulkan driver (mesa-vulkan-drivers, lavapipe);
WGPU_BACKEND=gl selects llvmpipe through OpenGL instead.";

/// Compute-first GPU hair and fur rendering on wgpu.
#[derive(Debug, Parser)]
#[command(
    name = "pelage",
    version,
    long_about = "Compute-first GPU hair and fur rendering on wgpu. Every frame grows strands \
                  from a mesh in a compute pass (gravity and wind for a time t), shadows them \
                  (voxel, deep opacity maps, shadow map, ADSM) and draws them as ribbons with a \
                  hair shading model and order-independent transparency, headless.",
    after_help = AFTER_HELP
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Render one frame of a scene to a PNG.
    #[command(
        long_about = "Render one frame of a scene to a PNG and print the GPU time of each pass \
                      (timestamp queries). The scene is the built-in furred creature unless \
                      --scene names a TOML scene file; the other options override the file.",
        after_help = "Examples:\n  \
                      pelage render\n  \
                      pelage render --size 96x72 --strands 500 -o /tmp/tiny.png\n  \
                      pelage render --scene scenes/default.toml --time 1.5 --model marschner\n  \
                      pelage render --shadow dom --shadow-res 512 --oit wboit --lights key_back\n  \
                      pelage render --lod --size 160x120"
    )]
    Render(render::RenderOpts),
    /// Render a scene in wind to a PNG sequence and an animated GIF.
    #[command(
        long_about = "Render a scene in gusting wind, frame i at i/FPS seconds with the camera \
                      orbiting slowly, to DIR/frame_0000.png ... and the animated preview \
                      DIR/wind.gif. Prints the GPU time per pass (median over the frames) and, \
                      as a cross-check that does not rely on the driver's timestamps, the wall \
                      clock of each stage submitted alone. The default job (48 frames of \
                      480x360, 20000 strands, voxel shadows) takes about 15 s in a release \
                      build on 2 CPU cores with lavapipe.",
        after_help = "Examples:\n  \
                      pelage animate\n  \
                      pelage animate --frames 96 --fps 30 --size 640x480 --out out/long\n  \
                      pelage animate --scene scenes/default.toml --oit k_buffer --model sadeghi\n  \
                      pelage animate --frames 2 --size 96x72 --strands 500 --out /tmp/smoke"
    )]
    Animate(animate::AnimateOpts),
    /// Run a lab: every method of a stage against ground truth, charted.
    #[command(
        subcommand,
        long_about = "Run a lab: every method of one stage, at several settings, timed on the GPU \
                      and measured against ground truth computed on the CPU (ray-traced \
                      transmittance, the exact sorted composite, the full-detail image). Each writes a CSV, charts of \
                      error against time with the Pareto front marked, and prints a table.",
        after_help = "Examples:\n  \
                      pelage lab shadows\n  \
                      pelage lab oit --quick --out /tmp/lab\n  \
                      pelage lab shading --quick\n  \
                      pelage lab lod"
    )]
    Lab(lab::Lab),
    /// Run the performance report: stage times, bandwidth, scaling.
    #[command(
        long_about = "The performance report: GPU time of each stage (timestamp queries, median \
                      of 20 frames after 3 of warm-up), its bandwidth against a plain copy \
                      kernel on the same device, scaling with strand count (10k, 50k, 200k), \
                      memory per strand and per pixel, and the cost of shadows plus transparency \
                      over the bare lit strand pass. Writes DIR/bench.csv and \
                      DIR/scaling.png|svg and prints the tables. About 4 minutes on 2 CPU cores; \
                      --quick: small scenes, few frames.",
        after_help = "Examples:\n  \
                      pelage bench\n  \
                      pelage bench --quick --out /tmp/bench",
        mut_arg("out", |arg| arg.default_value("out/bench"))
    )]
    Bench(lab::LabOpts),
    /// Show the adapter, the features pelage uses and the limits that bound a scene.
    #[command(
        long_about = "Show the adapter pelage would render on (name, backend, driver, device \
                      type), which of the optional features it uses are present (timestamps, \
                      64-bit atomics for the k-buffer and random subsets, float32 blending), \
                      and the limits that bound a scene: storage binding and buffer sizes, \
                      texture size, workgroups, with what they mean (most strands in one \
                      buffer, largest k-buffer at 1080p without slicing, ...).",
        after_help = "Examples:\n  \
                      pelage info\n  \
                      WGPU_BACKEND=gl pelage info"
    )]
    Info,
}

fn run(command: &Command) -> Result<(), CliError> {
    match command {
        Command::Render(opts) => render::run(opts),
        Command::Animate(opts) => animate::run(opts),
        Command::Lab(lab) => lab.run().map_err(CliError::Lab),
        Command::Bench(opts) => bench::run(opts).map_err(CliError::Lab),
        Command::Info => info::run(),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(&cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
