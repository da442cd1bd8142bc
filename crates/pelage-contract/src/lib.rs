//! What pelage's stages hand each other, in one place, each with its WGSL beside its Rust.
//!
//! The stage crates (`pelage-strands`, `pelage-shadow`, `pelage-shade`) depend on this
//! crate and on `pelage-gpu`, never on each other:
//!
//! - [`MeshBuffers`] ([`MESH`]): the triangle mesh in storage buffers, which stage 1
//!   grows from, stage 2 shadows and stage 3 draws; an engine may own and rewrite them.
//! - [`StrandBuffers`] ([`STRAND_VERTICES`], [`STRAND_ROOTS`]): the strands stage 1
//!   writes, one [`StrandRoot`] per strand (`StrandRoot` in `wgsl/shared/strand.wgsl`)
//!   and `segments + 1` vertices; [`StrandStyle`] says how wide and opaque they are.
//! - [`StrandFrame`]: which part of the strand buffer holds this frame's strands
//!   ([`StrandLayout`]), with an id: every pass after stage 1 is prepared and recorded
//!   with it and refuses another ([`FrameOrderError`], [`PreparedFrame`]).
//! - [`Visibility`] ([`VISIBILITY`]): each light's visibility at every strand vertex,
//!   which stage 2 writes and the shading stage reads.
//! - The shadow contract, `wgsl/shadow/none.wgsl`: `light_visibility(p)` at a fibre and
//!   `surface_visibility(p)` on the body, which every shading pass imports and every
//!   shadow method implements in its own file (the shading pass redirects the import,
//!   [`pelage_gpu::ShaderBinding`]).
//! - `wgsl/shared/ribbon.wgsl`: which strand vertex, and which side of it, each vertex
//!   of a ribbon draw stands for (the camera's passes and the light's).
//!
//! The resource names are those of the frame plan ([`pelage_gpu::FramePlan`]).

mod frame;
mod mesh;
mod strands;
mod visibility;

pub use frame::{FrameOrderError, PreparedFrame, StrandFrame, StrandLayout};
pub use mesh::{MESH, MeshBuffers};
pub use strands::{STRAND_ROOTS, STRAND_VERTICES, StrandBuffers, StrandRoot, StrandStyle};
pub use visibility::{VISIBILITY, Visibility};

use pelage_gpu::{GpuError, ShaderSources};
use pelage_scene::{MeshError, ParamError};

/// The contracts' WGSL (`wgsl/shared/strand.wgsl`, `wgsl/shared/ribbon.wgsl`, the shadow
/// contract `wgsl/shadow/none.wgsl`), importing pelage-gpu's helpers. Every stage's
/// sources use these.
pub static SHADERS: ShaderSources = pelage_gpu::wgsl_sources!(
    uses [&pelage_gpu::SHADERS];
    "shadow/none.wgsl",
    "shared/ribbon.wgsl",
    "shared/strand.wgsl",
);

/// The name of the shadow contract's file, which a shadow method's lookup redirects.
pub const SHADOW_CONTRACT: &str = "shadow/none.wgsl";

/// Buffers that do not hold what their description says.
#[derive(Debug, thiserror::Error)]
pub enum ContractError {
    /// A parameter is out of range (a box that is not finite, say).
    #[error(transparent)]
    Param(#[from] ParamError),
    /// The mesh is unusable (no triangles, NaN positions, ...).
    #[error("mesh: {0}")]
    Mesh(#[from] MeshError),
    /// The GPU refused something (a buffer larger than the device allows, ...).
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// Mesh buffers that do not match the mesh they are said to hold, or too small or
    /// without `STORAGE` usage.
    #[error(
        "mesh buffers hold {buffers} but the mesh has {mesh}; pass buffers made from the same mesh"
    )]
    MeshMismatch {
        /// What the buffers hold.
        buffers: String,
        /// What the mesh has (or what the buffers need).
        mesh: String,
    },
}

/// Result of building a contract's buffers.
pub type Result<T, E = ContractError> = std::result::Result<T, E>;
