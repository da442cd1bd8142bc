//! pelage's fur in Bevy: a [`Fur`] component on any entity with a [`Mesh3d`] grows
//! strands from that mesh every frame (bent by pelage's wind at Bevy's [`Time`]),
//! shadows them with pelage's voxel shadow in the direction of the scene's
//! [`DirectionalLight`] and draws them in each 3D camera's render schedule
//! ([`Core3d`], after Bevy's main transparent pass, before post-processing) into
//! Bevy's own view targets: its main colour texture (HDR or not, multisampled as the
//! camera's [`Msaa`] says) and its reverse-Z depth, with
//! the camera's own view and projection.
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy_pelage::{Fur, PelagePlugin};
//!
//! fn setup(mut commands: Commands, mut meshes: ResMut<Assets<Mesh>>) {
//!     let body = meshes.add(Sphere::new(0.5).mesh().uv(48, 24));
//!     commands.spawn((Mesh3d(body), Fur::default(), Transform::default()));
//! }
//! # App::new().add_plugins(PelagePlugin).add_systems(Startup, setup);
//! ```
//!
//! What this first version does and does not do:
//! - The mesh is read once from `Assets<Mesh>` (positions, normals, triangle-list
//!   indices, and `ATTRIBUTE_UV_0` as `(u, 1 - v)`, so that [`Fur::hair`]'s texture maps
//!   follow the mesh's UVs: [`pelage_mesh`]) and uploaded into pelage's own buffers; it is
//!   read again only when the entity's [`Fur`], [`Mesh3d`], [`SkinnedMesh`] or [`Groom`]
//!   changes, not when the asset is edited in place.
//! - Groom files are Bevy assets: the plugin registers [`GroomAsset`] and its
//!   [`GroomLoader`] (`.hair`, `.tfx`, and with the `usd` feature USD `BasisCurves`), and
//!   a [`Groom`] component with the asset's handle draws the groom on the entity's mesh
//!   instead of the grown fur: its own strands in the wind, simulated
//!   ([`Groom::dynamics`]) or as guides for strands rooted on the mesh
//!   ([`Groom::guides`]). A file pelage refuses is the asset's load error (Bevy's
//!   `LoadState::Failed`, logged by Bevy), and the entity is logged once and skipped.
//! - Every transparency method draws under the camera's [`Msaa`]
//!   and reverse-Z depth: the opaque method draws Bevy's samples itself, the others
//!   draw single-sampled into pelage's own targets between Bevy's (the library's
//!   `Frame` resolves Bevy's colour and depth into them, depth turned to standard for
//!   the methods that need it, and writes the picture back into every sample).
//! - A skinned mesh (an entity with a [`SkinnedMesh`] whose mesh has
//!   `ATTRIBUTE_JOINT_INDEX` and `ATTRIBUTE_JOINT_WEIGHT`) is skinned by pelage on the
//!   GPU every frame ([`pelage::Frame::with_skin`]: linear blend skinning of the mesh
//!   buffers before the strands grow): the roots ride on the skinned surface. Its joint
//!   indices and weights are read once ([`pelage_skin`]); each frame the extraction
//!   reads the joints' [`GlobalTransform`]s and the inverse bind matrices and hands
//!   pelage `mesh_from_world · world_from_joint · inverse_bindpose` per joint
//!   ([`skin_joint_matrices`]; Bevy skins with `world_from_joint · inverse_bindpose`
//!   and ignores the mesh entity's own transform, pelage works in the mesh's space and
//!   the view matrix carries that transform back), written into the frame's
//!   joint-matrix buffer in prepare (a queue write: no new buffer or bind group). Weights
//!   that do not sum to 1 within 1 %, joint indices past the [`SkinnedMesh`]'s joints,
//!   fewer inverse bind matrices than joints, a despawned joint or a non-finite matrix
//!   are errors (logged once, as below). pelage bounds its shadow and reach by a box the
//!   skinned mesh must stay in, in mesh space: [`Fur::skin_reach`] (by default the bind
//!   pose's box grown by a quarter of its diagonal on every side); a pose that may
//!   leave it (bounded by each joint's transformed box of the vertices it moves) is
//!   logged once with `warn!` (the fur is still drawn, its shadow may be clipped).
//! - Morph targets are not applied: the fur grows on the mesh without its morph
//!   weights. With this crate's `morph` feature (on by default; it turns on Bevy's) a
//!   mesh with morph targets is logged once with `warn!`; without it Bevy's mesh cannot
//!   tell.
//! - The entity's [`GlobalTransform`] is applied through the camera matrices: pelage
//!   grows, winds and shadows in the mesh's own space and the view matrix carries the
//!   model matrix, so [`HairParams::wind`] blows in mesh space and the light is turned
//!   into mesh space each frame. A uniform scale is fine; non-uniform scale stretches
//!   the strands with the mesh.
//! - The first [`DirectionalLight`] found lights and shadows the fur: pelage's light
//!   intensity is the light's illuminance times the camera's exposure (what Bevy's
//!   PBR shaders do), its colour the light's colour in linear RGB. Without one the fur
//!   gets only [`ShadeParams::ambient`].
//! - With [`Fur::draw_mesh`] (the default) pelage draws the body itself, shaded as its
//!   own renders shade it and shadowed by the fur; turn it off when the application
//!   draws the mesh with a Bevy material.
//! - Each camera records its own [`pelage::Frame`] of the fur (the stages the facade's
//!   renderer records, built from a [`pelage::scene::Scene`] of the entity's mesh and [`Fur`]
//!   with a voxel shadow): strands are grown and shadowed once per camera, at the level
//!   of detail of the hair's size on screen through that camera's own view and
//!   projection ([`HairParams::lod`](pelage::scene::HairParams::lod), as pelage's
//!   renderer chooses it).
//! - Nothing waits for the GPU: every stage only writes uniforms in
//!   [`RenderSystems::PrepareBindGroups`] and records into Bevy's command encoder; the
//!   frame's after-submit step (readbacks, pool growth; never a wait) runs at the next
//!   frame's prepare, after Bevy submitted.
//!
//! Errors (a mesh without normals, bad parameters, a groom file that did not load, a
//! transparency method the adapter lacks) are logged once with Bevy's `error!` and the
//! entity is skipped until its [`Fur`], mesh or [`Groom`] changes; nothing panics.

