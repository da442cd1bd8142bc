//! The growth pass: one compute invocation per strand (`wgsl/strands/grow.wgsl`), and
//! what every stage 1 method shares ([`StrandPass`], [`StrandStage`]).

use encase::ShaderType;
use glam::Vec3;
use pelage_gpu::{
    BindLayout, Gpu, GpuTimer, PassInfo, UniformBuffer, compute_pipeline_with_constants,
    dispatch_size, storage_buffer, wgpu, zeroed_storage,
};
use pelage_scene::{
    CameraMatrices, GrowthParams, HairParams, HairType, Mesh, SurfaceInterpolation, WindParams,
};

use crate::{
    LodLevel, MESH, MeshBuffers, STRAND_ROOTS, STRAND_VERTICES, StrandBuffers, StrandFrame,
    StrandRoot, StrandStyle, sample_roots,
};

/// Workgroup size of `grow.wgsl` and `groom.wgsl`.
const WORKGROUP: u32 = 64;

/// The uniforms of `grow.wgsl` and `groom.wgsl` (`GrowUniforms` in `strands/force.wgsl`),
/// rewritten every frame. Internal: the CPU mirrors work them out from the parameters on
/// their own, so that a mistake here shows as a difference from the mirror.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub(crate) struct GrowUniforms {
    /// Strands grown this frame (a prefix of the groom: see [`LodLevel`]).
    pub strand_count: u32,
    /// Segments per strand of the groom (each strand is grown at this resolution).
    pub segments: u32,
    /// Strands in the groom (`x = (i + ½) / strand_total` is strand `i`'s priority).
    pub strand_total: u32,
    /// Every `step`-th vertex is written: `segments / step` segments per strand, stored
    /// one strand after the other.
    pub step: u32,
    /// Stochastic simplification's `λ`.
    pub lod_lambda: f32,
    /// Its effective transition half width `t_e`.
    pub lod_t_e: f32,
    /// Its width scale at `x = 0`.
    pub lod_s_max: f32,
    /// Its width scale at `x = 1`.
    pub lod_s_min: f32,
    /// 0 = flat, 1 = PN triangle.
    pub surface: u32,
    /// Seed 001's force weight.
    pub force_weight: f32,
    /// Time in seconds.
    pub time: f32,
    /// Gravity force.
    pub gravity: Vec3,
    /// Mean wind force.
    pub wind_strength: f32,
    /// Unit wind direction, zero for none.
    pub wind_direction: Vec3,
    /// Relative gust amplitude.
    pub gust_strength: f32,
    /// Gusts per second.
    pub gust_frequency: f32,
    /// Turbulence force amplitude.
    pub turbulence: f32,
    /// Turbulence cells per scene unit.
    pub turbulence_scale: f32,
    /// Turbulence advection speed.
    pub turbulence_speed: f32,
    /// Seed of the wind noise.
    pub seed: u32,
    /// Spread of per-strand gust phases, seconds.
    pub phase_spread: f32,
}

impl GrowUniforms {
    /// The uniforms for `params` at time `t`, every strand and segment at full width.
    pub fn new(params: &HairParams, time: f32) -> Self {
        Self::at_level(params, time, &LodLevel::full(params))
    }

    /// The uniforms for `params` at time `t` and level of detail `level`.
    pub fn at_level(params: &HairParams, time: f32, level: &LodLevel) -> Self {
        let g = &params.growth;
        let w = &params.wind;
        let step = if level.segments > 0 && g.segments.is_multiple_of(level.segments) {
            g.segments / level.segments
        } else {
            1
        };
        Self {
            strand_count: level.strands.min(params.roots.count),
            segments: g.segments,
            strand_total: params.roots.count,
            step,
            lod_lambda: level.zone.lambda,
            lod_t_e: level.zone.t_e,
            lod_s_max: level.zone.s_max,
            lod_s_min: level.zone.s_min,
            surface: match g.surface {
                SurfaceInterpolation::Flat => 0,
                SurfaceInterpolation::PnTriangle => 1,
            },
            force_weight: g.force_weight,
            time,
            gravity: g.gravity,
            wind_strength: w.strength,
            wind_direction: w.direction.normalize_or_zero(),
            gust_strength: w.gust_strength,
            gust_frequency: w.gust_frequency,
            turbulence: w.turbulence,
            turbulence_scale: w.turbulence_scale,
            turbulence_speed: w.turbulence_speed,
            seed: params.roots.seed,
            phase_spread: w.phase_spread,
        }
    }
}

