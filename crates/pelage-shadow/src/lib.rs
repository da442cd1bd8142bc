//! Stage 2 of pelage: how much light reaches each point of the hair.
//!
//! Every method implements [`ShadowMethod`]: it is aimed with `prepare` for stage 1's
//! [`StrandFrame`], records its passes into the caller's encoder with `encode` for the
//! same frame (no readback), and hands the
//! shading stage a [`ShaderBinding`] implementing the shadow contract
//! (pelage-contract's `wgsl/shadow/none.wgsl`: `light_visibility(p)` and
//! `surface_visibility(p)`), so the shading pass never knows which method it got. The mesh casts its own shadow through a
//! [`MeshShadowMap`] with PCF in every method.
//!
//! - [`VoxelShadow`] (seed 001, corrected): a light-space grid fitted to the hair
//!   on the GPU ([`LightFit`]), segments splatted as `atomic<u32>` fixed-point
//!   optical depth, an exclusive prefix sum along the light;
//! - [`DeepOpacityMaps`] (Yuksel and Keyser 2008, seed 000 corrected): the front-most
//!   hair depth from the light and layers of accumulated opacity behind it;
//! - [`HairShadowMap`]: the hair as an opaque occluder, with PCF;
//! - [`Adsm`] (TressFX): fibres in front of a point estimated from its depth behind
//!   the front-most hair.

mod fit;
mod light_space;
mod map;
mod mesh_shadow;
mod probe;
mod visibility;
mod voxel;

pub use fit::{LightFit, LightGrid, LightGridUniforms};
pub use light_space::LightSpace;
pub use map::{Adsm, DeepOpacityMaps, HairShadowMap, MapUniforms};
pub use mesh_shadow::{MeshShadowMap, MeshShadowUniforms};
pub use probe::TransmittanceProbe;
pub use visibility::LightVisibility;
pub use voxel::VoxelShadow;

use glam::Vec3;
use pelage_contract::{MeshBuffers, StrandBuffers, StrandFrame};
use pelage_gpu::{Gpu, GpuTimer, PassInfo, ShaderBinding, ShaderSources, wgpu};
use pelage_scene::{DirectionalLight, ShadowParams};

/// The shaders of stage 2 (`wgsl/shadow/*.wgsl`), importing the contracts' and
/// pelage-gpu's.
pub static SHADERS: ShaderSources = pelage_gpu::wgsl_sources!(
    uses [&pelage_contract::SHADERS];
    "shadow/adsm_lookup.wgsl",
    "shadow/dom_lookup.wgsl",
    "shadow/hair_light.wgsl",
    "shadow/light_common.wgsl",
    "shadow/light_fit.wgsl",
    "shadow/map_bindings.wgsl",
    "shadow/map_common.wgsl",
    "shadow/map_lookup.wgsl",
    "shadow/mesh_depth.wgsl",
    "shadow/mesh_shadow.wgsl",
    "shadow/probe.wgsl",
    "shadow/voxel_lookup.wgsl",
    "shadow/voxel_scan.wgsl",
    "shadow/voxel_splat.wgsl",
);

/// The frame resource of a shadow's light-space grid (every method fits one).
pub const SHADOW_GRID: &str = "shadow.grid";
/// The frame resource of the voxel method's optical depth volume.
pub const SHADOW_VOLUME: &str = "shadow.volume";
/// The hair's light-space bounds the fit pass reduces (scratch of that pass).
pub const SHADOW_BOUNDS: &str = "shadow.bounds";
/// The frame resource of a shadow map's front-most hair depth.
pub const SHADOW_DEPTH: &str = "shadow.depth";
/// The frame resource of the deep opacity maps' layers.
pub const SHADOW_LAYERS: &str = "shadow.layers";
/// The frame resource of the mesh's own shadow map.
pub const SHADOW_MESH_MAP: &str = "shadow.mesh_map";

/// The WGSL file every shading pass imports for `light_visibility(p)` (and the mesh pass
/// for `surface_visibility(p)`); a method's
/// [`ShaderBinding`] redirects it to the method's lookup. It is one of
/// [`pelage_contract::SHADERS`], so the shading stage finds it without this crate.
pub use pelage_contract::SHADOW_CONTRACT as CONTRACT;