use std::collections::HashMap;
use std::sync::Arc;

use bevy::asset::AssetId;
use bevy::camera::Camera3d;
use bevy::core_pipeline::core_3d::main_transparent_pass_3d;
use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::ecs::query::QueryItem;
use bevy::light::DirectionalLight;
use bevy::log::{error, warn};
use bevy::mesh::skinning::{SkinnedMesh, SkinnedMeshInverseBindposes};
use bevy::mesh::{Indices, Mesh, Mesh3d, PrimitiveTopology, VertexAttributeValues};
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::render_resource::{LoadOp, StoreOp, TextureUsages};
use bevy::render::renderer::{
    RenderAdapterInfo, RenderContext, RenderDevice, RenderQueue, ViewQuery,
};
use bevy::render::view::{ExtractedView, ViewDepthStencilTexture, ViewTarget};
use bevy::render::{Extract, ExtractSchedule, Render, RenderApp, RenderSystems};

use pelage::gpu::Gpu;
use pelage::scene::{
    CameraMatrices, HairParams, Light, ShadeParams, ShadowParams, Skin, VoxelParams,
};
use pelage::shade::{TargetFormat, TargetViews};
use pelage::{Frame, FrameTarget, scene::Scene};

mod groom;
pub use groom::{Groom, GroomAsset, GroomLoadError, GroomLoader};

/// Why an entity's fur cannot be drawn.
#[derive(Debug, thiserror::Error)]
pub enum FurError {
    /// The Bevy mesh cannot be read as a triangle list with positions and normals.
    #[error("mesh: {0}")]
    Mesh(String),
    /// pelage refused the mesh, the parameters or the targets.
    #[error(transparent)]
    Pelage(#[from] pelage::Error),
    /// A [`SkinnedMesh`] pelage cannot skin: its joint attributes, inverse bind matrices
    /// or joint entities (pelage's own checks of the skin are [`FurError::Pelage`]).
    #[error("skin: {0}")]
    Skin(String),
    /// A [`Groom`] whose file did not load or that pelage cannot resample.
    #[error("groom: {0}")]
    Groom(String),
}

/// Fur on the [`Mesh3d`] of the same entity, or, with a [`Groom`], the groom's strands
/// (on the entity's mesh, or alone without a [`Mesh3d`]).
#[derive(Component, Clone, Debug)]
#[require(Transform)]
pub struct Fur {
    /// Roots, growth and wind (in the mesh's own space), as pelage takes them.
    pub hair: HairParams,
    /// Shading: the hair model, ambient term, mesh colour and transparency method.
    /// `background` is unused (Bevy clears its targets); `sample_count` is taken from
    /// the camera for opaque hair; every transparency method draws under any `Msaa`
    /// (single-sampled, through pelage's target bridge).
    pub shade: ShadeParams,
    /// pelage's voxel shadow (the fur's own shadow from the directional light).
    pub voxel: VoxelParams,
    /// pelage draws the mesh too (in `shade.mesh_color`, shadowed by the fur); `false`
    /// when the application draws the mesh itself.
    pub draw_mesh: bool,
    /// For a skinned mesh: a box (min, max corners, in the mesh's own space) the skinned
    /// mesh stays in, in every pose; the voxel shadow and pelage's reach size themselves
    /// from it. `None`: the bind pose's box grown by a quarter of its diagonal on every
    /// side. A pose outside it is logged once. Unused for a mesh without a skin.
    pub skin_reach: Option<(::glam::Vec3, ::glam::Vec3)>,
}

impl Default for Fur {
    fn default() -> Self {
        Self {
            hair: HairParams::default(),
            shade: ShadeParams::default(),
            voxel: VoxelParams::default(),
            draw_mesh: true,
            skin_reach: None,
        }
    }
}

/// Lets pelage's compute passes read every camera's depth: adds `TEXTURE_BINDING` to
/// each [`Camera3d`]'s depth texture usages (as Bevy's own occlusion culling does).
/// The strand rasterizer culls and depth-tests the hair against the opaque depth it
/// samples; without the flag Bevy's depth texture is a render attachment only.
fn let_pelage_read_depth(mut cameras: Query<&mut Camera3d>) {
    for mut camera in &mut cameras {
        let usages = TextureUsages::from(camera.depth_texture_usages);
        // Written only when missing, so change detection stays quiet.
        if !usages.contains(TextureUsages::TEXTURE_BINDING) {
            camera.depth_texture_usages = (usages | TextureUsages::TEXTURE_BINDING).into();
        }
    }
}

/// Adds fur to every entity with [`Fur`] and [`Mesh3d`], drawn by every [`Camera3d`].
pub struct PelagePlugin;

impl Plugin for PelagePlugin {
    fn build(&self, app: &mut App) {
        app.init_asset::<GroomAsset>()
            .register_asset_loader(GroomLoader)
            .add_systems(PostUpdate, (read_fur_meshes, let_pelage_read_depth));
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        render_app
            .init_resource::<ExtractedFurs>()
            .init_resource::<FurInstances>()
            .init_resource::<PelageCpuTime>()
            .add_systems(ExtractSchedule, extract_furs)
            .add_systems(
                Render,
                prepare_furs.in_set(RenderSystems::PrepareBindGroups),
            )
            .add_systems(
                Core3d,
                draw_fur
                    .after(main_transparent_pass_3d)
                    .in_set(Core3dSystems::MainPass),
            );
    }
}

/// Reads a Bevy triangle-list mesh (positions, normals, indices, and `ATTRIBUTE_UV_0`
/// where it has one, so that a scene's texture maps over UVs follow the mesh's) as
/// pelage's mesh. Bevy's UVs (glTF's: `v` grows downwards from the texture's top) become
/// pelage's (OBJ's: `v` grows upwards from its bottom) as `(u, 1 - v)`.
pub fn pelage_mesh(mesh: &Mesh) -> Result<pelage::scene::Mesh, FurError> {
    if mesh.primitive_topology() != PrimitiveTopology::TriangleList {
        return Err(FurError::Mesh(format!(
            "fur grows on triangle lists, not {:?}",
            mesh.primitive_topology()
        )));
    }
    let vectors = |id, name: &str| -> Result<Vec<::glam::Vec3>, FurError> {
        match mesh.try_attribute(id) {
            Ok(VertexAttributeValues::Float32x3(v)) => {
                Ok(v.iter().map(|p| ::glam::Vec3::from_array(*p)).collect())
            }
            Ok(_) => Err(FurError::Mesh(format!("{name} are not Float32x3"))),
            Err(e) => Err(FurError::Mesh(format!("no {name}: {e}"))),
        }
    };
    let positions = vectors(Mesh::ATTRIBUTE_POSITION, "positions")?;
    let normals = vectors(Mesh::ATTRIBUTE_NORMAL, "normals")?;
    let indices = match mesh.try_indices() {
        Ok(Indices::U16(i)) => i.iter().map(|&i| u32::from(i)).collect(),
        Ok(Indices::U32(i)) => i.clone(),
        Err(e) => return Err(FurError::Mesh(format!("no indices: {e}"))),
    };
    let uvs = match mesh.try_attribute(Mesh::ATTRIBUTE_UV_0) {
        Ok(VertexAttributeValues::Float32x2(v)) => v
            .iter()
            .map(|&[u, v]| ::glam::Vec2::new(u, 1.0 - v))
            .collect(),
        Ok(_) => return Err(FurError::Mesh("UV_0 is not Float32x2".into())),
        Err(_) => Vec::new(),
    };
    let mesh = pelage::scene::Mesh {
        positions,
        normals,
        indices,
        uvs,
    };
    mesh.validate().map_err(|e| FurError::Mesh(e.to_string()))?;
    Ok(mesh)
}

/// pelage's mesh as a Bevy mesh (triangle list, positions, normals, `u32` indices, and
/// `ATTRIBUTE_UV_0` as `(u, 1 - v)` where it has UVs): pelage's built-in creature as a
/// Bevy asset, say. [`pelage_mesh`] reads it back as it was.
pub fn bevy_mesh(mesh: &pelage::scene::Mesh) -> Mesh {
    let vectors = |v: &[::glam::Vec3]| v.iter().map(|p| p.to_array()).collect::<Vec<_>>();
    let bevy_mesh = Mesh::new(
        PrimitiveTopology::TriangleList,
        bevy::asset::RenderAssetUsages::default(),
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, vectors(&mesh.positions))
    .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, vectors(&mesh.normals))
    .with_inserted_indices(Indices::U32(mesh.indices.clone()));
    if !mesh.has_uvs() {
        return bevy_mesh;
    }
    let uvs: Vec<[f32; 2]> = mesh.uvs.iter().map(|uv| [uv.x, 1.0 - uv.y]).collect();
    bevy_mesh.with_inserted_attribute(Mesh::ATTRIBUTE_UV_0, uvs)
}

