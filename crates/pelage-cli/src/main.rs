//! `pelage`: the command line of the pelage hair renderer.
//!
//! `render` and `animate` run the frame pipeline on a scene (a TOML scene file or the
//! built-in creature), `lab` and `bench` chart every method's speed against its
//! accuracy, `trace` path-traces a scene (the ground truth) and `compare` measures an
//! image against it, and `info` says what the adapter can do. Run `pelage --help` or
//! `pelage <command> --help`.

use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

mod animate;
mod auto;
mod bench;
mod compare;
mod error;
mod gpu_bench;
mod hair_timing;
mod info;
mod lab;
mod output;
mod path_trace;
mod progress;
mod render;
mod report;
mod scene_opts;
mod trace;

use error::CliError;

const AFTER_HELP: &str = "\
Examples:
  pelage render --size 640x480 --oit k_buffer -o out/fur.png
  pelage animate --scene scenes/default.toml --frames 24 --shadow dom
  pelage lab shadows --quick --out /tmp/lab
  pelage info

Without a GPU, install Mesa's software Vulkan driver (mesa-vulkan-drivers, lavapipe);
WGPU_BACKEND=gl selects llvmpipe through OpenGL instead.

When XDG_RUNTIME_DIR is unset or not a private folder of yours, pelage sets it to
$TMPDIR/pelage-runtime-<uid> (created with mode 700) for the GPU drivers.
Outputs are written to a temporary (.pelage-<pid>-<n>.tmp) renamed into place;
symbolic links are followed and devices such as /dev/null written through. On
Ctrl-C or SIGTERM the temporaries are removed and pelage exits with 130.";

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
    /// Render one frame of a scene to a PNG or JPEG.
    #[command(
        long_about = "Render one frame of a scene to a PNG or JPEG (by the extension of -o) and print the GPU time of each pass \
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
    /// Path-trace a scene: the ground truth a render is compared with.
    #[command(
        long_about = "Path-trace a scene file with the renderer's meaning of it: the strands \
                      grown on the GPU for --time and read back, traced on the CPU as real \
                      cylinders with Chiang's fibre BSDF (every bounce up to --bounces), the \
                      mesh a diffuse surface of albedo pi x mesh_color, the scene's camera and \
                      lights; shade.background is what camera rays that miss see and \
                      shade.ambient/pi the sky that lights. Writes -o as PNG (sRGB) or HDR \
                      (linear) and the hair mask beside it (FILE.mask.png) for pelage compare. \
                      The scene options are render's; those the path tracer has no use for \
                      (--shadow, --shadow-res, --oit, --dual-scattering, --lod) are refused.",
        after_help = "Examples:\n  \
                      pelage trace --scene scenes/long_hair.toml --size 64x64 --spp 4 -o out/ref.png\n  \
                      pelage trace --scene scenes/blond_chiang.toml --size 240x180 --spp 64 -o out/ref.hdr\n  \
                      pelage render --scene scenes/long_hair.toml --size 64x64 -o out/test.png\n  \
                      pelage compare out/ref.png out/test.png --heat out/flip.png"
    )]
    Trace(trace::TraceOpts),
    /// Compare an image with a reference: FLIP, over the image and the hair.
    #[command(
        long_about = "Compare TEST with the reference REF (PNG, sRGB, or HDR, linear; one \
                      size): mean LDR-FLIP over the image and over the hair, the hair's mean \
                      luminance TEST/REF and its mean linear colour difference TEST - REF per \
                      channel. The hair is the mask (--mask, or REF.mask.png as pelage trace \
                      writes it); without one only the image-wide FLIP is printed.",
        after_help = "Examples:\n  \
                      pelage compare out/ref.png out/test.png\n  \
                      pelage compare out/ref.hdr out/test.png --mask out/ref.mask.png --heat out/flip.png"
    )]
    Compare(compare::CompareOpts),
    /// Run the performance report: stage times, bandwidth, scaling.
    #[command(
        long_about = "The performance report: GPU time of each stage (timestamp queries, median \
                      of 20 frames after 3 of warm-up), its bandwidth against a plain copy \
                      kernel on the same device, scaling with strand count (10k, 50k, 200k), \
                      memory per strand and per pixel, and the cost of shadows plus transparency \
                      over the bare lit strand pass. Writes DIR/bench.csv and \
                      DIR/scaling.png|svg and prints the tables. About 26 minutes on 2 CPU cores \
                      (lavapipe, AMD EPYC, December 2026); \
                      --quick: small scenes, few frames.\n\n\
                      --gpu: the real-GPU bench instead (docs/src/gpu_bench.md): GPU time per \
                      stage of whole frames at 1920x1080 for 10k, 50k and 200k strands of 16 \
                      segments, grown and as a groom, every transparency method, voxel, deep \
                      opacity and shadow-map shadows, and the Frostbite and vkhr anchors; writes \
                      DIR/gpu_bench.csv and DIR/gpu_bench.md. Refuses a CPU adapter unless \
                      --allow-cpu; with --quick, tiny sizes (a smoke run).",
        after_help = "Examples:\n  \
                      pelage bench\n  \
                      pelage bench --quick --out /tmp/bench\n  \
                      pelage bench --gpu --out out/gpu_bench\n  \
                      pelage bench --gpu --quick --allow-cpu --out /tmp/gpu_bench",
        mut_arg("out", |arg| arg.default_value("out/bench"))
    )]
    Bench(bench::BenchOpts),
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
        Command::Trace(opts) => trace::run(opts),
        Command::Compare(opts) => compare::run(opts),
        Command::Bench(opts) => bench::run_command(opts).map_err(CliError::Lab),
        Command::Info => info::run(),
    }
}

