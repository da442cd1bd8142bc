//! The hair shading models on the GPU: uniform blocks for the pure WGSL functions in
//! `wgsl/shade/models/` and the lookup tables of Marschner's model.
//!
//! | model | WGSL file | function | uniforms |
//! |---|---|---|---|
//! | Kajiya-Kay | `shade/models/kajiya_kay.wgsl` | `kajiya_kay_radiance` | [`KajiyaKayUniforms`] |
//! | Marschner | `shade/models/marschner.wgsl` | `marschner_radiance` | [`MarschnerUniforms`] |
//! | Marschner, tables | `shade/models/marschner_lut_lookup.wgsl` | `marschner_radiance_lut` | [`MarschnerUniforms`] + [`MarschnerLut`] at group 2 |
//! | Sadeghi | `shade/models/sadeghi.wgsl` | `sadeghi_radiance` | [`SadeghiUniforms`] |
//! | Chiang 2016 | `shade/models/chiang.wgsl` | `chiang_radiance`, `chiang_dual_radiance` (dual scattering) | [`ChiangUniforms`] + [`ChiangTables`] at group 2 |
//!
//! Every function has the shape
//! `fn X_radiance(m: XModel, t, l, v, base_color: vec3<f32>, strand_random: f32) -> vec3<f32>`
//! and returns the radiance toward `v` for a light of unit irradiance from `l` (multiply by
//! the light's colour and visibility). Their CPU twins are in `pelage_reference::shading`.
//!
//! # The lookup tables (after seed 003 §3.3.4 and GPU Gems 2 ch. 23; digest 002/003 §B.1.5)
//! [`MarschnerLut`] builds, in one compute dispatch of `shade/models/marschner_lut.wgsl`,
//! from the analytic WGSL functions (so each texel holds the analytic value):
//! - **M**, 1-D, `16·N` texels over `θ_h ∈ [-π/2, π/2]`: `M_R, M_TT, M_TRT`;
//! - **N0**, `N × N` over `(φ ∈ [0, π], cos θ_d ∈ [0, 1])`: `N_R` and `N_TT` (RGB);
//! - **N1**, `N × N × K` over `(φ, cos θ_d, cos 2φ_h ∈ [-1, 1])`: `N_TRT` (RGB).
//!
//! `marschner_radiance_lut` computes the angles as the analytic path does and applies
//! `cos θ_i / cos²θ_d` exactly; only `M_p` and `N_p` are interpolated.
//!
//! Deviations from seed 003, and why (numbers from `tests/models.rs`, p99 of the relative
//! error against the analytic path over its sweep, circular fibre):
//! - seed 003 tabulates `M/cos²θ_d` over `(sin θ_i, sin θ_r)` and `N` over
//!   `(cos φ, cos θ_d)`. Implemented that way first, it reached only 0.45 at `N = 64`,
//!   0.19 at 128 and 0.07 at 256 (RMSE/RMS about 0.6 at every size): the sine axes squeeze
//!   grazing angles into a few texels, `1/cos²θ_d` is singular at `sin θ_i = -sin θ_r = ±1`
//!   and bilinear filtering spreads it, and `cos φ` squeezes the R/TRT peaks near `φ = 0`
//!   and TT near `φ = π`. With `M` over `θ_h` (it depends on nothing else), the singular
//!   factor applied exactly and `N` over `φ`, the same sweep gives 0.017 at 64, 0.0045 at
//!   128 and 0.0012 at 256. The price is three `atan2` (refined, see `fibre.wgsl`) per
//!   lookup, which seed 003 avoided;
//! - storage buffers with filtering in the shader, not textures: exact `f32` everywhere (no
//!   filterable-float feature needed) and readable in any stage;
//! - `cos θ_d` spans `[0, 1]` (seed 003 maps `[-1, 1]`, but `cos θ_d ≥ 0`);
//! - N1 has a third axis, `cos 2φ_h`, with `K = clamp(N/4, 2, 32)` slices for an elliptical
//!   fibre (`K = 1` for a circular one): the eccentric index `η*(φ_h)` of TRT depends on it,
//!   and seed 003 does not say how its tables handle eccentricity. `K` is capped for memory,
//!   so an elliptical fibre's error stops falling beyond `N = 128`.

