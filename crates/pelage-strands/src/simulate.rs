//! Stage 1 with dynamics: strands simulated by position-based dynamics on the GPU
//! (`wgsl/strands/simulate.wgsl`), their roots bound to the triangles of a mesh that may
//! move every frame.

use encase::ShaderType;
use glam::{Mat4, UVec3, Vec2, Vec3, Vec4};
use pelage_gpu::{Gpu, GpuTimer, UniformBuffer, read_buffer, storage_buffer, wgpu, zeroed_storage};
use pelage_scene::{
    CameraMatrices, Collider, DynamicsParams, HairParams, HairType, MAX_COLLIDERS, Mesh,
    ParamError, Resampled, SdfGrid, Skin,
};

use crate::MESH;
use crate::groom::GroomShape;
use crate::grow::{Input, StrandPass, StrandStage};
use crate::{
    BODY_SDF, BodySdf, LodLevel, MeshBuffers, SDF_SKIN, STRAND_ROOTS, STRAND_VERTICES, SdfSkin,
    StrandFrame, StrandRoot, StrandsError,
};
use pelage_gpu::PassInfo;

/// `vec4`s of simulation state per strand before its vertices (`STATE_HEADER` in WGSL):
/// the root's position (w = 1 once posed), normal and tangent in the last frame.
pub(crate) const STATE_HEADER: u32 = 3;

/// The frame resource of a simulation's state (positions and velocities of the last
/// substep, the held-strand count), kept from frame to frame.
pub const SIMULATION_STATE: &str = "strands.state";

/// The timestamp label of the simulation's pass.
pub const SIMULATE_LABEL: &str = "strands: simulate";