/// Reads a skinned Bevy mesh's `ATTRIBUTE_JOINT_INDEX` (`Uint16x4`) and
/// `ATTRIBUTE_JOINT_WEIGHT` (`Float32x4`, or `Unorm16x4` as Bevy's quantisation leaves
/// it) as pelage's [`Skin`] of `joint_count` joints (the [`SkinnedMesh`]'s joint
/// entities), checked by pelage ([`Skin::validate`]): a joint index past the joint
/// count, a negative or non-finite weight, or weights not summing to 1 within
/// [`pelage::scene::skin::WEIGHT_SUM_TOLERANCE`] (1 %) is an error naming the vertex
/// (`skin.joints[17][2]`); sums within it are normalised on upload.
pub fn pelage_skin(mesh: &Mesh, joint_count: usize) -> Result<Skin, FurError> {
    let joints: Vec<[u32; 4]> = match mesh.try_attribute(Mesh::ATTRIBUTE_JOINT_INDEX) {
        Ok(VertexAttributeValues::Uint16x4(v)) => v.iter().map(|j| j.map(u32::from)).collect(),
        Ok(_) => return Err(FurError::Skin("joint indices are not Uint16x4".into())),
        Err(e) => return Err(FurError::Skin(format!("no joint indices: {e}"))),
    };
    let weights: Vec<[f32; 4]> = match mesh.try_attribute(Mesh::ATTRIBUTE_JOINT_WEIGHT) {
        Ok(VertexAttributeValues::Float32x4(v)) => v.clone(),
        Ok(VertexAttributeValues::Unorm16x4(v)) => v
            .iter()
            .map(|w| w.map(|x| f32::from(x) / f32::from(u16::MAX)))
            .collect(),
        Ok(_) => {
            return Err(FurError::Skin(
                "joint weights are neither Float32x4 nor Unorm16x4".into(),
            ));
        }
        Err(e) => return Err(FurError::Skin(format!("no joint weights: {e}"))),
    };
    let skin = Skin {
        joints,
        weights,
        // Past u32 (or MAX_JOINTS) pelage refuses it by name below.
        joint_count: u32::try_from(joint_count).unwrap_or(u32::MAX),
    };
    let vertices = mesh
        .try_attribute(Mesh::ATTRIBUTE_POSITION)
        .map_err(|e| FurError::Mesh(format!("no positions: {e}")))?
        .len();
    skin.validate(vertices).map_err(pelage::Error::from)?;
    Ok(skin)
}