use encase::ShaderType;
use glam::Vec3;
use pelage_gpu::{
    BindLayout, Gpu, UniformBuffer, compute_pipeline_with_layouts, wgpu, zeroed_storage,
};
use pelage_scene::{
    Absorption, ChiangParams, KajiyaKayParams, MarschnerParams, MultipleScattering, ParamError,
    SadeghiParams, chiang_color_scale,
};

/// `KajiyaKayModel` in `wgsl/shade/models/kajiya_kay.wgsl`.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct KajiyaKayUniforms {
    /// Diffuse weight.
    pub diffuse: f32,
    /// Primary specular weight.
    pub specular: f32,
    /// Primary exponent.
    pub shininess: f32,
    /// Primary tangent shift along the ribbon normal.
    pub shift_primary: f32,
    /// Primary highlight colour.
    pub specular_color: Vec3,
    /// Secondary specular weight.
    pub secondary_specular: f32,
    /// Secondary highlight colour (times the strand colour).
    pub secondary_color: Vec3,
    /// Secondary exponent.
    pub secondary_shininess: f32,
    /// Secondary tangent shift.
    pub shift_secondary: f32,
}

impl KajiyaKayUniforms {
    /// The uniforms of `p` (no conversion needed).
    pub fn from_params(p: &KajiyaKayParams) -> Self {
        Self {
            diffuse: p.diffuse,
            specular: p.specular,
            shininess: p.shininess,
            shift_primary: p.shift_primary,
            specular_color: p.specular_color,
            secondary_specular: p.secondary_specular,
            secondary_color: p.secondary_color,
            secondary_shininess: p.secondary_shininess,
            shift_secondary: p.shift_secondary,
        }
    }
}

/// `MarschnerModel` in `wgsl/shade/models/marschner.wgsl`; angles in radians.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct MarschnerUniforms {
    /// Longitudinal shifts `α_R, α_TT, α_TRT`.
    pub alpha: Vec3,
    /// Index of refraction.
    pub eta: f32,
    /// Longitudinal widths `β_R, β_TT, β_TRT`.
    pub beta: Vec3,
    /// Minor over major axis.
    pub eccentricity: f32,
    /// Absorption per unit radius.
    pub sigma_a: Vec3,
    /// Strand azimuth range (radians).
    pub azimuth_jitter: f32,
    /// `k_G`.
    pub glint_scale: f32,
    /// `w_c` (radians).
    pub caustic_width: f32,
    /// `Δη'`.
    pub caustic_fade: f32,
    /// `Δh_M`.
    pub caustic_limit: f32,
    /// Kajiya-Kay diffuse weight.
    pub diffuse: f32,
}

impl MarschnerUniforms {
    /// The uniforms of `p`, with the derived TT/TRT shifts and widths in radians.
    pub fn from_params(p: &MarschnerParams) -> Self {
        let alpha = p.lobe_shifts_deg().map(f32::to_radians);
        let beta = p.lobe_widths_deg().map(f32::to_radians);
        Self {
            alpha: Vec3::from_array(alpha),
            eta: p.eta,
            beta: Vec3::from_array(beta),
            eccentricity: p.eccentricity,
            sigma_a: p.sigma_a,
            azimuth_jitter: p.azimuth_jitter,
            glint_scale: p.glint_scale,
            caustic_width: p.caustic_width_deg.to_radians(),
            caustic_fade: p.caustic_fade,
            caustic_limit: p.caustic_limit,
            diffuse: p.diffuse,
        }
    }
}