/// One region's strand shape as `grow.wgsl` reads it (`RegionShape` there): the
/// storage buffer of a [`GrowStrands`] holds one per region, region 0 first, and each
/// strand reads the one of its [`StrandRoot::region`].
#[derive(Clone, Copy, Debug, Default, PartialEq, ShaderType)]
pub(crate) struct RegionShape {
    /// 0 = straight, 1 = wavy, 2 = curly.
    pub kind: u32,
    /// Wavy: amplitude. Curly: radius.
    pub a: f32,
    /// Wavy: frequency. Curly: pitch.
    pub b: f32,
}

impl RegionShape {
    /// The shape of `hair_type`.
    pub fn of(hair_type: HairType) -> Self {
        match hair_type {
            HairType::Straight => Self::default(),
            HairType::Wavy {
                amplitude,
                frequency,
            } => Self {
                kind: 1,
                a: amplitude,
                b: frequency,
            },
            HairType::Curly { radius, pitch } => Self {
                kind: 2,
                a: radius,
                b: pitch,
            },
        }
    }

    /// One shape per region of `growth`, region 0 (`growth.hair_type`) first.
    pub fn all(growth: &GrowthParams) -> Vec<Self> {
        growth
            .resolved_regions()
            .iter()
            .map(|g| Self::of(g.hair_type))
            .collect()
    }
}

/// Stage 1: grows strands over a mesh for any time `t`.
///
/// The per-frame calls (`set_lod`, `prepare`, `encode`, `buffers`, ...) are those of
/// every stage 1 method, in [`StrandStage`].
///
/// ```no_run
/// # fn demo(gpu: &pelage_gpu::Gpu) -> Result<(), pelage_strands::StrandsError> {
/// use pelage_scene::{HairParams, Mesh};
/// use pelage_strands::{GrowStrands, MeshBuffers, StrandStage};
/// let mesh = Mesh::creature();
/// let mesh_buffers = MeshBuffers::upload(gpu, &mesh)?;
/// let mut strands = GrowStrands::new(gpu, &mesh, &mesh_buffers, &HairParams::default())?;
/// let frame = strands.prepare(&gpu.queue, 0.5)?;
/// let mut encoder = gpu.device.create_command_encoder(&Default::default());
/// strands.encode(&mut encoder, &frame, None)?;
/// gpu.queue.submit([encoder.finish()]);
/// # Ok(()) }
/// ```
#[derive(Debug)]
pub struct GrowStrands {
    roots: Vec<StrandRoot>,
    pass: StrandPass,
    /// The rest roots the pass reads (rewritten by [`StrandStage::set_color`]).
    rest_roots: wgpu::Buffer,
    /// Each strand's colour texture factor ([`crate::root_tint`]); empty without one.
    tints: Vec<Vec3>,
}

impl GrowStrands {
    /// Samples roots on `mesh` (the rest pose; `mesh_buffers` may be rewritten later),
    /// allocates the strand buffers and builds the pipeline.
    pub fn new(
        gpu: &Gpu,
        mesh: &Mesh,
        mesh_buffers: &MeshBuffers,
        params: &HairParams,
    ) -> crate::Result<Self> {
        params.validate(mesh.positions.len())?;
        mesh_buffers.check_matches(mesh)?;
        // Refuse a groom the device cannot hold before spending time on its roots.
        StrandPass::vertex_bytes(gpu, params)?;
        let roots = sample_roots(mesh, &params.roots, &params.growth)?;
        let tints = if params.roots.textures.color.is_some() {
            roots
                .iter()
                .map(|r| {
                    let (u, v) = (r.bary.x, r.bary.y);
                    crate::root_tint(
                        mesh,
                        &params.roots,
                        r.triangle as usize,
                        [u, v, 1.0 - u - v],
                    )
                })
                .collect()
        } else {
            Vec::new()
        };
        let shapes = RegionShape::all(&params.growth);
        let storage = wgpu::BufferUsages::STORAGE;
        let rest_roots = storage_buffer(gpu, "pelage strand rest roots", &roots, storage)?;
        let shapes_buffer = storage_buffer(gpu, "pelage strand region shapes", &shapes, storage)?;
        pelage_gpu::audit::constant(&[&rest_roots, &shapes_buffer]);
        let pass = StrandPass::new(
            gpu,
            "strands: grow",
            "strands/grow.wgsl",
            params,
            Self::reach_of(mesh, params),
            &roots,
            &[
                &mesh_buffers.positions,
                &mesh_buffers.normals,
                &mesh_buffers.indices,
                &rest_roots,
                &shapes_buffer,
            ],
        )?;
        let mut pass = pass;
        // The mesh buffers may be rewritten every frame (skinning): a frame input.
        pass.inputs = &[MESH];
        Ok(Self {
            roots,
            pass,
            rest_roots,
            tints,
        })
    }

