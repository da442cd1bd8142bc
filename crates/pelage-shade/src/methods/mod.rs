//! Stage 3's methods: one type per way of compositing the hair, all with the same shape.
//!
//! | method | type | WGSL |
//! |---|---|---|
//! | opaque | [`Opaque`] | `shade/ribbons.wgsl` |
//! | weighted blended OIT | [`Wboit`] | `shade/oit/wboit.wgsl` |
//! | k-buffer (64-bit atomics) | [`KBuffer`] | `shade/oit/k_buffer.wgsl` |
//! | A-buffer (linked lists) | [`ABuffer`] | `shade/oit/a_buffer.wgsl` |
//! | DBK-buffer | [`Dbk`] | `shade/oit/dbk.wgsl` |
//! | random subsets | [`RandomSubsets`] | `shade/oit/random_subsets.wgsl` |
//! | strand rasterizer (compute) | [`StrandRaster`] | `shade/oit/strand_raster.wgsl` |
//!
//! Each draws the opaque mesh first (clearing the caller's colour and depth), then
//! the hair. Per-pixel storage is sized for the target and sliced into horizontal
//! bands when it would pass the device's storage binding limit.

pub(crate) mod a_buffer;
mod dbk;
mod k_buffer;
mod opaque;
mod random_subsets;
mod sliced;
mod strand_raster;
mod wboit;

pub use a_buffer::{ABuffer, CapturedFragment, FragmentCapture};
pub use dbk::Dbk;
pub use k_buffer::KBuffer;
pub use opaque::Opaque;
pub use random_subsets::RandomSubsets;
pub use sliced::OitTile;
pub use strand_raster::{RasterCapture, StrandRaster, StrandRasterUniforms};
pub use wboit::Wboit;

use pelage_contract::StrandFrame;
use pelage_gpu::{Gpu, GpuTimer, PassInfo, wgpu};
use pelage_scene::{CameraMatrices, Light, Transparency};

use crate::draw::{HairInputs, TargetViews};

/// What a transparency method counted, read back on request (never in the frame loop).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OitStats {
    /// Fragments stored in the node pool since the method was built (linked lists).
    pub stored: u64,
    /// Fragments that found the pool full and were dropped.
    pub dropped: u64,
    /// The most nodes one slice of one frame asked for: the pool size that would have held everything.
    pub peak_nodes: u64,
    /// Nodes in the pool per slice (the strand rasterizer: segment references).
    pub capacity: u64,
    /// Frames whose pool overflowed since the method was built (the strand rasterizer).
    pub overflowed_frames: u64,
}

/// One stage 3 method: draws the mesh and the hair into the caller's targets. Each
/// frame: [`HairPass::prepare`] with stage 1's [`StrandFrame`] (queue writes), then
/// [`HairPass::encode`] with the same frame (recording only: no device), and after the
/// caller's submit [`HairPass::after_submit`] (readbacks and pool growth, never a wait). `Send + Sync` on native targets
/// ([`wgpu::WasmNotSendSync`]), so that an engine keeps a boxed method in shared state
/// (a Bevy resource, say) and records it from any thread; on the web wgpu's own types
/// are neither, and neither is a method.
pub trait HairPass: std::fmt::Debug + wgpu::WasmNotSendSync {
    /// Short name (`opaque`, `wboit`, `k_buffer`, `a_buffer`, `dbk`, `random_subsets`,
    /// `strand_raster`).
    fn name(&self) -> &'static str;

    /// Writes camera and lights for the next [`HairPass::encode`], and takes the
    /// strands stage 1 grows in `strands`.
    fn prepare(
        &self,
        queue: &wgpu::Queue,
        strands: &StrandFrame,
        camera: &CameraMatrices,
        lights: &[Light],
        width: u32,
        height: u32,
    ) -> crate::Result<()>;