/// `SadeghiModel` in `wgsl/shade/models/sadeghi.wgsl`; angles in radians.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct SadeghiUniforms {
    /// `C_R`.
    pub color_r: Vec3,
    /// `I_R`.
    pub intensity_r: f32,
    /// `C_TT`.
    pub color_tt: Vec3,
    /// `I_TT`.
    pub intensity_tt: f32,
    /// `C_TRT`.
    pub color_trt: Vec3,
    /// `I_TRT`.
    pub intensity_trt: f32,
    /// `α_R, α_TT, α_TRT`.
    pub shift: Vec3,
    /// `γ_TT`.
    pub azimuthal_width_tt: f32,
    /// `β_R, β_TT, β_TRT`.
    pub width: Vec3,
    /// `I_G`.
    pub glint_intensity: f32,
    /// `γ_G`.
    pub glint_width: f32,
    /// Smallest `G_angle`.
    pub glint_angle_min: f32,
    /// Largest `G_angle`.
    pub glint_angle_max: f32,
    /// Kajiya-Kay diffuse weight.
    pub diffuse: f32,
}

impl SadeghiUniforms {
    /// The uniforms of `p`, angles in radians.
    pub fn from_params(p: &SadeghiParams) -> Self {
        Self {
            color_r: p.color_r,
            intensity_r: p.intensity_r,
            color_tt: p.color_tt,
            intensity_tt: p.intensity_tt,
            color_trt: p.color_trt,
            intensity_trt: p.intensity_trt,
            shift: Vec3::new(p.shift_r_deg, p.shift_tt_deg, p.shift_trt_deg)
                * (1.0f32).to_radians(),
            azimuthal_width_tt: p.azimuthal_width_tt_deg.to_radians(),
            width: Vec3::new(p.width_r_deg, p.width_tt_deg, p.width_trt_deg)
                * (1.0f32).to_radians(),
            glint_intensity: p.glint_intensity,
            glint_width: p.glint_width_deg.to_radians(),
            glint_angle_min: p.glint_angle_min_deg.to_radians(),
            glint_angle_max: p.glint_angle_max_deg.to_radians(),
            diffuse: p.diffuse,
        }
    }
}

/// `MarschnerLutInfo` in `wgsl/shade/models/marschner.wgsl`: the tables' sizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ShaderType)]
pub struct MarschnerLutInfo {
    /// Texels per axis of N0 and of the first two axes of N1 (M has `16 · size`).
    pub size: u32,
    /// Slices of N1 along `cos 2φ_h`.
    pub slices: u32,
    /// Padding.
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
}

/// Marschner's model tabulated on the GPU (see the module docs), for
/// `marschner_radiance_lut` in `wgsl/shade/models/marschner_lut_lookup.wgsl`.
///
/// [`MarschnerLut::new`] allocates the tables; [`MarschnerLut::encode`] fills them (run it
/// once, and again after [`MarschnerLut::update`]). A shading pass binds them at group 2
/// with [`MarschnerLut::bind_group`] (layout from [`MarschnerLut::layout_entries`]).
/// The `MarschnerModel` passed to `marschner_radiance_lut` should hold the same parameters
/// (only its `azimuth_jitter` and `diffuse` are read there; [`MarschnerLut::model_buffer`]
/// is a uniform that does).
#[derive(Debug)]
pub struct MarschnerLut {
    info: MarschnerLutInfo,
    model: UniformBuffer<MarschnerUniforms>,
    info_buffer: UniformBuffer<MarschnerLutInfo>,
    m: wgpu::Buffer,
    n0: wgpu::Buffer,
    n1: wgpu::Buffer,
    pipeline: wgpu::ComputePipeline,
    build_group: wgpu::BindGroup,
}

/// Bytes of one texel (a `vec4<f32>`).
const TEXEL_BYTES: u64 = 16;

impl MarschnerLut {
    /// Smallest table resolution accepted (the build dispatch fills M's 16 rows of
    /// `resolution` texels inside its `resolution × resolution` grid).
    pub const MIN_RESOLUTION: u32 = 16;
    /// Largest table resolution accepted. At 512 an elliptical fibre's N1 needs 128 MiB,
    /// which adapters with the minimum binding size refuse (a [`pelage_gpu::GpuError::TooLarge`]).
    pub const MAX_RESOLUTION: u32 = 512;
    /// Texels of the M table per unit of resolution (`MARSCHNER_LUT_M_ROWS` in WGSL).
    pub const M_ROWS: u32 = 16;