/// Exits at once with `code`, without running exit handlers: the GPU driver's teardown
/// would race the frame the main thread is rendering (and crash).
fn exit_now(code: i32) -> ! {
    #[cfg(unix)]
    // SAFETY: `_exit` ends the process; it touches no memory of ours.
    unsafe {
        libc::_exit(code)
    }
    #[cfg(not(unix))]
    std::process::exit(code)
}

/// Whether `dir` is a usable XDG runtime folder: a folder (not a link) of ours that
/// only we can enter (mode 700).
#[cfg(unix)]
fn is_private_dir(dir: &std::path::Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    // SAFETY: getuid has no preconditions and cannot fail.
    let uid = unsafe { libc::getuid() };
    std::fs::symlink_metadata(dir)
        .is_ok_and(|m| m.is_dir() && m.uid() == uid && m.mode() & 0o077 == 0)
}

/// Points XDG_RUNTIME_DIR at a private folder when it is unset or not usable, so
/// Mesa's drivers do not print "XDG_RUNTIME_DIR is invalid or not set" on every run:
/// `$TMPDIR/pelage-runtime-<uid>`, created with mode 700 (or, when that name is taken
/// by something else, one with the process id). Must run before any thread starts.
#[cfg(unix)]
fn ensure_runtime_dir() {
    use std::os::unix::fs::DirBuilderExt;
    if std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| is_private_dir(d.as_ref())) {
        return;
    }
    // SAFETY: getuid has no preconditions and cannot fail.
    let uid = unsafe { libc::getuid() };
    let base = std::env::temp_dir();
    for name in [
        format!("pelage-runtime-{uid}"),
        format!("pelage-runtime-{uid}-{}", std::process::id()),
    ] {
        let dir = base.join(name);
        let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
        if is_private_dir(&dir) {
            // SAFETY: called first thing in main, before any other thread exists.
            unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
            return;
        }
    }
}

/// Lets every option that takes a value take a negative number (`--time -5`): clap
/// otherwise reads `-5` as an unknown flag and names no option. Options whose values
/// are not plain numbers (`--size WxH`, `--range A..B`) allow leading hyphens
/// themselves; either way the value parser's error names the option and its range.
fn allow_negative_numbers(command: clap::Command) -> clap::Command {
    let command = command.mut_args(|arg| {
        if arg.get_action().takes_values() {
            arg.allow_negative_numbers(true)
        } else {
            arg
        }
    });
    let names: Vec<String> = command
        .get_subcommands()
        .map(|c| c.get_name().to_owned())
        .collect();
    names.iter().fold(command, |command, name| {
        command.mut_subcommand(name, allow_negative_numbers)
    })
}

/// The command line's grammar: [`Cli`]'s, every value allowed to be negative.
fn command() -> clap::Command {
    allow_negative_numbers(Cli::command())
}

