//! The stages wired once: a [`Frame`] owns stage 1 (strands), stage 2 (a shadow and its
//! hand-over per light) and stage 3 (the hair pass), and none of the targets. The
//! [`Renderer`](crate::Renderer), the Bevy plugin, the browser demo and an engine all
//! build this one object from a [`Scene`] and record it into their own encoder and views.
//!
//! Every stage has one shape: `prepare` writes its uniforms with the queue, `encode`
//! records into the caller's encoder (no device), and one step after the caller's submit
//! ([`Frame::after_submit`]) takes readbacks and grows pools without ever waiting.

use glam::Vec3;
use pelage_gpu::audit;
use pelage_gpu::{FramePlan, Gpu, GpuTimer, PassInfo, ShaderBinding, wgpu};
use pelage_scene::{
    CameraMatrices, Light, Mesh, MeshMotion, ShadowParams, Skin, SkinBend, SkinnedSdf,
};
use pelage_shade::{HairInputs, HairPass, TargetFormat, TargetViews, Visibility, VolumeGrid};
use pelage_shadow::{LightVisibility, ShadowMethod};
use pelage_strands::{
    GroomStrands, GrowStrands, GuideStrands, MeshBuffers, MeshSkin, SimulateStrands, StrandFrame,
    StrandSource, StrandStage,
};

use pelage_scene::Scene;

mod update;
use crate::bridge::TargetBridge;

/// The targets a [`Frame`] records into, as the caller describes them (the views
/// themselves come at every [`Frame::record`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameTarget {
    /// Colour and depth formats, sample count, depth direction.
    pub format: TargetFormat,
    /// Size in pixels.
    pub width: u32,
    /// Size in pixels.
    pub height: u32,
    /// pelage draws the scene's mesh (shaded and shadowed as its own renders do);
    /// `false` when the caller draws the mesh itself (a groom-only scene draws none).
    pub draw_mesh: bool,
}

impl FrameTarget {
    /// A `width` x `height` target in `format`, with the mesh drawn by pelage.
    pub fn new(format: TargetFormat, width: u32, height: u32) -> Self {
        Self {
            format,
            width,
            height,
            draw_mesh: true,
        }
    }
}

/// Builds stage 1 of `source` on `mesh` (already uploaded, or `None` to upload
/// `scene.mesh` here), returning the mesh buffers every stage reads, their box grown to
/// wherever `scene.motion` takes the mesh. In a groom-only scene (`groom_only`) the mesh
/// buffers are an empty stand-in. The one place a strand source becomes a stage.
fn build_strands(
    source: StrandSource<'_>,
    gpu: &Gpu,
    scene: &Scene,
    mesh: Option<MeshBuffers>,
    groom_only: bool,
) -> crate::Result<(MeshBuffers, Box<dyn StrandStage>)> {
    let (hair, rest) = (&scene.hair, &scene.mesh);
    let upload = |mesh: Option<MeshBuffers>| -> crate::Result<MeshBuffers> {
        Ok(match mesh {
            Some(mesh) => mesh,
            None => MeshBuffers::upload(gpu, rest)?,
        })
    };
    // The mesh's box is wherever the motion takes it: a simulation sizes itself
    // from it (grown before the stage is built); the stateless methods after.
    let moved = |mut mesh: MeshBuffers| -> crate::Result<MeshBuffers> {
        if let Some(motion) = &scene.motion {
            motion.validate()?;
            mesh.bounds = motion.reach(mesh.bounds);
        }
        if let Some(skin) = &scene.skin {
            skin.validate()?;
            mesh.bounds = skin.reach(mesh.bounds);
        }
        Ok(mesh)
    };
    let (mesh, strands): (MeshBuffers, Box<dyn StrandStage>) = match source {
        StrandSource::Grown => {
            let mesh = upload(mesh)?;
            let strands = GrowStrands::new(gpu, rest, &mesh, hair)?;
            (moved(mesh)?, Box::new(strands))
        }
        StrandSource::Groom(groom) if groom_only => {
            let strands = GroomStrands::new(gpu, groom, hair)?;
            let mesh = match mesh {
                Some(mesh) => mesh,
                None => no_mesh(gpu, strands.buffers().reach)?,
            };
            (mesh, Box::new(strands))
        }
        StrandSource::Groom(groom) => {
            let mesh = upload(mesh)?;
            let strands = GroomStrands::new(gpu, groom, hair)?;
            (moved(mesh)?, Box::new(strands))
        }
        StrandSource::Guides(groom, guides) => {
            let mesh = upload(mesh)?;
            let strands = GuideStrands::new(gpu, rest, &mesh, groom, hair, guides)?;
            (moved(mesh)?, Box::new(strands))
        }
        StrandSource::SimulatedGuides(groom, guides, dynamics) => {
            let mesh = moved(upload(mesh)?)?;
            let strands = GuideStrands::simulated(gpu, rest, &mesh, groom, hair, guides, dynamics)?;
            (mesh, Box::new(strands))
        }
        StrandSource::Simulated(groom, dynamics) => {
            let mesh = moved(upload(mesh)?)?;
            let strands = match groom {
                Some(groom) => SimulateStrands::groom(gpu, groom, rest, &mesh, hair, dynamics)?,
                None => SimulateStrands::grown(gpu, rest, &mesh, hair, dynamics)?,
            };
            (mesh, Box::new(strands))
        }
    };
    Ok((mesh, strands))
}