    /// Slices of N1 for `params` at `resolution`: `clamp(resolution / 4, 2, 32)` for an
    /// elliptical fibre, 1 for a circular one.
    pub fn slices_for(params: &MarschnerParams, resolution: u32) -> u32 {
        if params.eccentricity < 1.0 {
            (resolution / 4).clamp(2, 32)
        } else {
            1
        }
    }

    /// Allocates the tables for `params` at `resolution` texels per axis and builds the
    /// pipeline that fills them (call [`MarschnerLut::encode`] before sampling them).
    pub fn new(gpu: &Gpu, params: &MarschnerParams, resolution: u32) -> crate::Result<Self> {
        params.validate()?;
        if !(Self::MIN_RESOLUTION..=Self::MAX_RESOLUTION).contains(&resolution) {
            return Err(ParamError {
                name: "shading.marschner.lut_resolution".into(),
                value: resolution.to_string(),
                reason: format!(
                    "must be in {}..={}",
                    Self::MIN_RESOLUTION,
                    Self::MAX_RESOLUTION
                ),
            }
            .into());
        }
        let info = MarschnerLutInfo {
            size: resolution,
            slices: Self::slices_for(params, resolution),
            _pad0: 0,
            _pad1: 0,
        };
        let plane = u64::from(resolution) * u64::from(resolution) * TEXEL_BYTES;
        let usage = wgpu::BufferUsages::STORAGE;
        let m_bytes = u64::from(Self::M_ROWS) * u64::from(resolution) * TEXEL_BYTES;
        let m = zeroed_storage(gpu, "pelage marschner lut M", m_bytes, usage)?;
        let n0 = zeroed_storage(gpu, "pelage marschner lut N0", plane, usage)?;
        let n1 = zeroed_storage(
            gpu,
            "pelage marschner lut N1",
            plane * u64::from(info.slices),
            usage,
        )?;
        // Filled once by the build pass below; every frame only reads them.
        pelage_gpu::audit::constant(&[&m, &n0, &n1]);
        let model = UniformBuffer::new(
            gpu,
            "pelage marschner lut model",
            &MarschnerUniforms::from_params(params),
        )?;
        let info_buffer = UniformBuffer::new(gpu, "pelage marschner lut info", &info)?;
        let module = crate::SHADERS
            .library()
            .module(gpu, "shade/models/marschner_lut.wgsl")?;
        let (pipeline, build_group) = gpu.scoped(|device| {
            let label = "pelage marschner lut build";
            // marschner_lut.wgsl: the model and info uniforms, the three tables written.
            let layout = BindLayout::new(label, wgpu::ShaderStages::COMPUTE)
                .uniform(0)
                .uniform(1)
                .storage_rw(2)
                .storage_rw(3)
                .storage_rw(4)
                .build(device);
            let pipeline =
                compute_pipeline_with_layouts(device, label, &module, "build", &[Some(&layout)]);
            let group = pelage_gpu::bind_buffers(
                device,
                label,
                &layout,
                &[&model.buffer, &info_buffer.buffer, &m, &n0, &n1],
            );
            (pipeline, group)
        })?;
        Ok(Self {
            info,
            model,
            info_buffer,
            m,
            n0,
            n1,
            pipeline,
            build_group,
        })
    }

    /// Rewrites the model's parameters (takes effect at the next submit); call
    /// [`MarschnerLut::encode`] to rebuild the tables. Errors if `params` are invalid or
    /// would need a different number of N1 slices (an elliptical fibre turned circular or
    /// the reverse): build a new `MarschnerLut` then.
    pub fn update(&self, queue: &wgpu::Queue, params: &MarschnerParams) -> crate::Result<()> {
        params.validate()?;
        if Self::slices_for(params, self.info.size) != self.info.slices {
            return Err(ParamError {
                name: "shading.marschner.eccentricity".into(),
                value: params.eccentricity.to_string(),
                reason: "switches between a circular and an elliptical fibre, which changes \
                         the table layout; create a new MarschnerLut"
                    .into(),
            }
            .into());
        }
        self.model
            .write(queue, &MarschnerUniforms::from_params(params))?;
        Ok(())
    }