/// One shadow method, as the frame pipeline drives it: each frame `prepare` with stage
/// 1's [`StrandFrame`], then `encode` with the same frame. `Send + Sync` on native
/// targets ([`wgpu::WasmNotSendSync`]), as every stage is.
pub trait ShadowMethod: std::fmt::Debug + wgpu::WasmNotSendSync {
    /// A short description with its parameters, e.g. `voxel 128x128x128 trilinear`.
    fn name(&self) -> String;
    /// Aims the method along `light` and takes the strands stage 1 grows in `strands`;
    /// takes effect at the next `encode`.
    fn prepare(
        &self,
        queue: &wgpu::Queue,
        strands: &StrandFrame,
        light: &DirectionalLight,
    ) -> Result<()>;
    /// Records the method's passes for `strands`, the frame of the last `prepare`
    /// (another is a [`ShadowError::FrameOrder`]).
    fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        strands: &StrandFrame,
        timer: Option<&mut GpuTimer>,
    ) -> Result<()>;
    /// The passes [`ShadowMethod::encode`] records, with the named resources each reads
    /// and writes, under the namespace `shadow` (`shadow.grid`, `shadow.volume`, ...;
    /// a frame with several lights renames it per light, see
    /// [`PassInfo::renamed`](pelage_gpu::PassInfo::renamed)).
    fn passes(&self) -> Vec<PassInfo>;
    /// The resources behind [`ShadowMethod::binding`] that the passes write: what a
    /// pass sampling this shadow reads. By default every resource the passes write.
    fn lookup(&self) -> Vec<String> {
        let mut names: Vec<String> = Vec::new();
        for name in self.passes().into_iter().flat_map(|p| p.writes) {
            // The fit's bounds are its own scratch, not part of the binding.
            if name != SHADOW_BOUNDS && !names.contains(&name) {
                names.push(name);
            }
        }
        names
    }
    /// The shadow contract's implementation, for the shading passes.
    fn binding(&self) -> ShaderBinding;
    /// Bytes of GPU memory the method holds.
    fn memory_bytes(&self) -> u64;
}

/// Builds the method `params` chooses (`None` for no shadows) for `strands` on `mesh`,
/// covering [`reach`]`(strands, mesh)`.
pub fn build(
    gpu: &Gpu,
    params: &ShadowParams,
    strands: &StrandBuffers,
    mesh: &MeshBuffers,
) -> Result<Option<Box<dyn ShadowMethod>>> {
    let reach = reach(strands, mesh);
    Ok(match params {
        ShadowParams::None => None,
        ShadowParams::Voxel(p) => Some(Box::new(VoxelShadow::new(gpu, p, strands, mesh, reach)?)),
        ShadowParams::DeepOpacity(p) => Some(Box::new(DeepOpacityMaps::new(
            gpu, p, strands, mesh, reach,
        )?)),
        ShadowParams::ShadowMap(p) => {
            Some(Box::new(HairShadowMap::new(gpu, p, strands, mesh, reach)?))
        }
        ShadowParams::Adsm(p) => Some(Box::new(Adsm::new(gpu, p, strands, mesh, reach)?)),
    })
}

/// The world box a shadow covers: where the strands can reach
/// ([`StrandBuffers::reach`]) and where the mesh stays ([`MeshBuffers::bounds`]).
pub fn reach(strands: &StrandBuffers, mesh: &MeshBuffers) -> (Vec3, Vec3) {
    (
        strands.reach.0.min(mesh.bounds.0),
        strands.reach.1.max(mesh.bounds.1),
    )
}

/// What can go wrong in stage 2.
#[derive(Debug, thiserror::Error)]
pub enum ShadowError {
    /// A parameter is out of range.
    #[error(transparent)]
    Param(#[from] pelage_scene::ParamError),
    /// The GPU refused something.
    #[error(transparent)]
    Gpu(#[from] pelage_gpu::GpuError),
    /// A pass was recorded for another stage 1 frame than it was prepared for.
    #[error(transparent)]
    FrameOrder(#[from] pelage_contract::FrameOrderError),
}

/// Result of stage 2.
pub type Result<T, E = ShadowError> = std::result::Result<T, E>;