/// The joint matrices pelage skins a mesh with, in the mesh's own space: per joint
/// `mesh_from_world · world_from_joint · inverse_bindpose`. Bevy skins a vertex with
/// `world_from_joint · inverse_bindpose` (its `SkinnedMesh` convention, glTF's: the
/// inverse bind matrix takes the mesh's bind-pose space into the joint's) and ignores
/// the mesh entity's own [`GlobalTransform`]; pelage grows in the mesh's space and the
/// view matrix multiplies the entity's transform back in, so the entity's inverse is
/// folded in here. `inverse_bindposes` needs at least one matrix per joint (extra ones
/// are unused, as in Bevy).
pub fn skin_joint_matrices(
    world_from_mesh: &GlobalTransform,
    world_from_joints: &[GlobalTransform],
    inverse_bindposes: &[Mat4],
) -> Result<Vec<::glam::Mat4>, FurError> {
    if inverse_bindposes.len() < world_from_joints.len() {
        return Err(FurError::Skin(format!(
            "{} joints but {} inverse bind matrices: needs one per joint",
            world_from_joints.len(),
            inverse_bindposes.len()
        )));
    }
    let mesh_from_world = Mat4::from(world_from_mesh.affine().inverse());
    Ok(world_from_joints
        .iter()
        .zip(inverse_bindposes)
        .map(|(joint, bindpose)| {
            let m = mesh_from_world * Mat4::from(joint.affine()) * *bindpose;
            ::glam::Mat4::from_cols_array(&m.to_cols_array())
        })
        .collect())
}

/// A skinned mesh's skin as the render world takes it.
#[derive(Debug)]
struct FurSkin {
    skin: Skin,
    /// The box the skinned mesh stays in (mesh space): [`Fur::skin_reach`] or its default.
    reach: (::glam::Vec3, ::glam::Vec3),
    /// Per joint, the bind-pose box of the vertices it moves (`None`: none). A vertex is a
    /// convex combination of its joints' transforms of it, so the union of each joint's
    /// transformed box holds the skinned mesh: the check of [`FurSkin::reach`].
    joint_boxes: Vec<Option<(::glam::Vec3, ::glam::Vec3)>>,
}

impl FurSkin {
    fn new(fur: &Fur, mesh: &pelage::scene::Mesh, skin: Skin) -> Self {
        let mut joint_boxes = vec![None; skin.joint_count as usize];
        for ((p, joints), weights) in mesh.positions.iter().zip(&skin.joints).zip(&skin.weights) {
            for (&j, &w) in joints.iter().zip(weights) {
                if w > 0.0 {
                    let b = &mut joint_boxes[j as usize];
                    *b = Some(
                        b.map_or((*p, *p), |(lo, hi): (::glam::Vec3, ::glam::Vec3)| {
                            (lo.min(*p), hi.max(*p))
                        }),
                    );
                }
            }
        }
        let reach = fur.skin_reach.unwrap_or_else(|| {
            let (lo, hi) = mesh.bounds();
            let grow = ::glam::Vec3::splat((hi - lo).length() * 0.25);
            (lo - grow, hi + grow)
        });
        Self {
            skin,
            reach,
            joint_boxes,
        }
    }

    /// Whether the mesh skinned by `matrices` may leave the reach box: the union of the
    /// joints' transformed boxes does (a bound, never an underestimate).
    fn may_leave_reach(&self, matrices: &[::glam::Mat4]) -> bool {
        let (lo, hi) = self.reach;
        let slack = (hi - lo).length() * 1e-5;
        self.joint_boxes
            .iter()
            .zip(matrices)
            .filter_map(|(b, m)| b.map(|b| (b, m)))
            .any(|((blo, bhi), m)| {
                (0..8).any(|corner| {
                    let c = ::glam::Vec3::new(
                        if corner & 1 == 0 { blo.x } else { bhi.x },
                        if corner & 2 == 0 { blo.y } else { bhi.y },
                        if corner & 4 == 0 { blo.z } else { bhi.z },
                    );
                    let p = m.transform_point3(c);
                    !(p.cmpge(lo - slack).all() && p.cmple(hi + slack).all())
                })
            })
    }
}

/// Whether `mesh` has morph targets (which the fur does not follow). Only Bevy's
/// `morph` feature (this crate's `morph`) lets a mesh have them: without it, `false`.
fn has_morph_targets(mesh: &Mesh) -> bool {
    #[cfg(feature = "morph")]
    {
        mesh.try_has_morph_targets().unwrap_or(false)
    }
    #[cfg(not(feature = "morph"))]
    {
        let _ = mesh;
        false
    }
}

/// An entity's fur as read from the main world: the parameters, pelage's copy of the
/// mesh and, for a skinned mesh, its skin, and its groom.
#[derive(Debug)]
struct FurSetup {
    fur: Fur,
    mesh: pelage::scene::Mesh,
    skin: Option<FurSkin>,
    groom: Option<FurGroom>,
}

/// A [`Groom`] as pelage's scene takes it: the strands resampled, guides, dynamics.
#[derive(Debug)]
struct FurGroom {
    strands: pelage::scene::Resampled,
    guides: Option<pelage::scene::GuideParams>,
    dynamics: Option<pelage::scene::DynamicsParams>,
}

impl FurGroom {
    /// `groom`'s file (loaded) resampled as it asks; `Ok(None)` while it loads.
    fn read(
        groom: &Groom,
        grooms: &Assets<GroomAsset>,
        server: &AssetServer,
    ) -> Result<Option<Self>, FurError> {
        let Some(asset) = grooms.get(&groom.asset) else {
            if let bevy::asset::LoadState::Failed(e) = server.load_state(&groom.asset) {
                return Err(FurError::Groom(format!("the file did not load: {e}")));
            }
            return Ok(None);
        };
        if let Some(guides) = &groom.guides {
            guides.validate().map_err(pelage::Error::from)?;
        }
        let strands = asset
            .groom
            .resample(groom.segments)
            .map_err(|e| FurError::Groom(format!("Groom::segments = {}: {e}", groom.segments)))?;
        Ok(Some(Self {
            strands,
            guides: groom.guides.clone(),
            dynamics: groom.dynamics.clone(),
        }))
    }
}

