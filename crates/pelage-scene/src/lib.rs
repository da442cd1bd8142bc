//! CPU scene data for pelage: meshes (procedural and OBJ), Cem Yuksel `.hair`,
//! AMD TressFX `.tfx` and (feature `usd`) USD `BasisCurves` files, camera, lights and
//! the parameters of every stage.
//!
//! Everything here is plain CPU data with serde support; nothing here knows
//! about the GPU. The stage crates turn these types into GPU buffers.
//!
//! # Features
//!
//! The file formats that need a dependency are features, so an engine that builds its
//! scene in code compiles none of them: `obj` (OBJ meshes, tobj), `maps` (PNG texture
//! maps read from files, image), `scene-file` (TOML scene files, which name OBJ meshes
//! and maps; default) and `usd` (USD grooms, openusd). Within pelage every crate
//! depends on this one without default features; the facade's default feature
//! `files` turns `scene-file` on.

pub mod camera;
pub mod groom;
pub mod guides;
pub mod hair_file;
pub mod light;
pub mod limits;
pub mod lod;
pub mod mesh;
pub mod names;
#[cfg(feature = "obj")]
pub mod obj;
pub mod params;
pub mod scene;
#[cfg(feature = "scene-file")]
pub mod scene_file;
#[cfg(feature = "scene-file")]
mod scene_keys;
mod sdf_grid;
pub mod shading;
pub mod skin;
pub mod surface_map;
pub mod tfx_file;
pub mod transparency;
#[cfg(feature = "usd")]
pub mod usd_file;

pub use camera::{Camera, CameraMatrices, FOV_MARGIN, MAX_DEPTH_RATIO, MIN_NEAR};
pub use groom::{Groom, GroomError, GroomSource, Resampled};
pub use guides::{GuideParams, MAX_GUIDE_NEIGHBOURS, MAX_GUIDES};
pub use hair_file::{HairFile, HairFileError};
pub use light::{DirectionalLight, Light, MAX_LIGHTS, MAX_RADIANCE, PointLight, check_radiance};
pub use limits::{MAX_EXTENT, MAX_GROOM_FILE_BYTES, MAX_OBJ_FILE_BYTES, MAX_SCENE_FILE_BYTES};
pub use lod::{LodParams, Transition};
pub use mesh::{Mesh, MeshError, MeshReport};
pub use names::{MethodName, Named};
#[cfg(feature = "obj")]
pub use obj::{ObjError, load_obj, parse_obj};
pub use params::{
    AdsmParams, Collider, DeepOpacityParams, DynamicsParams, GrowthParams, HairParams, HairType,
    LayerSpacing, MAX_ACCELERATION, MAX_COLLIDERS, MAX_COLOR, MAX_FORCE, MAX_MAP_VALUE,
    MAX_REGIONS, MAX_SDF_STANDOFF, MAX_SEGMENTS, MAX_WAVES, MapParams, MeshMotion, OpacityFormat,
    ParamError, RegionParams, RootParams, RootTextures, STIFFNESS_INTERVAL, SUBSTEP_SLACK,
    SUBSTEP_ULPS, ShadeParams, ShadowMapParams, ShadowParams, SkinnedSdf, Splat,
    SurfaceInterpolation, VoxelParams, WindParams, mesh_albedo,
};
pub use scene::Scene;
#[cfg(feature = "scene-file")]
pub use scene_file::{MeshSource, SceneFile, SceneFileError};
pub use sdf_grid::{
    MAX_SDF_RESOLUTION, MIN_SDF_RESOLUTION, SDF_BAND_CELLS, SDF_MARGIN_CELLS, SdfGrid,
    check_sdf_resolution,
};
pub use shading::{
    ARTIST_EUMELANIN_SIGMA_A, ARTIST_PHEOMELANIN_SIGMA_A, Absorption, ChiangParams,
    DEFAULT_MELANIN_REDNESS, DEFAULT_VOLUME_GRID, DEFAULT_VOLUME_ITERATIONS, EUMELANIN_SIGMA_A,
    KajiyaKayParams, MAX_MELANIN, MAX_VOLUME_GRID, MAX_VOLUME_ITERATIONS, MIN_VOLUME_GRID,
    MarschnerParams, MultipleScattering, PHEOMELANIN_SIGMA_A, SadeghiParams, ShadingModel,
    chiang_color_scale, sigma_a_from_artist_melanin, sigma_a_from_color, sigma_a_from_melanin,
    sigma_a_from_reflectance,
};
pub use skin::{MAX_JOINTS, Skin, SkinBend, WEIGHT_SUM_TOLERANCE, check_finite_matrices};
pub use surface_map::{MAX_MAP_FILE_BYTES, MAX_MAP_SIZE, MapError, MapImage, TextureMap};
pub use tfx_file::{TfxFile, TfxFileError};
pub use transparency::{MAX_OIT_K, MIN_NODES_PER_PIXEL, MIN_POOL, Transparency, WboitWeight};
#[cfg(feature = "usd")]
pub use usd_file::UsdFileError;
