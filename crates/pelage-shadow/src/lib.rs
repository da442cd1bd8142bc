//! Stage 2 of pelage: how much light reaches each point of the hair.
//!
//! [`VoxelShadow`] (seed 001, corrected): every frame a compute reduction fits a
//! light-space grid to the hair, every segment splats its optical depth into
//! `atomic<u32>` fixed-point cells, and an exclusive prefix sum along the light
//! turns density into the optical depth in front of each voxel. The mesh casts
//! its own shadow through a [`MeshShadowMap`] with PCF.
//!
//! Every method hands the shading stage a [`ShaderBinding`](pelage_gpu::ShaderBinding)
//! implementing the shadow contract (`wgsl/shadow/none.wgsl`: `light_visibility(p)`),
//! so the shading pass never knows which method it got.

mod light_space;
mod mesh_shadow;
mod voxel;

pub use light_space::LightSpace;
pub use mesh_shadow::{MeshShadowMap, MeshShadowUniforms};
pub use voxel::{VoxelGrid, VoxelShadow, VoxelUniforms};

/// What can go wrong in stage 2.
#[derive(Debug, thiserror::Error)]
pub enum ShadowError {
    /// A parameter is out of range.
    #[error(transparent)]
    Param(#[from] pelage_scene::ParamError),
    /// The GPU refused something.
    #[error(transparent)]
    Gpu(#[from] pelage_gpu::GpuError),
}

/// Result of stage 2.
pub type Result<T, E = ShadowError> = std::result::Result<T, E>;