    /// A world box holding every point fur grown on `mesh` with `params` can reach: the
    /// mesh's bounds grown by the longest strand of any region (length, jitter and
    /// length map) and the widest. (A strand is a polyline of its length from its root,
    /// whatever the wind; a length texture scales by at most 1.)
    pub fn reach_of(mesh: &Mesh, params: &HairParams) -> (Vec3, Vec3) {
        let (lo, hi) = mesh.bounds();
        let map_max = params
            .roots
            .length_scale
            .as_ref()
            .map_or(1.0, |m| m.iter().copied().fold(0.0f32, f32::max));
        let reach = params
            .growth
            .resolved_regions()
            .iter()
            .map(|g| g.length * (1.0 + g.length_jitter) * map_max + g.width)
            .fold(0.0f32, f32::max);
        (lo - Vec3::splat(reach), hi + Vec3::splat(reach))
    }
}

impl StrandStage for GrowStrands {
    fn pass(&self) -> &StrandPass {
        &self.pass
    }

    fn pass_mut(&mut self) -> &mut StrandPass {
        &mut self.pass
    }

    fn roots(&self) -> &[StrandRoot] {
        &self.roots
    }

    fn set_color(
        &mut self,
        queue: &wgpu::Queue,
        color: Vec3,
        color_jitter: f32,
    ) -> crate::Result<()> {
        // Each strand keeps its region's colour (the new one for region 0) and tint.
        let mut growth = self.pass.params.growth.clone();
        growth.color = color;
        let regions = growth.resolved_regions();
        let tints = &self.tints;
        recolor_with(
            &mut self.pass,
            &mut self.roots,
            &self.rest_roots,
            crate::roots::GROWN_BRIGHTNESS_DRAW,
            queue,
            (color, color_jitter),
            &|i, root| {
                let base = regions.get(root.region as usize).map_or(color, |g| g.color);
                base * tints.get(i).copied().unwrap_or(Vec3::ONE)
            },
        )
    }

    fn level_for_view(
        &self,
        bounds: (Vec3, Vec3),
        camera: &CameraMatrices,
        width: u32,
        height: u32,
    ) -> LodLevel {
        LodLevel::for_view(self.params(), bounds, camera, width, height)
    }
}

/// What every stage 1 method shares: its pipeline and bind group, the per-frame
/// uniforms, the [`StrandBuffers`] it writes and the level of detail it draws.
/// A method's shader reads the uniforms at binding 0, its own inputs next, then writes
/// the vertices and the drawn roots at the last two bindings.
#[derive(Debug)]
pub struct StrandPass {
    /// The timestamp label of the pass.
    label: &'static str,
    /// The frame inputs the pass reads besides its own buffers (see
    /// [`StrandStage::passes`]).
    pub(crate) inputs: &'static [&'static str],
    /// What the pass keeps from frame to frame and rewrites (a simulation's state).
    pub(crate) state: &'static [&'static str],
    pub(crate) params: HairParams,
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    uniforms: UniformBuffer<GrowUniforms>,
    buffers: StrandBuffers,
    /// The level of detail the next `prepare` grows.
    level: LodLevel,
    /// The frame the last `prepare` returned (none before the first).
    frame: Option<StrandFrame>,
    limits: wgpu::Limits,
}

impl StrandPass {
    /// Bytes of the vertex buffer `params` needs at full detail, refused when the device
    /// cannot bind that much.
    pub(crate) fn vertex_bytes(gpu: &Gpu, params: &HairParams) -> crate::Result<u64> {
        let bytes = u64::from(params.roots.count) * u64::from(params.growth.segments + 1) * 16;
        gpu.check_storage_size("strand vertices", bytes)?;
        Ok(bytes)
    }