/// A 2³ texture of `format` standing in for the body's field or its skin when there is
/// none (the pass binds both either way; with `sdf_on` 0 or the pipeline constant
/// `SDF_SKIN` off, it is never read).
fn stand_in(gpu: &Gpu, format: wgpu::TextureFormat) -> crate::Result<wgpu::TextureView> {
    Ok(gpu.scoped(|device| {
        device
            .create_texture(&wgpu::TextureDescriptor {
                label: Some("pelage no body sdf"),
                size: wgpu::Extent3d {
                    width: 2,
                    height: 2,
                    depth_or_array_layers: 2,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D3,
                format,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
            .create_view(&wgpu::TextureViewDescriptor::default())
    })?)
}

/// `collider` as the shader reads it.
fn collider_uniform(collider: &Collider) -> ColliderUniform {
    let (a, b) = collider.axis();
    ColliderUniform {
        a,
        radius: collider.radius,
        b,
        pad: 0.0,
    }
}

/// A capsule from `a` to `b` (a sphere when equal), as `simulate.wgsl` reads it.
#[derive(Clone, Copy, Debug, Default, PartialEq, ShaderType)]
pub(crate) struct ColliderUniform {
    /// One end of the axis.
    pub a: Vec3,
    /// Radius.
    pub radius: f32,
    /// The other end.
    pub b: Vec3,
    /// Padding to 16 bytes.
    pub pad: f32,
}

/// The per-frame uniforms of `simulate.wgsl` (`SimUniforms` there), beside the
/// [`GrowUniforms`](crate::grow::GrowUniforms) that carry the wind and the level of
/// detail. Internal: the CPU mirror works them out from the parameters on its own.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub(crate) struct SimUniforms {
    /// Gravity, scene units per second squared.
    pub gravity: Vec3,
    /// Acceleration per unit of wind force.
    pub wind_response: f32,
    /// Substeps this frame.
    pub substeps: u32,
    /// Length of each, seconds.
    pub h: f32,
    /// Time at the start of the frame, seconds (the last substep ends at the frame's time).
    pub time0: f32,
    /// 1 puts every strand at rest in this frame's pose.
    pub reset: u32,
    /// Velocity kept per substep, `exp(-damping · h)`.
    pub keep: f32,
    /// [`DynamicsParams::local_stiffness`] for a substep of `h`
    /// ([`DynamicsParams::stiffness_per_substep`]).
    pub local_stiffness: f32,
    /// [`DynamicsParams::global_stiffness`] for a substep of `h`.
    pub global_stiffness: f32,
    /// [`DynamicsParams::global_range`].
    pub global_range: f32,
    /// [`DynamicsParams::length_damping`].
    pub length_damping: f32,
    /// [`DynamicsParams::friction`].
    pub friction: f32,
    /// [`DynamicsParams::teleport_distance`].
    pub teleport_distance: f32,
    /// Colliders in use (the first of `colliders`).
    pub collider_count: u32,
    /// The colliders.
    pub colliders: [ColliderUniform; MAX_COLLIDERS],
    /// World space to the space the body's distance field was built in
    /// ([`SimulateStrands::set_sdf_transform`]).
    pub sdf_from_world: Mat4,
    /// The field's node (0, 0, 0) ([`SdfGrid::origin`]).
    pub sdf_origin: Vec3,
    /// Its cell.
    pub sdf_cell: f32,
    /// Its nodes per axis.
    pub sdf_dims: UVec3,
    /// 1 when the strands collide with the field.
    pub sdf_on: u32,
    /// The skin's lattice point (0, 0, 0), bind pose ([`SdfSkin::lattice`]).
    pub skin_origin: Vec3,
    /// Its cell.
    pub skin_cell: f32,
    /// Its points per axis (read when the pipeline's `SDF_SKIN` is on).
    pub skin_dims: UVec3,
    /// [`DynamicsParams::sdf_standoff`], in the field's cells.
    pub sdf_standoff: f32,
}

impl SimUniforms {
    /// The uniforms of a frame ending at `time`, `dt` after the last (`None`: reset
    /// every strand to rest), with `dynamics` and `colliders`.
    pub fn new(
        dynamics: &DynamicsParams,
        colliders: &[Collider],
        time: f32,
        dt: Option<f32>,
    ) -> Self {
        let (substeps, h) = dt.map_or((0, 0.0), |dt| dynamics.substeps(dt));
        let mut uniforms = [ColliderUniform::default(); MAX_COLLIDERS];
        for (slot, c) in uniforms.iter_mut().zip(colliders) {
            *slot = collider_uniform(c);
        }
        Self {
            gravity: dynamics.gravity,
            wind_response: dynamics.wind_response,
            substeps,
            h,
            time0: time - h * substeps as f32,
            reset: u32::from(dt.is_none()),
            keep: (-dynamics.damping * h).exp(),
            // Given per STIFFNESS_INTERVAL; each substep takes its share.
            local_stiffness: DynamicsParams::stiffness_per_substep(dynamics.local_stiffness, h),
            global_stiffness: DynamicsParams::stiffness_per_substep(dynamics.global_stiffness, h),
            global_range: dynamics.global_range,
            length_damping: dynamics.length_damping,
            friction: dynamics.friction,
            teleport_distance: dynamics.teleport_distance,
            collider_count: colliders.len().min(MAX_COLLIDERS) as u32,
            colliders: uniforms,
            sdf_from_world: Mat4::IDENTITY,
            sdf_origin: Vec3::ZERO,
            sdf_cell: 1.0,
            sdf_dims: UVec3::splat(2),
            sdf_on: 0,
            skin_origin: Vec3::ZERO,
            skin_cell: 1.0,
            skin_dims: UVec3::splat(2),
            sdf_standoff: dynamics.sdf_standoff,
        }
    }

    /// These uniforms colliding with the body's field on `grid`, `from_world` taking
    /// world space to the field's.
    pub fn with_sdf(self, grid: &SdfGrid, from_world: Mat4) -> Self {
        Self {
            sdf_from_world: from_world,
            sdf_origin: grid.origin,
            sdf_cell: grid.cell,
            sdf_dims: grid.dims,
            sdf_on: 1,
            ..self
        }
    }

    /// These uniforms reading the field through the skin whose lattice is `lattice`.
    pub fn with_skin(self, lattice: &SdfGrid) -> Self {
        Self {
            skin_origin: lattice.origin,
            skin_cell: lattice.cell,
            skin_dims: lattice.dims,
            ..self
        }
    }
}

/// Stage 1 with dynamics: the strands of grown fur ([`SimulateStrands::grown`]) or of a
/// groom file ([`SimulateStrands::groom`]) simulated under gravity and the wind, their
/// roots following a mesh the caller may rewrite every frame (skinned or moved), kept
/// out of spheres and capsules ([`Collider`]: `DynamicsParams::colliders`, moved by the
/// caller with [`SimulateStrands::set_colliders`]).
///
/// **Scheme.** Position-based dynamics (Müller et al. 2007) with one compute invocation
/// per strand walking it root to tip, every substep: Verlet integration (gravity,
/// damping, the stateless methods' wind field as a force), then, vertex after vertex,
/// global shape (toward the rest position carried by the root's frame, stiffness falling
/// linearly to 0 over `global_range` of the strand), local shape (toward the rest
/// direction in the parent segment's frame, TressFX's local shape constraint) — both
/// pulls move the previous position too, so they shape the strand without giving it
/// speed (as velocity they set grown strands kinking) — then three rounds of collisions
/// (friction in the first) and inextensibility by follow-the-leader, with Müller et al.
/// 2012's velocity correction ("DFTL"). Gauss-Seidel along the strand converges in one
/// pass where Jacobi iterations need many, FTL makes every segment exactly its rest
/// length after every substep whatever the forces, and one thread per strand needs no
/// atomics, so runs are bit for bit repeatable and the CPU mirror
/// (`pelage_reference::simulate`) follows it loop for loop.
///
/// **Time.** [`StrandStage::prepare`] takes the frame's time: the method steps by
/// `dt = time - last time`, clamped to `max_frame` (0.1 s by default: a longer hitch is
/// simulated as 0.1 s) and cut into `ceil(dt / max_substep)` equal substeps (1/120 s by
/// default, so 1 ms takes one substep, 1/60 s two and 100 ms twelve; a substep may be
/// [`SUBSTEP_SLACK`](pelage_scene::SUBSTEP_SLACK) longer, for rounded frame times,
/// [`DynamicsParams::substeps`]); the root is interpolated
/// across the substeps. The first frame, time going backwards and
/// [`SimulateStrands::reset`] put every strand at rest in the current pose. Every
/// `prepare` must be followed by its `encode` and a submit: a prepared frame that is
/// never run is lost time.
///
/// **Roots.** Each root sits on a triangle (index and barycentrics); every frame its
/// position, normal and tangent (from the triangle's first edge, flat interpolation)
/// come from the current [`MeshBuffers`], and the rest shape, stored in that frame,
/// turns with it. A root that moved more than `teleport_distance` in one frame puts its
/// strand at rest in the new pose. A root whose triangle holds a non-finite position or
/// normal holds its strand at its last pose and is counted
/// ([`SimulateStrands::held_strands`]).
///
/// **State.** One storage buffer ([`SimulateStrands::state`]): per strand three `vec4`s
/// of root pose (the root's position, w = 1 once posed, normal and tangent in the last
/// frame), then its rest shape, positions and previous positions, `segments + 1` `vec4`
/// each. The pass binds 8 storage buffers (WebGPU's
/// default limit): the mesh's three, the roots, the state, the held counter, the
/// vertices and the drawn roots.
///
/// Every strand is simulated each frame, the level of detail only choosing which are
/// drawn (segment reduction is not offered: the simulated shape has no bend bound).
#[derive(Debug)]
pub struct SimulateStrands {
    roots: Vec<StrandRoot>,
    /// Rest shape of every strand in its root's frame, `segments + 1` per strand.
    rest_local: Vec<Vec3>,
    pass: StrandPass,
    rest_roots: wgpu::Buffer,
    state: wgpu::Buffer,
    held: wgpu::Buffer,
    sim: UniformBuffer<SimUniforms>,
    dynamics: DynamicsParams,
    colliders: Vec<Collider>,
    /// The time of the last frame prepared (`None`: the next one resets).
    last_time: Option<f32>,
    /// The hash draw the strands' brightness comes from (see [`crate::strand_brightness`]).
    brightness_draw: u32,
    /// How far from the origin the strands reach (the largest coordinate of the reach
    /// box), for [`DynamicsParams::validate_at_scale`].
    scale: f32,
    /// The wind, for the same.
    wind: pelage_scene::WindParams,
    /// The body's distance field, if any.
    sdf: Option<BodySdf>,
    /// Whether `encode` rebuilds it before every frame.
    sdf_every_frame: bool,
    /// The skin the field (built in the bind pose) is read through, if any.
    sdf_skin: Option<SdfSkin>,
    /// World space to the field's (the mesh's pose when the field was built).
    sdf_from_world: Mat4,
}

impl SimulateStrands {
    /// Fur grown on `mesh` with `hair` (roots sampled as [`GrowStrands`](crate::GrowStrands)
    /// samples them; the rest shape is the grown one without gravity or wind: straight,
    /// wavy or curly along the root's tilted normal), simulated with `dynamics`.
    /// `mesh_buffers` must hold `mesh` (in any later pose).
    pub fn grown(
        gpu: &Gpu,
        mesh: &Mesh,
        mesh_buffers: &MeshBuffers,
        hair: &HairParams,
        dynamics: &DynamicsParams,
    ) -> crate::Result<Self> {
        check_mesh(mesh, mesh_buffers)?;
        StrandPass::vertex_bytes(gpu, hair)?;
        let roots = crate::sample_roots(mesh, &hair.roots, &hair.growth)?;
        let segments = hair.growth.segments;
        // Each strand keeps its region's shape (region 0 is `growth.hair_type`); the
        // roots already carry their region's length, tilt, width and colour.
        let shapes: Vec<HairType> = hair
            .growth
            .resolved_regions()
            .iter()
            .map(|g| g.hair_type)
            .collect();
        let rest_local: Vec<Vec3> = roots
            .iter()
            .flat_map(|root| {
                let shape = shapes
                    .get(root.region as usize)
                    .copied()
                    .unwrap_or(hair.growth.hair_type);
                grown_rest(root, shape, segments)
            })
            .collect();
        let mut params = hair.clone();
        params.growth.gravity = Vec3::ZERO;
        Self::build(
            gpu,
            (mesh, mesh_buffers),
            params,
            dynamics,
            roots,
            rest_local,
            crate::roots::GROWN_BRIGHTNESS_DRAW,
        )
    }

    /// The strands of a groom file (shuffled, coloured and sized as
    /// [`GroomStrands`](crate::GroomStrands) does), each root bound to the triangle of
    /// `mesh` nearest to it, simulated with `dynamics`. `mesh_buffers` must hold `mesh`
    /// (in any later pose).
    pub fn groom(
        gpu: &Gpu,
        groom: &Resampled,
        mesh: &Mesh,
        mesh_buffers: &MeshBuffers,
        hair: &HairParams,
        dynamics: &DynamicsParams,
    ) -> crate::Result<Self> {
        // Shuffled, coloured and sized as the groom method does.
        let shape = GroomShape::new(gpu, groom, hair)?;
        Self::from_shape(gpu, &shape, mesh, mesh_buffers, dynamics)
    }

    /// [`SimulateStrands::groom`] from the groom's strands as
    /// [`GroomStrands`](crate::GroomStrands) holds them (its strands in that order).
    pub(crate) fn from_shape(
        gpu: &Gpu,
        shape: &GroomShape,
        mesh: &Mesh,
        mesh_buffers: &MeshBuffers,
        dynamics: &DynamicsParams,
    ) -> crate::Result<Self> {
        check_mesh(mesh, mesh_buffers)?;
        let params = shape.params.clone();
        let per_strand = params.growth.segments as usize + 1;
        let triangles = usable_triangles(mesh);
        if triangles.is_empty() {
            return Err(StrandsError::NoSurface(
                "every triangle has zero area: roots cannot be bound".into(),
            ));
        }
        let mut roots = shape.roots.clone();
        let mut rest_local = Vec::with_capacity(shape.rest.len());
        for (root, points) in roots.iter_mut().zip(shape.rest.chunks(per_strand)) {
            let (triangle, bary) = nearest_triangle(mesh, &triangles, points[0]);
            root.triangle = triangle;
            root.bary = bary;
            let frame = RootFrame::on(mesh, triangle, bary);
            rest_local.extend(points.iter().map(|&p| frame.to_local(p)));
        }
        Self::build(
            gpu,
            (mesh, mesh_buffers),
            params,
            dynamics,
            roots,
            rest_local,
            crate::groom::GROOM_BRIGHTNESS_DRAW,
        )
    }

    /// `meshes`: the mesh (its pose now: the body's field is of its surface) and the
    /// buffers that hold it.
    fn build(
        gpu: &Gpu,
        (mesh, mesh_buffers): (&Mesh, &MeshBuffers),
        params: HairParams,
        dynamics: &DynamicsParams,
        roots: Vec<StrandRoot>,
        rest_local: Vec<Vec3>,
        brightness_draw: u32,
    ) -> crate::Result<Self> {
        dynamics.validate()?;
        let per_strand = params.growth.segments as usize + 1;
        let header = STATE_HEADER as usize;
        // State: root pose (zero: not posed yet), rest shape, positions, previous.
        let mut state = vec![Vec4::ZERO; roots.len() * (header + 3 * per_strand)];
        for (chunk, rest) in state
            .chunks_mut(header + 3 * per_strand)
            .zip(rest_local.chunks(per_strand))
        {
            for (slot, p) in chunk[header..].iter_mut().zip(rest) {
                *slot = p.extend(0.0);
            }
        }
        let storage = wgpu::BufferUsages::STORAGE;
        let state = storage_buffer(gpu, "pelage simulation state", &state, storage)?;
        let held = zeroed_storage(gpu, "pelage simulation held strands", 4, storage)?;
        let rest_roots = storage_buffer(gpu, "pelage simulation rest roots", &roots, storage)?;
        pelage_gpu::audit::name_buffer(&state, SIMULATION_STATE);
        pelage_gpu::audit::name_buffer(&held, SIMULATION_STATE);
        pelage_gpu::audit::constant(&[&rest_roots]);
        let sim = UniformBuffer::new(
            gpu,
            "pelage simulation uniforms",
            &SimUniforms::new(dynamics, &[], 0.0, None),
        )?;
        // A strand reaches at most its length from its root point (which sits its rest
        // offset from the surface), anywhere the mesh goes.
        let max_width = roots.iter().map(|r| r.width).fold(0.0f32, f32::max);
        let pad = rest_local
            .chunks(per_strand)
            .zip(&roots)
            .map(|(rest, root)| rest[0].length() + root.length)
            .fold(0.0f32, f32::max)
            + max_width;
        let (lo, hi) = mesh_buffers.bounds;
        let reach = (lo - Vec3::splat(pad), hi + Vec3::splat(pad));
        // 32-bit positions this far out must still hold a substep's motion.
        let scale = reach.0.abs().max(reach.1.abs()).max_element();
        dynamics.validate_at_scale(scale, &params.wind)?;
        // The body's field, built now from the mesh buffers as they hold the mesh (its
        // pose at construction), or a 2³ stand-in never sampled.
        let (sdf, sdf_view) = match dynamics.sdf_resolution {
            0 => (None, stand_in(gpu, wgpu::TextureFormat::R32Float)?),
            resolution => {
                let sdf =
                    BodySdf::of_body(gpu, mesh_buffers, mesh, mesh_buffers.bounds, resolution)?;
                sdf.build(gpu)?;
                let view = sdf.view().clone();
                (Some(sdf), view)
            }
        };
        // Built outside the frame: a constant until the field is rebuilt every frame.
        pelage_gpu::audit::constant_view(&sdf_view);
        let skin_view = stand_in(gpu, wgpu::TextureFormat::Rgba32Float)?;
        pelage_gpu::audit::constant_view(&skin_view);
        let mut pass = StrandPass::with_inputs(
            gpu,
            SIMULATE_LABEL,
            "strands/simulate.wgsl",
            &params,
            reach,
            &roots,
            &[
                Input::Read(&mesh_buffers.positions),
                Input::Read(&mesh_buffers.normals),
                Input::Read(&mesh_buffers.indices),
                Input::Read(&rest_roots),
                Input::Uniform(&sim.buffer),
                Input::ReadWrite(&state),
                Input::ReadWrite(&held),
                Input::Texture3d(&sdf_view),
                Input::Texture3d(&skin_view),
            ],
            &[],
        )?;
        pass.inputs = &[MESH];
        pass.state = &[SIMULATION_STATE];
        Ok(Self {
            roots,
            rest_local,
            pass,
            rest_roots,
            state,
            held,
            sim,
            dynamics: dynamics.clone(),
            colliders: dynamics.colliders.clone(),
            last_time: None,
            brightness_draw,
            scale,
            wind: params.wind.clone(),
            sdf,
            sdf_every_frame: false,
            sdf_skin: None,
            sdf_from_world: Mat4::IDENTITY,
        })
    }

    /// The body's signed distance field (`DynamicsParams::sdf_resolution` > 0), built
    /// when the simulation was made from the mesh buffers' pose then.
    pub fn body_sdf(&self) -> Option<&BodySdf> {
        self.sdf.as_ref()
    }

    /// Rebuilds the body's field every frame, before the simulation's pass (a mesh the
    /// caller deforms in its own way: [`StrandStage::encode`] records
    /// [`BodySdf::encode`] first and [`StrandStage::passes`] declares it), or only once
    /// (`false`, the default: a still mesh, a rigid one moved with
    /// [`SimulateStrands::set_sdf_transform`], or a skinned one read through its skin,
    /// [`SimulateStrands::skin_body_sdf`]). Does nothing without a field. Refused, naming
    /// `skin`, after [`SimulateStrands::skin_body_sdf`]: that field is of the bind pose,
    /// and covers only its box.
    pub fn set_sdf_every_frame(&mut self, every_frame: bool) -> crate::Result<()> {
        if every_frame && self.sdf_skin.is_some() {
            return Err(ParamError::new(
                "skin",
                "a field read through the skin",
                "is built once in the bind pose (SimulateStrands::skin_body_sdf): it is not \
                 rebuilt every frame; make the simulation again to rebuild it instead",
            )
            .into());
        }
        if let Some(sdf) = &self.sdf {
            self.sdf_every_frame = every_frame;
            if every_frame {
                pelage_gpu::audit::name_view(sdf.view(), BODY_SDF);
                self.sdf_from_world = Mat4::IDENTITY;
            } else {
                pelage_gpu::audit::constant_view(sdf.view());
            }
        }
        Ok(())
    }

    /// Reads the body's field through a skin instead of rebuilding it every frame: the
    /// field is built again, once, from `bind` (the mesh's bind pose, which `skin`
    /// skins into `mesh_buffers` every frame: [`crate::MeshSkin`]) over `bind`'s own box,
    /// and an [`SdfSkin`] blends the joint matrices `joint_matrices` holds
    /// ([`crate::MeshSkin::joint_matrices`]) at a lattice over it every frame, before
    /// the simulation's pass, which finds each vertex's bind-pose point through the
    /// blend's inverse (see [`SdfSkin`]). The per-frame cost is the lattice's pass,
    /// not a build. Does nothing without a field (`sdf_resolution` 0). Refused, naming
    /// `mesh` or `skin`, when `bind` or `skin` does not match the simulation's mesh.
    pub fn skin_body_sdf(
        &mut self,
        gpu: &Gpu,
        mesh_buffers: &MeshBuffers,
        bind: &Mesh,
        skin: &Skin,
        joint_matrices: &wgpu::Buffer,
    ) -> crate::Result<()> {
        if self.sdf.is_none() {
            return Ok(());
        }
        bind.validate()?;
        mesh_buffers.check_matches(bind)?;
        skin.validate(bind.positions.len())?;
        let bind_buffers = MeshBuffers::upload(gpu, bind)?;
        let burial = crate::burial(bind);
        let triangles = crate::sdf::kept_triangles(bind, &burial);
        let sdf = BodySdf::with_burial(
            gpu,
            &bind_buffers,
            Some(&burial),
            bind_buffers.bounds,
            self.dynamics.sdf_resolution,
        )?;
        sdf.build(gpu)?;
        pelage_gpu::audit::constant_view(sdf.view());
        let sdf_skin = SdfSkin::new(gpu, bind, skin, &triangles, sdf.grid(), joint_matrices)?;
        self.pass.rebind(
            gpu,
            "strands/simulate.wgsl",
            &[
                Input::Read(&mesh_buffers.positions),
                Input::Read(&mesh_buffers.normals),
                Input::Read(&mesh_buffers.indices),
                Input::Read(&self.rest_roots),
                Input::Uniform(&self.sim.buffer),
                Input::ReadWrite(&self.state),
                Input::ReadWrite(&self.held),
                Input::Texture3d(sdf.view()),
                Input::Texture3d(sdf_skin.view()),
            ],
            &[("SDF_SKIN", 1.0)],
        )?;
        self.sdf = Some(sdf);
        self.sdf_skin = Some(sdf_skin);
        self.sdf_every_frame = false;
        self.sdf_from_world = Mat4::IDENTITY;
        Ok(())
    }

    /// The passes [`StrandStage::encode`] records before the simulation's for the body's
    /// field (its build when rebuilt every frame, or the skin's lattice pass) and what
    /// the simulation reads from them.
    pub(crate) fn field_passes(&self) -> (Vec<PassInfo>, Vec<&'static str>) {
        let mut passes = Vec::new();
        let mut reads = Vec::new();
        if let (Some(sdf), true) = (&self.sdf, self.sdf_every_frame) {
            passes.push(sdf.pass());
            reads.push(BODY_SDF);
        }
        if let Some(skin) = &self.sdf_skin {
            passes.push(skin.pass());
            reads.push(SDF_SKIN);
        }
        (passes, reads)
    }

    /// The skin the body's field is read through ([`SimulateStrands::skin_body_sdf`]).
    pub fn sdf_skin(&self) -> Option<&SdfSkin> {
        self.sdf_skin.as_ref()
    }

    /// Whether the field is rebuilt every frame.
    pub fn sdf_every_frame(&self) -> bool {
        self.sdf_every_frame
    }

    /// Moves the body's field (built once) rigidly: `world_from_built` takes the mesh's
    /// pose when the simulation was made to its pose this frame (a [`MeshMotion`]'s
    /// rotation about its pivot), from the next `prepare` on. Refuses a matrix that is not
    /// finite or not a rotation and translation (a scale would break distances), naming
    /// `motion`.
    ///
    /// [`MeshMotion`]: pelage_scene::MeshMotion
    pub fn set_sdf_transform(&mut self, world_from_built: Mat4) -> crate::Result<()> {
        let inverse = world_from_built.inverse();
        let (scale, _, _) = world_from_built.to_scale_rotation_translation();
        let rigid = (scale - Vec3::ONE).abs().max_element() < 1e-4
            && world_from_built.row(3).abs_diff_eq(Vec4::W, 1e-6);
        if !(world_from_built.is_finite() && inverse.is_finite() && rigid) {
            return Err(ParamError::new(
                "motion",
                world_from_built,
                "the body's distance field moves only by finite rotations and translations",
            )
            .into());
        }
        self.sdf_from_world = inverse;
        Ok(())
    }

    /// Replaces the colliders in use (world space, at most [`MAX_COLLIDERS`]; they start
    /// as `DynamicsParams::colliders`), taking effect at the next `prepare`: the caller
    /// moves them with the body. Refuses more, or a bad one, naming it, and then changes
    /// nothing.
    pub fn set_colliders(&mut self, colliders: &[Collider]) -> crate::Result<()> {
        if colliders.len() > MAX_COLLIDERS {
            return Err(ParamError::new(
                "dynamics.colliders",
                colliders.len(),
                &format!("at most {MAX_COLLIDERS} colliders"),
            )
            .into());
        }
        for (i, c) in colliders.iter().enumerate() {
            c.validate(&format!("colliders[{i}]"))?;
        }
        self.colliders = colliders.to_vec();
        Ok(())
    }

    /// The colliders in use.
    pub fn colliders(&self) -> &[Collider] {
        &self.colliders
    }

    /// Replaces the dynamics parameters (validated) and the colliders in use with its
    /// colliders, from the next `prepare` on. The body's field is made with the
    /// simulation: a different `sdf_resolution` or `sdf_skinned` is refused (build a new
    /// simulation).
    pub fn set_dynamics(&mut self, dynamics: &DynamicsParams) -> crate::Result<()> {
        dynamics.validate()?;
        if dynamics.sdf_skinned != self.dynamics.sdf_skinned {
            return Err(ParamError::new(
                "dynamics.sdf_skinned",
                format!("{:?}", dynamics.sdf_skinned),
                "is fixed when the simulation is made: make a new one to change it",
            )
            .into());
        }
        if dynamics.sdf_resolution != self.dynamics.sdf_resolution {
            return Err(ParamError::new(
                "dynamics.sdf_resolution",
                dynamics.sdf_resolution,
                &format!(
                    "is fixed when the simulation is made (it has {}): make a new one to change it",
                    self.dynamics.sdf_resolution
                ),
            )
            .into());
        }
        dynamics.validate_at_scale(self.scale, &self.wind)?;
        self.dynamics = dynamics.clone();
        self.colliders = dynamics.colliders.clone();
        Ok(())
    }

    /// The shortest `max_substep` this simulation accepts
    /// ([`DynamicsParams::min_substep`] for the strands' reach and the wind).
    pub fn min_substep(&self) -> f32 {
        self.dynamics.min_substep(self.scale, &self.wind)
    }

    /// The dynamics parameters in use.
    pub fn dynamics(&self) -> &DynamicsParams {
        &self.dynamics
    }

    /// Puts every strand back at rest (in the pose of the mesh) at the next `prepare`.
    pub fn reset(&mut self) {
        self.last_time = None;
    }

    /// The simulation state (see the type's docs; input of the CPU mirror).
    pub fn state(&self) -> &wgpu::Buffer {
        &self.state
    }

    /// The rest shape of every strand in its root's frame (x along the tangent, y along
    /// the normal, z along tangent × normal), `segments + 1` points per strand.
    pub fn rest_local(&self) -> &[Vec3] {
        &self.rest_local
    }

    /// The strands held at their last pose in the last frame run because the mesh under
    /// their root was not finite. Reads back from the GPU (waits for it): call it outside
    /// the frame loop.
    pub fn held_strands(&self, gpu: &Gpu) -> crate::Result<u32> {
        let bytes = read_buffer(gpu, &self.held)?;
        Ok(bytes
            .get(..4)
            .map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])))
    }
}

