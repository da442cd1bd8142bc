//! Stage 1 for guide strands: a groom's strands bent by the wind as guides
//! (`wgsl/strands/groom.wgsl`), then render strands rooted on the mesh interpolated from
//! them (`wgsl/strands/guides.wgsl`), two compute passes every frame.

use glam::Vec3;
use pelage_gpu::{Gpu, GpuTimer, PassInfo, storage_buffer, wgpu};
use pelage_scene::{
    CameraMatrices, DynamicsParams, GuideParams, HairParams, MAX_GUIDES, Mesh, ParamError,
    Resampled, SurfaceInterpolation, WindParams,
};

use crate::groom::GroomShape;
use crate::grow::{Input, StrandPass, StrandStage};
use crate::lod::{bend_error, bend_per_segment, fewest_segments};
use crate::roots::GROWN_BRIGHTNESS_DRAW;
use crate::simulate::closest_on_triangle;
use crate::{
    GroomStrands, LodLevel, MESH, MeshBuffers, STRAND_ROOTS, STRAND_VERTICES, SimulateStrands,
    StrandFrame, StrandRoot, StrandsError, sample_roots,
};

/// The frame resource naming the bent (or simulated) guides, which the first pass of
/// [`GuideStrands`] writes and the second reads.
pub const GUIDE_VERTICES: &str = "strands.guides";

/// The constants of `guides.wgsl`: its pipeline-overridable constants `K`, `CLUMP` and
/// `NOISE` ([`GuideUniforms::overrides`]), fixed when the pipeline is built, so that the
/// compiler leaves out the terms that add exactly 0 (guides past `k`, no noise, no
/// clumping).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct GuideUniforms {
    /// Guides blended per strand (1 to 4; fewer when the groom has fewer guides).
    pub k: u32,
    /// Clumping toward the nearest guide, in [0, 1].
    pub clump: f32,
    /// Per-strand noise, a fraction of the strand's length.
    pub noise: f32,
}

impl GuideUniforms {
    /// The values of `guides.wgsl`'s overridable constants, by name.
    pub fn overrides(&self) -> [(&'static str, f64); 3] {
        [
            ("K", f64::from(self.k)),
            ("CLUMP", f64::from(self.clump)),
            ("NOISE", f64::from(self.noise)),
        ]
    }
}

/// What one render strand keeps to be interpolated: four 16-bit guide indices (nearest
/// first; words 0 and 1, low half first; slots past `k` repeat the nearest) and the first `k - 1` weights as 10-bit
/// fractions of 1023 (word 2, lowest bits first); the `k`-th weight is 1 minus the
/// others, so they sum to 1. 12 bytes per render strand.
pub(crate) type GuideRecord = [u32; 3];

/// Largest 10-bit weight (a weight of 1).
const WEIGHT_ONE: u32 = 1023;

/// Stage 1 for guide strands: render strands rooted on the mesh, each shaped every frame
/// by a blend of the guides nearest its root, after the wind has bent the guides.
///
/// **Which guides.** Each render strand blends the `k` guides whose roots are nearest
/// its root (k-nearest neighbours found once on the CPU at build with a uniform grid),
/// weighted by `1/d_i − 1/d_(k+1)` (inverse distance, less that of the next guide
/// not taken, so a weight falls to 0 before its guide leaves the set: no seams where
/// neighbour sets change), normalised. Barycentric weights over the guides at the
/// triangle's corners would need a guide at every vertex; guides from files sit
/// anywhere near the surface, which nearest roots handle.
///
/// **How.** The guides' shapes are blended as offsets from their roots in world space
/// and placed at the render strand's root on the (flat) triangle; one guide gives
/// copies of itself translated to every root. World space is what the wind bends the
/// guides in; the price is that on a surface curved between guides far apart the
/// blend averages directions that a root frame would have turned. Then per-strand noise
/// (a drift `noise · length · s²` along a direction drawn from the strand's seed) and
/// clumping (a fraction `clump · s` of the way to the nearest guide, `s` the strand
/// parameter).
///
/// **Memory.** Per render strand: a guide record (12 bytes: four 16-bit guide indices,
/// nearest first, and the first `k − 1` weights as 10-bit fractions) besides the
/// [`StrandRoot`] every method keeps; the rest shape of render strands is never stored.
/// Per guide: its rest and bent points (`segments + 1` `vec4` each) and two roots; with
/// simulated guides, the simulation's state instead of the rest points. See
/// [`GuideStrands::memory`].
///
/// Of [`HairParams`] it uses `roots.seed` and `roots.density` (where render strands
/// grow; [`GuideParams::strands`] is their count; without a density map they grow near
/// the guides: at the mesh's vertices within twice the guides' median spacing, or the
/// longest edge, of a guide's root), the wind (on the guides), the level
/// of detail, and what [`GroomStrands`] uses of `growth`. The wind acts on the guides
/// only: later stages see only the interpolated strands.
///
/// **Colour.** Guides with colours of their own ([`GroomStrands::file_colors`]) give
/// each render strand the blend of its guides' colours with the shape's weights, times
/// the strand's brightness jitter; without, `growth.color`.
///
/// **Simulated guides** ([`GuideStrands::simulated`]): the first pass is then a
/// [`SimulateStrands`] of the guides (each guide's root bound to the triangle nearest
/// it, as for a simulated groom), so inertia, gravity, the wind's forces and the
/// colliders act on the guides only, and the render strands follow the simulated
/// guides. The rest of the method is the same; every segment is drawn (the simulated
/// shape has no bend bound for segment reduction).
#[derive(Debug)]
pub struct GuideStrands {
    /// The first pass: the guides bent by the wind, or simulated.
    first: GuidePass,
    /// The frame the guide pass was last prepared for.
    guide_frame: Option<StrandFrame>,
    roots: Vec<StrandRoot>,
    /// One [`GuideRecord`] per render strand, as the second pass reads them.
    records: wgpu::Buffer,
    /// Per render strand, the weighted blend of its guides' own colours (before the
    /// brightness jitter), when the guides have colours.
    file_colors: Option<Vec<Vec3>>,
    constants: GuideUniforms,
    pass: StrandPass,
    rest_roots: wgpu::Buffer,
    /// The box the mesh stays in ([`MeshBuffers::bounds`]).
    mesh_bounds: (Vec3, Vec3),
}

/// The first pass of [`GuideStrands`], which holds the guides' rest shape, roots and
/// colours (in the order the records index).
#[derive(Debug)]
enum GuidePass {
    /// The guides bent by the wind (the groom pass).
    Bent(Box<GroomStrands>),
    /// The guides simulated (no groom pass is built).
    Simulated(Box<SimulatedGuides>),
}

/// Simulated guides: the simulation, and the guides' shape on the CPU (the simulation
/// holds it on the GPU).
#[derive(Debug)]
struct SimulatedGuides {
    sim: SimulateStrands,
    shape: GroomShape,
}

impl GuidePass {
    fn stage(&self) -> &dyn StrandStage {
        match self {
            Self::Bent(bend) => bend.as_ref(),
            Self::Simulated(guides) => &guides.sim,
        }
    }