/// The stages of a frame built from a [`Scene`], owning no target: prepared with the
/// time, camera and lights, recorded into the caller's encoder and views.
///
/// Each frame: [`Frame::prepare`] with the view and projection, [`Frame::record`] into
/// the caller's encoder (or its two parts, [`Frame::record_before_shade`] and
/// [`Frame::record_shade`], with the caller's own passes between them), the caller's
/// submit, then [`Frame::after_submit`]. Nothing waits for the GPU and nothing is
/// created per frame in steady state.
#[derive(Debug)]
pub struct Frame {
    mesh: MeshBuffers,
    strands: Box<dyn StrandStage>,
    /// One shadow per light, with the pass that hands it to the hair.
    shadows: Vec<(Box<dyn ShadowMethod>, LightVisibility)>,
    /// Per-vertex light visibility, `stride` floats per light (none without shadows).
    visibility: Option<wgpu::Buffer>,
    stride: u32,
    hair: Box<dyn HairPass>,
    lights: Vec<Light>,
    /// Where point lights aim their shadows (the centre of the hair's reach).
    shadow_target: Vec3,
    /// The world box the hair can reach: its size on screen sets the level of detail.
    reach: (Vec3, Vec3),
    target: FrameTarget,
    /// The mesh's motion and its rest pose, written into the mesh buffers every frame.
    motion: Option<(MeshMotion, Mesh)>,
    /// The skinning pass writing the mesh buffers before stage 1, and the scene's rig
    /// that sets its joint matrices every prepare (`None`: the caller sets them).
    skin: Option<(MeshSkin, Option<SkinBend>)>,
    /// The steps a frame records, in order: what [`Frame::record`] walks and what the
    /// plan is built from.
    steps: Vec<Step>,
    /// The passes of those steps, checked at construction.
    plan: FramePlan,
    /// The frame stage 1 last prepared, which every stage records.
    prepared: Option<StrandFrame>,
    /// Targets the transparency method can draw, around it, when it cannot draw the
    /// caller's (multisampled, or reverse-Z for some methods); `None`: the hair pass
    /// draws into the caller's targets.
    bridge: Option<TargetBridge>,
    /// What the frame was built from (or last updated to), for [`Frame::update`].
    built: update::Built,
}

impl Frame {
    /// Uploads `scene`'s mesh, samples the roots (or uploads the groom), builds a shadow
    /// and its hand-over per light and the hair pass for `target`.
    pub fn new(gpu: &Gpu, scene: &Scene, target: &FrameTarget) -> crate::Result<Self> {
        Self::build(gpu, scene, None, target, None)
    }

    /// [`Frame::new`] on mesh buffers the caller owns (its vertex and index buffers,
    /// wrapped with [`MeshBuffers::from_buffers`], that it may rewrite every frame:
    /// skinning, say); `scene.mesh` is the rest pose the roots are sampled on.
    pub fn with_mesh_buffers(
        gpu: &Gpu,
        scene: &Scene,
        mesh: MeshBuffers,
        target: &FrameTarget,
    ) -> crate::Result<Self> {
        Self::build(gpu, scene, Some(mesh), target, None)
    }

    /// [`Frame::new`] with `scene.mesh` skinned on the GPU by `skin` every frame (a
    /// [`MeshSkin`] recorded before stage 1): `scene.mesh` is the bind pose the roots are
    /// sampled on, the caller sets the joint matrices before each prepare
    /// ([`Frame::set_joint_matrices`]), and `reach` is a world box the
    /// skinned mesh stays in, in every pose (shadow maps of the mesh and a simulation's
    /// grid size themselves from it). Until the first matrices the mesh is in its bind
    /// pose (every joint the identity). Refused with `scene.skin` or `scene.motion` set,
    /// and in a groom-only scene.
    pub fn with_skin(
        gpu: &Gpu,
        scene: &Scene,
        skin: &Skin,
        reach: (Vec3, Vec3),
        target: &FrameTarget,
    ) -> crate::Result<Self> {
        if scene.skin.is_some() {
            return Err(pelage_scene::ParamError::new(
                "skin",
                "a [skin] rig and a caller's skin",
                "give the frame one skin: the scene's rig or the caller's, not both",
            )
            .into());
        }
        if !(reach.0.is_finite() && reach.1.is_finite() && reach.0.cmple(reach.1).all()) {
            return Err(pelage_scene::ParamError::new(
                "skin.reach",
                reach,
                "must be a finite box with min <= max",
            )
            .into());
        }
        let mut mesh = MeshBuffers::upload(gpu, &scene.mesh)?;
        mesh.bounds = (reach.0.min(mesh.bounds.0), reach.1.max(mesh.bounds.1));
        Self::build(gpu, scene, Some(mesh), target, Some(skin))
    }

