//! CPU mirrors of pelage's shaders and ground truth to measure them against.
//!
//! Slow and obviously right: each function here follows its WGSL twin loop for
//! loop (the file it mirrors is named in its doc), in plain `f32`, so the GPU
//! can be compared against it within float noise. Nothing here ships in the
//! frame path: only tests, labs and benchmarks depend on this crate.

pub mod flip;
pub mod noise;
pub mod oit;
pub mod shading;
pub mod strands;
pub mod transmittance;
pub mod voxel;