    fn shape(&self) -> &GroomShape {
        match self {
            Self::Bent(bend) => bend.shape(),
            Self::Simulated(guides) => &guides.shape,
        }
    }
}

/// Bytes [`GuideStrands`] keeps beyond what every stage 1 method keeps (the output
/// vertices and the render strands' rest and drawn [`StrandRoot`]s), from its buffers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GuideMemory {
    /// The guides' rest points (`vec4` each) the bend pass reads; 0 when the guides are
    /// simulated (their rest shape is then part of `guide_state`).
    pub guide_rest: u64,
    /// The bent guides the first pass writes (`vec4` each).
    pub guide_vertices: u64,
    /// The guides' rest and drawn roots.
    pub guide_roots: u64,
    /// One guide record (12 bytes) per render strand.
    pub records: u64,
    /// The simulated guides' state ([`SimulateStrands::state`], 0 when not simulated):
    /// root pose, rest shape, positions and previous positions.
    pub guide_state: u64,
}

impl GuideMemory {
    /// Every byte counted.
    pub fn total(&self) -> u64 {
        self.guide_rest + self.guide_vertices + self.guide_roots + self.records + self.guide_state
    }

    /// What [`GroomStrands`] keeps for `strands` strands of `segments` segments beyond
    /// the same shared buffers: its rest points, one `vec4` per point.
    pub fn groom_rest_bytes(strands: u32, segments: u32) -> u64 {
        u64::from(strands) * u64::from(segments + 1) * 16
    }
}

impl GuideStrands {
    /// Bends `guides` (a groom whose strands are the guides, their roots on or near
    /// `mesh`) and interpolates `params.strands` render strands rooted on `mesh`.
    ///
    /// Errors: bad parameters (naming them), a groom the guide pass refuses (no strands,
    /// arrays that do not agree, ...), more than [`MAX_GUIDES`] guides, a guide whose root
    /// is farther from the mesh than `params.max_root_distance` allows
    /// ([`StrandsError::GuideOffMesh`]), mesh buffers not made from `mesh`, a mesh that
    /// cannot carry roots, and buffers the device cannot bind.
    pub fn new(
        gpu: &Gpu,
        mesh: &Mesh,
        mesh_buffers: &MeshBuffers,
        guides: &Resampled,
        hair: &HairParams,
        params: &GuideParams,
    ) -> crate::Result<Self> {
        Self::build(gpu, mesh, mesh_buffers, guides, hair, params, None)
    }

    /// [`GuideStrands::new`] with the guides simulated with `dynamics`
    /// ([`SimulateStrands::groom`]) instead of bent by the stateless wind: the render
    /// strands are interpolated from the simulated guides every frame.
    /// `mesh_buffers` must hold `mesh` (in any later pose; their `bounds` where the
    /// mesh goes).
    ///
    /// Errors: as [`GuideStrands::new`], and bad dynamics parameters (naming them).
    pub fn simulated(
        gpu: &Gpu,
        mesh: &Mesh,
        mesh_buffers: &MeshBuffers,
        guides: &Resampled,
        hair: &HairParams,
        params: &GuideParams,
        dynamics: &DynamicsParams,
    ) -> crate::Result<Self> {
        Self::build(
            gpu,
            mesh,
            mesh_buffers,
            guides,
            hair,
            params,
            Some(dynamics),
        )
    }

