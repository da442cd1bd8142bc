//! Parameters of the hair shading models (stage 3), as plain serde data.
//!
//! Three models, selected by [`ShadingModel`]:
//! - [`KajiyaKayParams`]: Kajiya & Kay 1989 (diffuse `sin(t, l)` plus the specular cone),
//!   with Scheuermann's two shifted highlights (digest 002/003 §B.1.4);
//! - [`MarschnerParams`]: Marschner et al. 2003, lobes R, TT and TRT with absorption,
//!   eccentricity and caustic handling (digest §A.1.5, §B.1.5);
//! - [`SadeghiParams`]: Sadeghi et al. 2010, the artist-friendly pseudo scattering
//!   function (digest §B.1.6, digest 000/001 §000.1.6).
//!
//! Angles are given in degrees here (they are what a person edits); the stage crate
//! converts them to radians for the GPU. Every struct has a `validate` method whose
//! error names the bad field (e.g. `shading.marschner.eta`).

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::params::ParamError;

/// A [`ParamError`] for `name` (built from its public fields: its constructor is private
/// to `params`).
fn error(name: &str, value: impl std::fmt::Debug, reason: &str) -> ParamError {
    ParamError {
        name: name.to_string(),
        value: format!("{value:?}"),
        reason: reason.to_string(),
    }
}

/// `v` must be finite and lie in `[lo, hi]`.
fn in_range(name: &str, v: f32, lo: f32, hi: f32) -> Result<(), ParamError> {
    if !v.is_finite() {
        return Err(error(name, v, "must be a finite number"));
    }
    if v < lo || v > hi {
        return Err(error(name, v, &format!("must be in [{lo}, {hi}]")));
    }
    Ok(())
}

/// `v` must be finite and lie in `(lo, hi]`.
fn in_range_open_low(name: &str, v: f32, lo: f32, hi: f32) -> Result<(), ParamError> {
    if !v.is_finite() {
        return Err(error(name, v, "must be a finite number"));
    }
    if v <= lo || v > hi {
        return Err(error(name, v, &format!("must be in ({lo}, {hi}]")));
    }
    Ok(())
}

/// Every component of `v` must be finite and lie in `[lo, hi]`.
fn vec_in_range(name: &str, v: Vec3, lo: f32, hi: f32) -> Result<(), ParamError> {
    if !v.is_finite() {
        return Err(error(name, v, "every component must be finite"));
    }
    if v.min_element() < lo || v.max_element() > hi {
        return Err(error(
            name,
            v,
            &format!("every component must be in [{lo}, {hi}]"),
        ));
    }
    Ok(())
}

/// Upper bound on colours and intensities: generous, it only keeps HDR values sane.
const MAX_WEIGHT: f32 = 1.0e4;

/// Kajiya-Kay (1989) with Scheuermann's (2004) two shifted highlights.
///
/// Radiance for a light of unit irradiance, `l` and `v` pointing away from the fibre:
/// ```text
/// diffuse  · base · sin(t, l)
/// + specular · specular_color · cone(t₁)^shininess
/// + secondary_specular · secondary_color · base · cone(t₂)^secondary_shininess
/// cone(t) = max(0, -(t·l)(t·v) + sin(t, l) sin(t, v))
/// t₁ = normalize(t + shift_primary · n),  t₂ = normalize(t + shift_secondary · n)
/// ```
/// `n` is the normal of the camera-facing ribbon, `normalize(v - (t·v) t)`. With the
/// defaults (no shift, no secondary highlight) this is exactly the shading of
/// `wgsl/shade/ribbons.wgsl` today.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct KajiyaKayParams {
    /// Diffuse weight (>= 0), multiplies the strand colour.
    pub diffuse: f32,
    /// Primary specular weight (>= 0).
    pub specular: f32,
    /// Primary specular exponent (> 0).
    pub shininess: f32,
    /// Colour of the primary highlight, linear RGB (>= 0).
    pub specular_color: Vec3,
    /// Tangent shift of the primary highlight along the ribbon normal, in [-1, 1]
    /// (tan of the tilt; Scheuermann uses about -0.1 to -0.2 toward the root).
    pub shift_primary: f32,
    /// Tangent shift of the secondary highlight along the ribbon normal, in [-1, 1].
    pub shift_secondary: f32,
    /// Secondary specular weight (>= 0); 0 turns the secondary highlight off.
    pub secondary_specular: f32,
    /// Secondary specular exponent (> 0).
    pub secondary_shininess: f32,
    /// Colour of the secondary highlight, linear RGB (>= 0), multiplied by the strand
    /// colour (the secondary highlight has passed through the fibre).
    pub secondary_color: Vec3,
}

impl Default for KajiyaKayParams {
    /// The look of `ribbons.wgsl`: diffuse 0.75, specular 0.3, exponent 40, no shift, no
    /// secondary highlight.
    fn default() -> Self {
        Self {
            diffuse: 0.75,
            specular: 0.3,
            shininess: 40.0,
            specular_color: Vec3::new(1.0, 0.95, 0.85),
            shift_primary: 0.0,
            shift_secondary: 0.0,
            secondary_specular: 0.0,
            secondary_shininess: 10.0,
            secondary_color: Vec3::ONE,
        }
    }
}

impl KajiyaKayParams {
    /// Checks every field; the error names the first bad one (`shading.kajiya_kay.*`).
    pub fn validate(&self) -> Result<(), ParamError> {
        let p = "shading.kajiya_kay";
        in_range(&format!("{p}.diffuse"), self.diffuse, 0.0, MAX_WEIGHT)?;
        in_range(&format!("{p}.specular"), self.specular, 0.0, MAX_WEIGHT)?;
        in_range_open_low(&format!("{p}.shininess"), self.shininess, 0.0, 1.0e4)?;
        vec_in_range(
            &format!("{p}.specular_color"),
            self.specular_color,
            0.0,
            MAX_WEIGHT,
        )?;
        in_range(&format!("{p}.shift_primary"), self.shift_primary, -1.0, 1.0)?;
        in_range(
            &format!("{p}.shift_secondary"),
            self.shift_secondary,
            -1.0,
            1.0,
        )?;
        in_range(
            &format!("{p}.secondary_specular"),
            self.secondary_specular,
            0.0,
            MAX_WEIGHT,
        )?;
        in_range_open_low(
            &format!("{p}.secondary_shininess"),
            self.secondary_shininess,
            0.0,
            1.0e4,
        )?;
        vec_in_range(
            &format!("{p}.secondary_color"),
            self.secondary_color,
            0.0,
            MAX_WEIGHT,
        )
    }
}