impl StrandStage for SimulateStrands {
    fn pass(&self) -> &StrandPass {
        &self.pass
    }

    fn pass_mut(&mut self) -> &mut StrandPass {
        &mut self.pass
    }

    fn roots(&self) -> &[StrandRoot] {
        &self.roots
    }

    /// Steps the simulation from the last frame's time to `time` (see the type's docs).
    fn prepare(&mut self, queue: &wgpu::Queue, time: f32) -> crate::Result<StrandFrame> {
        if !time.is_finite() {
            return Err(ParamError::new("time", time, "must be finite").into());
        }
        let dt = self
            .last_time
            .filter(|&last| time >= last)
            .map(|last| time - last);
        let mut uniforms = SimUniforms::new(&self.dynamics, &self.colliders, time, dt);
        if let Some(sdf) = &self.sdf {
            uniforms = uniforms.with_sdf(sdf.grid(), self.sdf_from_world);
        }
        if let Some(skin) = &self.sdf_skin {
            uniforms = uniforms.with_skin(skin.lattice());
        }
        self.sim.write(queue, &uniforms)?;
        self.last_time = Some(time);
        let grow = self.pass.uniforms_at(time);
        self.pass.begin_frame(queue, &grow)
    }

    /// Rebuilds the body's field when it is rebuilt every frame, clears the held counter
    /// and simulates every strand (drawn or not).
    fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        frame: &StrandFrame,
        mut timer: Option<&mut GpuTimer>,
    ) -> crate::Result<()> {
        frame.check_prepared(SIMULATE_LABEL, self.frame().map_or(0, |f| f.id))?;
        if let (Some(sdf), true) = (&self.sdf, self.sdf_every_frame) {
            sdf.encode(encoder, timer.as_deref_mut());
        }
        if let Some(skin) = &self.sdf_skin {
            skin.encode(encoder, timer.as_deref_mut());
        }
        encoder.clear_buffer(&self.held, 0, None);
        self.pass
            .record(encoder, frame, timer, self.buffers().strand_count)
    }

    /// The field's build when it runs every frame, then the simulation (reading the mesh
    /// and the field, writing the strands and its state).
    fn passes(&self) -> Vec<PassInfo> {
        let (mut passes, field) = self.field_passes();
        passes.push(
            PassInfo::new(SIMULATE_LABEL)
                .reads([MESH])
                .reads(field)
                .writes([STRAND_VERTICES, STRAND_ROOTS, SIMULATION_STATE]),
        );
        passes
    }

    fn set_color(
        &mut self,
        queue: &wgpu::Queue,
        color: Vec3,
        color_jitter: f32,
    ) -> crate::Result<()> {
        crate::grow::recolor(
            &mut self.pass,
            &mut self.roots,
            &self.rest_roots,
            self.brightness_draw,
            queue,
            (color, color_jitter),
        )
    }

    fn as_simulation_mut(&mut self) -> Option<&mut SimulateStrands> {
        Some(self)
    }

    /// Strand reduction as the stateless methods; always every segment.
    fn level_for_view(
        &self,
        bounds: (Vec3, Vec3),
        camera: &CameraMatrices,
        width: u32,
        height: u32,
    ) -> LodLevel {
        let full = self.params().growth.segments;
        LodLevel::for_view_with(self.params(), bounds, camera, width, height, |_| {
            (full, 0.0)
        })
    }
}