    fn build(
        gpu: &Gpu,
        mesh: &Mesh,
        mesh_buffers: &MeshBuffers,
        guides: &Resampled,
        hair: &HairParams,
        params: &GuideParams,
        dynamics: Option<&DynamicsParams>,
    ) -> crate::Result<Self> {
        params.validate()?;
        if let Some(dynamics) = dynamics {
            dynamics.validate()?;
        }
        mesh_buffers.check_matches(mesh)?;
        if guides.strands > MAX_GUIDES {
            return Err(ParamError::new(
                "groom.strands",
                guides.strands,
                &format!("at most {MAX_GUIDES} guides can be interpolated; subsample them"),
            )
            .into());
        }
        let render = Self::params_for(guides, hair, params)?;
        StrandPass::vertex_bytes(gpu, &render)?;
        let (lo, hi) = mesh.bounds();
        let diagonal = (hi - lo).length();
        check_guides_on_mesh(mesh, guides, params.max_root_distance * diagonal)?;

        // Both first passes shuffle, colour and size the guides as a groom: the same
        // guide at the same index.
        let first = match dynamics {
            None => GuidePass::Bent(Box::new(GroomStrands::labelled(
                gpu,
                guides,
                hair,
                "strands: guides bend",
            )?)),
            Some(dynamics) => {
                let shape = GroomShape::new(gpu, guides, hair)?;
                let sim = SimulateStrands::from_shape(gpu, &shape, mesh, mesh_buffers, dynamics)?;
                GuidePass::Simulated(Box::new(SimulatedGuides { sim, shape }))
            }
        };
        let (guide_stage, shape) = (first.stage(), first.shape());
        let per_guide = guides.segments as usize + 1;
        let guide_roots: Vec<Vec3> = shape.rest.iter().step_by(per_guide).copied().collect();
        let grid = PointGrid::new(&guide_roots);
        let mut render = render;
        if render.roots.density.is_none() {
            render.roots.density = Some(coverage(mesh, &grid));
        }
        let k = params.k.min(guides.strands) as usize;
        let epsilon = 1e-7 * diagonal.max(f32::MIN_POSITIVE);
        let mut roots = sample_roots(mesh, &render.roots, &render.growth)?;
        let mut records = Vec::with_capacity(roots.len());
        let guide_colors = shape.file_colors.as_deref();
        let mut file_colors = guide_colors.map(|_| Vec::with_capacity(roots.len()));
        let jitter = render.growth.color_jitter;
        for root in &mut roots {
            let at = flat_root(mesh, root);
            let nearest = grid.nearest(at, k + 1);
            let (record, weights) = encode_record(&nearest, k, epsilon);
            let blend = |f: &dyn Fn(&StrandRoot) -> f32| -> f32 {
                (nearest.iter().zip(&weights))
                    .map(|(&(guide, _), w)| f(&shape.roots[guide as usize]) * w)
                    .sum()
            };
            root.length = blend(&|g| g.length);
            root.width = blend(&|g| g.width);
            // The guides' own colours, blended with the same weights; the strand's own
            // brightness jitter on top (as grown fur's).
            if let (Some(colors), Some(blended)) = (guide_colors, file_colors.as_mut()) {
                let base: Vec3 = (nearest.iter().zip(&weights))
                    .map(|(&(guide, _), &w)| {
                        colors.get(guide as usize).copied().unwrap_or(Vec3::ZERO) * w
                    })
                    .sum();
                root.color =
                    base * crate::strand_brightness(root.seed, GROWN_BRIGHTNESS_DRAW, jitter);
                blended.push(base);
            }
            records.push(record);
        }
        let constants = GuideUniforms {
            k: k as u32,
            clump: params.clump,
            noise: params.noise,
        };
        let storage = wgpu::BufferUsages::STORAGE;
        let rest_roots = storage_buffer(gpu, "pelage guided rest roots", &roots, storage)?;
        let flat: Vec<u32> = records.iter().flatten().copied().collect();
        let records_buffer = storage_buffer(gpu, "pelage guide records", &flat, storage)?;
        pelage_gpu::audit::constant(&[&rest_roots, &records_buffer]);
        // The guides' own strands are the guide buffer, not the frame's strands.
        pelage_gpu::audit::name_buffer(&guide_stage.buffers().vertices, GUIDE_VERTICES);
        pelage_gpu::audit::name_buffer(&guide_stage.buffers().roots, GUIDE_VERTICES);
        let mesh_bounds = mesh_buffers.bounds;
        let reach = reach_around(
            guide_stage.buffers().reach,
            mesh_bounds,
            &render,
            params.noise,
        );
        let pass = StrandPass::with_inputs(
            gpu,
            "strands: guides",
            "strands/guides.wgsl",
            &render,
            reach,
            &roots,
            &[
                Input::Read(&mesh_buffers.positions),
                Input::Read(&mesh_buffers.indices),
                Input::Read(&rest_roots),
                Input::Read(&records_buffer),
                Input::Read(&guide_stage.buffers().vertices),
            ],
            &constants.overrides(),
        )?;
        Ok(Self {
            first,
            guide_frame: None,
            roots,
            records: records_buffer,
            file_colors,
            constants,
            pass,
            rest_roots,
            mesh_bounds,
        })
    }

    /// The parameters render strands interpolated from `guides` with `params` amount to
    /// (what [`StrandStage::params`] returns): `roots.count` is `params.strands` (seed
    /// and density map from `hair.roots`), `growth.segments` the guides' segments,
    /// `growth.length` the longest guide, `growth.width` their mean root width, flat
    /// roots, no gravity.
    ///
    /// Errors: bad parameters and a groom [`GroomStrands::params_for`] refuses.
    pub fn params_for(
        guides: &Resampled,
        hair: &HairParams,
        params: &GuideParams,
    ) -> crate::Result<HairParams> {
        params.validate()?;
        let mut render = GroomStrands::params_for(guides, hair)?;
        render.roots = hair.roots.clone();
        render.roots.count = params.strands;
        render.roots.length_scale = None;
        render.growth.surface = SurfaceInterpolation::Flat;
        Ok(render)
    }

    /// A world box holding every point render strands interpolated from `guides` can
    /// reach on a mesh inside `mesh_bounds`.
    ///
    /// Errors: as [`GuideStrands::params_for`].
    pub fn reach_of(
        guides: &Resampled,
        mesh_bounds: (Vec3, Vec3),
        hair: &HairParams,
        params: &GuideParams,
    ) -> crate::Result<(Vec3, Vec3)> {
        let guide_reach = GroomStrands::reach_of(guides, hair)?;
        Self::reach_around(guide_reach, mesh_bounds, guides, hair, params)
    }