/// Marschner et al. 2003: a dielectric fibre with cuticle tilt, absorption and an
/// elliptical cross-section; lobes R, TT and TRT (digest 002/003 §A.1.5, §B.1.5).
///
/// The TT and TRT shifts and widths are derived from R as in Marschner's Table 1:
/// `α_TT = -α_R/2`, `α_TRT = -3α_R/2`, `β_TT = β_R/2`, `β_TRT = 2β_R`
/// (see [`MarschnerParams::lobe_shifts_deg`], [`MarschnerParams::lobe_widths_deg`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MarschnerParams {
    /// Longitudinal shift of R in degrees (cuticle tilt; negative = toward the root).
    /// Marschner suggests [-10, -5]; any finite value in [-20, 0] is accepted.
    pub alpha_r_deg: f32,
    /// Longitudinal width (standard deviation) of R in degrees, in (0, 30].
    /// Marschner suggests [5, 10].
    pub beta_r_deg: f32,
    /// Index of refraction of the fibre, in (1, 4]; hair is about 1.55.
    pub eta: f32,
    /// Absorption coefficient per unit fibre radius, linear RGB, each in [0, 1e4]
    /// (see [`sigma_a_from_color`]).
    pub sigma_a: Vec3,
    /// Ratio of the cross-section's minor to major axis, in [0.85, 1] (1 = circular); the
    /// TRT lobe uses Marschner's eccentricity-corrected index η*(φ_h) (valid only in this range).
    pub eccentricity: f32,
    /// k_G, the scale of the TRT glints that replace the caustics (Algorithm 1 of seed 003),
    /// in [0, 10]; Marschner suggests [0.5, 5]. At 1 the glints carry about the energy that
    /// the damping removes from the caustics (within 15% for sin θ_d up to 0.7, measured in
    /// `pelage-reference`); larger values add energy, smaller ones remove it.
    pub glint_scale: f32,
    /// w_c, the azimuthal width (standard deviation) of a caustic glint in degrees, in (0, 60];
    /// Marschner suggests [10, 25].
    pub caustic_width_deg: f32,
    /// Δη', the range of η' over which the merged caustic fades out above η' = 2, in (0, 2];
    /// Marschner suggests [0.2, 0.4].
    pub caustic_fade: f32,
    /// Δh_M, the largest offset range that feeds one glint, in (0, 1]; Marschner uses 0.5.
    pub caustic_limit: f32,
    /// Range of the random rotation of each strand's cross-section about its tangent, in
    /// radians, in [0, 2π]: strand `i` turns by `azimuth_jitter · random_i`. Only visible when
    /// `eccentricity < 1` (π already covers every orientation of an ellipse).
    pub azimuth_jitter: f32,
    /// Weight of a Kajiya-Kay diffuse term `diffuse · base · sin(t, l)` added to the lobes
    /// (Marschner has no diffuse term; seed 003 adds this one), in [0, 1e4].
    pub diffuse: f32,
}

impl Default for MarschnerParams {
    /// Marschner's Table 1 middle values; σ_a of seed 003's brown hair (Fig. 32),
    /// eccentricity 0.85 (Dušek's typical value), energy-neutral glints (`k_G = 1`).
    fn default() -> Self {
        Self {
            alpha_r_deg: -7.5,
            beta_r_deg: 7.5,
            eta: 1.55,
            sigma_a: Vec3::new(0.22, 0.3, 0.4),
            eccentricity: 0.85,
            glint_scale: 1.0,
            caustic_width_deg: 15.0,
            caustic_fade: 0.3,
            caustic_limit: 0.5,
            azimuth_jitter: std::f32::consts::PI,
            diffuse: 0.0,
        }
    }
}

impl MarschnerParams {
    /// Longitudinal shifts `[α_R, α_TT, α_TRT]` in degrees (Marschner Table 1:
    /// `α_TT = -α_R/2`, `α_TRT = -3α_R/2`).
    pub fn lobe_shifts_deg(&self) -> [f32; 3] {
        [
            self.alpha_r_deg,
            -0.5 * self.alpha_r_deg,
            -1.5 * self.alpha_r_deg,
        ]
    }

    /// Longitudinal widths `[β_R, β_TT, β_TRT]` in degrees (Marschner Table 1:
    /// `β_TT = β_R/2`, `β_TRT = 2β_R`).
    pub fn lobe_widths_deg(&self) -> [f32; 3] {
        [
            self.beta_r_deg,
            0.5 * self.beta_r_deg,
            2.0 * self.beta_r_deg,
        ]
    }

    /// Checks every field; the error names the first bad one (`shading.marschner.*`).
    pub fn validate(&self) -> Result<(), ParamError> {
        let p = "shading.marschner";
        in_range(&format!("{p}.alpha_r_deg"), self.alpha_r_deg, -20.0, 0.0)?;
        in_range_open_low(&format!("{p}.beta_r_deg"), self.beta_r_deg, 0.0, 30.0)?;
        in_range_open_low(&format!("{p}.eta"), self.eta, 1.0, 4.0)?;
        vec_in_range(&format!("{p}.sigma_a"), self.sigma_a, 0.0, 1.0e4)?;
        in_range(&format!("{p}.eccentricity"), self.eccentricity, 0.85, 1.0)?;
        in_range(&format!("{p}.glint_scale"), self.glint_scale, 0.0, 10.0)?;
        in_range_open_low(
            &format!("{p}.caustic_width_deg"),
            self.caustic_width_deg,
            0.0,
            60.0,
        )?;
        in_range_open_low(&format!("{p}.caustic_fade"), self.caustic_fade, 0.0, 2.0)?;
        in_range_open_low(&format!("{p}.caustic_limit"), self.caustic_limit, 0.0, 1.0)?;
        in_range(
            &format!("{p}.azimuth_jitter"),
            self.azimuth_jitter,
            0.0,
            std::f32::consts::TAU,
        )?;
        in_range(&format!("{p}.diffuse"), self.diffuse, 0.0, MAX_WEIGHT)
    }
}

/// Absorption coefficient σ_a (per unit fibre radius) that gives a fibre the colour `color`.
///
/// Mapping: `σ_a = -ln(c) / 2`, per channel, `c` clamped to `[1e-4, 1]` (NaN counts as
/// black). It is Dušek's
/// `σ_a = -k ln(c)` (digest 002/003 §A.1.5 step 5) with `k = 1/2`, chosen so that a ray
/// crossing the fibre through its axis at normal incidence (path length 2 in a unit-radius
/// cross-section, the TT path with `h = 0`) keeps exactly the fraction `c` of its energy.
/// TRT crosses twice and comes out about `c²`: more saturated, as the secondary highlight is.
/// This is not Chiang et al. 2016's mapping, which targets the multiply scattered albedo of
/// a different (path-traced) model.
pub fn sigma_a_from_color(color: Vec3) -> Vec3 {
    let clamp = |x: f32| {
        if x.is_nan() {
            1.0e-4 // NaN counts as black
        } else {
            x.clamp(1.0e-4, 1.0)
        }
    };
    let c = Vec3::new(clamp(color.x), clamp(color.y), clamp(color.z));
    Vec3::new(-c.x.ln(), -c.y.ln(), -c.z.ln()) * 0.5
}

/// Eumelanin absorption per unit concentration, per unit fibre radius (linear RGB):
/// Chiang et al. 2016 eq. 8 (after d'Eon et al. 2011), as pbrt-v3 uses it.
pub const EUMELANIN_SIGMA_A: Vec3 = Vec3::new(0.419, 0.697, 1.37);

/// Pheomelanin absorption per unit concentration, per unit fibre radius (Chiang et al. 2016
/// eq. 8).
pub const PHEOMELANIN_SIGMA_A: Vec3 = Vec3::new(0.187, 0.4, 1.05);

/// Largest accepted melanin concentration: at 50 every channel of σ_a exceeds 9, which is
/// black (the residual after one TT pass is below 1e-7).
pub const MAX_MELANIN: f32 = 50.0;