/// Refuses mesh buffers that do not hold `mesh`.
fn check_mesh(mesh: &Mesh, buffers: &MeshBuffers) -> crate::Result<()> {
    mesh.validate()?;
    Ok(buffers.check_matches(mesh)?)
}

/// A root's frame on the mesh at rest, as `root_pose` in WGSL computes it.
#[derive(Clone, Copy, Debug)]
struct RootFrame {
    position: Vec3,
    normal: Vec3,
    tangent: Vec3,
}

impl RootFrame {
    /// The flat surface of `triangle` at barycentrics `bary`.
    fn on(mesh: &Mesh, triangle: u32, bary: Vec2) -> Self {
        let idx = |k: usize| mesh.indices[triangle as usize * 3 + k] as usize;
        let (i1, i2, i3) = (idx(0), idx(1), idx(2));
        let w = 1.0 - bary.x - bary.y;
        let position =
            mesh.positions[i1] * bary.x + mesh.positions[i2] * bary.y + mesh.positions[i3] * w;
        let normal = (mesh.normals[i1] * bary.x + mesh.normals[i2] * bary.y + mesh.normals[i3] * w)
            .try_normalize()
            .unwrap_or(Vec3::Y);
        let tangent = perpendicular(normal, mesh.positions[i2] - mesh.positions[i1]);
        Self {
            position,
            normal,
            tangent,
        }
    }