    /// Allocates the strand buffers for `params` (`roots` are the rest roots, copied to
    /// the drawn roots; every vertex stays in `reach`) and builds `shader`'s pipeline
    /// with the uniforms, `inputs` (read-only storage), the vertices and the drawn roots
    /// bound in that order.
    pub(crate) fn new(
        gpu: &Gpu,
        label: &'static str,
        shader: &str,
        params: &HairParams,
        reach: (Vec3, Vec3),
        roots: &[StrandRoot],
        inputs: &[&wgpu::Buffer],
    ) -> crate::Result<Self> {
        let inputs: Vec<Input> = inputs.iter().copied().map(Input::Read).collect();
        Self::with_inputs(gpu, label, shader, params, reach, roots, &inputs, &[])
    }

    /// [`StrandPass::new`] with inputs of any [`Input`] kind, and values for the shader's
    /// pipeline-overridable constants, by name (the method's own constants).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn with_inputs(
        gpu: &Gpu,
        label: &'static str,
        shader: &str,
        params: &HairParams,
        reach: (Vec3, Vec3),
        roots: &[StrandRoot],
        inputs: &[Input<'_>],
        overrides: &[(&str, f64)],
    ) -> crate::Result<Self> {
        let vertex_bytes = Self::vertex_bytes(gpu, params)?;
        let uniforms = UniformBuffer::new(
            gpu,
            "pelage strand uniforms",
            &GrowUniforms::new(params, 0.0),
        )?;
        let storage = wgpu::BufferUsages::STORAGE;
        // What later stages read: the roots with this frame's LOD width.
        let roots_buffer = storage_buffer(gpu, "pelage strand roots", roots, storage)?;
        let vertices = zeroed_storage(gpu, "pelage strand vertices", vertex_bytes, storage)?;
        pelage_gpu::audit::name_buffer(&vertices, crate::STRAND_VERTICES);
        pelage_gpu::audit::name_buffer(&roots_buffer, crate::STRAND_ROOTS);
        let (pipeline, bind_group) = Self::bind(
            gpu,
            label,
            shader,
            inputs,
            overrides,
            [&uniforms.buffer, &vertices, &roots_buffer],
        )?;
        let style = StrandStyle {
            max_width: roots
                .iter()
                .map(|r| r.width)
                .fold(params.growth.width, f32::max),
            ..StrandStyle::of(&params.growth)
        };
        Ok(Self {
            label,
            inputs: &[],
            state: &[],
            params: params.clone(),
            pipeline,
            bind_group,
            uniforms,
            buffers: StrandBuffers::new(
                vertices,
                roots_buffer,
                params.roots.count,
                params.growth.segments,
                style,
                reach,
            )?,
            level: LodLevel::full(params),
            frame: None,
            limits: gpu.limits().clone(),
        })
    }
}