/// What the render world builds an entity's fur from, made when [`Fur`], the mesh, its
/// [`SkinnedMesh`] or its [`Groom`] changes: the parameters, pelage's copy of the mesh,
/// its skin and groom, with a number that changes with them.
#[derive(Component, Clone, Debug)]
pub struct FurSource {
    setup: Arc<FurSetup>,
    generation: u64,
}

/// The mesh asset a [`FurSource`] (or its error) was made from (`None`: a groom without
/// a mesh).
#[derive(Component)]
struct FurSourceOf(Option<AssetId<Mesh>>);

/// Reads the mesh (and the skin of a [`SkinnedMesh`], the file of a [`Groom`]) of every
/// entity whose [`Fur`], [`Mesh3d`], [`SkinnedMesh`] or [`Groom`] is new or changed (or
/// whose mesh, inverse bind matrices or groom had not loaded yet) into a [`FurSource`];
/// logs a mesh that cannot carry fur, a groom that did not load, or a [`Fur`] with
/// neither a mesh nor a groom, once.
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
fn read_fur_meshes(
    mut commands: Commands,
    meshes: Res<Assets<Mesh>>,
    bindposes: Option<Res<Assets<SkinnedMeshInverseBindposes>>>,
    grooms: Res<Assets<GroomAsset>>,
    server: Res<AssetServer>,
    furs: Query<
        (
            Entity,
            Ref<Fur>,
            Option<Ref<Mesh3d>>,
            Option<Ref<SkinnedMesh>>,
            Option<Ref<Groom>>,
            Option<&FurSourceOf>,
        ),
        Or<(
            Changed<Fur>,
            Changed<Mesh3d>,
            Changed<SkinnedMesh>,
            Changed<Groom>,
            Without<FurSourceOf>,
        )>,
    >,
    mut unskinned: RemovedComponents<SkinnedMesh>,
    mut ungroomed: RemovedComponents<Groom>,
    mut unmeshed: RemovedComponents<Mesh3d>,
    mut generation: Local<u64>,
) {
    // An entity that lost its skin, groom or mesh is read again (next frame) without it.
    for entity in unskinned
        .read()
        .chain(ungroomed.read())
        .chain(unmeshed.read())
    {
        if let Ok(mut e) = commands.get_entity(entity) {
            e.remove::<FurSourceOf>();
        }
    }
    for (entity, fur, mesh3d, skinned, groom, done) in &furs {
        let id = mesh3d.as_ref().map(|m| m.id());
        let changed = fur.is_changed()
            || mesh3d.as_ref().is_some_and(|m| m.is_changed())
            || skinned.as_ref().is_some_and(|s| s.is_changed())
            || groom.as_ref().is_some_and(|g| g.is_changed());
        if done.is_some_and(|d| d.0 == id) && !changed {
            continue;
        }
        let mesh = match id {
            Some(id) => match meshes.get(id) {
                Some(mesh) => Some(mesh),
                None => continue, // not loaded yet: tried again next frame
            },
            None if groom.is_some() => None, // a groom alone
            None => {
                let e = "Fur needs a Mesh3d on its entity to grow from, or a Groom";
                refuse(&mut commands, entity, id, FurError::Mesh(e.into()));
                continue;
            }
        };
        if let Some(skinned) = &skinned
            && mesh.is_some()
            && bindposes
                .as_ref()
                .is_none_or(|b| b.get(&skinned.inverse_bindposes).is_none())
        {
            continue; // the inverse bind matrices are not loaded yet: tried again
        }
        let groom = match groom.map(|g| FurGroom::read(&g, &grooms, &server)) {
            None => None,
            Some(Ok(Some(groom))) => Some(groom),
            Some(Ok(None)) => continue, // the groom is not loaded yet: tried again
            Some(Err(e)) => {
                refuse(&mut commands, entity, id, e);
                continue;
            }
        };
        *generation += 1;
        let setup = match mesh {
            Some(mesh) => fur_setup(entity, &fur, mesh, skinned.as_deref(), &bindposes, groom),
            // A groom-only scene: pelage draws the groom alone (no mesh, no skin).
            None => Ok(FurSetup {
                fur: (*fur).clone(),
                mesh: pelage::scene::Mesh::default(),
                skin: None,
                groom,
            }),
        };
        match setup {
            Ok(setup) => {
                commands.entity(entity).insert((
                    FurSource {
                        setup: Arc::new(setup),
                        generation: *generation,
                    },
                    FurSourceOf(id),
                ));
            }
            Err(e) => refuse(&mut commands, entity, id, e),
        }
    }
}

/// Logs why `entity` gets no fur, once: it is read again only when it changes.
fn refuse(commands: &mut Commands, entity: Entity, id: Option<AssetId<Mesh>>, e: FurError) {
    error!("pelage: no fur on {entity}: {e}");
    commands
        .entity(entity)
        .insert(FurSourceOf(id))
        .remove::<FurSource>();
}

/// An entity's [`FurSetup`] on its Bevy `mesh` (with the skin of `skinned`).
fn fur_setup(
    entity: Entity,
    fur: &Fur,
    mesh: &Mesh,
    skinned: Option<&SkinnedMesh>,
    bindposes: &Option<Res<Assets<SkinnedMeshInverseBindposes>>>,
    groom: Option<FurGroom>,
) -> Result<FurSetup, FurError> {
    if has_morph_targets(mesh) {
        warn!("pelage: the mesh of {entity} has morph targets; the fur grows on it without them");
    }
    let pelage_mesh = pelage_mesh(mesh)?;
    let skin = match skinned {
        Some(skinned) => {
            let bindposes = bindposes
                .as_ref()
                .and_then(|b| b.get(&skinned.inverse_bindposes))
                .map_or(0, |b| b.len());
            if bindposes < skinned.joints.len() {
                return Err(FurError::Skin(format!(
                    "{} joints but {bindposes} inverse bind matrices: needs one per joint",
                    skinned.joints.len()
                )));
            }
            let skin = pelage_skin(mesh, skinned.joints.len())?;
            Some(FurSkin::new(fur, &pelage_mesh, skin))
        }
        None => None,
    };
    Ok(FurSetup {
        fur: fur.clone(),
        mesh: pelage_mesh,
        skin,
        groom,
    })
}