    /// `p` in this frame's coordinates (x tangent, y normal, z tangent × normal).
    fn to_local(self, p: Vec3) -> Vec3 {
        let d = p - self.position;
        Vec3::new(
            d.dot(self.tangent),
            d.dot(self.normal),
            d.dot(self.tangent.cross(self.normal)),
        )
    }
}

/// A unit vector perpendicular to unit `n`, as close to `hint` as possible.
fn perpendicular(n: Vec3, hint: Vec3) -> Vec3 {
    let fallback = if n.x.abs() > 0.9 { Vec3::Y } else { Vec3::X };
    let f = (fallback - fallback.dot(n) * n)
        .try_normalize()
        .unwrap_or(Vec3::Z);
    (hint - hint.dot(n) * n).try_normalize().unwrap_or(f)
}

/// The rest shape of a grown strand in its root's frame: `grow.wgsl`'s strand without
/// force (the root direction tilted from the normal, the wave or curl of `shape`, its
/// region's hair type).
fn grown_rest(root: &StrandRoot, shape: HairType, segments: u32) -> Vec<Vec3> {
    // Root frame: tangent = x, normal = y, tangent × normal = z, so normal × tangent = -z.
    let (st, ct) = root.tilt.sin_cos();
    let (sa, ca) = root.azimuth.sin_cos();
    let d = Vec3::new(st * ca, ct, -st * sa);
    let e1 = perpendicular(d, Vec3::X);
    let e2 = d.cross(e1);
    let seg_len = root.length / segments as f32;
    let mut p = Vec3::ZERO;
    let mut out = Vec::with_capacity(segments as usize + 1);
    out.push(p);
    for i in 0..segments {
        let s = (i as f32 + 0.5) * seg_len;
        let tangent = match shape {
            HairType::Straight => d,
            HairType::Wavy {
                amplitude,
                frequency,
            } => {
                let k = std::f32::consts::TAU * frequency;
                let theta = (k * amplitude * (k * s).cos()).atan();
                d * theta.cos() + e1 * theta.sin()
            }
            HairType::Curly { radius, pitch } => {
                let circumference = std::f32::consts::TAU * radius;
                let turn_length = (circumference * circumference + pitch * pitch).sqrt();
                let theta = circumference.atan2(pitch);
                let phi = std::f32::consts::TAU * s / turn_length;
                d * theta.cos() + (e1 * phi.cos() + e2 * phi.sin()) * theta.sin()
            }
        };
        p += tangent * seg_len;
        out.push(p);
    }
    out
}