    /// A world box holding every point render strands interpolated from `guides` can
    /// reach on a mesh inside `mesh_bounds` when the guides stay inside `guide_reach`
    /// (simulated guides: their simulation's reach).
    ///
    /// Errors: as [`GuideStrands::params_for`].
    pub fn reach_around(
        guide_reach: (Vec3, Vec3),
        mesh_bounds: (Vec3, Vec3),
        guides: &Resampled,
        hair: &HairParams,
        params: &GuideParams,
    ) -> crate::Result<(Vec3, Vec3)> {
        let render = Self::params_for(guides, hair, params)?;
        Ok(reach_around(
            guide_reach,
            mesh_bounds,
            &render,
            params.noise,
        ))
    }

    /// The guide pass when the guides are bent by the wind ([`GuideStrands::new`]): the
    /// guides' rest points and roots (inputs of the CPU mirror), and their bent points
    /// ([`StrandStage::buffers`]). `None` when they are simulated.
    pub fn guides(&self) -> Option<&GroomStrands> {
        match &self.first {
            GuidePass::Bent(bend) => Some(bend.as_ref()),
            GuidePass::Simulated(_) => None,
        }
    }

    /// The guides' simulation, when they are simulated ([`GuideStrands::simulated`]):
    /// its vertices are the guides the interpolation reads.
    pub fn simulation(&self) -> Option<&SimulateStrands> {
        match &self.first {
            GuidePass::Bent(_) => None,
            GuidePass::Simulated(guides) => Some(&guides.sim),
        }
    }

    /// The guides' rest roots (length, width, colour, seed), in the order the guide
    /// records index, whichever the first pass.
    pub fn guide_roots(&self) -> &[StrandRoot] {
        &self.first.shape().roots
    }

    /// The first pass: the simulation, or the guides bent by the wind.
    fn guide_stage(&self) -> &dyn StrandStage {
        self.first.stage()
    }

    /// The bytes this method keeps beyond the buffers every stage 1 method keeps.
    pub fn memory(&self) -> GuideMemory {
        let guides = self.guide_stage().buffers();
        let (guide_rest, guide_state) = match &self.first {
            GuidePass::Bent(bend) => (bend.rest_points().len() as u64 * 16, 0),
            GuidePass::Simulated(guides) => (0, guides.sim.state().size()),
        };
        GuideMemory {
            guide_rest,
            guide_vertices: guides.vertices.size(),
            guide_roots: 2 * guides.roots.size(),
            records: self.records.size(),
            guide_state,
        }
    }
}

/// The reach of render strands: a blend of bent guide offsets (each at most the longest
/// guide long) plus the noise's drift from a root inside `mesh_bounds`, or a point of
/// the guides (`guide_reach`), or a point between the two (clumping).
fn reach_around(
    guide_reach: (Vec3, Vec3),
    mesh_bounds: (Vec3, Vec3),
    render: &HairParams,
    noise: f32,
) -> (Vec3, Vec3) {
    let g = &render.growth;
    let pad = Vec3::splat(g.length * (1.0 + 3f32.sqrt() * noise) + g.width);
    let (lo, hi) = (mesh_bounds.0 - pad, mesh_bounds.1 + pad);
    (lo.min(guide_reach.0), hi.max(guide_reach.1))
}

/// The farthest a strand of parameter-span `h` (a fraction of the strand) can be from
/// the chord that skips it, when the guides are at most `guides` from theirs: the blend
/// is as far as its guides (plus the noise's parabola), and clumping adds at most
/// `clump · (guides + blend + h² · longest · (2 + 2√3 · noise) / 4)`.
fn interpolation_error(guides: f32, h: f32, longest: f32, clump: f32, noise: f32) -> f32 {
    let drift = noise * 3f32.sqrt() * longest;
    let blend = guides + drift * h * h / 4.0;
    blend + clump * (guides + blend + h * h * (2.0 * longest + 2.0 * drift) / 4.0)
}

impl StrandStage for GuideStrands {
    fn pass(&self) -> &StrandPass {
        &self.pass
    }

    fn pass_mut(&mut self) -> &mut StrandPass {
        &mut self.pass
    }

    fn roots(&self) -> &[StrandRoot] {
        &self.roots
    }

    /// Prepares both passes: the guides bent for `time` (or simulated up to it), then the
    /// interpolation.
    fn prepare(&mut self, queue: &wgpu::Queue, time: f32) -> crate::Result<StrandFrame> {
        let guide_frame = match &mut self.first {
            GuidePass::Bent(bend) => bend.prepare(queue, time)?,
            GuidePass::Simulated(guides) => guides.sim.prepare(queue, time)?,
        };
        self.guide_frame = Some(guide_frame);
        let uniforms = self.pass.uniforms_at(time);
        self.pass.begin_frame(queue, &uniforms)
    }