/// Eumelanin absorption per unit concentration as Blender's Principled Hair BSDF (Cycles and
/// EEVEE) and Unreal's hair shading define it, per unit fibre radius (linear RGB). Not pbrt's
/// [`EUMELANIN_SIGMA_A`]: the same concentration gives different hair in the two conventions.
pub const ARTIST_EUMELANIN_SIGMA_A: Vec3 = Vec3::new(0.506, 0.841, 1.653);

/// Pheomelanin absorption per unit concentration in Blender's and Unreal's convention (see
/// [`ARTIST_EUMELANIN_SIGMA_A`]); pbrt's is [`PHEOMELANIN_SIGMA_A`].
pub const ARTIST_PHEOMELANIN_SIGMA_A: Vec3 = Vec3::new(0.343, 0.733, 1.924);

/// The `melanin_redness` a [`ChiangParams`] with `melanin` and no redness takes: 1, Blender's
/// default for the Principled Hair BSDF's "Melanin Redness" input.
pub const DEFAULT_MELANIN_REDNESS: f32 = 1.0;

/// Absorption σ_a (per unit fibre radius) of hair given as Blender's Principled Hair BSDF
/// ("Melanin concentration" parametrization) and Unreal's hair material give it:
///
/// ```text
/// quantity    = -ln(max(1 - melanin, 1e-4))          melanin in [0, 1]
/// eumelanin   = quantity · (1 - redness)             redness in [0, 1]
/// pheomelanin = quantity · redness
/// σ_a = eumelanin · (0.506, 0.841, 1.653) + pheomelanin · (0.343, 0.733, 1.924)
///     + (ln(tint) / s(β_n))²                         per channel; tint (1, 1, 1) adds nothing
/// ```
///
/// `s(β_n)` is [`chiang_color_scale`] of the azimuthal roughness (Blender's "Radial
/// Roughness"), as Blender's tint uses it. A tint channel of 0 (infinite absorption in
/// Blender) is taken as the smallest normal f32, an absorption above 200 per unit radius:
/// black. Blender's "Random Color" is not modelled (it is 0 by default).
pub fn sigma_a_from_artist_melanin(melanin: f32, redness: f32, tint: Vec3, beta_n: f32) -> Vec3 {
    let quantity = -(1.0 - melanin).max(1.0e-4).ln();
    let eumelanin = quantity * (1.0 - redness);
    let pheomelanin = quantity * redness;
    ARTIST_EUMELANIN_SIGMA_A * eumelanin
        + ARTIST_PHEOMELANIN_SIGMA_A * pheomelanin
        + reflectance_sigma(tint, beta_n, f32::MIN_POSITIVE)
}

/// Absorption σ_a (per unit fibre radius) of a fibre with `eumelanin` and `pheomelanin`
/// concentrations: `σ_a = eumelanin · (0.419, 0.697, 1.37) + pheomelanin · (0.187, 0.4, 1.05)`
/// (Chiang et al. 2016 eq. 8, after d'Eon et al. 2011). About 8 eumelanin is black hair, 1.3
/// brown, 0.3 blond; pheomelanin adds red.
pub fn sigma_a_from_melanin(eumelanin: f32, pheomelanin: f32) -> Vec3 {
    EUMELANIN_SIGMA_A * eumelanin + PHEOMELANIN_SIGMA_A * pheomelanin
}

/// The denominator of Chiang et al. 2016's colour inversion (their eq. 9) for azimuthal
/// roughness `beta_n`: `5.969 - 0.215β + 2.532β² - 10.73β³ + 5.574β⁴ + 0.245β⁵`.
pub fn chiang_color_scale(beta_n: f32) -> f32 {
    let b = beta_n;
    5.969 - 0.215 * b + 2.532 * b * b - 10.73 * b.powi(3) + 5.574 * b.powi(4) + 0.245 * b.powi(5)
}

/// Absorption σ_a (per unit fibre radius) that makes a dense volume of Chiang et al. 2016
/// fibres of azimuthal roughness `beta_n` appear `color` (linear RGB) under uniform light:
/// Chiang's eq. 9, `σ_a = (ln c / s(β_n))²` per channel, fitted by them to path-traced
/// multiple scattering. `c` is clamped to `[1e-4, 1]` (NaN counts as black). This is what a
/// scene's hair `color` means to the physically based models.
pub fn sigma_a_from_reflectance(color: Vec3, beta_n: f32) -> Vec3 {
    reflectance_sigma(color, beta_n, 1.0e-4)
}

/// Chiang's eq. 9 per channel with `c` clamped to `[floor, 1]` (NaN counts as `floor`).
fn reflectance_sigma(color: Vec3, beta_n: f32, floor: f32) -> Vec3 {
    let s = chiang_color_scale(beta_n);
    let f = |x: f32| {
        let c = if x.is_nan() {
            floor
        } else {
            x.clamp(floor, 1.0)
        };
        let y = c.ln() / s;
        y * y
    };
    Vec3::new(f(color.x), f(color.y), f(color.z))
}