/// One furred entity as the render world sees it this frame.
struct ExtractedFur {
    entity: Entity,
    source: FurSource,
    world_from_model: Mat4,
    /// A skinned mesh's joint matrices (mesh space) this frame, or why there are none.
    joints: Option<Result<Vec<::glam::Mat4>, String>>,
}

/// This frame's furred entities, time and key light.
#[derive(Resource, Default)]
struct ExtractedFurs {
    furs: Vec<ExtractedFur>,
    time: f32,
    /// Direction the light travels in (world space), linear colour, illuminance (lux).
    light: Option<(Vec3, Vec3, f32)>,
}

/// This frame's furred entities (with a skinned mesh's joint matrices), time and light.
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
fn extract_furs(
    mut extracted: ResMut<ExtractedFurs>,
    time: Extract<Res<Time>>,
    furs: Extract<Query<(Entity, &FurSource, &GlobalTransform, Option<&SkinnedMesh>)>>,
    transforms: Extract<Query<&GlobalTransform>>,
    bindposes: Extract<Option<Res<Assets<SkinnedMeshInverseBindposes>>>>,
    lights: Extract<Query<(&DirectionalLight, &GlobalTransform)>>,
    mut joint_globals: Local<Vec<GlobalTransform>>,
    mut cpu: ResMut<PelageCpuTime>,
) {
    let start = std::time::Instant::now();
    extracted.time = time.elapsed_secs();
    extracted.furs.clear();
    for (entity, source, transform, skinned) in &furs {
        let joints = match (&source.setup.skin, skinned) {
            (Some(_), Some(skinned)) => Some(extract_joints(
                transform,
                skinned,
                &transforms,
                bindposes.as_deref(),
                &mut joint_globals,
            )),
            // Removed this frame: `read_fur_meshes` reads the mesh again without it.
            (Some(_), None) => None,
            (None, _) => None,
        };
        extracted.furs.push(ExtractedFur {
            entity,
            source: source.clone(),
            world_from_model: transform.to_matrix(),
            joints,
        });
    }
    extracted.light = lights.iter().next().map(|(light, transform)| {
        let color = light.color.to_linear();
        (
            transform.forward().as_vec3(),
            Vec3::new(color.red, color.green, color.blue),
            light.illuminance,
        )
    });
    cpu.extract = start.elapsed();
}

/// A skinned mesh's joint matrices in its own space this frame ([`skin_joint_matrices`]
/// of its joints' [`GlobalTransform`]s, gathered into `joint_globals`), or why not.
fn extract_joints(
    world_from_mesh: &GlobalTransform,
    skinned: &SkinnedMesh,
    transforms: &Query<&GlobalTransform>,
    bindposes: Option<&Assets<SkinnedMeshInverseBindposes>>,
    joint_globals: &mut Vec<GlobalTransform>,
) -> Result<Vec<::glam::Mat4>, String> {
    joint_globals.clear();
    for &joint in &skinned.joints {
        let global = transforms
            .get(joint)
            .map_err(|_| format!("joint entity {joint} has no GlobalTransform"))?;
        joint_globals.push(*global);
    }
    let bindposes = bindposes
        .and_then(|b| b.get(&skinned.inverse_bindposes))
        .ok_or("the inverse bind matrices are gone")?;
    skin_joint_matrices(world_from_mesh, joint_globals, bindposes).map_err(|e| e.to_string())
}

/// The CPU time the plugin spent in Bevy's last frame (a render-world resource):
/// extracting (and a skinned mesh's joint matrices), preparing (uniform writes, and
/// building stages when a fur or camera is new) and recording into Bevy's encoder,
/// summed over cameras. None includes a wait for the GPU: the plugin never waits.
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct PelageCpuTime {
    /// The `ExtractSchedule`: furred entities, light and joint matrices read.
    pub extract: std::time::Duration,
    /// `RenderSystems::PrepareBindGroups`: stages built or prepared.
    pub prepare: std::time::Duration,
    /// The `Core3d` schedules: passes recorded.
    pub record: std::time::Duration,
}

/// pelage on Bevy's device.
#[derive(Resource)]
struct PelageGpu(Gpu);

/// An entity's fur in the render world: one pelage [`Frame`] per camera.
struct FurInstance {
    generation: u64,
    setup: Arc<FurSetup>,
    /// A pose left [`FurSkin::reach`] and was logged.
    left_reach: bool,
    /// Per view (render-world camera entity): the fur's frame for its targets.
    views: HashMap<Entity, ViewFur>,
}

/// A camera's frame of one fur, with the targets it was built for.
struct ViewFur {
    format: TargetFormat,
    size: (u32, u32),
    frame: Frame,
    /// Prepared for this frame.
    ready: bool,
}

/// The 3D cameras of this frame, with their targets.
type CameraViews<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static ExtractedView,
        &'static ExtractedCamera,
        &'static ViewTarget,
        &'static ViewDepthStencilTexture,
    ),
    With<Camera3d>,
>;

/// (entity, camera) pairs whose hair pass failed, with the targets it failed for.
type FailedViews = HashMap<(Entity, Entity), (TargetFormat, (u32, u32))>;

/// Every furred entity's render-world state, and the errors already logged.
#[derive(Resource, Default)]
struct FurInstances {
    instances: HashMap<Entity, FurInstance>,
    /// Entities (and the generation) whose error was logged: skipped until they change.
    failed: HashMap<Entity, u64>,
    /// (entity, view) pairs whose hair pass failed for the given targets.
    failed_views: FailedViews,
}