/// The triangles of `mesh` with a non-zero area.
fn usable_triangles(mesh: &Mesh) -> Vec<u32> {
    mesh.triangle_areas()
        .iter()
        .enumerate()
        .filter(|(_, a)| **a > 0.0 && a.is_finite())
        .map(|(t, _)| t as u32)
        .collect()
}

/// The triangle of `triangles` nearest to `p` and the barycentrics (of its first and
/// second corner) of the nearest point on it.
fn nearest_triangle(mesh: &Mesh, triangles: &[u32], p: Vec3) -> (u32, Vec2) {
    let mut best = (triangles[0], Vec2::new(1.0 / 3.0, 1.0 / 3.0), f32::INFINITY);
    for &t in triangles {
        let idx = |k: usize| mesh.indices[t as usize * 3 + k] as usize;
        let (a, b, c) = (
            mesh.positions[idx(0)],
            mesh.positions[idx(1)],
            mesh.positions[idx(2)],
        );
        let (u, v, w) = closest_on_triangle(p, a, b, c);
        let d = p.distance_squared(a * u + b * v + c * w);
        if d < best.2 {
            best = (t, Vec2::new(u, v), d);
        }
    }
    (best.0, best.1)
}

/// Barycentrics `(u, v, w)` of the point of triangle `abc` nearest to `p` (Ericson,
/// Real-Time Collision Detection, 5.1.5); a degenerate triangle's nearest corner.
pub(crate) fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> (f32, f32, f32) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (1.0, 0.0, 0.0);
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (0.0, 1.0, 0.0);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (1.0 - v, v, 0.0);
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (0.0, 0.0, 1.0);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (1.0 - w, 0.0, w);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (0.0, 1.0 - w, w);
    }
    let denom = va + vb + vc;
    if denom.abs() <= f32::MIN_POSITIVE {
        // A degenerate triangle: its nearest corner.
        let (da, db, dc) = (p.distance(a), p.distance(b), p.distance(c));
        return if da <= db && da <= dc {
            (1.0, 0.0, 0.0)
        } else if db <= dc {
            (0.0, 1.0, 0.0)
        } else {
            (0.0, 0.0, 1.0)
        };
    }
    let v = vb / denom;
    let w = vc / denom;
    (1.0 - v - w, v, w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_point_barycentrics_cover_the_regions() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        assert_eq!(
            closest_on_triangle(Vec3::new(-1.0, -1.0, 0.0), a, b, c),
            (1.0, 0.0, 0.0)
        );
        assert_eq!(
            closest_on_triangle(Vec3::new(2.0, -0.5, 0.0), a, b, c),
            (0.0, 1.0, 0.0)
        );
        let (u, v, w) = closest_on_triangle(Vec3::new(0.25, 0.25, 3.0), a, b, c);
        assert!((u - 0.5).abs() < 1e-6 && (v - 0.25).abs() < 1e-6 && (w - 0.25).abs() < 1e-6);
        let (u, v, w) = closest_on_triangle(Vec3::new(0.5, -2.0, 0.0), a, b, c);
        assert!((u - 0.5).abs() < 1e-6 && (v - 0.5).abs() < 1e-6 && w == 0.0);
    }

    #[test]
    fn grown_rest_shape_has_the_strand_length_along_the_normal() {
        let root = StrandRoot {
            triangle: 0,
            seed: 0,
            bary: Vec2::ZERO,
            length: 2.0,
            width: 0.01,
            phase: 0.0,
            tilt: 0.0,
            azimuth: 0.0,
            color: Vec3::ONE,
            region: 0,
        };
        let rest = grown_rest(&root, HairType::Straight, 8);
        assert_eq!(rest.len(), 9);
        assert!(
            (rest[8] - Vec3::new(0.0, 2.0, 0.0)).length() < 1e-5,
            "{rest:?}"
        );
    }
}
