//! pelage-gpu: the GPU plumbing every pelage stage shares.
//!
//! - [`Gpu`]: a device and queue, headless or brought by an engine, whose
//!   errors come back as [`GpuError`] instead of panics;
//! - [`ShaderLibrary`]: the WGSL each crate embeds from its `wgsl/` folder
//!   ([`ShaderSources`], [`wgsl_sources!`]), `#import`-composed across crates and
//!   naga-validated; this crate's own [`SHADERS`] are numeric helpers
//!   (`shared/*.wgsl`). It knows no stage: what the stages hand each other is
//!   `pelage-contract`'s;
//! - typed buffers laid out by encase ([`storage_buffer`], [`UniformBuffer`]);
//! - [`GpuTimer`]: per-pass GPU time from timestamp queries;
//! - [`ShaderBinding`]: a WGSL contract implementation plus its resources, handed
//!   from one stage to another;
//! - readback of buffers and textures for tests and tools.

#![warn(missing_docs)]

pub mod audit;
pub mod binding;
pub mod buffers;
pub mod context;
pub mod counters;
pub mod error;
pub mod frame;
pub mod pipelines;
pub mod readback;
pub mod shaders;
pub mod timer;

pub use audit::set_bind_group;
pub use binding::{BoundResource, ShaderBinding};
pub use buffers::{UniformBuffer, storage_buffer, write_storage, zeroed_storage};
pub use context::{Gpu, WANTED_FEATURES, feature_names};
pub use counters::{Created, create_bind_group, create_buffer, create_buffer_init, wait, waits};
pub use error::{GpuError, Result};
pub use frame::{FramePlan, PassInfo, PlanError};
pub use pipelines::{
    BindLayout, bind_buffers, bind_numbered, compute_pipeline, compute_pipeline_with_constants,
    compute_pipeline_with_layouts, dispatch_size, pipeline_layout,
};
pub use readback::{TextureData, f16_to_f32, read_buffer, read_buffer_range, read_texture};
pub use shaders::{
    Redirect, SHADERS, ShaderError, ShaderLibrary, ShaderSources, SourcesCheckError,
};
pub use timer::{GpuTimer, TimerReport};

pub use encase;
pub use wgpu;