    /// The one sequence that builds the stages: reach, strand source, shadow method per
    /// light, visibility stride and hand-over per light, hair pass, plan.
    fn build(
        gpu: &Gpu,
        scene: &Scene,
        mesh: Option<MeshBuffers>,
        target: &FrameTarget,
        skin: Option<&Skin>,
    ) -> crate::Result<Self> {
        // The targets' size first: every method would refuse it in its own words.
        pelage_shade::check_image_size(gpu, target.width, target.height)?;
        // The scene's rig, or the caller's skin: either skins the mesh every frame.
        let rig = scene.skin.as_ref().map(|bend| bend.skin(&scene.mesh));
        let skin = skin.or(rig.as_ref());
        // A groom with an empty mesh is a groom-only scene: nothing of the mesh is drawn
        // or shadowed, and nothing moves it or binds roots to it.
        let groom_only = scene.groom.is_some() && scene.mesh.indices.is_empty();
        if groom_only {
            let refuse = |name: &str, what: &str| {
                pelage_scene::ParamError::new(
                    name,
                    "set",
                    &format!(
                        "a groom-only scene (an empty mesh, [mesh] kind = \"none\") has no mesh {what}; give the scene a mesh or leave it out"
                    ),
                )
            };
            if scene.dynamics.is_some() {
                return Err(refuse("dynamics", "to bind the simulated roots to").into());
            }
            if scene.motion.is_some() {
                return Err(refuse("motion", "to move").into());
            }
            if scene.guides.is_some() {
                return Err(refuse("guides", "to root the render strands on").into());
            }
            if skin.is_some() {
                return Err(refuse("skin", "to skin").into());
            }
        }
        if skin.is_some() && scene.motion.is_some() {
            return Err(pelage_scene::ParamError::new(
                "skin",
                "set with motion",
                "a mesh is moved either rigidly (motion) or by its skin, not both: leave one out",
            )
            .into());
        }
        let draw_mesh = target.draw_mesh && !groom_only;
        let (mesh, mut strands) =
            build_strands(StrandSource::of(scene), gpu, scene, mesh, groom_only)?;
        // The resources that cross stages and that the frame may take from its caller,
        // named as the plan names them (for an audit of what each pass binds:
        // pelage_gpu::audit; nothing happens outside one). Stage 1 names its strands.
        for buffer in [&mesh.positions, &mesh.normals, &mesh.indices] {
            audit::name_buffer(buffer, pelage_strands::MESH);
        }
        let skin = match skin {
            Some(skin) => {
                let mesh_skin = MeshSkin::new(gpu, &scene.mesh, skin, &mesh)?;
                // A skinned body's distance field: built once in the bind pose and read
                // through the skin, or rebuilt every frame after the skinning
                // (`dynamics.sdf_skinned`).
                if let Some(sim) = strands.as_simulation_mut() {
                    match sim.dynamics().sdf_skinned {
                        SkinnedSdf::ThroughSkin => sim.skin_body_sdf(
                            gpu,
                            &mesh,
                            &scene.mesh,
                            skin,
                            mesh_skin.joint_matrices(),
                        )?,
                        SkinnedSdf::Rebuilt => sim.set_sdf_every_frame(true)?,
                    }
                }
                Some((mesh_skin, scene.skin.clone()))
            }
            None => None,
        };
        Light::validate_all(&scene.lights).map_err(pelage_shade::ShadeError::from)?;
        // Every later stage sizes itself from what stage 1 hands over: the strand
        // buffers carry their counts, widths and reach.
        let reach = pelage_shadow::reach(strands.buffers(), &mesh);
        let vertices =
            u64::from(strands.buffers().strand_count) * u64::from(strands.buffers().segments + 1);
        let stride = pelage_contract::Visibility::stride_for(vertices)?;
        // Without a shadow method every vertex is lit: no visibility buffer at all.
        let visibility = match scene.shadow {
            ShadowParams::None => None,
            _ => Some(LightVisibility::buffer(
                gpu,
                scene.lights.len() as u32,
                stride,
            )?),
        };
        if let Some(buffer) = &visibility {
            audit::name_buffer(buffer, pelage_contract::VISIBILITY);
        }
        let mut shadows = Vec::new();
        for index in 0..scene.lights.len() as u32 {
            let Some(buffer) = &visibility else {
                break;
            };
            let Some(shadow) = pelage_shadow::build(gpu, &scene.shadow, strands.buffers(), &mesh)?
            else {
                break;
            };
            let hand_over = LightVisibility::new(
                gpu,
                &shadow.binding(),
                strands.buffers(),
                buffer,
                index,
                stride,
            )?;
            shadows.push((shadow, hand_over));
        }
        // Each light's shadow, which also shadows the mesh for that light.
        let bindings: Vec<_> = shadows.iter().map(|(s, _)| s.binding()).collect();
        scene
            .shade
            .validate()
            .map_err(pelage_shade::ShadeError::from)?;
        // A transparency method draws single-sampled (and some only standard depth): on
        // targets it cannot draw it draws into the bridge's, resolved from and written
        // back into the caller's.
        let transparency = &scene.shade.transparency;
        let bridge = TargetBridge::needed(&target.format, transparency)
            .then(|| {
                TargetBridge::new(
                    gpu,
                    target.format,
                    transparency,
                    target.width,
                    target.height,
                )
            })
            .transpose()?;
        let hair = pelage_shade::build(
            gpu,
            &HairInputs {
                params: &scene.shade,
                mesh: &mesh,
                strands: strands.buffers(),
                shadows: &bindings,
                visibility: visibility
                    .as_ref()
                    .map(|buffer| Visibility { buffer, stride }),
                target: bridge.as_ref().map_or(target.format, TargetBridge::inner),
                draw_mesh,
                // The frame records the grid itself (Step::Grid), before the shade part:
                // a caller's mesh between the parts reads the body's sky from it.
                grid_apart: true,
            },
            target.width,
            target.height,
        )?;
        let steps = Step::order(skin.is_some(), shadows.len(), bridge.is_some());
        let plan = Stages {
            skin: skin.as_ref().map(|(skin, _)| skin),
            strands: strands.as_ref(),
            shadows: &shadows,
            hair: hair.as_ref(),
            bridge: bridge.as_ref(),
        }
        .plan(&steps, []);
        plan.validate()?;
        // A point light at the centre the shadows are fitted around has no direction.
        let shadow_target = (reach.0 + reach.1) * 0.5;
        for (i, light) in scene.lights.iter().enumerate() {
            light.shadow_light(i, shadow_target)?;
        }
        Ok(Self {
            motion: scene.motion.clone().map(|m| (m, scene.mesh.clone())),
            skin,
            mesh,
            strands,
            shadows,
            visibility,
            stride,
            hair,
            lights: scene.lights.clone(),
            shadow_target,
            reach,
            target: *target,
            steps,
            plan,
            prepared: None,
            bridge,
            built: update::Built::of(scene),
        })
    }