    /// Records the method's passes into `encoder` for `strands`, the frame of the last
    /// `prepare` (another is a [`ShadeError::FrameOrder`](crate::ShadeError::FrameOrder)):
    /// the mesh (clearing colour and depth unless `target.load`), then the hair. The
    /// targets must have the size the method was built for. Takes no device: the bind
    /// groups that sample the caller's depth view are built on the first frame (and
    /// again only when the view changes) on the device the method was built on.
    fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        strands: &StrandFrame,
        target: &TargetViews<'_>,
        timer: Option<&mut GpuTimer>,
    ) -> crate::Result<()>;

    /// The one step after the caller submitted the encoder of [`HairPass::encode`]:
    /// takes the readbacks of frames the GPU has finished (`device.poll(Poll)` and
    /// mapped buffers, never a wait) and grows per-frame storage that a frame found too
    /// small, for a later frame (the strand rasterizer's pool). Nothing for most
    /// methods. Calling it is optional: without it a pool keeps its size and the
    /// overflow stays counted ([`HairPass::stats`]).
    fn after_submit(&self, _gpu: &Gpu) -> crate::Result<()> {
        Ok(())
    }

    /// The passes [`HairPass::encode`] records in order (a pass drawn once per slice of
    /// the screen appears once per slice), with the named resources each reads and
    /// writes; `lookup` names what the lights' shadows (those the mesh samples, one
    /// draw per light: [`HairInputs::shadows`](crate::HairInputs::shadows)) wrote, empty
    /// without shadows.
    fn passes(&self, lookup: &[String]) -> Vec<PassInfo>;

    /// Bytes of GPU memory the method owns beyond the caller's targets.
    fn memory_bytes(&self) -> u64;

    /// Takes the parameters of `params` that live in uniforms or small tables, in place:
    /// the background, the mesh colour, the ambient light, the root occlusion and the
    /// shading model's parameters when the model stays the same kind (Marschner's lookup
    /// tables and Chiang's tables are computed again, one compute submission waited for,
    /// when what they depend on changed). Pictures are those of a method built with
    /// `params`. Anything else differing from what the method was built with (the
    /// transparency method, sample count, minimum ribbon width, the model's kind, or a
    /// Marschner fibre turning from circular to elliptical) is a
    /// [`ShadeError::NeedsRebuild`](crate::ShadeError::NeedsRebuild) naming it, and
    /// then nothing changes; bad values are a parameter error.
    fn set_params(&mut self, gpu: &Gpu, params: &pelage_scene::ShadeParams) -> crate::Result<()>;

    /// Horizontal slices the screen is drawn in (1 unless per-pixel storage for the
    /// whole target would pass the storage binding limit).
    fn slices(&self) -> u32 {
        1
    }

    /// The volume method's grid, which the shading reads (Chiang with volume
    /// scattering; `None` for the other models): a caller that built the method with
    /// [`HairInputs::grid_apart`](crate::HairInputs::grid_apart) records it
    /// ([`VolumeGrid::encode`](crate::VolumeGrid::encode)) after stage 2 and before its
    /// own mesh pass, and declares it ([`VolumeGrid::pass_info`](crate::VolumeGrid::pass_info)).
    fn grid(&self) -> Option<&crate::VolumeGrid> {
        None
    }

    /// The body's sky contract (`shade/body_sky.wgsl`: `body_sky(p, n, ambient)`, the
    /// irradiance on the body from the sky and from the light the hair scatters) as the
    /// method's model implements it, for a caller's own mesh shader: `Some` with the
    /// volume method (the grid, read in the hair model's group; record the grid first,
    /// [`HairPass::grid`]), `None` for the others (the open sky: `body_sky` returns
    /// `ambient` unredirected).
    fn body_sky_binding(&self) -> Option<pelage_gpu::ShaderBinding> {
        None
    }

    /// Counters of the node pool (linked-list methods); zeros for the others. Waits for the GPU.
    fn stats(&self, _gpu: &Gpu) -> crate::Result<OitStats> {
        Ok(OitStats::default())
    }
}

/// Builds the method `inputs.params.transparency` names for `width` x `height` targets
/// with [`ShadeParams::samples`](pelage_scene::ShadeParams::samples) samples.
pub fn build(
    gpu: &Gpu,
    inputs: &HairInputs<'_>,
    width: u32,
    height: u32,
) -> crate::Result<Box<dyn HairPass>> {
    inputs.params.validate()?;
    Ok(match inputs.params.transparency {
        Transparency::Opaque => Box::new(Opaque::new(gpu, inputs)?),
        Transparency::Wboit { weight } => Box::new(Wboit::new(gpu, inputs, weight, width, height)?),
        Transparency::KBuffer { k } => Box::new(KBuffer::new(gpu, inputs, k, width, height)?),
        Transparency::ABuffer {
            nodes_per_pixel,
            resolve_k,
        } => Box::new(ABuffer::new(
            gpu,
            inputs,
            nodes_per_pixel,
            resolve_k,
            width,
            height,
        )?),
        Transparency::Dbk {
            depth_shift,
            nodes_per_pixel,
            resolve_k,
        } => Box::new(Dbk::new(
            gpu,
            inputs,
            depth_shift,
            nodes_per_pixel,
            resolve_k,
            width,
            height,
        )?),
        Transparency::RandomSubsets { k } => {
            Box::new(RandomSubsets::new(gpu, inputs, k, width, height)?)
        }
        Transparency::StrandRaster { tile, bins, pool } => Box::new(StrandRaster::new(
            gpu, inputs, tile, bins, pool, width, height,
        )?),
    })
}