fn main() -> ExitCode {
    #[cfg(unix)]
    ensure_runtime_dir();
    let cli = Cli::from_arg_matches(&command().get_matches()).unwrap_or_else(|e| e.exit());
    // On SIGINT, SIGTERM or SIGHUP, remove the temporary of any output being written
    // (the target keeps its old content) and exit with 130, as a shell reports Ctrl-C.
    // Without a handler (it could not be installed) a later run sweeps the leftovers.
    let _ = ctrlc::set_handler(|| {
        output::remove_pending_temporaries();
        eprintln!("interrupted: removed unfinished outputs");
        exit_now(130);
    });
    match run(&cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every subcommand that takes options, as the words that reach it
    /// (`["lab", "scattering"]`), with its grammar.
    fn leaves(
        command: &clap::Command,
        path: Vec<String>,
        out: &mut Vec<(Vec<String>, clap::Command)>,
    ) {
        if command.has_subcommands() {
            for sub in command.get_subcommands() {
                let mut path = path.clone();
                path.push(sub.get_name().to_owned());
                leaves(sub, path, out);
            }
        } else {
            out.push((path, command.clone()));
        }
    }

    /// Negative values of the shape an option takes.
    fn negatives(value_name: &str) -> &'static [&'static str] {
        match value_name {
            "WxH" => &["-5x5", "5x-5", "-1x-1"],
            "A..B" => &["-1..2", "1..-2"],
            "EU[,PHEO]" => &["-1", "1,-1"],
            _ => &["-1", "-5", "-0.5", "-1e3"],
        }
    }

    /// `--time -5` and every other negative number on the command line: parsed when the
    /// option takes it, or an error naming the option; never clap's "unexpected
    /// argument '-1' found". Walks every option of every command, so it holds for new
    /// ones.
    #[test]
    fn every_option_names_itself_for_a_negative_number() {
        let mut found = Vec::new();
        leaves(&command(), Vec::new(), &mut found);
        let mut checked = 0;
        for (path, sub) in &found {
            for arg in sub.get_arguments() {
                let Some(long) = arg.get_long() else { continue };
                if !arg.get_action().takes_values() {
                    continue;
                }
                let value_name = arg
                    .get_value_names()
                    .and_then(|v| v.first())
                    .map_or(String::new(), |v| v.to_string());
                for value in negatives(&value_name) {
                    let option = format!("--{long}");
                    let mut argv = vec!["pelage".to_owned()];
                    argv.extend(path.iter().cloned());
                    argv.push(option.clone());
                    argv.push((*value).to_owned());
                    checked += 1;
                    match command().try_get_matches_from(&argv) {
                        Ok(matches) => {
                            // Parsed: the option holds the value (the command checks it).
                            let cli = Cli::from_arg_matches(&matches);
                            assert!(cli.is_ok(), "{argv:?}: {:?}", cli.err());
                        }
                        Err(e) => {
                            let message = e.to_string();
                            assert_ne!(
                                e.kind(),
                                clap::error::ErrorKind::UnknownArgument,
                                "{argv:?}: {message}"
                            );
                            assert!(message.contains(&option), "{argv:?}: {message}");
                        }
                    }
                }
            }
        }
        // render's and animate's scene options, their own, the labs' and bench's.
        assert!(
            checked > 60,
            "only {checked} cases: the walk missed commands"
        );
    }

    /// The negative numbers that are valid are taken, and the others name the allowed
    /// range.
    #[test]
    fn negative_numbers_are_values() {
        let parse = |args: &[&str]| {
            command().try_get_matches_from(std::iter::once("pelage").chain(args.iter().copied()))
        };
        let matches = parse(&["render", "--time", "-5"]).unwrap();
        let Ok(Cli {
            command: Command::Render(opts),
        }) = Cli::from_arg_matches(&matches)
        else {
            panic!("not render");
        };
        assert_eq!(opts.time, -5.0);
        for (args, range) in [
            (&["render", "--strands", "-1"][..], "1.."),
            (&["render", "--shadow-res", "-1"], "1.."),
            (&["render", "--fps", "-1"], "1..=1000000"),
            (&["animate", "--fps", "-1"], "1..=1000000"),
            (&["animate", "--frames", "-1"], "1..=1000000"),
            (&["animate", "--range", "-1..2"], "0 to 1000000"),
            (&["render", "--size", "-5x5"], "from 1 to"),
            (&["lab", "scattering", "--spp", "-5"], "1..=65536"),
            (&["lab", "scattering", "--spp", "4294967295"], "1..=65536"),
        ] {
            let e = parse(args).unwrap_err().to_string();
            assert!(
                e.contains(args[args.len() - 2]) && e.contains(range),
                "{args:?}: {e}"
            );
        }
    }
}