impl FurInstance {
    /// The fur's frame for a camera's targets: the scene of the entity's mesh and
    /// [`Fur`], its voxel shadow, one light (set every frame).
    fn view_frame(
        &self,
        gpu: &Gpu,
        format: TargetFormat,
        size: (u32, u32),
    ) -> Result<ViewFur, FurError> {
        let FurSetup {
            fur,
            mesh,
            skin,
            groom,
        } = &*self.setup;
        let mut shade = fur.shade.clone();
        if shade.transparency == pelage::scene::Transparency::Opaque {
            shade.sample_count = format.samples;
        }
        let scene = Scene {
            mesh: mesh.clone(),
            hair: fur.hair.clone(),
            groom: groom.as_ref().map(|g| g.strands.clone()),
            guides: groom.as_ref().and_then(|g| g.guides.clone()),
            dynamics: groom.as_ref().and_then(|g| g.dynamics.clone()),
            motion: None,
            skin: None,
            shadow: ShadowParams::Voxel(fur.voxel.clone()),
            shade,
            camera: Default::default(),
            lights: vec![Light::default()],
        };
        let target = FrameTarget {
            draw_mesh: fur.draw_mesh,
            ..FrameTarget::new(format, size.0, size.1)
        };
        let frame = match skin {
            Some(skin) => Frame::with_skin(gpu, &scene, &skin.skin, skin.reach, &target)?,
            None => Frame::new(gpu, &scene, &target)?,
        };
        Ok(ViewFur {
            format,
            size,
            frame,
            ready: false,
        })
    }
}

/// The targets of a camera as pelage is told about them.
fn target_format(target: &ViewTarget, depth: &ViewDepthStencilTexture) -> TargetFormat {
    TargetFormat {
        color: target.main_texture_format(),
        depth: depth.texture().format(),
        samples: depth.texture().sample_count(),
        // Bevy's perspective and orthographic projections are both reverse-Z.
        reverse_z: true,
    }
}

/// A camera's view of one fur: Bevy's view matrix times the entity's model matrix
/// (pelage works in the mesh's space), Bevy's projection.
fn camera_matrices(view: &ExtractedView, world_from_model: Mat4) -> CameraMatrices {
    let glam = |m: Mat4| ::glam::Mat4::from_cols_array(&m.to_cols_array());
    let view_from_world = view.world_from_view.to_matrix().inverse();
    CameraMatrices {
        view: glam(view_from_world * world_from_model),
        projection: glam(view.clip_from_view),
    }
}

/// Builds or rebuilds each entity's pelage stages and each camera's hair pass, and
/// writes this frame's uniforms (strand time, light, camera). Only queue writes.
#[allow(clippy::too_many_arguments)]
fn prepare_furs(
    mut commands: Commands,
    gpu: Option<Res<PelageGpu>>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    adapter: Res<RenderAdapterInfo>,
    extracted: Res<ExtractedFurs>,
    mut state: ResMut<FurInstances>,
    views: CameraViews,
    mut cpu: ResMut<PelageCpuTime>,
) {
    let start = std::time::Instant::now();
    cpu.record = std::time::Duration::ZERO;
    let Some(gpu) = gpu else {
        let gpu = Gpu::from_device(
            device.wgpu_device().clone(),
            (**queue).clone(),
            Some((**adapter).clone()),
        );
        commands.insert_resource(PelageGpu(gpu));
        return; // the resource is there from the next frame on
    };
    let gpu = &gpu.0;
    let FurInstances {
        instances,
        failed,
        failed_views,
    } = &mut *state;
    instances.retain(|e, _| extracted.furs.iter().any(|f| f.entity == *e));
    failed.retain(|e, _| extracted.furs.iter().any(|f| f.entity == *e));
    failed_views
        .retain(|(e, v), _| extracted.furs.iter().any(|f| f.entity == *e) && views.contains(*v));

    for fur in &extracted.furs {
        let entity = fur.entity;
        let generation = fur.source.generation;
        if failed.get(&entity) == Some(&generation) {
            continue;
        }
        if instances
            .get(&entity)
            .is_none_or(|i| i.generation != generation)
        {
            instances.insert(
                entity,
                FurInstance {
                    generation,
                    setup: fur.source.setup.clone(),
                    left_reach: false,
                    views: HashMap::new(),
                },
            );
        }
        let Some(instance) = instances.get_mut(&entity) else {
            continue;
        };
        if let Err(e) = prepare_instance(gpu, instance, fur, &extracted, &views, failed_views) {
            error!("pelage: no fur on {entity}: {e}");
            failed.insert(entity, generation);
            instances.remove(&entity);
        }
    }
    cpu.prepare = start.elapsed();
}