    /// Records the guide pass, then the interpolation.
    fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        frame: &StrandFrame,
        mut timer: Option<&mut GpuTimer>,
    ) -> crate::Result<()> {
        frame.check_prepared(self.pass.label(), self.frame().map_or(0, |f| f.id))?;
        let Some(guide_frame) = &self.guide_frame else {
            // Unreachable: prepare sets both frames.
            return Err(crate::FrameOrderError {
                stage: "strands: guides bend".into(),
                prepared: 0,
                given: frame.id,
            }
            .into());
        };
        self.guide_stage()
            .encode(encoder, guide_frame, timer.as_deref_mut())?;
        self.pass
            .record(encoder, frame, timer, frame.layout.strands)
    }

    fn passes(&self) -> Vec<PassInfo> {
        let guides = PassInfo::new(self.guide_stage().pass().label());
        let mut passes = Vec::new();
        let guides = match &self.first {
            GuidePass::Bent(_) => guides,
            GuidePass::Simulated(guides_sim) => {
                // The body's field, rebuilt or read through the skin, comes first.
                let (field, reads) = guides_sim.sim.field_passes();
                passes.extend(field);
                guides.reads([MESH]).reads(reads)
            }
        };
        passes.extend([
            guides.writes([GUIDE_VERTICES]),
            PassInfo::new(self.pass.label())
                .reads([MESH, GUIDE_VERTICES])
                .writes([STRAND_VERTICES, STRAND_ROOTS]),
        ]);
        passes
    }

    fn set_wind(&mut self, wind: WindParams) -> crate::Result<()> {
        match &mut self.first {
            GuidePass::Bent(bend) => bend.set_wind(wind.clone())?,
            GuidePass::Simulated(guides) => guides.sim.set_wind(wind.clone())?,
        }
        self.pass.params.wind = wind;
        Ok(())
    }

    fn reach_with_wind(&self, wind: &WindParams) -> crate::Result<(Vec3, Vec3)> {
        let guide_reach = self.guide_stage().reach_with_wind(wind)?;
        Ok(reach_around(
            guide_reach,
            self.mesh_bounds,
            self.params(),
            self.constants.noise,
        ))
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
            GROWN_BRIGHTNESS_DRAW,
            queue,
            (color, color_jitter),
        )?;
        // Colours blended from the guides' own stay; only their jitter changes.
        let drawn = self.buffers().roots.clone();
        crate::groom::keep_file_colors(
            &mut self.roots,
            (&self.rest_roots, &drawn),
            self.file_colors.as_deref(),
            (GROWN_BRIGHTNESS_DRAW, color_jitter),
            queue,
        )
    }

    /// The guides' simulation, when they are simulated: the colliders a caller moves
    /// with the body act on the guides.
    fn as_simulation_mut(&mut self) -> Option<&mut SimulateStrands> {
        match &mut self.first {
            GuidePass::Bent(_) => None,
            GuidePass::Simulated(guides) => Some(&mut guides.sim),
        }
    }

    /// Segment reduction bounded by the guides' rest shape and the wind's bend (as for
    /// a groom), carried through the blend, the noise and the clumping
    /// (`interpolation_error`); simulated guides: every segment.
    fn level_for_view(
        &self,
        bounds: (Vec3, Vec3),
        camera: &CameraMatrices,
        width: u32,
        height: u32,
    ) -> LodLevel {
        let params = self.params();
        let full = params.growth.segments;
        let turn = bend_per_segment(&params.growth, &params.wind);
        let max_error = params.lod.segment_error_pixels;
        let longest = params.growth.length;
        let GuideUniforms { clump, noise, .. } = self.constants;
        let simulated = matches!(self.first, GuidePass::Simulated(_));
        let shape = self.first.shape();
        LodLevel::for_view_with(params, bounds, camera, width, height, |pixels_per_unit| {
            if simulated {
                return (full, 0.0);
            }
            fewest_segments(full, max_error, pixels_per_unit, |k| {
                let rest = (shape.chord_error)
                    .get(k as usize)
                    .copied()
                    .unwrap_or(f32::MAX);
                let guides = rest + bend_error(k, shape.longest_segment, turn);
                interpolation_error(guides, k as f32 / full as f32, longest, clump, noise)
            })
        })
    }
}

/// Where render strands grow when no density map is given: 1 at the vertices of `mesh`
/// within `max(2 × the guides' median spacing, the longest edge)` of a guide's root, 0
/// elsewhere (so hair grows where the guides are, and every triangle a guide's root is
/// on has a corner inside).
fn coverage(mesh: &Mesh, guides: &PointGrid<'_>) -> Vec<f32> {
    let mut spacing: Vec<f32> = (guides.points.iter())
        .filter_map(|&p| guides.nearest(p, 2).get(1).map(|&(_, d)| d))
        .collect();
    spacing.sort_by(f32::total_cmp);
    let median = spacing.get(spacing.len() / 2).copied().unwrap_or(0.0);
    let longest_edge = (mesh.indices.chunks_exact(3))
        .flat_map(|t| {
            let p = |k: usize| mesh.positions[t[k] as usize];
            [
                p(0).distance(p(1)),
                p(1).distance(p(2)),
                p(2).distance(p(0)),
            ]
        })
        .fold(0.0f32, f32::max);
    let radius = (2.0 * median).max(longest_edge);
    (mesh.positions.iter())
        .map(|&v| {
            let near = guides
                .nearest(v, 1)
                .first()
                .is_some_and(|&(_, d)| d <= radius);
            if near { 1.0 } else { 0.0 }
        })
        .collect()
}

/// The root of `root` on its triangle, flat (as `guides.wgsl` places it).
fn flat_root(mesh: &Mesh, root: &StrandRoot) -> Vec3 {
    let corner = |k: usize| {
        let index = mesh.indices[root.triangle as usize * 3 + k] as usize;
        mesh.positions[index]
    };
    let bw = 1.0 - root.bary.x - root.bary.y;
    corner(0) * root.bary.x + corner(1) * root.bary.y + corner(2) * bw
}

