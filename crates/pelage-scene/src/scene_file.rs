//! Scene files: a whole scene (mesh, hair, shadows, shading, camera, lights) in TOML.
//!
//! Every table and key is optional; what is left out takes its default, and
//! `scenes/default.toml` in the repository lists every key with its default value
//! (it is [`SceneFile::default`] written out, and a test keeps the two equal). An
//! unknown key, a value of the wrong type or a missing file is an error that names the
//! key (with its line) or the path. Every table refuses a key it does not use, the
//! tagged ones included (`[mesh]`, `[hair.growth.hair_type]`, `[shadow]`,
//! `[shadow.spacing]`, `[shade.model]`, `[shade.transparency]`, `[[lights]]`), whatever
//! the variant: `method = "none"` with another key is an error at that key's line.
//!
//! The tag of a tagged table is optional too: left out, it is the variant of the type's
//! `Default` (`[shadow]` with only `resolution` is voxel shadows at that resolution;
//! `[shade.model]` is Kajiya-Kay, `[shade.transparency]` opaque, `[mesh]` the creature,
//! a light directional), and an error about a key there says so. Marschner's parameters
//! may sit directly in `[shade.model]`, as every other model's do, or in
//! `[shade.model.params]` (the form [`SceneFile::to_toml`] writes); a parameter given in
//! both is an error.
//!
//! ```toml
//! [mesh]
//! kind = "obj"            # or "creature", "icosphere", "torus", "plane", "none"
//! path = "head.obj"       # relative to the scene file
//!
//! [hair.roots]
//! count = 40000
//!
//! [shade.transparency]
//! method = "k_buffer"
//! k = 8
//!
//! [[lights]]
//! kind = "directional"
//! direction = [-0.85, -0.6, 0.1]
//! ```
//!
//! A `[dynamics]` table simulates the hair (grown or from a groom) instead of bending it
//! by the stateless wind, and a `[motion]` table turns and nods the mesh over time (see
//! `scenes/head_turn.toml`):
//!
//! ```toml
//! [dynamics]
//! damping = 2.0
//! colliders = [{ center = [0.0, 0.0, 0.0], radius = 0.95 }]
//!
//! [motion]
//! turn = 1.0              # radians about the vertical axis through `pivot`
//! turn_frequency = 0.35   # per second
//! ```
//!
//! A `[skin]` table bends and twists the mesh by a procedural two-joint rig, skinned on
//! the GPU every frame (see [`SkinBend`] and `scenes/creature_skinned.toml`; not with
//! `[motion]`):
//!
//! ```toml
//! [skin]
//! origin = [0.0, 0.1, 0.2]  # the joint
//! axis = [0.0, 0.0, 1.0]    # into the part that moves
//! bend = 0.6                # radians about bend_axis
//! bend_frequency = 0.5      # per second
//! ```
//!
//! A `[groom]` table draws the strands of a `.hair`, `.tfx` or (feature `usd`) USD file
//! (`.usda`, `.usdc`, `.usd`, `.usdz`) instead of growing fur from the mesh (see
//! [`GroomSource`]; the mesh is still drawn, as the head, say):
//!
//! ```toml
//! [groom]
//! path = "long_hair.hair" # relative to the scene file
//! segments = 16           # resampled by arc length
//! fit = 1.8               # centred, longest side 1.8 units (leave out: the file's units)
//! ```
//!
//! A groom keeps its file shape at t = 0 unless the scene asks for wind: in a scene
//! with a `[groom]` and no `[hair.wind]` table the wind is [`WindParams::calm`] (without
//! a groom the default breeze stays). A **groom-only scene** draws no mesh at all, and
//! shadows none: `[mesh] kind = "none"` (which needs a `[groom]`; leaving `[mesh]` out
//! still means the creature).
//!
//! **Regions** give parts of the fur their own shape, length, width and colour: each
//! `[[hair.growth.regions]]` entry overrides some of `[hair.growth]`'s keys (see
//! [`RegionParams`](crate::RegionParams)), and a region map over the mesh says which
//! region each root is in, as a texture over the mesh's UVs or per vertex (see
//! [`RootTextures`](crate::RootTextures); `scenes/creature_mane.toml`):
//!
//! ```toml
//! [hair.roots.textures]
//! region = "creature_mane_regions.png"  # red channel: 0 = [hair.growth], 1 = first region
//!
//! [[hair.growth.regions]]
//! length = 0.5
//! color = [0.5, 0.3, 0.12]
//! hair_type = { kind = "wavy", amplitude = 0.02, frequency = 6.0 }
//! ```
//!
//! Regions are grown by the growth pass alone: with `[groom]` or `[dynamics]` they are
//! refused.
//!
//! `guides = { strands = 6000, clump = 0.3 }` in `[groom]` takes the file's strands as
//! guides and interpolates render strands rooted on the mesh from them (see
//! [`GuideParams`](crate::GuideParams)).
//!
//! **Nothing is silently ignored**: a value that would have no effect in the scene is
//! an error naming its key (a key left at its default is fine). With a `[groom]`:
//! `roots.count`, `roots.length_scale`, `roots.textures.length_scale`, region maps and
//! the shape keys of `[hair.growth]` (`segments`, `length`, `length_jitter`,
//! `direction_jitter`, `hair_type`, `gravity`, `surface`), and without `guides` also
//! `roots.density`, `roots.textures.density` and `roots.textures.color` (with guides
//! the colour map is refused when the groom has colours of its own); with
//! `[dynamics]`: `growth.gravity` and `growth.force_weight`; `[[hair.growth.regions]]`
//! without a region map and a region map without regions; `shadow.resolution` beside
//! `shadow.voxel_size`.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::{
    Camera, DynamicsParams, GroomError, GroomSource, HairParams, Light, Mesh, MeshError,
    MeshMotion, ObjError, Resampled, ShadeParams, ShadowParams, SkinBend, WindParams, scene_keys,
};

