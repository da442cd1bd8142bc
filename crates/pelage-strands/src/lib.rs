//! Stage 1 of pelage: strands on the GPU, grown from a triangle mesh or read from a
//! groom file.
//!
//! Four methods with one shape ([`StrandStage`]), each writing [`StrandBuffers`], which
//! later stages bind directly:
//! - [`GrowStrands`] samples roots over the mesh once (on the CPU, deterministic from a
//!   seed), then every frame a compute pass evaluates the surface under each root (PN
//!   triangles or flat) and grows the strand under gravity and wind for a time `t`;
//! - [`GroomStrands`] takes the strands of a `.hair` or `.tfx` file (resampled to a
//!   fixed segment count) and every frame bends their rest shape by the wind for `t`;
//! - [`SimulateStrands`] simulates either (position-based dynamics with their roots
//!   bound to the mesh, colliders, the wind as a force), stepping from frame to frame;
//! - [`GuideStrands`] takes a groom's strands as guides: every frame it bends them by
//!   the wind, then interpolates render strands rooted on the mesh from the guides
//!   nearest each root (two passes).
//!
//! The mesh lives in [`MeshBuffers`]: tightly packed `f32 x3` positions and
//! normals and a `u32` triangle list in storage buffers, which an engine may own
//! and rewrite every frame (a skinned mesh, say). [`MeshSkin`] skins a mesh into them on
//! the GPU (linear blend skinning, up to four joints per vertex), recorded before the
//! method's pass.
//!
//! Level of detail ([`LodLevel`], from `HairParams::lod`): stochastic simplification
//! grows only a prefix of the (randomly ordered) strands, widened by seed 002's
//! area-preserving scale with a transition zone, and segment reduction keeps every
//! `step`-th vertex where the curvature bound says the picture cannot tell. The
//! [`StrandLayout`] of each frame travels in the [`StrandFrame`] that
//! [`StrandStage::prepare`] returns: every later pass is prepared and recorded with it,
//! and refuses to record a frame it was not prepared for ([`FrameOrderError`]).

mod groom;
mod grow;
mod guides;
mod lod;
mod roots;
mod sdf;
mod sdf_skin;
mod simulate;
mod skin;
mod source;

pub use groom::GroomStrands;
pub use grow::{GrowStrands, StrandPass, StrandStage};
pub use guides::{GUIDE_VERTICES, GuideMemory, GuideStrands};
pub use lod::{LodLevel, bend_error, bend_per_segment, fewest_segments, reduced_segments};
/// What stage 1 writes and later stages read, defined in `pelage-contract` (re-exported
/// here so that stage 1's examples need one import).
pub use pelage_contract::{
    ContractError, FrameOrderError, MESH, MeshBuffers, PreparedFrame, STRAND_ROOTS,
    STRAND_VERTICES, StrandBuffers, StrandFrame, StrandLayout, StrandRoot, StrandStyle,
};
pub use roots::{hash_to_unit, pcg_hash, root_region, root_tint, sample_roots, strand_brightness};
pub use sdf::{
    BODY_SDF, BodySdf, COARSE_FACTOR, MAX_BURIED_CHECK, MAX_SDF_TRIANGLES, SDF_LABEL, SWEEP_AXES,
    body_triangles, burial, coarse_grid,
};
pub use sdf_skin::{SDF_SKIN, SDF_SKIN_LABEL, SKIN_LATTICE_MIN_CELLS, SdfSkin};
pub use simulate::{SIMULATE_LABEL, SIMULATION_STATE, SimulateStrands};
pub use skin::{MeshSkin, SKIN_LABEL, SKIN_NON_FINITE};
pub use source::{StrandSource, scene_reach, sized_for_view};

use pelage_gpu::{GpuError, ShaderSources};
use pelage_scene::{MeshError, ParamError};

/// The shaders of stage 1 (`wgsl/strands/*.wgsl`), importing the contracts' and
/// pelage-gpu's.
pub static SHADERS: ShaderSources = pelage_gpu::wgsl_sources!(
    uses [&pelage_contract::SHADERS];
    "strands/force.wgsl",
    "strands/groom.wgsl",
    "strands/grow.wgsl",
    "strands/guides.wgsl",
    "strands/lod.wgsl",
    "strands/rotation.wgsl",
    "strands/sdf.wgsl",
    "strands/sdf_skin.wgsl",
    "strands/simulate.wgsl",
    "strands/skin.wgsl",
);

/// What can go wrong in stage 1.
#[derive(Debug, thiserror::Error)]
pub enum StrandsError {
    /// A parameter is out of range.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// The mesh is unusable (no triangles, NaN positions, ...).
    #[error("mesh: {0}")]
    Mesh(#[from] MeshError),
    /// The GPU refused something (a buffer too large, a validation error, ...).
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// A pass was recorded for another frame than the one it was prepared for.
    #[error(transparent)]
    FrameOrder(#[from] FrameOrderError),
    /// Roots cannot be placed: every triangle has zero area or zero density.
    #[error("no triangle can carry strands: {0}")]
    NoSurface(String),
    /// A guide's root is too far from the mesh for render strands rooted on the mesh to
    /// be interpolated from it.
    #[error(
        "guide {guide}'s root is {distance} from the mesh, farther than {limit} \
         (guides.max_root_distance times the mesh's diagonal); place the groom on the mesh \
         (groom.fit, groom.scale, groom.translation) or raise guides.max_root_distance"
    )]
    GuideOffMesh {
        /// The guide (the groom file's strand index).
        guide: u32,
        /// Its root's distance from the nearest triangle.
        distance: f32,
        /// The largest distance allowed.
        limit: f32,
    },
    /// The mesh buffers do not hold the mesh the method was built from (or are too
    /// small, or lack `STORAGE` usage).
    #[error(transparent)]
    Contract(#[from] ContractError),
}

/// Result of stage 1.
pub type Result<T, E = StrandsError> = std::result::Result<T, E>;