    /// Records the compute pass that fills the three tables.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder) {
        let groups = self.info.size.div_ceil(8);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("pelage marschner lut build"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pelage_gpu::set_bind_group(&mut pass, 0, &self.build_group);
        pass.dispatch_workgroups(groups, groups, 2 + self.info.slices);
    }

    /// Texels per axis.
    pub fn resolution(&self) -> u32 {
        self.info.size
    }

    /// Slices of the TRT table along `cos 2φ_h`.
    pub fn slices(&self) -> u32 {
        self.info.slices
    }

    /// The tables' sizes, as the shader reads them.
    pub fn info(&self) -> MarschnerLutInfo {
        self.info
    }

    /// GPU memory held by the tables and their uniforms, in bytes.
    pub fn memory_bytes(&self) -> u64 {
        self.m.size()
            + self.n0.size()
            + self.n1.size()
            + self.model.buffer.size()
            + self.info_buffer.buffer.size()
    }

    /// The uniform holding the [`MarschnerUniforms`] the tables were built from; a pass
    /// can bind it as the `MarschnerModel` it hands to `marschner_radiance_lut`, so the
    /// tables and the model's other fields (azimuth jitter, diffuse) never disagree.
    pub fn model_buffer(&self) -> &wgpu::Buffer {
        &self.model.buffer
    }

    /// The uniform describing the tables ([`MarschnerLutInfo`], binding 3 of group 2).
    pub fn info_buffer(&self) -> &wgpu::Buffer {
        &self.info_buffer.buffer
    }

    /// The M table (`vec4` per texel, `16 · resolution` texels, see the module docs).
    pub fn m_buffer(&self) -> &wgpu::Buffer {
        &self.m
    }

    /// The N0 table (`N_R`, `N_TT`).
    pub fn n0_buffer(&self) -> &wgpu::Buffer {
        &self.n0
    }

    /// The N1 table (`N_TRT`).
    pub fn n1_buffer(&self) -> &wgpu::Buffer {
        &self.n1
    }

    /// Layout entries of group 2 as `marschner_lut_lookup.wgsl` declares it (bindings 0..=2:
    /// read-only storage tables, 3: the info uniform), visible to `visibility`.
    pub fn layout_entries(visibility: wgpu::ShaderStages) -> [wgpu::BindGroupLayoutEntry; 4] {
        let storage = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        [
            storage(0),
            storage(1),
            storage(2),
            wgpu::BindGroupLayoutEntry {
                binding: 3,
                visibility,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
        ]
    }

    /// The entries of group 2 (the tables and the info uniform at bindings 0..=3).
    pub fn bind_group_entries(&self) -> [wgpu::BindGroupEntry<'_>; 4] {
        [
            (0, &self.m),
            (1, &self.n0),
            (2, &self.n1),
            (3, &self.info_buffer.buffer),
        ]
        .map(|(binding, buffer)| wgpu::BindGroupEntry {
            binding,
            resource: buffer.as_entire_binding(),
        })
    }

    /// A bind group for group 2 of a pipeline that includes `marschner_lut_lookup.wgsl`.
    pub fn bind_group(
        &self,
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
    ) -> wgpu::BindGroup {
        pelage_gpu::create_bind_group(
            device,
            &wgpu::BindGroupDescriptor {
                label: Some("pelage marschner lut"),
                layout,
                entries: &self.bind_group_entries(),
            },
        )
    }
}

/// `ChiangModel` in `wgsl/shade/models/chiang.wgsl`: the fibre of Chiang et al. 2016 with
/// pbrt-v3's derived constants.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct ChiangUniforms {
    /// Absorption per unit fibre radius (when `from_color` is 0).
    pub sigma_a: Vec3,
    /// 1: σ_a from each strand's colour (Chiang eq. 9); 0: `sigma_a`.
    pub from_color: u32,
    /// Longitudinal variances `v_R, v_TT, v_TRT` (pbrt: `v_0 = (0.726 β_m + 0.812 β_m² +
    /// 3.7 β_m^20)²`, `v_1 = v_0 / 4`, `v_2 = 4 v_0`; the residual lobe uses `v_2`).
    pub v: Vec3,
    /// Index of refraction.
    pub eta: f32,
    /// `sin(2^k α)`, `k = 0, 1, 2`.
    pub sin_2k_alpha: Vec3,
    /// Logistic scale `s = √(π/8) (0.265 β_n + 1.194 β_n² + 5.372 β_n^22)`.
    pub s: f32,
    /// `cos(2^k α)`, `k = 0, 1, 2`.
    pub cos_2k_alpha: Vec3,
    /// [`pelage_scene::chiang_color_scale`] of `β_n`.
    pub color_scale: f32,
    /// 1: dual scattering. The test kernel `chiang_eval.wgsl` reads it; the hair passes
    /// bind `chiang_dual_model.wgsl` or `chiang_model.wgsl` by the model instead.
    pub dual: u32,
    /// Padding.
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
    /// Padding.
    pub _pad2: u32,
}