/// The surface the hair grows from.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum MeshSource {
    /// The built-in creature ([`Mesh::creature`]).
    #[default]
    Creature,
    /// A sphere ([`Mesh::icosphere`]).
    Icosphere {
        /// Radius (> 0).
        radius: f32,
        /// Subdivisions of the icosahedron (0..=7).
        subdivisions: u32,
    },
    /// A torus ([`Mesh::torus`]).
    Torus {
        /// Distance from the centre to the tube's centre (> minor_radius).
        major_radius: f32,
        /// Radius of the tube (> 0).
        minor_radius: f32,
        /// Segments around the ring.
        major_segments: u32,
        /// Segments around the tube.
        minor_segments: u32,
    },
    /// A flat square in the xz plane ([`Mesh::plane`]).
    Plane {
        /// Size along x.
        size_x: f32,
        /// Size along z.
        size_z: f32,
        /// Subdivisions along x.
        subdivisions_x: u32,
        /// Subdivisions along z.
        subdivisions_z: u32,
    },
    /// A Wavefront OBJ file, relative to the scene file's folder.
    Obj {
        /// The file.
        path: PathBuf,
    },
    /// No mesh: a groom-only scene (needs a `[groom]`). [`SceneFile::mesh`] gives an
    /// empty [`Mesh`], which the renderer neither draws nor shadows.
    None,
}