/// One fur's frame for each camera: the last frame's after-submit step (Bevy has
/// submitted it), the joint matrices of a skinned mesh, the light in the mesh's space,
/// then every stage's uniforms.
fn prepare_instance(
    gpu: &Gpu,
    instance: &mut FurInstance,
    fur: &ExtractedFur,
    extracted: &ExtractedFurs,
    views: &CameraViews,
    failed_views: &mut FailedViews,
) -> Result<(), FurError> {
    // The light in the mesh's space (pelage works there).
    let model_from_world = fur.world_from_model.inverse();
    let (direction, color, illuminance) =
        extracted
            .light
            .unwrap_or((Vec3::new(-0.85, -0.6, 0.1), Vec3::ONE, 0.0));
    let direction = model_from_world
        .transform_vector3(direction)
        .normalize_or(Vec3::NEG_Y);
    let v3 = |v: Vec3| ::glam::Vec3::from_array(v.to_array());
    let joints = match &fur.joints {
        Some(Ok(joints)) => Some(joints.as_slice()),
        Some(Err(e)) => return Err(FurError::Skin(e.clone())),
        None => None,
    };
    if let (Some(skin), Some(joints)) = (&instance.setup.skin, joints)
        && !instance.left_reach
        && skin.may_leave_reach(joints)
    {
        instance.left_reach = true;
        let (lo, hi) = skin.reach;
        warn!(
            "pelage: the skinned mesh of {} may leave its reach box {lo} .. {hi} (mesh space): \
             its fur's shadow may be clipped; set Fur::skin_reach to a box that holds every pose",
            fur.entity
        );
    }

    for view in instance.views.values_mut() {
        view.ready = false;
    }
    for (view_entity, view, camera, target, depth) in views {
        let format = target_format(target, depth);
        let size = (view.viewport.z, view.viewport.w);
        if size.0 == 0 || size.1 == 0 {
            continue;
        }
        let key = (fur.entity, view_entity);
        if failed_views.get(&key) == Some(&(format, size)) {
            continue;
        }
        let fresh = instance
            .views
            .get(&view_entity)
            .is_some_and(|h| h.format == format && h.size == size);
        if !fresh {
            instance.views.remove(&view_entity);
            match instance.view_frame(gpu, format, size) {
                Ok(frame) => {
                    instance.views.insert(view_entity, frame);
                }
                Err(e) => {
                    error!(
                        "pelage: the fur on {} cannot draw into camera {view_entity}'s targets: {e}",
                        fur.entity
                    );
                    failed_views.insert(key, (format, size));
                    continue;
                }
            }
        }
        let Some(view_fur) = instance.views.get_mut(&view_entity) else {
            continue;
        };
        let frame = &mut view_fur.frame;
        frame.after_submit(gpu)?;
        if let Some(joints) = joints {
            frame.set_joint_matrices(&gpu.queue, joints)?;
        }
        frame.set_lights(&[Light::Directional(pelage::scene::DirectionalLight {
            direction: v3(direction),
            color: v3(color),
            intensity: illuminance * camera.exposure,
        })])?;
        frame.prepare(
            &gpu.queue,
            extracted.time,
            &camera_matrices(view, fur.world_from_model),
        )?;
        view_fur.ready = true;
    }
    instance.views.retain(|v, _| views.contains(*v));
    Ok(())
}

/// Records each fur's frame for the current camera into its targets (strands, shadow,
/// hair; recording only).
fn draw_fur(
    view: ViewQuery<(&ViewTarget, &ViewDepthStencilTexture)>,
    mut state: ResMut<FurInstances>,
    mut cpu: ResMut<PelageCpuTime>,
    mut ctx: RenderContext,
) {
    let start = std::time::Instant::now();
    let view_entity = view.entity();
    let (target, depth): QueryItem<(&ViewTarget, &ViewDepthStencilTexture)> = view.into_inner();
    let color = target.get_color_attachment();
    let depth_attachment = depth.get_attachment(StoreOp::Store);
    let size = depth.texture().size();
    let views = TargetViews {
        color: color.view,
        resolve: color.resolve_target,
        depth: depth_attachment.view,
        depth_sampled: None,
        width: size.width,
        height: size.height,
        // Bevy's main passes have drawn (and cleared) the target already.
        load: matches!(color.ops.load, LoadOp::Load),
    };
    let mut failed = Vec::new();
    for (entity, instance) in &state.instances {
        let Some(view_fur) = instance.views.get(&view_entity) else {
            continue;
        };
        if !view_fur.ready {
            continue;
        }
        let encoder = ctx.command_encoder();
        if let Err(e) = view_fur.frame.record(encoder, &views, None) {
            error!("pelage: the fur on {entity} was not drawn: {e}");
            failed.push((*entity, instance.generation));
        }
    }
    for (entity, generation) in failed {
        state.instances.remove(&entity);
        state.failed.insert(entity, generation);
    }
    cpu.record += start.elapsed();
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A two-joint skin of the unit icosphere: the upper half on joint 1.
    fn sphere_skin() -> (pelage::scene::Mesh, Skin) {
        let mesh = pelage::scene::Mesh::icosphere(1.0, 1).unwrap();
        let joints = (mesh.positions.iter())
            .map(|p| if p.y > 0.0 { [1, 0, 0, 0] } else { [0; 4] })
            .collect();
        let skin = Skin {
            joints,
            weights: vec![[1.0, 0.0, 0.0, 0.0]; mesh.positions.len()],
            joint_count: 2,
        };
        (mesh, skin)
    }

    #[test]
    fn a_pose_that_may_leave_the_reach_box_is_seen() {
        let (mesh, skin) = sphere_skin();
        let fur = Fur::default();
        let skin = FurSkin::new(&fur, &mesh, skin);
        // The default box: the bind box grown by a quarter of its diagonal.
        let (lo, hi) = mesh.bounds();
        let grow = (hi - lo).length() * 0.25;
        assert_eq!(skin.reach, (lo - grow, hi + grow));
        let still = [::glam::Mat4::IDENTITY; 2];
        assert!(!skin.may_leave_reach(&still));
        // The upper half turned about the centre stays inside; moved up by 1 it leaves.
        let turned = [::glam::Mat4::IDENTITY, ::glam::Mat4::from_rotation_z(1.0)];
        assert!(!skin.may_leave_reach(&turned));
        let lifted = [
            ::glam::Mat4::IDENTITY,
            ::glam::Mat4::from_translation(::glam::Vec3::Y),
        ];
        assert!(skin.may_leave_reach(&lifted));
        // The caller's box is used as given.
        let tight = Fur {
            skin_reach: Some((::glam::Vec3::splat(-1.0), ::glam::Vec3::splat(1.0))),
            ..Fur::default()
        };
        let (mesh, bend) = sphere_skin();
        let tight = FurSkin::new(&tight, &mesh, bend);
        assert!(tight.may_leave_reach(&turned));
    }

    /// With Bevy's `morph` feature a mesh with morph targets is seen (and logged).
    #[cfg(feature = "morph")]
    #[test]
    fn morph_targets_are_seen() {
        let mesh = bevy_mesh(&pelage::scene::Mesh::icosphere(1.0, 0).unwrap());
        assert!(!has_morph_targets(&mesh));
        // One target of 12 vertices (the icosahedron's), displacing nothing.
        let target = vec![bevy::mesh::morph::MorphAttributes::default(); 12];
        assert!(has_morph_targets(&mesh.with_morph_targets(target)));
    }
}