/// The fibre model of Chiang et al. 2016 (pbrt-v3's hair BSDF): lobes R, TT, TRT and a
/// residual lobe for every longer path, each with a longitudinal term of roughness
/// `beta_m` (a von Mises-Fisher-like lobe with a modified Bessel function) and a logistic
/// azimuthal term of roughness `beta_n`; cuticle tilt `alpha_deg`; absorption from
/// melanin, from a given σ_a, or (the default) from the hair's own colour.
///
/// Absorption, one of (setting two is refused, naming the second key):
/// - `sigma_a`: that σ_a, per unit fibre radius;
/// - `eumelanin` and/or `pheomelanin`: concentrations with pbrt-v3's coefficients,
///   [`sigma_a_from_melanin`] (an unset one is 0);
/// - `melanin` (with `melanin_redness` and `tint`): Blender's Principled Hair and Unreal's
///   definition, [`sigma_a_from_artist_melanin`]; `melanin_redness` and `tint` only go with
///   `melanin`;
/// - none: every strand's own colour through [`sigma_a_from_reflectance`], so the hair
///   appears the colour the scene asks for (`growth.color`, with its jitter).
///
/// # From a Blender Principled Hair BSDF
///
/// Copy the node's inputs: "Melanin" → `melanin`, "Melanin Redness" → `melanin_redness`,
/// "Tint" → `tint`, "Roughness" → `beta_m`, "Radial Roughness" → `beta_n`, "IOR" → `eta`,
/// and "Offset" → `alpha_deg` **with its sign flipped**: `alpha_deg` follows pbrt-v3 and
/// Chiang et al. 2016, and Blender's Offset tilts the scales the other way, so Blender's
/// default Offset of 2° is `alpha_deg = -2`. (With the sign matched, the path tracer's mean
/// FLIP against Cycles over a long brown groom fell from 0.105 to 0.057.) "Coat", "Random
/// Color", "Random Roughness" and "Random" have no counterpart; their defaults (0) are what
/// pelage renders. The "Absorption coefficient" parametrization is `sigma_a` (same units).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ChiangParams {
    /// Longitudinal roughness in (0, 1] (pbrt's `beta_m`; 0.3 by default).
    pub beta_m: f32,
    /// Azimuthal roughness in (0, 1] (pbrt's `beta_n`; 0.3 by default). Below 0.15 the
    /// azimuthal lobes get narrower than the GPU tables resolve well.
    pub beta_n: f32,
    /// Cuticle scale tilt in degrees, in [-10, 10] (pbrt's `alpha`; 2 by default). Blender's
    /// Principled Hair "Offset" has the opposite sign: its +2° is -2 here.
    pub alpha_deg: f32,
    /// Index of refraction in (1, 4]; hair is about 1.55.
    pub eta: f32,
    /// Eumelanin concentration in [0, 50] with pbrt-v3's coefficients (black about 8, brown
    /// 1.3, blond 0.3). For Blender's and Unreal's convention use `melanin`.
    pub eumelanin: Option<f32>,
    /// Pheomelanin concentration in [0, 50] with pbrt-v3's coefficients (red hair).
    pub pheomelanin: Option<f32>,
    /// Melanin in [0, 1] as Blender's Principled Hair and Unreal's hair define it (a
    /// perceptually even amount: 0 white, about 0.25 blond, 0.5 brown, 0.9 and above black);
    /// see [`sigma_a_from_artist_melanin`].
    pub melanin: Option<f32>,
    /// Fraction of `melanin` that is pheomelanin, in [0, 1] (Blender's "Melanin Redness",
    /// Unreal's "Redness"); [`DEFAULT_MELANIN_REDNESS`] (1, Blender's default) when unset.
    /// Only with `melanin`.
    pub melanin_redness: Option<f32>,
    /// Dye colour in [0, 1] per channel, linear RGB (Blender's "Tint"); white when unset.
    /// Only with `melanin`.
    pub tint: Option<Vec3>,
    /// Absorption per unit fibre radius, linear RGB, each in [0, 1e4].
    pub sigma_a: Option<Vec3>,
    /// Light scattered between fibres ([`MultipleScattering`]): `none` (single scattering),
    /// `dual` (Zinke et al. 2008, from stage 2's shadows), `volume` (a radiance grid over
    /// the hair, after Moon, Walter and Marschner 2008) or `dual_volume` (dual scattering
    /// for the lights, the grid for the sky and the body's bounce). Scene files may still write
    /// `dual_scattering = true/false` (read as `dual` / `none`).
    #[serde(alias = "dual_scattering")]
    pub multiple_scattering: MultipleScattering,
    /// Cells per side of the `volume` method's cubic grid over the hair, in
    /// [[`MIN_VOLUME_GRID`], [`MAX_VOLUME_GRID`]] (a device may allow less: its storage
    /// binding size is checked when the grid is built).
    pub volume_grid: u32,
    /// Propagation steps of the `volume` method (light moves one cell per step), in
    /// [1, [`MAX_VOLUME_ITERATIONS`]].
    pub volume_iterations: u32,
}

/// Smallest `volume_grid`.
pub const MIN_VOLUME_GRID: u32 = 4;
/// Largest `volume_grid` (the grid holds 336 bytes per cell: 128³ is 705 MB).
pub const MAX_VOLUME_GRID: u32 = 128;
/// Default `volume_grid` (1.38 MB of GPU memory; see docs/src/shading.md for its cost in
/// the shade stage, `pelage bench --quick`): the scattering lab measures 16³ within 1.1
/// points of 32³'s hair luminance.
pub const DEFAULT_VOLUME_GRID: u32 = 16;
/// Largest `volume_iterations`.
pub const MAX_VOLUME_ITERATIONS: u32 = 256;
/// Default `volume_iterations`: light moves one cell per step along the axes; on the
/// default grid the scattering lab measures 12 steps the same as 16 and 64 to the third
/// decimal of hair luminance and FLIP (8 lose up to 0.001 of FLIP; see
/// docs/src/path-tracer.md). A finer grid needs proportionally more (the lab runs 32 at
/// 32³).
pub const DEFAULT_VOLUME_ITERATIONS: u32 = 12;

/// How Chiang's fibres carry light scattered by other fibres (the orders the single
/// scattering term leaves out). Names in [`crate::names`]: `none`, `dual`, `volume`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MultipleScattering {
    /// Single scattering only (times stage 2's visibility).
    None,
    /// Dual scattering (Zinke et al. 2008) from stage 2's visibility.
    Dual,
    /// Single scattering plus a volumetric radiance grid (orders >= 2): fibre density and
    /// direction splatted into a grid over the hair, single-scattered light injected
    /// through the grid's own transmittance toward each light, propagated cell to cell with
    /// a fibre phase function from Chiang's energy tables, read at shading. The default:
    /// the scattering lab measures it closest to the path tracer on every row, at 1.37x
    /// single scattering's shade stage (16³ cells, `pelage bench --quick`;
    /// docs/src/shading.md).
    #[default]
    Volume,
    /// Dual scattering for the lights (what they scatter through the hair, forward and
    /// back, from stage 2's visibility) and the volume method's grid for the rest: the
    /// sky's light (every order) and the light the body reflects into the hair; the grid
    /// injects no fibre-scattered light of the lights. The scattering lab measures it
    /// closer than `volume` on blond hair lit from behind, where the grid's first-order
    /// reading loses the forward-scattered beam (docs/src/path-tracer.md).
    DualVolume,
}

impl MultipleScattering {
    /// Whether the method fills the volume grid (`volume`, `dual_volume`).
    pub fn uses_grid(self) -> bool {
        matches!(self, Self::Volume | Self::DualVolume)
    }

    /// Whether the grid carries the lights' light the fibres scatter (`volume`; with
    /// `dual_volume` dual scattering carries it).
    pub fn grid_carries_lights(self) -> bool {
        self == Self::Volume
    }
}

impl<'de> Deserialize<'de> for MultipleScattering {
    /// A name of the method table (or an alias), or a bool for `dual_scattering`'s old
    /// spelling: `true` is `dual`, `false` is `none`.
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Either {
            Flag(bool),
            Name(String),
        }
        match Either::deserialize(d)? {
            Either::Flag(true) => Ok(Self::Dual),
            Either::Flag(false) => Ok(Self::None),
            Either::Name(n) => <Self as crate::names::Named>::named(&n).ok_or_else(|| {
                serde::de::Error::custom(format!(
                    "unknown multiple_scattering `{n}`: expected one of {} (or true/false)",
                    <Self as crate::names::Named>::name_list()
                ))
            }),
        }
    }
}

impl Default for ChiangParams {
    /// pbrt-v3's defaults (β_m = β_n = 0.3, α = 2°, η = 1.55), absorption from the hair's
    /// colour, volume scattering (16³ cells, 12 steps).
    fn default() -> Self {
        Self {
            beta_m: 0.3,
            beta_n: 0.3,
            alpha_deg: 2.0,
            eta: 1.55,
            eumelanin: None,
            pheomelanin: None,
            melanin: None,
            melanin_redness: None,
            tint: None,
            sigma_a: None,
            multiple_scattering: MultipleScattering::Volume,
            volume_grid: DEFAULT_VOLUME_GRID,
            volume_iterations: DEFAULT_VOLUME_ITERATIONS,
        }
    }
}

/// Where a physically based model's absorption comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Absorption {
    /// Each strand's colour through [`sigma_a_from_reflectance`].
    FromColor,
    /// This σ_a for every strand.
    Fixed(Vec3),
}

impl ChiangParams {
    /// Hair of melanin concentrations `eumelanin`, `pheomelanin`, defaults otherwise.
    pub fn melanin(eumelanin: f32, pheomelanin: f32) -> Self {
        Self {
            eumelanin: Some(eumelanin),
            pheomelanin: Some(pheomelanin),
            ..Self::default()
        }
    }