impl ChiangUniforms {
    /// The uniforms of `p`.
    pub fn from_params(p: &ChiangParams) -> Self {
        let bm = p.beta_m;
        let bn = p.beta_n;
        let v0 = (0.726 * bm + 0.812 * bm * bm + 3.7 * bm.powi(20)).powi(2);
        let s = (std::f32::consts::PI / 8.0).sqrt()
            * (0.265 * bn + 1.194 * bn * bn + 5.372 * bn.powi(22));
        let mut sin_2k = [0.0f32; 3];
        let mut cos_2k = [0.0f32; 3];
        sin_2k[0] = p.alpha_deg.to_radians().sin();
        cos_2k[0] = (1.0 - sin_2k[0] * sin_2k[0]).max(0.0).sqrt();
        for i in 1..3 {
            sin_2k[i] = 2.0 * cos_2k[i - 1] * sin_2k[i - 1];
            cos_2k[i] = cos_2k[i - 1] * cos_2k[i - 1] - sin_2k[i - 1] * sin_2k[i - 1];
        }
        let (sigma_a, from_color) = match p.absorption() {
            Absorption::Fixed(s) => (s, 0),
            Absorption::FromColor => (Vec3::ZERO, 1),
        };
        Self {
            sigma_a,
            from_color,
            v: Vec3::new(v0, 0.25 * v0, 4.0 * v0),
            eta: p.eta,
            sin_2k_alpha: Vec3::from_array(sin_2k),
            s,
            cos_2k_alpha: Vec3::from_array(cos_2k),
            color_scale: chiang_color_scale(bn),
            dual: u32::from(p.multiple_scattering == MultipleScattering::Dual),
            _pad0: 0,
            _pad1: 0,
            _pad2: 0,
        }
    }
}

/// The tables of Chiang's far-field fibre on the GPU (`wgsl/shade/models/chiang_tables.wgsl`
/// builds them, `chiang.wgsl` reads them), with the model's uniform.
///
/// - **N**, `PHI × THETA × SIGMA` vec4 over `(φ ∈ [0, π], |θ_o| ∈ [0, π/2], x = σ/(σ + 1) ∈
///   [0, 1])`: the azimuthal terms `N_R, N_TT, N_TRT, N_3` with the fibre offset `h`
///   integrated out (512 midpoints over `γ_o = asin h`). A channel reads them at its own
///   σ_a, so strands of any colour share one table; only η and β_n shape it.
/// - **Dual**, `THETA × SIGMA × 2` vec4: the forward and backward energy of each lobe for
///   light at `|θ_i|`, integrals over φ of the N table, for dual scattering.
///
/// The tables depend on η and β_n only: [`ChiangTables::update`] rewrites the uniform and
/// tells whether the tables must be rebuilt (then [`ChiangTables::encode`] again).
#[derive(Debug)]
pub struct ChiangTables {
    uniforms: ChiangUniforms,
    model: UniformBuffer<ChiangUniforms>,
    n: wgpu::Buffer,
    dual: wgpu::Buffer,
    pipelines: [wgpu::ComputePipeline; 2],
    group: wgpu::BindGroup,
}

impl ChiangTables {
    /// Texels of the N table along φ (`CHIANG_PHI` in WGSL).
    pub const PHI: u32 = 64;
    /// Texels along `|θ|` (`CHIANG_THETA`).
    pub const THETA: u32 = 32;
    /// Texels along `x = σ/(σ + 1)` (`CHIANG_SIGMA`).
    pub const SIGMA: u32 = 32;