/// The record and the weights (as the shader decodes them) for the guides `nearest`
/// (index and distance, nearest first; `k + 1` of them when there are that many):
/// weights `1/d_i − 1/d_(k+1)` (plain `1/d_i` without a `(k+1)`-th), normalised, the
/// first `k - 1` rounded to 10 bits.
fn encode_record(nearest: &[(u32, f32)], k: usize, epsilon: f32) -> (GuideRecord, Vec<f32>) {
    let taken = &nearest[..k.min(nearest.len())];
    let beyond = nearest.get(k).map_or(0.0, |&(_, d)| 1.0 / d.max(epsilon));
    let mut raw: Vec<f64> = taken
        .iter()
        .map(|&(_, d)| f64::from((1.0 / d.max(epsilon) - beyond).max(0.0)))
        .collect();
    let sum: f64 = raw.iter().sum();
    if sum <= 0.0 || !sum.is_finite() {
        raw.iter_mut().for_each(|w| *w = 1.0);
    }
    let sum: f64 = raw.iter().sum();
    let mut quantized: Vec<u32> = raw
        .iter()
        .take(taken.len().saturating_sub(1))
        .map(|w| (w / sum * f64::from(WEIGHT_ONE)).round() as u32)
        .collect();
    // The last weight is 1 minus the others: keep it >= 0.
    while quantized.iter().sum::<u32>() > WEIGHT_ONE {
        if let Some(largest) = quantized.iter_mut().max() {
            *largest -= 1;
        }
    }
    let mut weights: Vec<f32> = quantized
        .iter()
        .map(|&q| q as f32 / WEIGHT_ONE as f32)
        .collect();
    let last = weights.iter().fold(1.0f32, |rest, w| rest - w);
    weights.push(last);
    // A slot past `k` repeats the nearest guide (weight 0: its points are read anyway,
    // and the nearest guide's are already at hand).
    let first = taken.first().map_or(0, |&(g, _)| g);
    let index = |n: usize| taken.get(n).map_or(first, |&(g, _)| g);
    let packed = quantized
        .iter()
        .enumerate()
        .fold(0u32, |word, (n, &q)| word | (q << (10 * n)));
    let record = [
        index(0) | (index(1) << 16),
        index(2) | (index(3) << 16),
        packed,
    ];
    (record, weights)
}

/// Errors unless every guide's root is within `limit` of a triangle of `mesh`.
fn check_guides_on_mesh(mesh: &Mesh, guides: &Resampled, limit: f32) -> crate::Result<()> {
    let per_guide = guides.segments as usize + 1;
    let grid = TriangleGrid::new(mesh, limit);
    for (guide, &root) in guides.points.iter().step_by(per_guide).enumerate() {
        if grid.any_within(mesh, root, limit) {
            continue;
        }
        let distance = (0..mesh.indices.len() / 3)
            .map(|t| distance_to_triangle(mesh, t, root))
            .fold(f32::INFINITY, f32::min);
        return Err(StrandsError::GuideOffMesh {
            guide: guides
                .source_strands
                .get(guide)
                .copied()
                .unwrap_or(guide as u32),
            distance,
            limit,
        });
    }
    Ok(())
}

/// Distance from `p` to triangle `t` of `mesh` (its closest point,
/// [`closest_on_triangle`]).
pub(crate) fn distance_to_triangle(mesh: &Mesh, t: usize, p: Vec3) -> f32 {
    let corner = |k: usize| mesh.positions[mesh.indices[t * 3 + k] as usize];
    let (a, b, c) = (corner(0), corner(1), corner(2));
    let (u, v, w) = closest_on_triangle(p, a, b, c);
    p.distance(a * u + b * v + c * w)
}

/// A uniform grid of cubic cells over a box, cells numbered x fastest.
#[derive(Debug)]
struct Cells {
    origin: Vec3,
    size: f32,
    dims: [i32; 3],
}

impl Cells {
    /// Cells of side `size` (> 0) covering `lo..hi`, at most `max_per_axis` per axis
    /// (the side grows to keep to it).
    fn new((lo, hi): (Vec3, Vec3), size: f32, max_per_axis: i32) -> Self {
        let extent = (hi - lo).max_element();
        let size = size
            .max(extent / max_per_axis as f32)
            .max(f32::MIN_POSITIVE);
        let dims = ((hi - lo) / size).floor().as_ivec3() + 1;
        Self {
            origin: lo,
            size,
            dims: dims
                .clamp(glam::IVec3::ONE, glam::IVec3::splat(max_per_axis))
                .to_array(),
        }
    }

    /// The cell holding `p`, clamped into the grid.
    fn cell(&self, p: Vec3) -> [i32; 3] {
        let c = ((p - self.origin) / self.size).floor();
        std::array::from_fn(|axis| (c[axis] as i32).clamp(0, self.dims[axis] - 1))
    }

    fn index(&self, c: [i32; 3]) -> usize {
        (c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2])) as usize
    }

    fn count(&self) -> usize {
        self.dims.iter().map(|&d| d as usize).product()
    }

    /// Every cell in `lo..=hi` (cell coordinates, clamped into the grid).
    fn range(&self, lo: [i32; 3], hi: [i32; 3]) -> impl Iterator<Item = [i32; 3]> + '_ {
        let clamp = |c: [i32; 3], axis: usize| c[axis].clamp(0, self.dims[axis] - 1);
        let (x0, y0, z0) = (clamp(lo, 0), clamp(lo, 1), clamp(lo, 2));
        let (x1, y1, z1) = (clamp(hi, 0), clamp(hi, 1), clamp(hi, 2));
        (z0..=z1).flat_map(move |z| (y0..=y1).flat_map(move |y| (x0..=x1).map(move |x| [x, y, z])))
    }
}

/// Points bucketed in a uniform grid (about one per cell), for nearest-neighbour queries.
#[derive(Debug)]
struct PointGrid<'a> {
    points: &'a [Vec3],
    cells: Cells,
    /// `cells.count() + 1` offsets into `order`.
    starts: Vec<u32>,
    /// Point indices sorted by cell.
    order: Vec<u32>,
}