    /// The absorption these parameters ask for (see the type's docs).
    pub fn absorption(&self) -> Absorption {
        if let Some(s) = self.sigma_a {
            return Absorption::Fixed(s);
        }
        if self.eumelanin.is_some() || self.pheomelanin.is_some() {
            return Absorption::Fixed(sigma_a_from_melanin(
                self.eumelanin.unwrap_or(0.0),
                self.pheomelanin.unwrap_or(0.0),
            ));
        }
        if let Some(melanin) = self.melanin {
            return Absorption::Fixed(sigma_a_from_artist_melanin(
                melanin,
                self.melanin_redness.unwrap_or(DEFAULT_MELANIN_REDNESS),
                self.tint.unwrap_or(Vec3::ONE),
                self.beta_n,
            ));
        }
        Absorption::FromColor
    }

    /// Hair as Blender's Principled Hair BSDF gives it with "Melanin", "Melanin Redness" and
    /// "Tint" (see [`sigma_a_from_artist_melanin`]), defaults otherwise.
    pub fn artist_melanin(melanin: f32, redness: f32, tint: Vec3) -> Self {
        Self {
            melanin: Some(melanin),
            melanin_redness: Some(redness),
            tint: Some(tint),
            ..Self::default()
        }
    }

    /// σ_a of a strand of colour `color`.
    pub fn sigma_a_for(&self, color: Vec3) -> Vec3 {
        match self.absorption() {
            Absorption::Fixed(s) => s,
            Absorption::FromColor => sigma_a_from_reflectance(color, self.beta_n),
        }
    }

    /// Checks every field; the error names the first bad one (`shading.chiang.*`).
    pub fn validate(&self) -> Result<(), ParamError> {
        let p = "shading.chiang";
        in_range_open_low(&format!("{p}.beta_m"), self.beta_m, 0.0, 1.0)?;
        in_range_open_low(&format!("{p}.beta_n"), self.beta_n, 0.0, 1.0)?;
        in_range(&format!("{p}.alpha_deg"), self.alpha_deg, -10.0, 10.0)?;
        in_range_open_low(&format!("{p}.eta"), self.eta, 1.0, 4.0)?;
        if let Some(e) = self.eumelanin {
            in_range(&format!("{p}.eumelanin"), e, 0.0, MAX_MELANIN)?;
        }
        if let Some(e) = self.pheomelanin {
            in_range(&format!("{p}.pheomelanin"), e, 0.0, MAX_MELANIN)?;
        }
        if let Some(m) = self.melanin {
            in_range(&format!("{p}.melanin"), m, 0.0, 1.0)?;
        }
        if let Some(r) = self.melanin_redness {
            in_range(&format!("{p}.melanin_redness"), r, 0.0, 1.0)?;
            if self.melanin.is_none() {
                return Err(error(
                    &format!("{p}.melanin_redness"),
                    r,
                    "melanin_redness is the red fraction of `melanin`; set melanin too (Blender's \
                     convention) or use eumelanin/pheomelanin (pbrt's)",
                ));
            }
        }
        if let Some(t) = self.tint {
            vec_in_range(&format!("{p}.tint"), t, 0.0, 1.0)?;
            if self.melanin.is_none() {
                return Err(error(
                    &format!("{p}.tint"),
                    t,
                    "tint dyes `melanin` hair (as Blender's Principled Hair does); set melanin \
                     too, or give the hair's colour with growth.color",
                ));
            }
        }
        let pbrt = self.eumelanin.is_some() || self.pheomelanin.is_some();
        if let (Some(m), true) = (self.melanin, pbrt) {
            return Err(error(
                &format!("{p}.melanin"),
                m,
                "give either melanin (Blender's and Unreal's convention) or eumelanin/pheomelanin \
                 (pbrt's), not both",
            ));
        }
        if !(MIN_VOLUME_GRID..=MAX_VOLUME_GRID).contains(&self.volume_grid) {
            return Err(error(
                &format!("{p}.volume_grid"),
                self.volume_grid,
                &format!("must be in [{MIN_VOLUME_GRID}, {MAX_VOLUME_GRID}] cells per side"),
            ));
        }
        if !(1..=MAX_VOLUME_ITERATIONS).contains(&self.volume_iterations) {
            return Err(error(
                &format!("{p}.volume_iterations"),
                self.volume_iterations,
                &format!("must be in [1, {MAX_VOLUME_ITERATIONS}] propagation steps"),
            ));
        }
        if let Some(s) = self.sigma_a {
            vec_in_range(&format!("{p}.sigma_a"), s, 0.0, 1.0e4)?;
            if pbrt || self.melanin.is_some() {
                return Err(error(
                    &format!("{p}.sigma_a"),
                    s,
                    "give either sigma_a or melanin (melanin, or eumelanin/pheomelanin), not both",
                ));
            }
        }
        Ok(())
    }
}

/// Sadeghi et al. 2010, the artist-friendly pseudo scattering function
/// (digest 002/003 §B.1.6; digest 000/001 §000.1.6):
/// ```text
/// f = Σ_p C_p I_p M'_p(θ_h) N'_p(φ) / cos²θ_d,  M'_p = exp(-(θ_h - α_p)² / (2 β_p²))
/// N'_R = cos(φ/2),  N'_TT = exp(-(π - φ)² / (2 γ_TT²)),
/// N'_TRT = cos(φ/2) + I_G exp(-(G_angle - φ)² / (2 γ_G²))
/// ```
/// with unit-height Gaussians, φ in [0, π], and `G_angle` drawn per strand from
/// `[glint_angle_min_deg, glint_angle_max_deg]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SadeghiParams {
    /// C_R, colour of the primary highlight (linear RGB, >= 0); not tinted by the strand.
    pub color_r: Vec3,
    /// I_R, intensity of the primary highlight (>= 0).
    pub intensity_r: f32,
    /// α_R, longitudinal shift of R in degrees, in [-30, 30].
    pub shift_r_deg: f32,
    /// β_R, longitudinal width (standard deviation) of R in degrees, in (0, 60].
    pub width_r_deg: f32,
    /// C_TT, colour of the transmission (>= 0), multiplied by the strand colour.
    pub color_tt: Vec3,
    /// I_TT, intensity of the transmission (>= 0).
    pub intensity_tt: f32,
    /// α_TT in degrees, in [-30, 30].
    pub shift_tt_deg: f32,
    /// β_TT in degrees, in (0, 60].
    pub width_tt_deg: f32,
    /// γ_TT, azimuthal width (standard deviation) of the transmission around φ = π, in
    /// degrees, in (0, 180].
    pub azimuthal_width_tt_deg: f32,
    /// C_TRT, colour of the secondary highlight (>= 0), multiplied by the strand colour.
    pub color_trt: Vec3,
    /// I_TRT, intensity of the secondary highlight (>= 0).
    pub intensity_trt: f32,
    /// α_TRT in degrees, in [-30, 30].
    pub shift_trt_deg: f32,
    /// β_TRT in degrees, in (0, 60].
    pub width_trt_deg: f32,
    /// I_G, glint intensity relative to the secondary highlight (>= 0).
    pub glint_intensity: f32,
    /// γ_G, azimuthal width of a glint in degrees, in (0, 90].
    pub glint_width_deg: f32,
    /// Smallest glint half angle G_angle in degrees, in [0, 90] (Sadeghi: 30).
    pub glint_angle_min_deg: f32,
    /// Largest glint half angle in degrees, in [glint_angle_min_deg, 90] (Sadeghi: 45).
    pub glint_angle_max_deg: f32,
    /// Weight of a Kajiya-Kay diffuse term `diffuse · base · sin(t, l)` (seed 000's listing
    /// uses 0.4), in [0, 1e4].
    pub diffuse: f32,
}

