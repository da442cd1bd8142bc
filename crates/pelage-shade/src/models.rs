//! The hair shading models on the GPU: uniform blocks for the pure WGSL functions in
//! `wgsl/shade/models/` and the lookup tables of Marschner's model.
//!
//! | model | WGSL file | function | uniforms |
//! |---|---|---|---|
//! | Kajiya-Kay | `shade/models/kajiya_kay.wgsl` | `kajiya_kay_radiance` | [`KajiyaKayUniforms`] |
//! | Marschner | `shade/models/marschner.wgsl` | `marschner_radiance` | [`MarschnerUniforms`] |
//! | Marschner, tables | `shade/models/marschner_lut_lookup.wgsl` | `marschner_radiance_lut` | [`MarschnerUniforms`] + [`MarschnerLut`] at group 2 |
//! | Sadeghi | `shade/models/sadeghi.wgsl` | `sadeghi_radiance` | [`SadeghiUniforms`] |
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
use pelage_gpu::{Gpu, ShaderLibrary, UniformBuffer, compute_pipeline, wgpu, zeroed_storage};
use pelage_scene::{KajiyaKayParams, MarschnerParams, ParamError, SadeghiParams};

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
        let model = UniformBuffer::new(
            gpu,
            "pelage marschner lut model",
            &MarschnerUniforms::from_params(params),
        )?;
        let info_buffer = UniformBuffer::new(gpu, "pelage marschner lut info", &info)?;
        let module = ShaderLibrary::module(gpu, "shade/models/marschner_lut.wgsl")?;
        let pipeline = gpu.scoped(|device| {
            compute_pipeline(device, "pelage marschner lut build", &module, "build")
        })?;
        let build_group = gpu.scoped(|device| {
            pelage_gpu::bind_buffers(
                device,
                "pelage marschner lut build",
                &pipeline.get_bind_group_layout(0),
                &[&model.buffer, &info_buffer.buffer, &m, &n0, &n1],
            )
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
        pass.set_bind_group(0, &self.build_group, &[]);
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
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("pelage marschner lut"),
            layout,
            entries: &self.bind_group_entries(),
        })
    }
}