impl StrandPass {
    /// The pipeline of `shader` and its bind group: `own` (the uniforms, the vertices and
    /// the drawn roots) around `inputs` (see [`StrandPass::with_inputs`]).
    fn bind(
        gpu: &Gpu,
        label: &'static str,
        shader: &str,
        inputs: &[Input<'_>],
        overrides: &[(&str, f64)],
        own: [&wgpu::Buffer; 3],
    ) -> crate::Result<(wgpu::ComputePipeline, wgpu::BindGroup)> {
        let module = crate::SHADERS.library().module(gpu, shader)?;
        let (pipeline, bind_group) = gpu.scoped(|device| {
            // grow.wgsl / groom.wgsl: the uniforms (force.wgsl), the read-only inputs,
            // then the vertices and drawn roots written.
            let inputs_end = inputs.len() as u32 + 1;
            let layout = (1..inputs_end)
                .zip(inputs)
                .fold(
                    BindLayout::new(label, wgpu::ShaderStages::COMPUTE).uniform(0),
                    |layout, (binding, input)| match input {
                        Input::Read(_) => layout.storage(binding),
                        Input::ReadWrite(_) => layout.storage_rw(binding),
                        Input::Uniform(_) => layout.uniform(binding),
                        Input::Texture3d(_) => layout.entry(
                            binding,
                            wgpu::BindingType::Texture {
                                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                                view_dimension: wgpu::TextureViewDimension::D3,
                                multisampled: false,
                            },
                        ),
                    },
                )
                .storage_rw(inputs_end)
                .storage_rw(inputs_end + 1)
                .build(device);
            let pipeline = compute_pipeline_with_constants(
                device,
                label,
                &module,
                "main",
                &[Some(&layout)],
                overrides,
            );
            let mut entries = vec![wgpu::BindGroupEntry {
                binding: 0,
                resource: own[0].as_entire_binding(),
            }];
            entries.extend(
                (1..)
                    .zip(inputs)
                    .map(|(binding, input)| wgpu::BindGroupEntry {
                        binding,
                        resource: match input {
                            Input::Read(b) | Input::ReadWrite(b) | Input::Uniform(b) => {
                                b.as_entire_binding()
                            }
                            Input::Texture3d(view) => wgpu::BindingResource::TextureView(view),
                        },
                    }),
            );
            for (binding, buffer) in [(inputs_end, own[1]), (inputs_end + 1, own[2])] {
                entries.push(wgpu::BindGroupEntry {
                    binding,
                    resource: buffer.as_entire_binding(),
                });
            }
            let bind_group = pelage_gpu::create_bind_group(
                device,
                &wgpu::BindGroupDescriptor {
                    label: Some(label),
                    layout: &layout,
                    entries: &entries,
                },
            );
            (pipeline, bind_group)
        })?;
        Ok((pipeline, bind_group))
    }

    /// Builds the pipeline and bind group again over new `inputs` (the same kinds of
    /// input the shader declares), keeping the pass's own buffers: the strand buffers
    /// later stages bound stay the same.
    pub(crate) fn rebind(
        &mut self,
        gpu: &Gpu,
        shader: &str,
        inputs: &[Input<'_>],
        overrides: &[(&str, f64)],
    ) -> crate::Result<()> {
        let (pipeline, bind_group) = Self::bind(
            gpu,
            self.label,
            shader,
            inputs,
            overrides,
            [
                &self.uniforms.buffer,
                &self.buffers.vertices,
                &self.buffers.roots,
            ],
        )?;
        self.pipeline = pipeline;
        self.bind_group = bind_group;
        Ok(())
    }

    /// What [`StrandStage::prepare`] does once the method knows its uniforms: writes
    /// them and starts the frame at the level of detail last set.
    pub(crate) fn begin_frame(
        &mut self,
        queue: &wgpu::Queue,
        uniforms: &GrowUniforms,
    ) -> crate::Result<StrandFrame> {
        self.uniforms.write(queue, uniforms)?;
        let frame = StrandFrame::next(self.level.layout());
        self.frame = Some(frame);
        Ok(frame)
    }

    /// What [`StrandStage::encode`] does: records the pass for `frame` (which must be
    /// the one [`StrandPass::begin_frame`] returned last) over `strands` invocations.
    pub(crate) fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        frame: &StrandFrame,
        timer: Option<&mut GpuTimer>,
        strands: u32,
    ) -> crate::Result<()> {
        frame.check_prepared(self.label, self.frame.map_or(0, |f| f.id))?;
        let timestamp_writes = timer.and_then(|t| t.compute_pass(self.label));
        let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(self.label),
            timestamp_writes,
        });
        compute.set_pipeline(&self.pipeline);
        pelage_gpu::set_bind_group(&mut compute, 0, &self.bind_group);
        let groups = dispatch_size(&self.limits, u64::from(strands), WORKGROUP);
        compute.dispatch_workgroups(groups.0, groups.1, 1);
        Ok(())
    }

    /// The timestamp label of the pass.
    pub(crate) fn label(&self) -> &'static str {
        self.label
    }

    /// The uniforms of a frame at `time`, at the level of detail last set.
    pub(crate) fn uniforms_at(&self, time: f32) -> GrowUniforms {
        GrowUniforms::at_level(&self.params, time, &self.level)
    }
}

