//! `pelage render`: one frame of a scene to a PNG.

use std::path::PathBuf;
use std::time::Instant;

use pelage::gpu::Gpu;
use pelage::{Renderer, save_png};

use crate::error::CliError;
use crate::scene_opts::SceneOpts;

/// Options of `pelage render`.
#[derive(Clone, Debug, clap::Args)]
pub struct RenderOpts {
    /// The scene and its overrides.
    #[command(flatten)]
    pub scene: SceneOpts,
    /// Time in seconds at which the wind is evaluated (any time can be rendered on its
    /// own: the strands of time T do not depend on earlier frames).
    #[arg(long, value_name = "T", default_value_t = 0.0)]
    pub time: f32,
    /// The PNG to write; its folder is created if missing.
    #[arg(short, long, value_name = "FILE.png", default_value = "out/render.png")]
    pub out: PathBuf,
}

/// Renders one frame, writes it and prints the GPU time of each pass.
pub fn run(opts: &RenderOpts) -> Result<(), CliError> {
    let started = Instant::now();
    let scene = opts.scene.scene()?;
    if !opts.time.is_finite() {
        return Err(CliError::Usage(format!(
            "--time {}: must be a finite number of seconds",
            opts.time
        )));
    }
    let gpu = Gpu::headless()?;
    println!("adapter: {}", gpu.describe());
    let size = opts.scene.size;
    let mut renderer = Renderer::new(&gpu, &scene, size.width, size.height)?;
    renderer.render(&gpu, opts.time, &scene.camera)?;
    let stats = renderer.finish(&gpu)?;
    save_png(&renderer.image(&gpu)?, &opts.out)?;
    println!(
        "wrote {} ({size}, {} strands x {} segments, t = {} s)",
        opts.out.display(),
        renderer.strands().params().roots.count,
        renderer.strands().params().growth.segments,
        opts.time
    );
    if scene.hair.lod.enabled {
        let lod = renderer.lod();
        println!(
            "level of detail: hair box {:.0} px on screen, lambda {:.3}: {} strands x {} segments drawn",
            lod.pixels, lod.zone.lambda, lod.strands, lod.segments
        );
    }
    crate::report::print_pass_times(&stats.passes, "GPU time per pass (one frame):");
    println!("wall time: {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}