impl Default for SadeghiParams {
    /// Intensities of seed 003's Fig. 32 (I_R = 0.45, I_TRT = 0.3), lobe positions and
    /// widths of Marschner's Table 1 at α_R = -7.5°, β_R = 7.5°, glints between 30° and 45°.
    fn default() -> Self {
        Self {
            color_r: Vec3::ONE,
            intensity_r: 0.45,
            shift_r_deg: -7.5,
            width_r_deg: 7.5,
            color_tt: Vec3::ONE,
            intensity_tt: 0.5,
            shift_tt_deg: 3.75,
            width_tt_deg: 3.75,
            azimuthal_width_tt_deg: 20.0,
            color_trt: Vec3::ONE,
            intensity_trt: 0.3,
            shift_trt_deg: 11.25,
            width_trt_deg: 15.0,
            glint_intensity: 1.5,
            glint_width_deg: 5.0,
            glint_angle_min_deg: 30.0,
            glint_angle_max_deg: 45.0,
            diffuse: 0.4,
        }
    }
}

impl SadeghiParams {
    /// Checks every field; the error names the first bad one (`shading.sadeghi.*`).
    pub fn validate(&self) -> Result<(), ParamError> {
        let p = "shading.sadeghi";
        for (name, color, intensity, shift, width) in [
            (
                "r",
                self.color_r,
                self.intensity_r,
                self.shift_r_deg,
                self.width_r_deg,
            ),
            (
                "tt",
                self.color_tt,
                self.intensity_tt,
                self.shift_tt_deg,
                self.width_tt_deg,
            ),
            (
                "trt",
                self.color_trt,
                self.intensity_trt,
                self.shift_trt_deg,
                self.width_trt_deg,
            ),
        ] {
            vec_in_range(&format!("{p}.color_{name}"), color, 0.0, MAX_WEIGHT)?;
            in_range(&format!("{p}.intensity_{name}"), intensity, 0.0, MAX_WEIGHT)?;
            in_range(&format!("{p}.shift_{name}_deg"), shift, -30.0, 30.0)?;
            in_range_open_low(&format!("{p}.width_{name}_deg"), width, 0.0, 60.0)?;
        }
        in_range_open_low(
            &format!("{p}.azimuthal_width_tt_deg"),
            self.azimuthal_width_tt_deg,
            0.0,
            180.0,
        )?;
        in_range(
            &format!("{p}.glint_intensity"),
            self.glint_intensity,
            0.0,
            MAX_WEIGHT,
        )?;
        in_range_open_low(
            &format!("{p}.glint_width_deg"),
            self.glint_width_deg,
            0.0,
            90.0,
        )?;
        in_range(
            &format!("{p}.glint_angle_min_deg"),
            self.glint_angle_min_deg,
            0.0,
            90.0,
        )?;
        in_range(
            &format!("{p}.glint_angle_max_deg"),
            self.glint_angle_max_deg,
            self.glint_angle_min_deg,
            90.0,
        )?;
        in_range(&format!("{p}.diffuse"), self.diffuse, 0.0, MAX_WEIGHT)
    }
}

/// Which hair shading model stage 3 uses, with its parameters.
///
/// In TOML: `model = "kajiya_kay"` (or `"marschner"`, `"sadeghi"`, `"chiang"`) next to the model's
/// fields; Marschner's fields sit under `params`, next to `lut`. A scene file
/// ([`SceneFile`](crate::SceneFile)) also takes Marschner's fields directly next to
/// `model`, as for the other models, and takes Kajiya-Kay when `model` is left out.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "model", deny_unknown_fields)]
pub enum ShadingModel {
    /// Kajiya-Kay with optional shifted highlights.
    KajiyaKay(KajiyaKayParams),
    /// Marschner et al. 2003.
    Marschner {
        /// The model's parameters.
        #[serde(default)]
        params: MarschnerParams,
        /// Evaluate through precomputed lookup tables (seed 003 §3.3.4) instead of
        /// analytically.
        #[serde(default)]
        lut: bool,
    },
    /// Sadeghi et al. 2010.
    Sadeghi(SadeghiParams),
    /// Chiang et al. 2016 (pbrt-v3's hair), optionally with dual scattering.
    Chiang(ChiangParams),
}

impl Default for ShadingModel {
    /// Chiang et al. 2016 with dual scattering: of the models, the one the scattering
    /// lab (`pelage lab scattering`) measures closest to the path tracer.
    fn default() -> Self {
        Self::Chiang(ChiangParams::default())
    }
}

