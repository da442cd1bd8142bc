//! CPU mirrors of pelage's shaders and ground truth to measure them against.
//!
//! Slow and obviously right: each function here follows its WGSL twin loop for
//! loop (the file it mirrors is named in its doc), in plain `f32`, so the GPU
//! can be compared against it within float noise. Nothing here ships in the
//! frame path: only tests, labs and benchmarks depend on this crate.
//!
//! Two modules are ground truth rather than twins, in `f64`: [`chiang`], the hair fibre
//! BSDF of Chiang et al. 2016 as pbrt-v3 defines it (with its far-field, h-averaged form
//! for the GPU model to match), and [`path_tracer`], a multi-threaded path tracer of the
//! strands as real cylinders with that BSDF (multiple scattering, shadows, a Lambertian
//! mesh).
//!
//! [`oit_raster`] rasterises strands as ribbons on the CPU, so the exact composite of
//! [`oit`] can be fed fragments that do not come from the GPU.
//!
//! [`strand_raster`] mirrors the compute strand rasterizer's binning and compositing
//! (`shade/oit/strand_raster.wgsl`) from the segments the GPU projected: its tile lists
//! equal the GPU's exactly and its composite matches within 1/255.

pub mod chiang;
pub mod dual;
pub mod flip;
pub mod guides;
pub mod noise;
pub mod oit;
pub mod oit_raster;
pub mod path_tracer;
pub mod sdf;
pub mod shading;
pub mod simulate;
pub mod skin;
pub mod strand_raster;
pub mod strands;
pub mod transmittance;
pub mod volume;
pub mod voxel;
