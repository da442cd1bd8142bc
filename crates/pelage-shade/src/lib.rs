//! Stage 3 of pelage: strands drawn as camera-facing ribbons and shaded.
//!
//! [`RibbonPass`] draws the opaque mesh and then the hair, pulled straight from
//! stage 1's [`StrandBuffers`](pelage_strands::StrandBuffers) in the vertex
//! shader, Kajiya-Kay shaded, depth tested. It renders into colour and depth
//! views the caller owns ([`Targets`] makes offscreen ones).
//!
//! Transparency and the other shading models have their own methods (to come);
//! this pass is the opaque baseline.

mod ribbons;
mod targets;

pub use pelage_scene::ShadeParams;
pub use ribbons::{FrameUniforms, MeshStyle, RibbonPass, RibbonStyle};
pub use targets::{COLOR_FORMAT, DEPTH_FORMAT, Targets};

/// What can go wrong in stage 3.
#[derive(Debug, thiserror::Error)]
pub enum ShadeError {
    /// A parameter is out of range.
    #[error(transparent)]
    Param(#[from] pelage_scene::ParamError),
    /// The GPU refused something.
    #[error(transparent)]
    Gpu(#[from] pelage_gpu::GpuError),
}

/// Result of stage 3.
pub type Result<T, E = ShadeError> = std::result::Result<T, E>;