impl ShadingModel {
    /// The model's name as the command line and the labs write it: `kajiya_kay`,
    /// `marschner`, `marschner_lut` (Marschner from its lookup tables), `sadeghi`, `chiang`.
    pub fn name(&self) -> &'static str {
        crate::names::Named::method_name(self)
    }

    /// Checks the chosen model's parameters; the error names the bad field.
    pub fn validate(&self) -> Result<(), ParamError> {
        match self {
            Self::KajiyaKay(p) => p.validate(),
            Self::Marschner { params, .. } => params.validate(),
            Self::Sadeghi(p) => p.validate(),
            Self::Chiang(p) => p.validate(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_validate() {
        ShadingModel::default().validate().unwrap();
        KajiyaKayParams::default().validate().unwrap();
        MarschnerParams::default().validate().unwrap();
        SadeghiParams::default().validate().unwrap();
        ChiangParams::default().validate().unwrap();
    }

    #[test]
    fn bad_values_name_the_field() {
        let p = MarschnerParams {
            eta: f32::NAN,
            ..Default::default()
        };
        assert_eq!(p.validate().unwrap_err().name, "shading.marschner.eta");
        let p = MarschnerParams {
            eta: 1.0,
            ..Default::default()
        };
        assert_eq!(p.validate().unwrap_err().name, "shading.marschner.eta");
        let p = MarschnerParams {
            sigma_a: Vec3::new(0.1, -0.1, 0.0),
            ..Default::default()
        };
        assert_eq!(p.validate().unwrap_err().name, "shading.marschner.sigma_a");
        let p = MarschnerParams {
            alpha_r_deg: f32::INFINITY,
            ..Default::default()
        };
        assert_eq!(
            p.validate().unwrap_err().name,
            "shading.marschner.alpha_r_deg"
        );
        let p = MarschnerParams {
            beta_r_deg: 0.0,
            ..Default::default()
        };
        assert_eq!(
            p.validate().unwrap_err().name,
            "shading.marschner.beta_r_deg"
        );
        let p = MarschnerParams {
            eccentricity: 0.5,
            ..Default::default()
        };
        assert_eq!(
            p.validate().unwrap_err().name,
            "shading.marschner.eccentricity"
        );
        let k = KajiyaKayParams {
            shininess: 0.0,
            ..Default::default()
        };
        assert_eq!(
            k.validate().unwrap_err().name,
            "shading.kajiya_kay.shininess"
        );
        let s = SadeghiParams {
            glint_angle_min_deg: 50.0,
            glint_angle_max_deg: 40.0,
            ..Default::default()
        };
        assert_eq!(
            s.validate().unwrap_err().name,
            "shading.sadeghi.glint_angle_max_deg"
        );
        let s = SadeghiParams {
            color_tt: Vec3::new(f32::NAN, 0.0, 0.0),
            ..Default::default()
        };
        assert_eq!(s.validate().unwrap_err().name, "shading.sadeghi.color_tt");
        let m = ShadingModel::Sadeghi(SadeghiParams {
            width_trt_deg: -1.0,
            ..Default::default()
        });
        assert_eq!(
            m.validate().unwrap_err().name,
            "shading.sadeghi.width_trt_deg"
        );
    }

    #[test]
    fn chiang_bad_values_name_the_field() {
        ChiangParams::default().validate().unwrap();
        ChiangParams::melanin(0.3, 0.0).validate().unwrap();
        ChiangParams::melanin(MAX_MELANIN, MAX_MELANIN)
            .validate()
            .unwrap();
        let with = |f: fn(&mut ChiangParams)| {
            let mut p = ChiangParams::default();
            f(&mut p);
            p.validate().map_err(|e| e.name)
        };
        type Spoil = fn(&mut ChiangParams);
        let cases: [(Spoil, &str); 17] = [
            (|p| p.beta_m = 0.0, "beta_m"),
            (|p| p.beta_m = -0.1, "beta_m"),
            (|p| p.beta_m = 1.01, "beta_m"),
            (|p| p.beta_m = f32::NAN, "beta_m"),
            (|p| p.beta_n = 0.0, "beta_n"),
            (|p| p.beta_n = 2.0, "beta_n"),
            (|p| p.beta_n = f32::NAN, "beta_n"),
            (|p| p.alpha_deg = f32::NAN, "alpha_deg"),
            (|p| p.alpha_deg = 11.0, "alpha_deg"),
            (|p| p.eta = 1.0, "eta"),
            (|p| p.eta = 0.5, "eta"),
            (|p| p.eta = f32::NAN, "eta"),
            (|p| p.eumelanin = Some(-0.1), "eumelanin"),
            (|p| p.eumelanin = Some(f32::NAN), "eumelanin"),
            (|p| p.pheomelanin = Some(-1.0), "pheomelanin"),
            (
                |p| p.sigma_a = Some(Vec3::new(0.1, f32::NAN, 0.1)),
                "sigma_a",
            ),
            (
                |p| {
                    p.sigma_a = Some(Vec3::splat(0.1));
                    p.pheomelanin = Some(0.5);
                },
                "sigma_a",
            ),
        ];
        for (spoil, field) in cases {
            assert_eq!(
                with(spoil),
                Err(format!("shading.chiang.{field}")),
                "{field}"
            );
        }
        // The edges of the ranges are accepted.
        assert_eq!(with(|p| p.beta_m = 1.0), Ok(()));
        assert_eq!(with(|p| p.eta = 1.0001), Ok(()));
        assert_eq!(with(|p| p.eumelanin = Some(0.0)), Ok(()));
        let m = ShadingModel::Chiang(ChiangParams {
            beta_n: 0.0,
            ..Default::default()
        });
        assert_eq!(m.validate().unwrap_err().name, "shading.chiang.beta_n");
    }

    #[test]
    fn chiang_absorption_comes_from_sigma_a_then_melanin_then_the_colour() {
        let brown = Vec3::new(0.36, 0.2, 0.09);
        let p = ChiangParams::default();
        assert_eq!(p.absorption(), Absorption::FromColor);
        assert_eq!(p.sigma_a_for(brown), sigma_a_from_reflectance(brown, 0.3));
        let p = ChiangParams {
            eumelanin: Some(0.3),
            ..Default::default()
        };
        assert_eq!(p.absorption(), Absorption::Fixed(EUMELANIN_SIGMA_A * 0.3));
        let p = ChiangParams {
            pheomelanin: Some(2.0),
            ..Default::default()
        };
        assert_eq!(p.absorption(), Absorption::Fixed(PHEOMELANIN_SIGMA_A * 2.0));
        let s = Vec3::new(0.1, 0.2, 0.3);
        let p = ChiangParams {
            sigma_a: Some(s),
            ..Default::default()
        };
        assert_eq!(p.sigma_a_for(brown), s);
        // A lighter colour absorbs less, white not at all.
        let light = sigma_a_from_reflectance(Vec3::splat(0.8), 0.3);
        let dark = sigma_a_from_reflectance(Vec3::splat(0.2), 0.3);
        assert!(light.x < dark.x, "{light} {dark}");
        assert_eq!(sigma_a_from_reflectance(Vec3::ONE, 0.3), Vec3::ZERO);
    }

    /// Numbers computed outside this code (Python, f64) from Blender's definition: Cycles'
    /// `NODE_PRINCIPLED_HAIR_PIGMENT_CONCENTRATION` branch (melanin quantity
    /// `-ln(max(1 - m, 1e-4))`, split by redness, coefficients (0.506, 0.841, 1.653) and
    /// (0.343, 0.733, 1.924), tint through Chiang's eq. 9 with the radial roughness).
    #[test]
    fn artist_melanin_matches_blenders_definition() {
        let close = |got: Vec3, want: [f64; 3]| {
            for (g, w) in got.to_array().iter().zip(want) {
                assert!(
                    ((*g as f64) - w).abs() <= 2e-6 * w.max(1.0),
                    "{got} against {want:?}"
                );
            }
        };
        // Blender's defaults: Melanin 0.8, Melanin Redness 1, Tint white.
        close(
            sigma_a_from_artist_melanin(0.8, 1.0, Vec3::ONE, 0.3),
            [0.5520372039648965, 1.1797179898141956, 3.0965585435232095],
        );
        let tint = Vec3::new(0.9, 0.5, 0.2);
        close(
            sigma_a_from_artist_melanin(0.5, 0.25, tint, 0.3),
            [0.32280687979894734, 0.5780783238698722, 1.2674383551665216],
        );
        close(
            sigma_a_from_artist_melanin(0.5, 0.25, tint, 0.6),
            [0.32290119069962503, 0.5821601738541662, 1.2894450373970239],
        );
        // Melanin 1 is clamped as Blender clamps it (1 - m at least 1e-4).
        close(
            sigma_a_from_artist_melanin(1.0, 0.0, Vec3::ONE, 0.3),
            [4.660432228219948, 7.745896252831969, 15.224692634876629],
        );
        // Not pbrt's coefficients: the same eumelanin quantity absorbs more here.
        let q = -(0.5f32.ln());
        assert!(
            sigma_a_from_artist_melanin(0.5, 0.0, Vec3::ONE, 0.3).x
                > sigma_a_from_melanin(q, 0.0).x * 1.2
        );
        // A tint channel of 0 is black, and finite.
        let black = sigma_a_from_artist_melanin(0.0, 0.0, Vec3::new(1.0, 0.0, 1.0), 0.3);
        assert!(black.y.is_finite() && black.y > 200.0, "{black}");
        assert_eq!((black.x, black.z), (0.0, 0.0));
        // Through the parameters: redness defaults to Blender's 1, tint to white.
        let p = ChiangParams {
            melanin: Some(0.8),
            ..Default::default()
        };
        p.validate().unwrap();
        let Absorption::Fixed(s) = p.absorption() else {
            panic!("melanin does not fix the absorption");
        };
        close(
            s,
            [0.5520372039648965, 1.1797179898141956, 3.0965585435232095],
        );
        let p = ChiangParams {
            beta_n: 0.6,
            ..ChiangParams::artist_melanin(0.5, 0.25, tint)
        };
        close(
            p.sigma_a_for(Vec3::ONE),
            [0.32290119069962503, 0.5821601738541662, 1.2894450373970239],
        );
    }

    #[test]
    fn artist_melanin_keys_are_checked_and_not_mixed() {
        let with = |f: fn(&mut ChiangParams)| {
            let mut p = ChiangParams::default();
            f(&mut p);
            p.validate().map_err(|e| (e.name, e.reason))
        };
        type Spoil = fn(&mut ChiangParams);
        let cases: [(Spoil, &str); 14] = [
            (|p| p.melanin = Some(1.01), "melanin"),
            (|p| p.melanin = Some(-0.01), "melanin"),
            (|p| p.melanin = Some(f32::NAN), "melanin"),
            (
                |p| {
                    p.melanin = Some(0.5);
                    p.melanin_redness = Some(1.5);
                },
                "melanin_redness",
            ),
            (
                |p| {
                    p.melanin = Some(0.5);
                    p.tint = Some(Vec3::new(0.5, 1.2, 0.5));
                },
                "tint",
            ),
            (
                |p| {
                    p.melanin = Some(0.5);
                    p.tint = Some(Vec3::new(0.5, f32::NAN, 0.5));
                },
                "tint",
            ),
            // The volume grid: no cells, too many, no steps, absurd steps.
            (|p| p.volume_grid = 0, "volume_grid"),
            (|p| p.volume_grid = MAX_VOLUME_GRID + 1, "volume_grid"),
            (|p| p.volume_iterations = 0, "volume_iterations"),
            (|p| p.volume_iterations = u32::MAX, "volume_iterations"),
            // Nothing silently ignored: redness and tint without melanin.
            (|p| p.melanin_redness = Some(0.5), "melanin_redness"),
            (|p| p.tint = Some(Vec3::splat(0.5)), "tint"),
            // One source of absorption.
            (
                |p| {
                    p.melanin = Some(0.5);
                    p.eumelanin = Some(1.0);
                },
                "melanin",
            ),
            (
                |p| {
                    p.melanin = Some(0.5);
                    p.sigma_a = Some(Vec3::splat(0.1));
                },
                "sigma_a",
            ),
        ];
        for (spoil, field) in cases {
            let got = with(spoil);
            assert_eq!(
                got.as_ref().map_err(|e| e.0.as_str()),
                Err(format!("shading.chiang.{field}").as_str()),
                "{field}: {got:?}"
            );
        }
        // The edges are accepted.
        assert_eq!(with(|p| p.melanin = Some(0.0)), Ok(()));
        assert_eq!(
            with(|p| {
                p.melanin = Some(1.0);
                p.melanin_redness = Some(0.0);
                p.tint = Some(Vec3::ZERO);
            }),
            Ok(())
        );
    }

    #[test]
    fn derived_lobes_follow_marschner_table_1() {
        let p = MarschnerParams::default();
        assert_eq!(p.lobe_shifts_deg(), [-7.5, 3.75, 11.25]);
        assert_eq!(p.lobe_widths_deg(), [7.5, 3.75, 15.0]);
    }

    #[test]
    fn sigma_a_from_color_is_minus_half_log() {
        let s = sigma_a_from_color(Vec3::new(1.0, 0.5, 0.0));
        assert_eq!(s.x, 0.0);
        assert!((s.y - 0.5 * 2.0f32.ln()).abs() < 1e-6);
        assert!(s.z.is_finite() && s.z > 4.0);
        let n = sigma_a_from_color(Vec3::new(f32::NAN, 2.0, -1.0));
        assert!(n.is_finite() && n.min_element() >= 0.0);
    }

    #[test]
    fn round_trips_through_toml() {
        for model in [
            ShadingModel::default(),
            ShadingModel::Marschner {
                params: MarschnerParams::default(),
                lut: true,
            },
            ShadingModel::Sadeghi(SadeghiParams::default()),
            ShadingModel::Chiang(ChiangParams::default()),
            ShadingModel::Chiang(ChiangParams::melanin(0.3, 0.0)),
            ShadingModel::Chiang(ChiangParams {
                sigma_a: Some(Vec3::new(0.2, 0.4, 0.8)),
                multiple_scattering: MultipleScattering::None,
                ..Default::default()
            }),
        ] {
            let text = toml::to_string(&model).unwrap();
            let back: ShadingModel = toml::from_str(&text).unwrap();
            assert_eq!(back, model, "{text}");
        }
        let m: ShadingModel = toml::from_str("model = \"marschner\"\nlut = true\n").unwrap();
        assert_eq!(
            m,
            ShadingModel::Marschner {
                params: MarschnerParams::default(),
                lut: true
            }
        );
        let m: ShadingModel =
            toml::from_str("model = \"marschner\"\n[params]\neta = 1.6\n").unwrap();
        let ShadingModel::Marschner { params, lut } = m else {
            panic!("not marschner");
        };
        assert!(!lut);
        assert_eq!(params.eta, 1.6);
        let k: ShadingModel = toml::from_str("model = \"kajiya_kay\"\nshininess = 20.0\n").unwrap();
        assert_eq!(
            k,
            ShadingModel::KajiyaKay(KajiyaKayParams {
                shininess: 20.0,
                ..Default::default()
            })
        );
        assert!(
            toml::from_str::<ShadingModel>("model = \"kajiya_kay\"\nshinyness = 2.0\n").is_err()
        );
        assert!(toml::from_str::<ShadingModel>("model = \"phong\"\n").is_err());
        // Marschner's own level refuses what it does not know (it used to drop it).
        assert!(toml::from_str::<ShadingModel>("model = \"marschner\"\nbogus_key = 1\n").is_err());
        let c: ShadingModel =
            toml::from_str("model = \"chiang\"\neumelanin = 0.3\ndual_scattering = false\n")
                .unwrap();
        assert_eq!(
            c,
            ShadingModel::Chiang(ChiangParams {
                eumelanin: Some(0.3),
                multiple_scattering: MultipleScattering::None,
                ..Default::default()
            })
        );
        // The method's names, and dual_scattering's old spelling both ways.
        for (text, want) in [
            (
                "multiple_scattering = \"volume\"",
                MultipleScattering::Volume,
            ),
            ("multiple_scattering = \"dual\"", MultipleScattering::Dual),
            (
                "multiple_scattering = \"dual_volume\"",
                MultipleScattering::DualVolume,
            ),
            ("multiple_scattering = \"none\"", MultipleScattering::None),
            ("dual_scattering = true", MultipleScattering::Dual),
            ("dual_scattering = false", MultipleScattering::None),
        ] {
            let c: ChiangParams = toml::from_str(text).unwrap();
            assert_eq!(c.multiple_scattering, want, "{text}");
        }
        let bad = toml::from_str::<ChiangParams>("multiple_scattering = \"photons\"").unwrap_err();
        assert!(bad.to_string().contains("none, dual, volume"), "{bad}");
    }
}