/// How a method's shader binds one of its own inputs (between the uniforms at binding
/// 0 and the vertices and drawn roots at the last two bindings).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Input<'a> {
    /// `var<storage, read>`.
    Read(&'a wgpu::Buffer),
    /// `var<storage, read_write>` (state the method keeps from frame to frame).
    ReadWrite(&'a wgpu::Buffer),
    /// `var<uniform>`.
    Uniform(&'a wgpu::Buffer),
    /// `texture_3d<f32>` read with `textureLoad` (not filterable: a simulation's body
    /// distance field).
    Texture3d(&'a wgpu::TextureView),
}

/// The shape every stage 1 method has: [`GrowStrands`] (fur grown from a mesh),
/// [`GroomStrands`](crate::GroomStrands) (a groom file bent by the wind),
/// [`GuideStrands`](crate::GuideStrands) (render strands interpolated from guides) and
/// [`SimulateStrands`](crate::SimulateStrands) (grown fur or a groom simulated). Each frame:
/// [`StrandStage::set_lod`] (optional), [`StrandStage::prepare`], which returns the
/// frame's [`StrandFrame`], then [`StrandStage::encode`] with that frame; later passes
/// bind [`StrandStage::buffers`] and are prepared and recorded with the same frame
/// (the shape of every stage: `prepare` writes the per-frame uniforms, `encode`
/// records, both take the [`StrandFrame`]). `Send + Sync` on native targets, as every
/// stage is, so that an engine keeps a `pelage::Frame` in shared
/// state.
pub trait StrandStage: std::fmt::Debug + wgpu::WasmNotSendSync {
    /// The state the method shares with every other.
    fn pass(&self) -> &StrandPass;

    /// The same, to change.
    fn pass_mut(&mut self) -> &mut StrandPass;

    /// One root per strand, in the order of the strand buffer (input of the CPU mirror).
    fn roots(&self) -> &[StrandRoot];

    /// The level of detail `params().lod` asks for when the hair, inside the world box
    /// `bounds`, is seen by `camera` on a `width` x `height` target (see
    /// [`LodLevel::for_view`]; each method bounds the error of its segment reduction).
    fn level_for_view(
        &self,
        bounds: (Vec3, Vec3),
        camera: &CameraMatrices,
        width: u32,
        height: u32,
    ) -> LodLevel;

    /// Writes the uniforms for time `time` at the level of detail last given to
    /// [`StrandStage::set_lod`], and returns the frame this is: its
    /// [`StrandLayout`](crate::StrandLayout) for every later pass's `prepare`, and the id
    /// every `encode` of this frame checks.
    fn prepare(&mut self, queue: &wgpu::Queue, time: f32) -> crate::Result<StrandFrame> {
        if !time.is_finite() {
            return Err(pelage_scene::ParamError {
                name: "time".into(),
                value: format!("{time}"),
                reason: "must be finite".into(),
            }
            .into());
        }
        let uniforms = self.pass().uniforms_at(time);
        self.pass_mut().begin_frame(queue, &uniforms)
    }

    /// The frame the last [`StrandStage::prepare`] returned (`None` before the first).
    fn frame(&self) -> Option<StrandFrame> {
        self.pass().frame
    }

    /// Sets the level of detail the next [`StrandStage::prepare`] draws; see
    /// [`StrandStage::level_for_view`]. A level asking for more strands than the groom
    /// has, or for a segment count that does not divide the groom's, is an error.
    fn set_lod(&mut self, level: LodLevel) -> crate::Result<()> {
        let pass = self.pass_mut();
        let segments = pass.params.growth.segments;
        if level.strands == 0 || level.strands > pass.params.roots.count {
            return Err(pelage_scene::ParamError::new(
                "lod.strands",
                level.strands,
                &format!("must be in 1..={}", pass.params.roots.count),
            )
            .into());
        }
        if level.segments == 0 || !segments.is_multiple_of(level.segments) {
            return Err(pelage_scene::ParamError::new(
                "lod.segments",
                level.segments,
                &format!("must divide the groom's {segments} segments"),
            )
            .into());
        }
        pass.level = level;
        Ok(())
    }

    /// The level of detail in use.
    fn lod(&self) -> &LodLevel {
        &self.pass().level
    }

    /// Replaces the wind (validated); takes effect at the next `prepare`.
    /// [`StrandBuffers::reach`] keeps the wind the method was built with: a groom in a
    /// much stronger wind may leave it (rebuild the stage then).
    fn set_wind(&mut self, wind: WindParams) -> crate::Result<()> {
        wind.validate()?;
        self.pass_mut().params.wind = wind;
        Ok(())
    }

    /// Recolours every strand as if the method had been built with `growth.color =
    /// color` and `growth.color_jitter = color_jitter` (each strand keeps its brightness
    /// draw, so the colours are bit for bit those of a new method): rewrites the roots
    /// (rest and drawn; the drawn widths come back at the next `encode`), taking effect at
    /// the next submit. Refuses a negative or non-finite colour or a jitter outside
    /// [0, 1), naming it, and then changes nothing.
    fn set_color(
        &mut self,
        queue: &wgpu::Queue,
        color: Vec3,
        color_jitter: f32,
    ) -> crate::Result<()>;

    /// The [`StrandBuffers::reach`] a method built with `wind` (and otherwise these
    /// parameters) would have: the same for grown fur, whose reach does not depend on the
    /// wind; for a groom, how far the wind can swing it. When it differs from the reach in
    /// use, [`StrandStage::set_wind`] leaves the later stages sized for the old wind.
    fn reach_with_wind(&self, wind: &WindParams) -> crate::Result<(Vec3, Vec3)> {
        wind.validate()?;
        Ok(self.buffers().reach)
    }

    /// Records the pass for `frame`, which must be the one the last
    /// [`StrandStage::prepare`] returned.
    fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        frame: &StrandFrame,
        timer: Option<&mut GpuTimer>,
    ) -> crate::Result<()> {
        self.pass()
            .record(encoder, frame, timer, frame.layout.strands)
    }

    /// The passes [`StrandStage::encode`] records, with the named resources each reads
    /// and writes ([`STRAND_VERTICES`], [`STRAND_ROOTS`]; [`MESH`] for grown fur), for a
    /// [`FramePlan`](pelage_gpu::FramePlan).
    fn passes(&self) -> Vec<PassInfo> {
        let pass = self.pass();
        vec![
            PassInfo::new(pass.label)
                .reads(pass.inputs.iter().copied())
                .writes([STRAND_VERTICES, STRAND_ROOTS])
                .writes(pass.state.iter().copied()),
        ]
    }

    /// The method as a [`SimulateStrands`](crate::SimulateStrands) (`None` for the
    /// stateless methods): what a caller moving colliders with the body needs.
    fn as_simulation_mut(&mut self) -> Option<&mut crate::SimulateStrands> {
        None
    }

    /// The buffers this stage writes.
    fn buffers(&self) -> &StrandBuffers {
        &self.pass().buffers
    }

    /// The parameters in use (for a groom, those its strands amount to).
    fn params(&self) -> &HairParams {
        &self.pass().params
    }
}

/// What [`StrandStage::set_color`] does for either method: validates `(color, jitter)`,
/// recolours `roots` from each strand's `draw`-th hash draw, writes them to `rest` and to
/// the drawn roots, and keeps the new colour in the pass's parameters.
pub(crate) fn recolor(
    pass: &mut StrandPass,
    roots: &mut [StrandRoot],
    rest: &wgpu::Buffer,
    draw: u32,
    queue: &wgpu::Queue,
    (color, jitter): (Vec3, f32),
) -> crate::Result<()> {
    recolor_with(pass, roots, rest, draw, queue, (color, jitter), &|_, _| {
        color
    })
}

/// [`recolor`] with each strand's colour before its brightness given by `base` (of the
/// strand's index and root), called after `(color, jitter)` is validated.
pub(crate) fn recolor_with(
    pass: &mut StrandPass,
    roots: &mut [StrandRoot],
    rest: &wgpu::Buffer,
    draw: u32,
    queue: &wgpu::Queue,
    (color, jitter): (Vec3, f32),
    base: &dyn Fn(usize, &StrandRoot) -> Vec3,
) -> crate::Result<()> {
    let mut growth = pass.params.growth.clone();
    growth.color = color;
    growth.color_jitter = jitter;
    growth.validate()?;
    for (i, root) in roots.iter_mut().enumerate() {
        root.color = base(i, root) * crate::strand_brightness(root.seed, draw, jitter);
    }
    pelage_gpu::write_storage(queue, "pelage strand rest roots", rest, &*roots)?;
    pelage_gpu::write_storage(queue, "pelage strand roots", &pass.buffers.roots, &*roots)?;
    pass.params.growth = growth;
    Ok(())
}
