//! pelage: compute-first GPU hair and fur rendering on wgpu.
//!
//! Three stages chained through GPU storage buffers, never through the CPU, each
//! reading what the one before hands over ([`contract`]: the mesh and strand buffers,
//! the frame's [`contract::StrandFrame`], the per-vertex light visibility, the shadow
//! contract in WGSL):
//!
//! 1. [`strands`]: compute passes grow strands from a mesh (PN triangles, hair
//!    types, gravity and wind for a time `t`), bend a groom file's (`.hair`, `.tfx`,
//!    USD) by the wind, interpolate them from guides, or simulate them;
//! 2. [`shadow`]: one shadow per light (voxel density splatted into a light-space grid
//!    fitted to the hair and summed along the light, deep opacity maps, a hair shadow
//!    map, ADSM) evaluated at every strand vertex, and a shadow map for the mesh;
//! 3. [`shade`]: the hair drawn over the opaque mesh by one of seven compositing
//!    methods (the compute strand rasterizer by default), shaded by one of four fibre
//!    models (Chiang with the volume grid's multiple scattering by default).
//!
//! [`Frame`] owns the stages of one scene, wired once, and records them into the
//! caller's encoder against the caller's colour and depth views (what an engine, the
//! Bevy plugin and the browser demo use); [`Renderer`] is a [`Frame`] with its own
//! targets and readback (what the command line uses). An engine with its own device
//! and buffers may also call the stage types directly ([`strands::GrowStrands`],
//! [`shadow::VoxelShadow`], [`shade::StrandRaster`], ...) on its own encoder.
//!
//! ```no_run
//! let gpu = pelage::gpu::Gpu::headless()?;
//! let scene = pelage::scene::Scene::default();
//! let mut renderer = pelage::Renderer::new(&gpu, &scene, 320, 240)?;
//! renderer.render(&gpu, 0.0, &scene.camera)?; // submits and returns, no wait
//! let stats = renderer.finish(&gpu)?; // waits; the GPU time of each pass
//! let (width, height, rgba) = renderer.rgba8(&gpu)?; // sRGB RGBA8, rows top to bottom
//! assert_eq!(rgba.len(), 4 * width as usize * height as usize);
//! println!("{:.2} ms on the GPU", stats.total_ms());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Features
//!
//! - `backends` (default): wgpu's native backends (Vulkan, GLES, Metal, DX12), for a
//!   program that depends on pelage alone. The stage crates enable none; an engine that
//!   brings its own device turns default features off and keeps its own wgpu features.
//! - `png` (default): `Renderer::image` as an `image::RgbaImage`. Without it the `image` crate is no dependency and [`Renderer::rgba8`] returns the
//!   plain pixels.
//! - `files` (default): scene files (`Scene::from_file`, TOML naming OBJ meshes and PNG
//!   maps). Without it `toml`, `tobj` and `image` are no dependencies of the library: a
//!   scene is built in code ([`scene::Scene`]'s fields, `scene::Mesh`, `scene::MapImage::new`).
//! - `usd` (default): USD grooms (`BasisCurves` in `.usda`, `.usdc`, `.usd`, `.usdz`)
//!   in `scene::Groom::load` and scene files, through the pure-Rust `openusd` crate,
//!   which needs Rust 1.96 (without it pelage builds on 1.87).

pub use pelage_contract as contract;
pub use pelage_gpu as gpu;
pub use pelage_scene as scene;
pub use pelage_shade as shade;
pub use pelage_shadow as shadow;
pub use pelage_strands as strands;

mod bridge;
mod frame;
mod renderer;

pub use frame::{Frame, FrameTarget};
pub use renderer::Renderer;

/// Any error of the frame pipeline.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Buffers handed between stages do not hold what they say (mesh buffers that
    /// do not match the mesh, say).
    #[error("{0}")]
    Contract(#[from] contract::ContractError),
    /// Stage 1 failed.
    #[error("strands: {0}")]
    Strands(#[from] strands::StrandsError),
    /// Stage 2 failed.
    #[error("shadow: {0}")]
    Shadow(#[from] shadow::ShadowError),
    /// Stage 3 failed.
    #[error("shade: {0}")]
    Shade(#[from] shade::ShadeError),
    /// The GPU failed.
    #[error(transparent)]
    Gpu(#[from] gpu::GpuError),
    /// The scene is not usable.
    #[error("scene: {0}")]
    Param(#[from] scene::ParamError),
    /// A change cannot be made to a built [`Frame`] (or [`Renderer`]) in place (it
    /// shapes buffers, passes or pipelines); names the parameter. Build a new one for it.
    #[error("{0} cannot change in place; build a new Frame or Renderer for the scene")]
    NeedsRebuild(String),
    /// The passes of a frame are in an order that reads a resource before it is written.
    #[error("frame plan: {0}")]
    Plan(#[from] gpu::PlanError),
    /// The frame read back was never drawn: every frame starts by clearing to the
    /// opaque background, so pixels that are not opaque mean the adapter dropped the
    /// passes (or no frame was rendered yet). Returned instead of a blank picture.
    #[error(
        "the frame was not drawn: {transparent} of {pixels} pixels are not opaque, but every \
         frame clears to an opaque background, so this adapter ({adapter}) dropped the passes \
         without reporting an error; no image is given"
    )]
    Undrawn {
        /// Pixels whose alpha is below 1.
        transparent: usize,
        /// Pixels in the frame.
        pixels: usize,
        /// The adapter, as [`gpu::Gpu::describe`] names it.
        adapter: String,
    },
}

/// Result of the frame pipeline.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// The README's Rust examples, compiled as doc tests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
mod readme {}

/// The book's library page, compiled as doc tests (the engine example).
#[cfg(doctest)]
#[doc = include_str!("../docs/src/library.md")]
mod book_library {}