/// A scene as a TOML file describes it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SceneFile {
    /// The surface.
    pub mesh: MeshSource,
    /// Roots, growth and wind.
    pub hair: HairParams,
    /// A groom file to draw instead of fur grown from the mesh (none by default): its
    /// strands replace `hair.roots` and the shape keys of `hair.growth`, and the wind
    /// bends them (see `pelage_strands::GroomStrands`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub groom: Option<GroomSource>,
    /// Strand dynamics (none by default: the stateless wind): the hair, grown or from
    /// `groom`, simulated (see `pelage_strands::SimulateStrands`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dynamics: Option<DynamicsParams>,
    /// A rigid motion of the mesh over time (none by default): the mesh, its colliders
    /// and the hair on it turn and nod.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub motion: Option<MeshMotion>,
    /// A procedural two-joint rig skinning the mesh on the GPU every frame (none by
    /// default): the mesh bends and twists, and the hair on it follows (see
    /// [`SkinBend`]; not with `[motion]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skin: Option<SkinBend>,
    /// Stage 2's method.
    pub shadow: ShadowParams,
    /// Stage 3: shading model, transparency, look.
    pub shade: ShadeParams,
    /// The camera.
    pub camera: Camera,
    /// 1 to 4 lights; the first is the key light.
    pub lights: Vec<Light>,
}

