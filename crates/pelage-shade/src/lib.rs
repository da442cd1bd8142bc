//! Stage 3 of pelage: strands drawn as camera-facing ribbons and shaded.
//!
//! Every method ([`HairPass`]: [`Opaque`], [`Wboit`], [`KBuffer`], [`ABuffer`],
//! [`Dbk`], [`RandomSubsets`], [`StrandRaster`]; [`build`] picks one from
//! [`ShadeParams::transparency`]) draws the opaque mesh and then the hair, pulled
//! straight from stage 1's [`StrandBuffers`](pelage_contract::StrandBuffers) in the
//! vertex shader (`wgsl/shade/hair.wgsl`), shaded, and composited its own way. They
//! render into colour and depth views the caller owns ([`Targets`] makes offscreen
//! ones).

mod draw;
mod hair_model;
mod methods;
mod models;
mod ribbons;
mod targets;
mod volume;

pub use draw::{HairInputs, OIT_STORAGE, TARGET_COLOR, TARGET_DEPTH, TargetViews};
pub use hair_model::{HairModel, LUT_RESOLUTION};
pub use methods::supported_methods;
pub use methods::{
    ABuffer, CapturedFragment, Dbk, FragmentCapture, HairPass, KBuffer, OitStats, OitTile, Opaque,
    RandomSubsets, RasterCapture, StrandRaster, StrandRasterUniforms, Wboit, build,
};
pub use models::{
    ChiangTables, ChiangUniforms, KajiyaKayUniforms, MarschnerLut, MarschnerLutInfo,
    MarschnerUniforms, SadeghiUniforms,
};
/// The per-vertex light visibility every method reads (the contract's; its frame
/// resource name is `pelage_contract::VISIBILITY`).
pub use pelage_contract::Visibility;
pub use pelage_scene::ShadeParams;
pub use ribbons::{FrameLight, FrameUniforms, MeshStyle, RibbonStyle};
pub use targets::{
    COLOR_FORMAT, DEPTH_FORMAT, TargetFormat, TargetViewSet, Targets, check_image_size,
};
pub use volume::{VOLUME_FIXED_SCALE, VOLUME_FLUENCE, VolumeField, VolumeGrid, VolumeUniforms};

/// The shaders of stage 3 (`wgsl/shade/*.wgsl`), importing the contracts' (the strand
/// record, the ribbon and the shadow contract `shadow/none.wgsl`) and pelage-gpu's. A
/// shadow method's lookup comes in through its
/// [`ShaderBinding`](pelage_gpu::ShaderBinding), with its own crate's sources.
pub static SHADERS: pelage_gpu::ShaderSources = pelage_gpu::wgsl_sources!(
    uses [&pelage_contract::SHADERS];
    "shade/body_sky.wgsl",
    "shade/body_sky_volume.wgsl",
    "shade/frame.wgsl",
    "shade/hair.wgsl",
    "shade/hair_model.wgsl",
    "shade/mesh.wgsl",
    "shade/models/chiang.wgsl",
    "shade/models/chiang_common_model.wgsl",
    "shade/models/chiang_dual_model.wgsl",
    "shade/models/chiang_dual_volume_model.wgsl",
    "shade/models/chiang_eval.wgsl",
    "shade/models/chiang_model.wgsl",
    "shade/models/chiang_tables.wgsl",
    "shade/models/chiang_volume_common_model.wgsl",
    "shade/models/chiang_volume_model.wgsl",
    "shade/models/eval.wgsl",
    "shade/models/fibre.wgsl",
    "shade/models/kajiya_kay.wgsl",
    "shade/models/marschner.wgsl",
    "shade/models/marschner_lut.wgsl",
    "shade/models/marschner_lut_lookup.wgsl",
    "shade/models/marschner_lut_model.wgsl",
    "shade/models/marschner_model.wgsl",
    "shade/models/sadeghi.wgsl",
    "shade/models/sadeghi_model.wgsl",
    "shade/models/volume_common.wgsl",
    "shade/models/volume_field.wgsl",
    "shade/oit/a_buffer.wgsl",
    "shade/oit/bindings.wgsl",
    "shade/oit/common.wgsl",
    "shade/oit/dbk.wgsl",
    "shade/oit/k_buffer.wgsl",
    "shade/oit/ppll.wgsl",
    "shade/oit/random_subsets.wgsl",
    "shade/oit/slots.wgsl",
    "shade/oit/strand_raster.wgsl",
    "shade/oit/tail.wgsl",
    "shade/oit/wboit.wgsl",
    "shade/ribbons.wgsl",
    "shade/volume.wgsl",
);

/// What can go wrong in stage 3.
#[derive(Debug, thiserror::Error)]
pub enum ShadeError {
    /// A parameter is out of range.
    #[error(transparent)]
    Param(#[from] pelage_scene::ParamError),
    /// The GPU refused something.
    #[error(transparent)]
    Gpu(#[from] pelage_gpu::GpuError),
    /// A pass was recorded for another stage 1 frame than it was prepared for.
    #[error(transparent)]
    FrameOrder(#[from] pelage_contract::FrameOrderError),
    /// A parameter cannot change in place: it shapes pipelines or buffers; build the
    /// method (or the renderer) again with it.
    #[error("{0} cannot change in place; build again with the new parameters")]
    NeedsRebuild(String),
    /// The adapter lacks a feature the method needs.
    #[error("{0}")]
    Unsupported(String),
    /// The targets passed to `encode` differ in size from those the method was built for.
    #[error(
        "the method was built for {}x{} targets but was given {}x{}; build it again for the new size",
        .built.0, .built.1, .given.0, .given.1
    )]
    TargetSize {
        /// Size the method's buffers were made for.
        built: (u32, u32),
        /// Size of the targets given.
        given: (u32, u32),
    },
}

/// Result of stage 3.
pub type Result<T, E = ShadeError> = std::result::Result<T, E>;