impl<'a> PointGrid<'a> {
    fn new(points: &'a [Vec3]) -> Self {
        let first = points.first().copied().unwrap_or(Vec3::ZERO);
        let bounds = points
            .iter()
            .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let per_axis = (points.len() as f32).cbrt().ceil().max(1.0);
        let extent = (bounds.1 - bounds.0).max_element();
        let cells = Cells::new(bounds, extent / per_axis, 64);
        let key: Vec<usize> = points.iter().map(|&p| cells.index(cells.cell(p))).collect();
        let mut starts = vec![0u32; cells.count() + 1];
        for &k in &key {
            starts[k + 1] += 1;
        }
        for i in 1..starts.len() {
            starts[i] += starts[i - 1];
        }
        let mut order: Vec<u32> = (0..points.len() as u32).collect();
        order.sort_by_key(|&i| (key[i as usize], i));
        Self {
            points,
            cells,
            starts,
            order,
        }
    }

    /// The `n` points nearest `p` (index and distance, nearest first, ties by index),
    /// or all of them when there are fewer.
    fn nearest(&self, p: Vec3, n: usize) -> Vec<(u32, f32)> {
        let n = n.min(self.points.len());
        let centre = self.cells.cell(p);
        let mut found: Vec<(u32, f32)> = Vec::new();
        let reach = self.cells.dims.iter().copied().max().unwrap_or(1);
        for ring in 0..=reach {
            let lo = centre.map(|c| c - ring);
            let hi = centre.map(|c| c + ring);
            for cell in self.cells.range(lo, hi) {
                let on_ring = (0..3).any(|a| (cell[a] - centre[a]).abs() == ring);
                if !on_ring {
                    continue;
                }
                let index = self.cells.index(cell);
                let (start, end) = (self.starts[index] as usize, self.starts[index + 1] as usize);
                for &i in &self.order[start..end] {
                    found.push((i, self.points[i as usize].distance(p)));
                }
            }
            found.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            found.truncate(n);
            // Every point in a later ring is at least `ring` cells away.
            if found.len() == n && found[n - 1].1 <= ring as f32 * self.cells.size {
                break;
            }
        }
        found
    }
}

/// Triangles bucketed by their bounding boxes in a uniform grid.
#[derive(Debug)]
struct TriangleGrid {
    cells: Cells,
    buckets: std::collections::HashMap<usize, Vec<u32>>,
}