/// What a per-pixel (sliced) method needs of every adapter: its passes sample the
/// opaque depth while holding it as their read-only depth attachment, which wgpu's GL
/// backend does not allow.
const SLICED_DOWNLEVEL: wgpu::DownlevelFlags = wgpu::DownlevelFlags::READ_ONLY_DEPTH_STENCIL;

/// The transparency methods (by [`HairPass::name`]) `gpu` can build: opaque and wboit
/// everywhere; the strand rasterizer wherever compute shaders run; the k-buffer, A-buffer, DBK and random subsets where the adapter has the
/// downlevel capability `READ_ONLY_DEPTH_STENCIL` (not wgpu's GL backend), the k-buffer
/// and random subsets also their 64-bit atomics. The others fail before drawing with
/// [`ShadeError::Unsupported`](crate::ShadeError::Unsupported), which lists these.
pub fn supported_methods(gpu: &Gpu) -> Vec<&'static str> {
    let sliced = gpu.downlevel_flags().contains(SLICED_DOWNLEVEL);
    let has = |f| gpu.features().contains(f);
    Transparency::defaults()
        .iter()
        .filter(|method| match method {
            Transparency::Opaque | Transparency::Wboit { .. } => true,
            Transparency::KBuffer { .. } => {
                sliced && has(wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS)
            }
            Transparency::ABuffer { .. } | Transparency::Dbk { .. } => sliced,
            Transparency::RandomSubsets { .. } => {
                sliced && has(wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX)
            }
            Transparency::StrandRaster { .. } => gpu
                .downlevel_flags()
                .contains(wgpu::DownlevelFlags::COMPUTE_SHADERS),
        })
        .map(Transparency::name)
        .collect()
}

/// Errors, before anything is built, unless the device has `feature` and what every
/// per-pixel method needs ([`SLICED_DOWNLEVEL`]), naming the method, what is missing
/// and the methods that work on this adapter.
fn require_feature(gpu: &Gpu, method: &str, feature: wgpu::Features) -> crate::Result<()> {
    let missing_features = feature - gpu.features();
    let missing_downlevel = SLICED_DOWNLEVEL - gpu.downlevel_flags();
    if missing_features.is_empty() && missing_downlevel.is_empty() {
        return Ok(());
    }
    let mut what = Vec::new();
    if !missing_features.is_empty() {
        what.push(format!(
            "the device feature {}",
            pelage_gpu::feature_names(missing_features)
        ));
    }
    if !missing_downlevel.is_empty() {
        let names: Vec<&str> = missing_downlevel.iter_names().map(|(n, _)| n).collect();
        what.push(format!(
            "the downlevel capability {} (sampling the depth texture a pass also holds \
             as its read-only depth attachment)",
            names.join(" | ")
        ));
    }
    let what = what.join(" and ");
    Err(crate::ShadeError::Unsupported(format!(
        "{method} needs {what}, which this adapter ({}) lacks; the transparency methods \
         that work here: {}",
        gpu.describe(),
        supported_methods(gpu).join(", ")
    )))
}

/// Errors when `inputs` asks for reversed depth: the methods that test fragments against
/// the opaque depth in the shader (k-buffer, A-buffer, DBK, random subsets) compare one
/// way only. (Reading the direction from the slice uniform there crashes lavapipe, Mesa
/// 22.3, when it runs the DBK and random-subsets passes.)
fn refuse_reverse_z(inputs: &HairInputs<'_>, method: &str) -> crate::Result<()> {
    if !inputs.target.reverse_z {
        return Ok(());
    }
    Err(crate::ShadeError::Unsupported(format!(
        "{method} does not draw into reverse-Z targets yet; use opaque or wboit, \
         or standard depth (TargetFormat::reverse_z = false)"
    )))
}
