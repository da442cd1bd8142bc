//! A whole scene: the mesh, the hair on it and how it is lit, shadowed and drawn. What a
//! frame (`pelage::Frame`) is built from; plain data like every other parameter here.

use crate::{
    Camera, DynamicsParams, GuideParams, HairParams, Light, Mesh, MeshMotion, Resampled,
    ShadeParams, ShadowParams, SkinBend,
};

/// Everything a frame is made of.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The surface the hair grows from (drawn under a groom, as its head, say). An empty
    /// mesh (`Mesh::default()`, no triangles) with a groom is a groom-only scene: no mesh
    /// is drawn or shadowed.
    pub mesh: Mesh,
    /// Roots, growth and wind.
    pub hair: HairParams,
    /// A groom to draw instead of growing fur from `mesh` (pelage-strands'
    /// `GroomStrands` says which parts of `hair` it uses); `None` grows fur.
    pub groom: Option<Resampled>,
    /// With a groom: take its strands as guides and interpolate render strands rooted on
    /// `mesh` from them (pelage-strands' `GuideStrands`); `None` draws the groom's own
    /// strands.
    pub guides: Option<GuideParams>,
    /// Strand dynamics: `Some` simulates the hair (grown or the groom); `None` (the
    /// default) bends it by the stateless wind.
    pub dynamics: Option<DynamicsParams>,
    /// A rigid motion of the mesh over time (written into the mesh buffers every
    /// frame: the hair on it, its colliders and its drawing follow); `None` keeps it still.
    pub motion: Option<MeshMotion>,
    /// A procedural two-joint rig skinning the mesh on the GPU every frame (the hair on
    /// it follows); `None` keeps it still. Not with `motion`. An engine's own skin and
    /// joint matrices go through `pelage::Frame::with_skin` instead.
    pub skin: Option<SkinBend>,
    /// Shadow method.
    pub shadow: ShadowParams,
    /// Raster and shading.
    pub shade: ShadeParams,
    /// The camera.
    pub camera: Camera,
    /// The lights, 1 to 4 (the first is the key light); each gets its own shadow from
    /// `shadow`, which shadows the hair and the mesh for that light.
    pub lights: Vec<Light>,
}

impl Default for Scene {
    /// The built-in scene: the procedural creature, furred, in gusting wind.
    fn default() -> Self {
        Self {
            mesh: Mesh::creature(),
            hair: HairParams::default(),
            groom: None,
            guides: None,
            dynamics: None,
            motion: None,
            skin: None,
            shadow: ShadowParams::default(),
            shade: ShadeParams::default(),
            camera: Camera::default(),
            lights: vec![Light::default()],
        }
    }
}

#[cfg(feature = "scene-file")]
impl Scene {
    /// Reads a scene file (TOML, see [`crate::SceneFile`]) and builds or loads its mesh
    /// and groom. (Feature `scene-file`.)
    pub fn from_file(path: &std::path::Path) -> Result<Self, crate::SceneFileError> {
        Self::from_scene_file(&crate::SceneFile::load(path)?, path)
    }

    /// The scene a parsed scene file describes (`path` names it in errors). (Feature
    /// `scene-file`.)
    pub fn from_scene_file(
        file: &crate::SceneFile,
        path: &std::path::Path,
    ) -> Result<Self, crate::SceneFileError> {
        Ok(Self {
            mesh: file.mesh(path)?,
            hair: file.hair.clone(),
            groom: file.groom(path)?,
            guides: file.groom.as_ref().and_then(|g| g.guides.clone()),
            dynamics: file.dynamics.clone(),
            motion: file.motion.clone(),
            skin: file.skin.clone(),
            shadow: file.shadow.clone(),
            shade: file.shade.clone(),
            camera: file.camera.clone(),
            lights: file.lights.clone(),
        })
    }
}