impl Default for SceneFile {
    fn default() -> Self {
        Self {
            mesh: MeshSource::default(),
            hair: HairParams::default(),
            groom: None,
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

/// What can go wrong reading a scene file.
#[derive(Debug, thiserror::Error)]
pub enum SceneFileError {
    /// The file could not be read.
    #[error("cannot read scene file {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The TOML is malformed, has an unknown key or a value of the wrong type.
    #[error("scene file {}: {message}", path.display())]
    Toml {
        /// The file (`<text>` when parsed from a string).
        path: PathBuf,
        /// toml's report: the key, its line and column, and what was expected.
        message: String,
    },
    /// A value is out of range.
    #[error("scene file {}: {source}", path.display())]
    Param {
        /// The file.
        path: PathBuf,
        /// The parameter and its valid range.
        source: crate::ParamError,
    },
    /// The mesh could not be built or loaded.
    #[error("scene file {}: mesh: {source}", path.display())]
    Mesh {
        /// The file.
        path: PathBuf,
        /// The mesh error.
        source: MeshError,
    },
    /// The groom file could not be loaded or resampled.
    #[error("scene file {}: groom {}: {source}", path.display(), groom.display())]
    Groom {
        /// The scene file.
        path: PathBuf,
        /// The groom file.
        groom: PathBuf,
        /// Why (boxed: a file error is large).
        source: Box<GroomError>,
    },
    /// A texture map could not be loaded (its path is in the message).
    #[error("scene file {}: {key}: {source}", path.display())]
    Map {
        /// The scene file.
        path: PathBuf,
        /// The key naming the map (`roots.textures.region`, ...).
        key: &'static str,
        /// Why.
        source: crate::MapError,
    },
    /// The OBJ file could not be loaded (its path is in the message).
    #[error("scene file {}: {source}", path.display())]
    Obj {
        /// The scene file.
        path: PathBuf,
        /// The OBJ error, naming the OBJ file.
        source: ObjError,
    },
}

impl SceneFile {
    /// Parses TOML text; relative OBJ paths stay relative to the current folder.
    pub fn parse(text: &str) -> Result<Self, SceneFileError> {
        Self::parse_named(text, Path::new("<text>"))
    }

    fn parse_named(text: &str, path: &Path) -> Result<Self, SceneFileError> {
        let toml_error = |message: String| SceneFileError::Toml {
            path: path.to_path_buf(),
            message,
        };
        let mut doc = toml::de::DeTable::parse(text).map_err(|e| toml_error(e.to_string()))?;
        let has_wind = has_table(doc.get_ref(), &["hair", "wind"]);
        let normalized = scene_keys::normalize(&mut doc).map_err(|e| toml_error(e.render(text)))?;
        let mut file = SceneFile::deserialize(toml::de::Deserializer::from(doc.clone())).map_err(
            |mut e| {
                e.set_input(Some(text));
                toml_error(scene_keys::repoint(&e, &doc, &normalized, text))
            },
        )?;
        scene_keys::check_every_key_used(&doc, &file, &normalized)
            .map_err(|e| toml_error(e.render(text)))?;
        // A groom keeps its file shape unless the scene asks for wind.
        if file.groom.is_some() && !has_wind {
            file.hair.wind = WindParams::calm();
        }
        file.validate().map_err(|source| SceneFileError::Param {
            path: path.to_path_buf(),
            source,
        })?;
        Ok(file)
    }

    /// Reads and parses `path`; relative OBJ, groom and texture map paths are made
    /// relative to the file's folder, and the texture maps are read. At most [`MAX_SCENE_FILE_BYTES`](crate::MAX_SCENE_FILE_BYTES) are
    /// read.
    pub fn load(path: &Path) -> Result<Self, SceneFileError> {
        let io = |source| SceneFileError::Io {
            path: path.to_path_buf(),
            source,
        };
        let bytes = crate::limits::read_capped(path, crate::MAX_SCENE_FILE_BYTES, "scene files")
            .map_err(io)?;
        let text = String::from_utf8(bytes).map_err(|e| {
            io(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!("not UTF-8 text (at byte {})", e.utf8_error().valid_up_to()),
            ))
        })?;
        let mut file = Self::parse_named(&text, path)?;
        let relative = |p: &mut PathBuf| {
            if p.is_relative() {
                if let Some(folder) = path.parent() {
                    *p = folder.join(&*p);
                }
            }
        };
        if let MeshSource::Obj { path: obj } = &mut file.mesh {
            relative(obj);
        }
        if let Some(groom) = &mut file.groom {
            relative(&mut groom.path);
        }
        for (key, map) in file.hair.roots.textures.maps_mut() {
            relative(&mut map.path);
            map.load().map_err(|source| SceneFileError::Map {
                path: path.to_path_buf(),
                key,
                source,
            })?;
        }
        file.hair
            .roots
            .validate_maps(file.hair.growth.regions.len() + 1, None)
            .map_err(|source| SceneFileError::Param {
                path: path.to_path_buf(),
                source,
            })?;
        Ok(file)
    }

    /// Checks every parameter; the error names the first bad one.
    pub fn validate(&self) -> Result<(), crate::ParamError> {
        // The roots are checked against the mesh when the renderer is built.
        self.hair.growth.validate()?;
        self.hair.wind.validate()?;
        self.shadow.validate()?;
        self.shade.validate()?;
        self.camera.validate()?;
        if let Some(groom) = &self.groom {
            groom.validate()?;
        } else if self.mesh == MeshSource::None {
            return Err(crate::ParamError::new(
                "mesh.kind",
                "none",
                "needs a [groom] table: without a mesh there is nothing to grow fur from",
            ));
        }
        if !self.hair.growth.regions.is_empty() && self.groom.is_some() {
            return Err(crate::ParamError::new(
                "growth.regions",
                format!("{} regions with [groom]", self.hair.growth.regions.len()),
                "a groom's strands take their shape from its file (or its guides), not from \
                 growth regions: leave out the regions or the [groom] table",
            ));
        }
        if let Some(dynamics) = &self.dynamics {
            dynamics.validate()?;
        }
        if let Some(motion) = &self.motion {
            motion.validate()?;
        }
        if let Some(skin) = &self.skin {
            skin.validate()?;
            if self.motion.is_some() {
                return Err(crate::ParamError::new(
                    "skin",
                    "set with [motion]",
                    "a mesh is moved either rigidly ([motion]) or by its skin ([skin]), not \
                     both: leave one out",
                ));
            }
            if self.mesh == MeshSource::None {
                return Err(crate::ParamError::new(
                    "skin",
                    "set with mesh.kind = \"none\"",
                    "a groom-only scene has no mesh to skin; give the scene a mesh or leave \
                     [skin] out",
                ));
            }
        }
        Light::validate_all(&self.lights)?;
        self.shade.transparency.validate_pools()?;
        self.check_every_value_used()
    }

    /// Refuses a value that has no effect in this scene (a key left at its default is
    /// fine: [`SceneFile::to_toml`] writes every key). With a `[groom]`: the roots'
    /// count, length maps and region maps, and the growth keys of the strands' shape
    /// (the groom's file, or its guides, gives them), and without guides its density and
    /// colour maps too (the file places and colours every strand); with `[dynamics]`:
    /// `growth.gravity` and `growth.force_weight` (the simulation's gravity and wind
    /// response move the strands); regions without a region map and a region map
    /// without regions; `shadow.resolution` beside `shadow.voxel_size`.
    fn check_every_value_used(&self) -> Result<(), crate::ParamError> {
        let ignored = |key: &str, value: String, why: &str| {
            Err(crate::ParamError::new(
                key,
                value,
                &format!("has no effect here: {why}; leave it out"),
            ))
        };
        let (roots, growth) = (&self.hair.roots, &self.hair.growth);
        let (root_defaults, growth_defaults) =
            (crate::RootParams::default(), crate::GrowthParams::default());
        if let Some(groom) = &self.groom {
            let why = if groom.guides.is_some() {
                "with [groom] guides the render strands' count is guides.strands and their \
                 shape and length the guides'"
            } else {
                "a [groom]'s strands, their roots, shape, length and placement come from its \
                 file"
            };
            if roots.count != root_defaults.count {
                return ignored("roots.count", roots.count.to_string(), why);
            }
            let mut maps = vec![
                ("roots.length_scale", roots.length_scale.is_some()),
                (
                    "roots.textures.length_scale",
                    roots.textures.length_scale.is_some(),
                ),
            ];
            if groom.guides.is_none() {
                maps.extend([
                    ("roots.density", roots.density.is_some()),
                    ("roots.textures.density", roots.textures.density.is_some()),
                    ("roots.textures.color", roots.textures.color.is_some()),
                ]);
            }
            if let Some((key, _)) = maps.into_iter().find(|(_, given)| *given) {
                return ignored(key, "a map".into(), why);
            }
            let shape = [
                (
                    "growth.segments",
                    growth.segments != growth_defaults.segments,
                    format!(
                        "{} (the groom's segments are groom.segments)",
                        growth.segments
                    ),
                ),
                (
                    "growth.length",
                    growth.length != growth_defaults.length,
                    growth.length.to_string(),
                ),
                (
                    "growth.length_jitter",
                    growth.length_jitter != growth_defaults.length_jitter,
                    growth.length_jitter.to_string(),
                ),
                (
                    "growth.direction_jitter",
                    growth.direction_jitter != growth_defaults.direction_jitter,
                    growth.direction_jitter.to_string(),
                ),
                (
                    "growth.hair_type",
                    growth.hair_type != growth_defaults.hair_type,
                    format!("{:?}", growth.hair_type),
                ),
                (
                    "growth.gravity",
                    growth.gravity != growth_defaults.gravity,
                    format!("{:?} (a groom's rest shape already hangs)", growth.gravity),
                ),
                (
                    "growth.surface",
                    growth.surface != growth_defaults.surface,
                    format!("{:?}", growth.surface),
                ),
            ];
            if let Some((key, _, value)) = shape.into_iter().find(|(_, differs, _)| *differs) {
                return ignored(key, value, why);
            }
        }
        if self.dynamics.is_some() {
            let why = "with [dynamics] the simulation moves the strands (dynamics.gravity, \
                       dynamics.wind_response); their rest shape is grown without gravity or \
                       wind";
            if growth.gravity != growth_defaults.gravity {
                return ignored("growth.gravity", format!("{:?}", growth.gravity), why);
            }
            if growth.force_weight != growth_defaults.force_weight {
                return ignored("growth.force_weight", growth.force_weight.to_string(), why);
            }
        }
        if self.groom.is_none() || !growth.regions.is_empty() {
            roots.validate_with(growth)?;
        } else if roots.region.is_some() || roots.textures.region.is_some() {
            let key = if roots.region.is_some() {
                "roots.region"
            } else {
                "roots.textures.region"
            };
            return ignored(key, "a region map".into(), "a [groom] has no regions");
        }
        if let ShadowParams::Voxel(v) = &self.shadow {
            if v.voxel_size.is_some() && v.resolution != crate::VoxelParams::default().resolution {
                return ignored(
                    "shadow.resolution",
                    format!("{:?}", v.resolution),
                    "shadow.voxel_size sets the resolution",
                );
            }
        }
        Ok(())
    }

    /// Loads and resamples the groom file, if the scene has one (`path` names the scene
    /// file in errors).
    pub fn groom(&self, path: &Path) -> Result<Option<Resampled>, SceneFileError> {
        let Some(source) = &self.groom else {
            return Ok(None);
        };
        let resampled = source
            .load()
            .map_err(|source_error| SceneFileError::Groom {
                path: path.to_path_buf(),
                groom: source.path.clone(),
                source: Box::new(source_error),
            })?;
        // Guides with colours of their own colour the render strands: a colour map
        // beside them would change nothing.
        if let Some(map) = &self.hair.roots.textures.color {
            if resampled.colors.is_some() {
                return Err(SceneFileError::Param {
                    path: path.to_path_buf(),
                    source: crate::ParamError::new(
                        "roots.textures.color",
                        &map.path,
                        &format!(
                            "has no effect here: the groom {} has colours of its own, which \
                             colour the strands interpolated from its guides; leave it out",
                            source.path.display()
                        ),
                    ),
                });
            }
        }
        Ok(Some(resampled))
    }

    /// Builds or loads the mesh (`path` names the scene file in errors); an empty mesh
    /// for `kind = "none"`.
    pub fn mesh(&self, path: &Path) -> Result<Mesh, SceneFileError> {
        let mesh_error = |source| SceneFileError::Mesh {
            path: path.to_path_buf(),
            source,
        };
        match &self.mesh {
            MeshSource::None => Ok(Mesh::default()),
            MeshSource::Creature => Ok(Mesh::creature()),
            MeshSource::Icosphere {
                radius,
                subdivisions,
            } => Mesh::icosphere(*radius, *subdivisions).map_err(mesh_error),
            MeshSource::Torus {
                major_radius,
                minor_radius,
                major_segments,
                minor_segments,
            } => Mesh::torus(
                *major_radius,
                *minor_radius,
                *major_segments,
                *minor_segments,
            )
            .map_err(mesh_error),
            MeshSource::Plane {
                size_x,
                size_z,
                subdivisions_x,
                subdivisions_z,
            } => {
                Mesh::plane(*size_x, *size_z, *subdivisions_x, *subdivisions_z).map_err(mesh_error)
            }
            MeshSource::Obj { path: obj } => {
                crate::load_obj(obj).map_err(|source| SceneFileError::Obj {
                    path: path.to_path_buf(),
                    source,
                })
            }
        }
    }

    /// The scene as TOML (every key, defaults included).
    pub fn to_toml(&self) -> Result<String, SceneFileError> {
        toml::to_string(self).map_err(|e| SceneFileError::Toml {
            path: PathBuf::from("<output>"),
            message: e.to_string(),
        })
    }
}

/// Whether `table` has a table at `keys` (`["hair", "wind"]`: `[hair.wind]`).
fn has_table(table: &toml::de::DeTable<'_>, keys: &[&str]) -> bool {
    let Some((first, rest)) = keys.split_first() else {
        return true;
    };
    table.iter().any(|(key, value)| {
        key.get_ref() == first
            && match value.get_ref() {
                toml::de::DeValue::Table(inner) => has_table(inner, rest),
                _ => false,
            }
    })
}