    /// Allocates the tables and the build pipelines for `params` (call
    /// [`ChiangTables::encode`] before sampling them).
    pub fn new(gpu: &Gpu, params: &ChiangParams) -> crate::Result<Self> {
        params.validate()?;
        let uniforms = ChiangUniforms::from_params(params);
        let model = UniformBuffer::new(gpu, "pelage chiang model", &uniforms)?;
        let usage = wgpu::BufferUsages::STORAGE;
        let n_bytes = u64::from(Self::PHI * Self::THETA * Self::SIGMA) * TEXEL_BYTES;
        let dual_bytes = u64::from(Self::THETA * Self::SIGMA * 2) * TEXEL_BYTES;
        let n = zeroed_storage(gpu, "pelage chiang N", n_bytes, usage)?;
        let dual = zeroed_storage(gpu, "pelage chiang dual", dual_bytes, usage)?;
        // Filled once by the table pass below; every frame only reads them.
        pelage_gpu::audit::constant(&[&n, &dual]);
        let module = crate::SHADERS
            .library()
            .module(gpu, "shade/models/chiang_tables.wgsl")?;
        // One explicit layout for both entry points (each uses only some of the bindings,
        // so layouts derived from them would differ).
        let (pipelines, group) = gpu.scoped(|device| {
            let layout = BindLayout::new("pelage chiang tables", wgpu::ShaderStages::COMPUTE)
                .uniform(0)
                .storage_rw(1)
                .storage_rw(2)
                .build(device);
            let layouts = [Some(&layout)];
            let pipeline = |label, entry_point| {
                compute_pipeline_with_layouts(device, label, &module, entry_point, &layouts)
            };
            let pipelines = [
                pipeline("pelage chiang N", "azimuthal"),
                pipeline("pelage chiang dual", "energies"),
            ];
            let group = pelage_gpu::bind_buffers(
                device,
                "pelage chiang tables",
                &layout,
                &[&model.buffer, &n, &dual],
            );
            (pipelines, group)
        })?;
        Ok(Self {
            uniforms,
            model,
            n,
            dual,
            pipelines,
            group,
        })
    }

    /// Rewrites the uniform for `params` (takes effect at the next submit). Returns whether
    /// the tables depend on what changed (η or β_n), so [`ChiangTables::encode`] must run again.
    pub fn update(&mut self, queue: &wgpu::Queue, params: &ChiangParams) -> crate::Result<bool> {
        params.validate()?;
        let next = ChiangUniforms::from_params(params);
        let rebuild = next.eta != self.uniforms.eta || next.s != self.uniforms.s;
        self.model.write(queue, &next)?;
        self.uniforms = next;
        Ok(rebuild)
    }

    /// Records the two compute passes that fill the tables (N, then the energies from it).
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("pelage chiang tables"),
            timestamp_writes: None,
        });
        pelage_gpu::set_bind_group(&mut pass, 0, &self.group);
        pass.set_pipeline(&self.pipelines[0]);
        pass.dispatch_workgroups(Self::PHI.div_ceil(64), Self::THETA, Self::SIGMA);
        pass.set_pipeline(&self.pipelines[1]);
        pass.dispatch_workgroups(Self::THETA.div_ceil(8), Self::SIGMA.div_ceil(8), 1);
    }

    /// The uniforms as last written.
    pub fn uniforms(&self) -> &ChiangUniforms {
        &self.uniforms
    }

    /// The `ChiangModel` uniform (binding 0 of group 2).
    pub fn model_buffer(&self) -> &wgpu::Buffer {
        &self.model.buffer
    }

    /// The N table (binding 1).
    pub fn n_buffer(&self) -> &wgpu::Buffer {
        &self.n
    }

    /// The dual-scattering energies (binding 2).
    pub fn dual_buffer(&self) -> &wgpu::Buffer {
        &self.dual
    }

    /// GPU memory held, in bytes.
    pub fn memory_bytes(&self) -> u64 {
        self.n.size() + self.dual.size() + self.model.buffer.size()
    }
}