    /// Writes every stage's uniforms for time `t` seen through `camera`'s view and
    /// projection (any handedness, a jitter; reverse-Z exactly when the target's depth
    /// is: a pelage camera's are [`Camera::matrices`] or [`Camera::matrices_reverse_z`]):
    /// the mesh's motion and the colliders, the level of detail for the hair's size on
    /// screen, stage 1 (whose [`StrandFrame`] is returned and recorded with), each
    /// light's shadow and hand-over, and the hair pass. Queue writes only. Matrices that
    /// are not finite, not invertible or not a perspective projection, or whose depth
    /// direction is not the target's, are an error.
    ///
    /// [`Camera::matrices`]: pelage_scene::Camera::matrices
    /// [`Camera::matrices_reverse_z`]: pelage_scene::Camera::matrices_reverse_z
    pub fn prepare(
        &mut self,
        queue: &wgpu::Queue,
        t: f32,
        camera: &CameraMatrices,
    ) -> crate::Result<StrandFrame> {
        camera.validate()?;
        if camera.reverse_z() != self.target.format.reverse_z {
            let (given, target) = match camera.reverse_z() {
                true => ("reverse-Z", "standard depth (near 0, far 1)"),
                false => ("standard depth (near 0, far 1)", "reverse-Z"),
            };
            return Err(pelage_scene::ParamError {
                name: "camera.projection".into(),
                value: given.into(),
                reason: format!(
                    "the frame's target has {target} (FrameTarget::format.reverse_z): project \
                     the same way, or build the frame for this projection"
                ),
            }
            .into());
        }
        let frame = self.prepare_strands(queue, t, Some(camera))?;
        self.prepare_later_stages(queue, &frame, camera)?;
        Ok(frame)
    }

    /// The first half of a prepare: the mesh's motion, the colliders, the level of
    /// detail (for `camera`, when given) and stage 1's uniforms for time `t`.
    pub(crate) fn prepare_strands(
        &mut self,
        queue: &wgpu::Queue,
        t: f32,
        camera: Option<&CameraMatrices>,
    ) -> crate::Result<StrandFrame> {
        if let Some((skin, Some(rig))) = &self.skin {
            skin.set_joint_matrices(queue, &rig.joint_matrices(t))?;
        }
        if let Some((motion, rest)) = &self.motion {
            self.mesh.update(queue, &motion.apply(rest, t))?;
            if let Some(sim) = self.strands.as_simulation_mut() {
                let moved: Vec<_> = (sim.dynamics().colliders.iter())
                    .map(|c| c.moved(|p| motion.point(p, t)))
                    .collect();
                sim.set_colliders(&moved)?;
                // The body's field, built once at rest, moves with it.
                sim.set_sdf_transform(motion.matrix(t))?;
            }
        }
        if let Some(camera) = camera {
            let (width, height) = (self.target.width, self.target.height);
            let level = self
                .strands
                .level_for_view(self.reach, camera, width, height);
            self.strands.set_lod(level)?;
        }
        let frame = self.strands.prepare(queue, t)?;
        self.prepared = Some(frame);
        Ok(frame)
    }