impl TriangleGrid {
    /// Cells at least `radius` wide (at most 64 per axis) over `mesh`.
    fn new(mesh: &Mesh, radius: f32) -> Self {
        let cells = Cells::new(mesh.bounds(), radius, 64);
        let mut buckets: std::collections::HashMap<usize, Vec<u32>> = Default::default();
        for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
            let corners = tri.iter().map(|&i| mesh.positions[i as usize]);
            let (lo, hi) =
                corners.fold((Vec3::MAX, Vec3::MIN), |(lo, hi), p| (lo.min(p), hi.max(p)));
            for cell in cells.range(cells.cell(lo), cells.cell(hi)) {
                buckets.entry(cells.index(cell)).or_default().push(t as u32);
            }
        }
        Self { cells, buckets }
    }

    /// Whether a triangle of `mesh` is within `radius` of `p`.
    fn any_within(&self, mesh: &Mesh, p: Vec3, radius: f32) -> bool {
        let (lo, hi) = (p - Vec3::splat(radius), p + Vec3::splat(radius));
        let (bounds_lo, bounds_hi) = mesh.bounds();
        if lo.cmpgt(bounds_hi).any() || hi.cmplt(bounds_lo).any() {
            return false;
        }
        self.cells
            .range(self.cells.cell(lo), self.cells.cell(hi))
            .filter_map(|cell| self.buckets.get(&self.cells.index(cell)))
            .flatten()
            .any(|&t| distance_to_triangle(mesh, t as usize, p) <= radius)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pelage_gpu::read_buffer;

    #[test]
    fn nearest_points_match_a_brute_force_search() {
        let mut h = 7u32;
        let mut next = || {
            h = crate::pcg_hash(h);
            crate::hash_to_unit(h)
        };
        let points: Vec<Vec3> = (0..500)
            .map(|_| Vec3::new(next(), next() * 0.3, next() * 2.0))
            .collect();
        let grid = PointGrid::new(&points);
        for q in 0..200 {
            // Queries inside and well outside the points' box.
            let p =
                Vec3::new(next() * 3.0 - 1.0, next(), next() * 4.0 - 1.0) * (1.0 + q as f32 / 50.0);
            let mut brute: Vec<(u32, f32)> = points
                .iter()
                .enumerate()
                .map(|(i, x)| (i as u32, x.distance(p)))
                .collect();
            brute.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            assert_eq!(grid.nearest(p, 5), brute[..5].to_vec(), "query {p}");
        }
        assert_eq!(PointGrid::new(&points[..2]).nearest(Vec3::ZERO, 5).len(), 2);
    }

    #[test]
    fn weights_sum_to_one_and_vanish_at_the_next_guide() {
        let (record, w) = encode_record(&[(3, 0.1), (9, 0.2), (1, 0.3), (4, 0.4)], 3, 1e-9);
        assert_eq!(w.len(), 3);
        assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6, "{w:?}");
        assert!(w[0] > w[1] && w[1] > w[2] && w[2] > 0.0, "{w:?}");
        assert_eq!(record[0], 3 | (9 << 16));
        assert_eq!(record[1] & 0xffff, 1);
        // The third guide as far as the fourth gets no weight.
        let (_, w) = encode_record(&[(0, 0.1), (1, 0.2), (2, 0.4), (3, 0.4)], 3, 1e-9);
        assert!(w[2].abs() < 2e-3, "{w:?}");
        // One guide: weight 1, nothing stored.
        let (record, w) = encode_record(&[(5, 2.0)], 1, 1e-9);
        assert_eq!((record, w), ([5 | (5 << 16), 5 | (5 << 16), 0], vec![1.0]));
        // Equal distances: equal weights.
        let (_, w) = encode_record(&[(0, 1.0), (1, 1.0), (2, 1.0)], 2, 1e-9);
        assert!(
            (w[0] - 0.5).abs() < 1e-3 && (w[1] - 0.5).abs() < 1e-3,
            "{w:?}"
        );
    }

    /// `count` guides rooted on the upper half of a sphere of radius 0.5 (a golden-angle
    /// spiral), hanging out and down, 8 segments each.
    fn spiral_guides(count: usize) -> Resampled {
        let strands: Vec<Vec<Vec3>> = (0..count)
            .map(|i| {
                let a = i as f32 * 2.399_963;
                let y = 1.0 - (i as f32 + 0.5) / count as f32;
                let r = (1.0 - y * y).sqrt();
                let n = Vec3::new(r * a.cos(), y, r * a.sin());
                (0..12)
                    .map(|k| n * (0.5 + 0.3 * k as f32 / 11.0) - Vec3::Y * (0.02 * k as f32))
                    .collect()
            })
            .collect();
        pelage_scene::Groom::from_strands(&strands)
            .and_then(|g| g.resample(8))
            .expect("a valid groom")
    }

    /// The records the GPU pass reads (its storage buffer, read back and decoded as
    /// `guides.wgsl` decodes them) hold, for every render strand, the guides and weights
    /// the CPU mirror chooses from the roots' positions by the documented rule: the
    /// choice is checked, not handed to the mirror. Also: `k` is capped by the guide
    /// count, and two builds give the same records.
    #[test]
    fn the_records_on_the_gpu_hold_the_guides_the_mirror_chooses() {
        use pelage_reference::guides::{choose_guides, decode_record, guide_count};
        use pelage_reference::strands::Root;

        let gpu = Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
        let mesh = Mesh::icosphere(0.5, 2).expect("icosphere");
        let buffers = MeshBuffers::upload(&gpu, &mesh).expect("mesh buffers");
        let hair = HairParams::default();
        for (guides, k) in [(40, 1), (40, 2), (40, 3), (40, 4), (3, 4), (1, 4)] {
            let groom = spiral_guides(guides);
            let params = GuideParams {
                strands: 700,
                k,
                ..GuideParams::default()
            };
            let build = || GuideStrands::new(&gpu, &mesh, &buffers, &groom, &hair, &params);
            let strands = build().expect("guide strands");
            let want_k = guide_count(&params, guides);
            assert_eq!(strands.constants.k, want_k, "{guides} guides, k = {k}");
            assert_eq!(want_k, k.min(guides as u32));
            let words = read_buffer(&gpu, &strands.records).expect("read the records");
            let words: &[u32] = bytemuck::cast_slice(&words);
            let roots: Vec<Root> = strands
                .roots
                .iter()
                .map(|r| Root {
                    triangle: r.triangle,
                    seed: r.seed,
                    bary: r.bary,
                    length: r.length,
                    width: r.width,
                    phase: r.phase,
                    tilt: r.tilt,
                    azimuth: r.azimuth,
                    color: r.color,
                    region: r.region,
                })
                .collect();
            let per_guide = groom.segments as usize + 1;
            let guide_roots: Vec<Vec3> = strands
                .first
                .shape()
                .rest
                .iter()
                .step_by(per_guide)
                .copied()
                .collect();
            let chosen = choose_guides(&mesh, &roots, &guide_roots, want_k);
            assert_eq!(words.len(), 3 * chosen.len());
            let mut blended = 0;
            for (strand, (record, choice)) in words.chunks_exact(3).zip(&chosen).enumerate() {
                let on_gpu = decode_record(&[record[0], record[1], record[2]], want_k);
                assert_eq!(
                    &on_gpu, choice,
                    "strand {strand} ({guides} guides, k = {k})"
                );
                blended += usize::from(choice.weights[..want_k as usize].iter().all(|&w| w > 0.0));
            }
            // Most strands blend all k guides (the weights are no degenerate 1, 0, 0, ...).
            assert!(blended * 2 > chosen.len(), "{blended} of {}", chosen.len());
            // A second build of the same inputs writes the same records.
            let again = build().expect("guide strands");
            let words_again = read_buffer(&gpu, &again.records).expect("read the records");
            assert_eq!(bytemuck::cast_slice::<u8, u32>(&words_again), words);
        }
    }

    #[test]
    fn triangle_distance_is_that_to_the_closest_point() {
        let mesh = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Z],
            normals: vec![Vec3::Y; 3],
            indices: vec![0, 1, 2],
            uvs: Vec::new(),
        };
        let d = |p: Vec3| distance_to_triangle(&mesh, 0, p);
        assert!((d(Vec3::new(0.2, 0.5, 0.2)) - 0.5).abs() < 1e-6);
        assert!((d(Vec3::new(-1.0, 0.0, -1.0)) - 2f32.sqrt()).abs() < 1e-6);
        assert!((d(Vec3::new(1.0, 0.0, 1.0)) - 0.5f32.sqrt()).abs() < 1e-6);
        assert!((d(Vec3::new(0.5, 0.0, -2.0)) - 2.0).abs() < 1e-6);
        let grid = TriangleGrid::new(&mesh, 0.1);
        assert!(grid.any_within(&mesh, Vec3::new(0.3, 0.05, 0.3), 0.1));
        assert!(!grid.any_within(&mesh, Vec3::new(0.3, 0.5, 0.3), 0.1));
    }
}
