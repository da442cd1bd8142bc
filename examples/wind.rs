//! Fur in the wind: the smallest complete pelage program.
//!
//! Renders a few frames of the built-in scene (a furred creature in gusting wind)
//! and writes them to `out/wind/frame_0000.png` ... . Run it with
//!
//! ```text
//! cargo run --release --example wind
//! ```
//!
//! The full job, with options, a progress bar, an animated GIF and timings, is
//! `cargo run --release -p pelage-cli -- animate` (`--help` lists its options).

use std::path::Path;

use pelage::{Renderer, gpu::Gpu, scene::Scene};

/// Frames to render, and how many of them make a second of animation.
const FRAMES: u32 = 12;
const FPS: f32 = 24.0;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // A device of our own, with no window: a real GPU if there is one, otherwise a
    // software adapter (lavapipe or llvmpipe).
    let gpu = Gpu::headless()?;
    println!("adapter: {}", gpu.describe());

    // Everything a frame is made of: mesh, hair (roots, growth, wind), shadow method,
    // shading and transparency, camera and lights. `Scene::from_file` reads the same
    // from a TOML file (see scenes/default.toml).
    let scene = Scene::default();

    // The renderer builds every GPU resource once (strand buffers, the shadow grid,
    // the render targets); each frame reuses them.
    let mut renderer = Renderer::new(&gpu, &scene, 480, 360)?;

    let out = Path::new("out/wind");
    for frame in 0..FRAMES {
        // The wind is a function of time alone: any frame can be rendered on its own,
        // in any order, and no time step can make the strands explode.
        let t = frame as f32 / FPS;

        // Turn the camera a little each frame so the wind is seen from several sides.
        let camera = scene.camera.orbited(-0.02 * frame as f32);

        // Grow the strands for time t, shadow them and draw them, all on the GPU.
        // `render` returns without waiting; `finish` waits for the GPU and returns the
        // GPU time of each pass (when the adapter has timestamps).
        renderer.render(&gpu, t, &camera)?;
        let stats = renderer.finish(&gpu)?;

        // Read the image back and save it (written to a temporary file, then renamed).
        let path = out.join(format!("frame_{frame:04}.png"));
        renderer.image(&gpu)?.save(&path)?;
        println!(
            "{}: t = {t:.3} s, {:.1} ms on the GPU",
            path.display(),
            stats.total_ms()
        );
    }
    Ok(())
}