    /// The second half of a prepare: every later stage's uniforms for stage 1's `frame`.
    fn prepare_later_stages(
        &mut self,
        queue: &wgpu::Queue,
        frame: &StrandFrame,
        camera: &CameraMatrices,
    ) -> crate::Result<()> {
        for (i, ((shadow, hand_over), light)) in self.shadows.iter().zip(&self.lights).enumerate() {
            shadow.prepare(queue, frame, &light.shadow_light(i, self.shadow_target)?)?;
            hand_over.prepare(queue, frame)?;
        }
        let (width, height) = (self.target.width, self.target.height);
        let camera = match &self.bridge {
            Some(bridge) => &bridge.matrices(camera),
            None => camera,
        };
        self.hair
            .prepare(queue, frame, camera, &self.lights, width, height)?;
        Ok(())
    }

    /// The frame the last prepare returned; recording before any is an error.
    fn prepared(&self) -> crate::Result<StrandFrame> {
        self.prepared.ok_or_else(|| {
            crate::Error::Strands(
                pelage_strands::FrameOrderError {
                    stage: "frame (record before any prepare)".into(),
                    prepared: 0,
                    given: 0,
                }
                .into(),
            )
        })
    }

    /// Records the whole frame into `encoder`: stage 1, each light's shadow and its
    /// hand-over, then the hair pass into `views` (clearing them unless `views.load`).
    /// Records only: no device, no wait; submitting is the caller's, followed by
    /// [`Frame::after_submit`]. The same as [`Frame::record_before_shade`] then
    /// [`Frame::record_shade`], between which a caller may record passes of its own.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        views: &TargetViews<'_>,
        mut timer: Option<&mut GpuTimer>,
    ) -> crate::Result<()> {
        self.record_before_shade(encoder, timer.as_deref_mut())?;
        self.record_shade(encoder, views, timer)
    }

    /// The first part of [`Frame::record`]: stage 1, each light's shadow and hand-over,
    /// and the volume method's grid. A caller's pass sampling the shadow
    /// ([`Frame::shadow_binding`]) or the body's sky ([`Frame::body_sky_binding`]) goes
    /// after it, before [`Frame::record_shade`] (its plan: [`Frame::plan`]).
    pub fn record_before_shade(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        mut timer: Option<&mut GpuTimer>,
    ) -> crate::Result<()> {
        self.record_strands(encoder, timer.as_deref_mut())?;
        self.record_shadow_part(encoder, timer, |_| true)
    }

    /// Stage 1's passes alone.
    pub(crate) fn record_strands(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        mut timer: Option<&mut GpuTimer>,
    ) -> crate::Result<()> {
        let frame = self.prepared()?;
        for step in self.steps_of(Part::Strands) {
            match step {
                Step::Skin => {
                    if let Some((skin, _)) = &self.skin {
                        skin.encode(encoder, timer.as_deref_mut());
                    }
                }
                Step::Strands => self.strands.encode(encoder, &frame, timer.as_deref_mut())?,
                _ => {}
            }
        }
        Ok(())
    }

    /// Stage 2 alone: each light's shadow and hand-over, without the grid (the
    /// renderer's wall-clock timing of the stages counts the grid with the shade stage).
    #[cfg(not(target_arch = "wasm32"))]
    pub(crate) fn record_stage2(&self, encoder: &mut wgpu::CommandEncoder) -> crate::Result<()> {
        self.record_shadow_part(encoder, None, |step| step != Step::Grid)
    }

    /// The volume method's grid alone (nothing for the other models).
    #[cfg(not(target_arch = "wasm32"))]
    pub(crate) fn record_grid(&self, encoder: &mut wgpu::CommandEncoder) -> crate::Result<()> {
        self.record_shadow_part(encoder, None, |step| step == Step::Grid)
    }

    /// The shadow steps (each light's shadow and hand-over, the grid) that `keep` takes.
    fn record_shadow_part(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        mut timer: Option<&mut GpuTimer>,
        keep: impl Fn(Step) -> bool,
    ) -> crate::Result<()> {
        let frame = self.prepared()?;
        for step in self.steps_of(Part::Shadows).filter(|&s| keep(s)) {
            match step {
                Step::Shadow(i) => {
                    if let Some((shadow, _)) = self.shadows.get(i) {
                        shadow.encode(encoder, &frame, timer.as_deref_mut())?;
                    }
                }
                Step::HandOver(i) => {
                    if let Some((_, hand_over)) = self.shadows.get(i) {
                        hand_over.encode(encoder, &frame, timer.as_deref_mut())?;
                    }
                }
                Step::Grid => {
                    if let Some(grid) = self.hair.grid() {
                        grid.encode(encoder, timer.as_deref_mut());
                    }
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// The hair pass into `views` (the second part of [`Frame::record`], after
    /// [`Frame::record_before_shade`]), with the target bridge's passes around it when the
    /// hair pass draws the bridge's targets.
    pub fn record_shade(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        views: &TargetViews<'_>,
        mut timer: Option<&mut GpuTimer>,
    ) -> crate::Result<()> {
        for view in [Some(views.color), views.resolve].into_iter().flatten() {
            audit::name_view(view, pelage_shade::TARGET_COLOR);
        }
        for view in [Some(views.depth), views.depth_sampled]
            .into_iter()
            .flatten()
        {
            audit::name_view(view, pelage_shade::TARGET_DEPTH);
        }
        let frame = self.prepared()?;
        // The views the hair pass draws: the bridge's when there is one.
        let inner = self.bridge.as_ref().map(|bridge| bridge.views(views));
        if let Some(inner) = &inner {
            audit::name_view(inner.color, pelage_shade::TARGET_COLOR);
            audit::name_view(inner.depth, pelage_shade::TARGET_DEPTH);
        }
        for step in self.steps_of(Part::Shade) {
            match (step, &self.bridge) {
                (Step::BridgeBefore, Some(bridge)) => {
                    bridge.encode_before(encoder, views, timer.as_deref_mut())?;
                }
                (Step::Hair, _) => self.hair.encode(
                    encoder,
                    &frame,
                    inner.as_ref().unwrap_or(views),
                    timer.as_deref_mut(),
                )?,
                (Step::BridgeAfter, Some(bridge)) => {
                    bridge.encode_after(encoder, views, timer.as_deref_mut());
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// The frame's steps that `part` records, in order.
    fn steps_of(&self, part: Part) -> impl Iterator<Item = Step> + '_ {
        self.steps.iter().copied().filter(move |s| s.part() == part)
    }

    /// The stages, as [`Stages::plan`] reads them.
    fn stages(&self) -> Stages<'_> {
        Stages {
            skin: self.skin.as_ref().map(|(skin, _)| skin),
            strands: self.strands.as_ref(),
            shadows: &self.shadows,
            hair: self.hair.as_ref(),
            bridge: self.bridge.as_ref(),
        }
    }

    /// The one step after the caller submitted a recorded frame: takes the readbacks of
    /// frames the GPU has finished and grows per-frame storage a frame found too small
    /// (the strand rasterizer's pool), for a later frame. Never waits
    /// (`device.poll(Poll)` and already mapped buffers only); a frame whose pool
    /// overflowed stays counted in [`HairPass::stats`].
    pub fn after_submit(&mut self, gpu: &Gpu) -> crate::Result<()> {
        Ok(self.hair.after_submit(gpu)?)
    }

    /// The passes [`Frame::record`] records, in order, with the named resources each
    /// reads and writes, and the caller's `passes_before_shade` recorded between
    /// [`Frame::record_before_shade`] and [`Frame::record_shade`] (an engine's mesh
    /// sampling the shadow, say; none: `[]`, the plan checked when the frame was built).
    /// A plan whose passes read a resource before any pass wrote it is
    /// [`Error::Plan`](crate::Error::Plan), naming the pass and the resource.
    pub fn plan(
        &self,
        passes_before_shade: impl IntoIterator<Item = PassInfo>,
    ) -> crate::Result<FramePlan> {
        let mut passes = passes_before_shade.into_iter().peekable();
        if passes.peek().is_none() {
            return Ok(self.plan.clone());
        }
        let plan = self.stages().plan(&self.steps, passes);
        plan.validate()?;
        Ok(plan)
    }

    /// Light `light`'s shadow (0: the key light) as the shadow contract's implementation,
    /// for a caller's own shader (`None` without shadows or past the last light): bound
    /// once per light, as pelage draws its mesh. Its `reads` are the resources under the
    /// frame's names for that light (`shadow0.*`, ...), what the caller's pass declares
    /// it reads.
    pub fn shadow_binding(&self, light: usize) -> Option<ShaderBinding> {
        let (shadow, _) = self.shadows.get(light)?;
        Some(ShaderBinding {
            reads: rename_lookup(shadow.as_ref(), light),
            ..shadow.binding()
        })
    }

    /// The body's sky (`shade/body_sky.wgsl`: `body_sky(p, n, ambient)`, the light
    /// reaching the body from the sky and, with the volume method, scattered by the hair)
    /// as the frame's shading implements it, for a caller's own mesh shader drawn
    /// between [`Frame::record_before_shade`] and [`Frame::record_shade`]: `Some` with
    /// the volume method (the grid [`Frame::record_before_shade`] fills, in the hair
    /// model's group; its `reads` name the grid), `None` for the other models (the open
    /// sky: `body_sky` returns `ambient` as the contract file has it).
    pub fn body_sky_binding(&self) -> Option<ShaderBinding> {
        self.hair.body_sky_binding()
    }

    /// Stage 1, for binding its buffers or reading its roots.
    pub fn strands(&self) -> &dyn StrandStage {
        self.strands.as_ref()
    }

    /// Stage 3's method.
    pub fn hair_pass(&self) -> &dyn HairPass {
        self.hair.as_ref()
    }

    /// The mesh buffers every stage reads, posed for the last prepared frame (moved or
    /// skinned on the GPU): the caller's own with [`Frame::with_mesh_buffers`].
    pub fn mesh_buffers(&self) -> &MeshBuffers {
        &self.mesh
    }

    /// Writes the joint matrices the next recorded frame skins the mesh with (see
    /// [`MeshSkin::set_joint_matrices`]): a frame without a skin, one whose scene rig
    /// sets them at every prepare, a wrong count or a non-finite matrix is an error
    /// naming `skin` or `skin.joint_matrices[i]`.
    pub fn set_joint_matrices(
        &self,
        queue: &wgpu::Queue,
        matrices: &[glam::Mat4],
    ) -> crate::Result<()> {
        match &self.skin {
            Some((skin, None)) => Ok(skin.set_joint_matrices(queue, matrices)?),
            Some((_, Some(_))) => Err(pelage_scene::ParamError::new(
                "skin",
                "a [skin] rig",
                "the scene's rig sets the joint matrices at every prepare; build the frame \
                 with Frame::with_skin to set them yourself",
            )
            .into()),
            None => Err(pelage_scene::ParamError::new(
                "skin",
                "none",
                "this frame has no skin: build it with Frame::with_skin or a scene with a skin rig",
            )
            .into()),
        }
    }

    /// Replaces the lights from the next prepare on. With shadows the count must stay
    /// the one the frame was built with (each light has its own shadow passes and slice
    /// of the visibility buffer): another count is
    /// [`Error::NeedsRebuild`](crate::Error::NeedsRebuild). Bad lights are an error.
    /// Nothing changes on an error.
    pub fn set_lights(&mut self, lights: &[Light]) -> crate::Result<()> {
        Light::validate_all(lights)?;
        self.lights_in_place(lights)
            .map_err(crate::Error::NeedsRebuild)?;
        for (i, light) in lights.iter().enumerate() {
            light.shadow_light(i, self.shadow_target)?;
        }
        self.lights = lights.to_vec();
        Ok(())
    }

    /// `Err(why)` when `lights` cannot replace the frame's in place.
    fn lights_in_place(&self, lights: &[Light]) -> Result<(), String> {
        if self.visibility.is_some() && lights.len() != self.lights.len() {
            return Err(format!(
                "the light count ({} to {}: each light has its own shadow passes)",
                self.lights.len(),
                lights.len()
            ));
        }
        Ok(())
    }

    /// The per-vertex light visibility stage 2 hands the hair pass (`None` without
    /// shadows): what an engine drawing the strands itself binds, one slice per light.
    pub fn visibility(&self) -> Option<Visibility<'_>> {
        self.visibility.as_ref().map(|buffer| Visibility {
            buffer,
            stride: self.stride,
        })
    }

    /// The number of lights with a shadow (0 without shadows).
    #[cfg(not(target_arch = "wasm32"))]
    pub(crate) fn shadowed_lights(&self) -> usize {
        self.shadows.len()
    }
}

/// The frame's name for light `light`'s shadow resources (`shadow0`, `shadow1`, ...):
/// a method's `shadow.*` become `shadow{light}.*`.
fn shadow_name(light: usize) -> String {
    format!("shadow{light}")
}

/// `shadow`'s lookup resources under the frame's names for light `light`.
fn rename_lookup(shadow: &dyn ShadowMethod, light: usize) -> Vec<String> {
    let name = shadow_name(light);
    shadow
        .lookup()
        .iter()
        .map(|r| match r.strip_prefix("shadow.") {
            Some(rest) => format!("{name}.{rest}"),
            None => r.clone(),
        })
        .collect()
}

/// One step of a frame. A [`Frame`] keeps its steps in recording order: its plan is
/// built by walking them ([`Stages::plan`]) and its recording walks the same list
/// ([`Frame::record_before_shade`], [`Frame::record_shade`]), so
/// the plan is the order and the membership of what runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    /// The skinning pass writing the mesh buffers stage 1 reads.
    Skin,
    /// Stage 1.
    Strands,
    /// Light `i`'s shadow.
    Shadow(usize),
    /// Light `i`'s hand-over to the hair (its per-vertex visibility).
    HandOver(usize),
    /// The volume method's grid (nothing for the other models), after stage 2 and before
    /// the shade part: a caller's mesh pass between [`Frame::record_before_shade`] and
    /// [`Frame::record_shade`] reads the body's sky from it.
    Grid,
    /// The target bridge's passes before the hair pass.
    BridgeBefore,
    /// Stage 3.
    Hair,
    /// The target bridge's passes after it.
    BridgeAfter,
}

/// Which of the three recording calls records a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Part {
    Strands,
    Shadows,
    Shade,
}

impl Step {
    /// The steps of a frame with or without a skinning pass, with `lights` shadows and
    /// with or without a target bridge, in recording order.
    fn order(skin: bool, lights: usize, bridge: bool) -> Vec<Step> {
        let mut steps = Vec::with_capacity(2 * lights + 6);
        if skin {
            steps.push(Step::Skin);
        }
        steps.push(Step::Strands);
        for i in 0..lights {
            steps.push(Step::Shadow(i));
            steps.push(Step::HandOver(i));
        }
        steps.push(Step::Grid);
        if bridge {
            steps.push(Step::BridgeBefore);
        }
        steps.push(Step::Hair);
        if bridge {
            steps.push(Step::BridgeAfter);
        }
        steps
    }

    fn part(self) -> Part {
        match self {
            Step::Skin | Step::Strands => Part::Strands,
            Step::Shadow(_) | Step::HandOver(_) | Step::Grid => Part::Shadows,
            Step::BridgeBefore | Step::Hair | Step::BridgeAfter => Part::Shade,
        }
    }
}

/// The stages a [`Frame`]'s plan is built from.
struct Stages<'a> {
    skin: Option<&'a MeshSkin>,
    strands: &'a dyn StrandStage,
    shadows: &'a [(Box<dyn ShadowMethod>, LightVisibility)],
    hair: &'a dyn HairPass,
    bridge: Option<&'a TargetBridge>,
}

impl Stages<'_> {
    /// The resources every light's shadow writes under the frame's names (`shadow0.*`,
    /// `shadow1.*`, ...): what the mesh pass, drawn once per light with a shadow, reads.
    fn lookups(&self) -> Vec<String> {
        (self.shadows.iter().enumerate())
            .flat_map(|(i, (shadow, _))| rename_lookup(shadow.as_ref(), i))
            .collect()
    }

    /// The passes of `steps`, in order, over the mesh and the targets, with `before_shade`
    /// (a caller's own passes) between the shadows and the first shade step.
    fn plan(&self, steps: &[Step], before_shade: impl IntoIterator<Item = PassInfo>) -> FramePlan {
        let mut plan = FramePlan::new([
            pelage_strands::MESH,
            pelage_shade::TARGET_COLOR,
            pelage_shade::TARGET_DEPTH,
        ]);
        let lookups = self.lookups();
        let mut before_shade = Some(before_shade);
        for &step in steps {
            if step.part() == Part::Shade
                && let Some(passes) = before_shade.take()
            {
                plan.push(passes);
            }
            match step {
                Step::Skin => plan.push(self.skin.map(MeshSkin::pass)),
                Step::Strands => plan.push(self.strands.passes()),
                Step::Shadow(i) => {
                    if let Some((shadow, _)) = self.shadows.get(i) {
                        let name = shadow_name(i);
                        plan.push(
                            shadow
                                .passes()
                                .into_iter()
                                .map(|p| p.renamed("shadow", &name)),
                        );
                    }
                }
                Step::HandOver(i) => {
                    if let Some((shadow, hand_over)) = self.shadows.get(i) {
                        let lookup = rename_lookup(shadow.as_ref(), i);
                        plan.push(hand_over.passes(&lookup));
                    }
                }
                Step::BridgeBefore => {
                    plan.push(
                        self.bridge
                            .map(TargetBridge::passes_before)
                            .unwrap_or_default(),
                    );
                }
                Step::Grid => plan.push(self.hair.grid().map(VolumeGrid::pass_info)),
                Step::Hair => plan.push(self.hair.passes(&lookups)),
                Step::BridgeAfter => {
                    plan.push(
                        self.bridge
                            .map(TargetBridge::passes_after)
                            .unwrap_or_default(),
                    );
                }
            }
        }
        if let Some(passes) = before_shade {
            plan.push(passes);
        }
        plan
    }
}

/// The mesh buffers of a groom-only scene: no triangles (so stage 2's mesh shadow map
/// and stage 3's mesh draw draw nothing), one zero vertex so that every binding has a
/// size, and the hair's reach as bounds (so that the shadow fits and
/// [`pelage_shadow::reach`] are the hair's alone).
fn no_mesh(gpu: &Gpu, reach: (Vec3, Vec3)) -> crate::Result<MeshBuffers> {
    let usage =
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
    let make = |label: &str| {
        pelage_gpu::create_buffer_init(
            &gpu.device,
            &wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: &[0u8; 12],
                usage,
            },
        )
    };
    Ok(MeshBuffers::from_buffers(
        make("pelage no mesh: positions"),
        make("pelage no mesh: normals"),
        make("pelage no mesh: indices"),
        1,
        0,
        reach,
    )?)
}
