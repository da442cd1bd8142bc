//! The hair fibre BSDF of Chiang et al. 2016 ("A Practical and Controllable Hair and Fur
//! Model for Production Path Tracing"), as pbrt-v3 defines it (`src/materials/hair.cpp`),
//! in `f64`: the CPU ground truth of pelage's GPU Chiang model and the BSDF of the
//! [`crate::path_tracer`].
//!
//! Slow and obviously right: every term follows pbrt-v3's definition; where this code
//! deviates from pbrt it says so (all deviations are numerical, none changes the model).
//!
//! # Conventions
//! - **Local frame** (pbrt's): `x` along the fibre (the unit tangent, root to tip), `y` and
//!   `z` span the normal plane, right-handed (`x × y = z`). A direction `w` has
//!   `sin θ = w.x`, `cos θ = sqrt(1 - w.x²)` (θ measured from the normal plane, positive
//!   toward the tip) and azimuth `φ = atan2(w.z, w.y)`. Both `wo` (toward the eye) and `wi`
//!   (toward the light) point away from the fibre. [`FibreFrame`] builds such a frame.
//! - **Azimuth**: `φ = φ_i - φ_o` (pbrt's `phiI - phiO`), so `φ = 0` is backscattering
//!   (`wi = wo` for `θ_i = θ_o`) and `φ = π` is forward scattering. The lobe `p` is centred
//!   at `φ = Φ(p, h) = 2p γ_t - 2γ_o + pπ`.
//! - **h**: the signed offset of the ray across the fibre, in [-1, 1], `γ_o = asin h`. The
//!   sign is fixed by the geometry of the R lobe: the surface normal where a ray of offset `h`
//!   hits the cylinder has azimuth `φ_o - γ_o`, so that the mirror direction is at
//!   `φ_i - φ_o = -2γ_o`. Equivalently, for a ray travelling along `d` that passes the axis
//!   at the perpendicular offset `q` (a vector from the axis to the ray, perpendicular to both),
//!   `h = x · (d̂⊥ × q) / radius` (see [`crate::transmittance::SegmentBvh::closest_hit`]).
//! - **σ_a** is pbrt's: the absorption coefficient per unit length of a fibre of radius 1
//!   (per fibre radius; dimensionless and independent of the real width). A chord through
//!   the axis at normal incidence (length 2) keeps `exp(-2 σ_a)`; in general a single
//!   internal pass keeps `T = exp(-σ_a · 2 cos γ_t / cos θ_t)`. It is the same unit as
//!   `MarschnerParams::sigma_a` in `pelage-scene`.
//! - **α** (cuticle tilt) is in **radians** here (pbrt takes degrees; its default 2° is
//!   `0.0349`). Lobe `p` evaluates `M_p` with `θ_o` turned by `[-2α, α, 4α, 0][p]`
//!   ([`ChiangFibre::lobe_tilts`]), so the R lobe peaks at `θ_i = 2α - θ_o`: with `x` from
//!   root to tip a positive α moves R toward the tip, as pbrt's formula does (Marschner's
//!   physical shift toward the root corresponds to a negative α in this convention).
//! - **The cosine**: pbrt divides the lobe sum by `|wi.z|` (the normal of its camera-facing
//!   ribbon) so that its integrator's cosine cancels. Here [`ChiangFibre::eval`] divides by
//!   the longitudinal `cos θ_i` instead, the cosine a cylinder's projected width actually
//!   has; in both cases "f times its cosine" is the same lobe sum
//!   `Σ_p M_p A_p N_p` ([`ChiangFibre::eval_projected`]), and every integral here uses
//!   `f |cos θ_i| dω_i` with that `cos θ_i`.
//! - RGB: `A_p` is per channel; lobe selection in sampling uses pbrt's luminance weights
//!   [`LUMINANCE`].
//!
//! # Far field
//! [`ChiangFibre::far_field_radiance`] averages the BSDF over the fibre's width,
//! `½ ∫ f(h) cos θ_i dh = Σ_p M_p(θ_i, θ_o) N̄_p(φ; θ_o)`: the longitudinal terms
//! ([`ChiangFibre::mp`]) times the h-integrated azimuthal terms
//! ([`ChiangFibre::far_field_np`]), which a GPU model can tabulate over `(|φ|, sin θ_o)` (and
//! σ_a). `N̄_p` is even in `φ`, so the sign of the azimuth does not matter there.
//!
//! # Reciprocity
//! pbrt's model is not reciprocal in general: `A_p`, `γ_t` and the tilt use `θ_o` only.
//! What holds exactly (tested) is `f(wo, wi; h) = f(wi, wo; -h)` when `α = 0` and
//! `|θ_i| = |θ_o|`, hence the same for the far field. For `|θ_i| ≠ |θ_o|` the far field
//! differs from its swap by up to ~70% (measured over a sweep, where `σ_a` makes `T` depend
//! strongly on `θ_t`).
//!
//! # Numerical deviations from pbrt-v3
//! `I₀` is summed to `f64` precision with an exact asymptotic series above 20 (pbrt: 10
//! series terms, switching to a one-term asymptotic at 12, 2% off there); `M_p` uses the
//! log-form normalisation `-ln(2v) - ln sinh(1/v)` at every `v` (pbrt: the log form with
//! `ln 2 ≈ 0.6931` for `v <= 0.1`); the `M_p` sampling inverse CDF is exact (pbrt clamps
//! `u >= 1e-5`) and takes four independent numbers (pbrt demultiplexes two); `eval` divides
//! by `cos θ_i`, not by pbrt's ribbon `|wi.z|` (see above). [`PreparedFibre`] holds the
//! parameter-only terms for repeated evaluation.

use std::f64::consts::{FRAC_PI_2, LN_2, PI, TAU};

use glam::{DVec3, Vec3};

use crate::path_tracer::Pcg32;

/// Number of explicit lobes (R, TT, TRT); lobe `P_MAX` = 3 holds all higher orders.
pub const P_MAX: usize = 3;

/// `sqrt(π / 8)`, the scale from β_n to the logistic's `s`.
pub const SQRT_PI_OVER_8: f64 = 0.626_657_068_657_750_1;

/// pbrt's RGB luminance weights (`Spectrum::y()`), used to choose a lobe when sampling.
pub const LUMINANCE: DVec3 = DVec3::new(0.212_671, 0.715_160, 0.072_169);

/// Smallest number of Gauss-Legendre panels over `γ_o ∈ [-π/2, π/2]` used by
/// [`ChiangFibre::far_field_np`] (more are used for narrow logistics: see there).
pub const FAR_FIELD_MIN_PANELS: usize = 256;

/// Most panels [`ChiangFibre::far_field_np_panels`] uses (a larger request is cut to it).
pub const FAR_FIELD_MAX_PANELS: usize = 1 << 20;

/// Most samples the furnace integrals take (a larger request is cut to it).
pub const MAX_FURNACE_SAMPLES: usize = 1 << 30;

/// Eight-point Gauss-Legendre nodes on [-1, 1] (positive half; the rule is symmetric).
const GL8_X: [f64; 4] = [
    0.183_434_642_495_649_8,
    0.525_532_409_916_329,
    0.796_666_477_413_626_7,
    0.960_289_856_497_536_3,
];
/// Weights of [`GL8_X`].
const GL8_W: [f64; 4] = [
    0.362_683_783_378_362,
    0.313_706_645_877_887_3,
    0.222_381_034_453_374_5,
    0.101_228_536_290_376_3,
];

/// A parameter of [`ChiangFibre`] out of its range.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("Chiang fibre parameter `{name}` = {value}: {reason}")]
pub struct ChiangError {
    /// Field name (`sigma_a`, `beta_m`, `beta_n`, `alpha` or `eta`).
    pub name: &'static str,
    /// The offending value, formatted.
    pub value: String,
    /// The valid range.
    pub reason: &'static str,
}

/// One hair fibre's scattering parameters (Chiang et al. 2016, pbrt-v3's `HairBSDF`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChiangFibre {
    /// Absorption coefficient per unit length of a unit-radius fibre (per fibre radius),
    /// linear RGB, each >= 0 and finite (see the module docs).
    pub sigma_a: DVec3,
    /// Longitudinal roughness β_m in (0, 1].
    pub beta_m: f64,
    /// Azimuthal roughness β_n in (0, 1].
    pub beta_n: f64,
    /// Cuticle scale tilt α in radians, |α| < π/4 (pbrt's default 2° = 0.0349 rad).
    pub alpha: f64,
    /// Index of refraction of the fibre, > 1 and finite (hair: 1.55).
    pub eta: f64,
}

impl Default for ChiangFibre {
    /// pbrt-v3's defaults: η = 1.55, β_m = β_n = 0.3, α = 2°, σ_a of eumelanin
    /// concentration 1.3 (brown hair).
    fn default() -> Self {
        Self {
            sigma_a: sigma_a_from_concentration(1.3, 0.0),
            beta_m: 0.3,
            beta_n: 0.3,
            alpha: 2f64.to_radians(),
            eta: 1.55,
        }
    }
}

/// pbrt's `SigmaAFromConcentration`: σ_a (per fibre radius) of eumelanin and pheomelanin
/// concentrations (negative values count as 0).
pub fn sigma_a_from_concentration(eumelanin: f64, pheomelanin: f64) -> DVec3 {
    let ce = eumelanin.max(0.0);
    let cp = pheomelanin.max(0.0);
    DVec3::new(0.419, 0.697, 1.37) * ce + DVec3::new(0.187, 0.4, 1.05) * cp
}

/// pbrt's `SigmaAFromReflectance` (Chiang et al. eq. 9): the σ_a whose multiply scattered
/// albedo is about `color` at azimuthal roughness `beta_n`. Channels are clamped to
/// `[1e-4, 1]` (NaN counts as black).
pub fn sigma_a_from_reflectance(color: DVec3, beta_n: f64) -> DVec3 {
    let b = beta_n;
    let denom = 5.969 - 0.215 * b + 2.532 * b * b - 10.73 * b.powi(3)
        + 5.574 * b.powi(4)
        + 0.245 * b.powi(5);
    let f = |c: f64| {
        let c = if c.is_nan() {
            1.0e-4
        } else {
            c.clamp(1.0e-4, 1.0)
        };
        (c.ln() / denom).powi(2)
    };
    DVec3::new(f(color.x), f(color.y), f(color.z))
}

/// `1 / (k!)²` for `k = 0..48`: the coefficients of `I₀`'s power series in `(x/2)²`.
const INV_FACTORIAL_SQUARED: [f64; 48] = {
    let mut t = [0.0f64; 48];
    let mut f = 1.0f64;
    let mut k = 0;
    while k < 48 {
        if k > 0 {
            f *= k as f64;
        }
        t[k] = 1.0 / (f * f);
        k += 1;
    }
    t
};

/// `(2k - 1)² / k` for `k = 0..48` (0 at `k = 0`): the ratios of `I₀`'s asymptotic series
/// `c_k = c_{k-1} (2k-1)² / (8 k x)`.
const ASYMPTOTIC_RATIO: [f64; 48] = {
    let mut t = [0.0f64; 48];
    let mut k = 1;
    while k < 48 {
        let m = (2 * k - 1) as f64;
        t[k] = m * m / k as f64;
        k += 1;
    }
    t
};

/// Where [`log_bessel_i0`] switches from the power series to the asymptotic series (both are
/// accurate to about 1e-16 relative there: the asymptotic series' smallest term is ~e^{-2x}).
pub const BESSEL_SERIES_LIMIT: f64 = 20.0;

/// `I₀(x)`, the modified Bessel function of the first kind of order 0: the power series
/// `Σ (x²/4)^k / (k!)²` summed to `f64` precision for `|x| <= 20` (pbrt truncates it after
/// 10 terms, which is 2% low at `x = 12`), `exp` of [`log_bessel_i0`] above. Overflows to
/// infinity above `x ≈ 713`.
pub fn bessel_i0(x: f64) -> f64 {
    if x.abs() <= BESSEL_SERIES_LIMIT {
        i0_series(x)
    } else {
        log_bessel_i0(x).exp()
    }
}

fn i0_series(x: f64) -> f64 {
    let q = 0.25 * x * x;
    let mut power = 1.0f64;
    let mut sum = 1.0f64;
    for c in &INV_FACTORIAL_SQUARED[1..] {
        power *= q;
        let term = power * c;
        sum += term;
        if term < 1.0e-17 * sum {
            break;
        }
    }
    sum
}

/// `ln I₀(x)`: the power series of [`bessel_i0`] for `|x| <= 20`, above that the asymptotic
/// series `x - ln(2πx)/2 + ln Σ_k ((2k-1)!!)² / (k! (8x)^k)` summed to `f64` precision
/// (pbrt switches at 12 and keeps one term, a 2% jump; here both sides agree with
/// mpmath to ~1e-15, tested).
pub fn log_bessel_i0(x: f64) -> f64 {
    let x = x.abs();
    if x <= BESSEL_SERIES_LIMIT {
        return i0_series(x).ln();
    }
    x - 0.5 * (TAU * x).ln() + asymptotic_sum(x).ln()
}

/// `e^c I₀(a)` without overflow and without logarithms (the hot path of `M_p`): the power series
/// times `e^c` for `|a| <= 20`, `e^{a + c} S(a) / sqrt(2πa)` with the asymptotic series `S`
/// above (the same two series as [`log_bessel_i0`]).
fn scaled_i0(a: f64, c: f64) -> f64 {
    let a = a.abs();
    if a <= BESSEL_SERIES_LIMIT {
        return i0_series(a) * c.exp();
    }
    let e = a + c;
    if e < -745.0 {
        return 0.0;
    }
    e.exp() * asymptotic_sum(a) / (TAU * a).sqrt()
}

/// `Σ_k ((2k-1)!!)² / (k! (8x)^k)`, summed until its terms fall below 1e-17 or grow.
fn asymptotic_sum(x: f64) -> f64 {
    let inv8x = 1.0 / (8.0 * x);
    let mut c = 1.0f64;
    let mut sum = 1.0f64;
    for ratio in &ASYMPTOTIC_RATIO[1..] {
        let next = c * ratio * inv8x;
        if next > c {
            break; // the asymptotic series starts to diverge
        }
        c = next;
        sum += c;
        if c < 1.0e-17 * sum {
            break;
        }
    }
    sum
}

/// `ln sinh(x)` for `x > 0`, without overflow: `x - ln 2 + ln(1 - e^{-2x})`.
fn log_sinh(x: f64) -> f64 {
    x - LN_2 + (-(-2.0 * x).exp()).ln_1p()
}

/// d'Eon et al.'s longitudinal scattering (pbrt's `Mp`):
/// `M = e^{-sin θ_i sin θ_o / v} I₀(cos θ_i cos θ_o / v) / (2 v sinh(1/v))`,
/// normalised so that `∫ M cos θ_i dθ_i = 1` over `θ_i ∈ [-π/2, π/2]`.
///
/// Evaluated in log form for every `v` (pbrt uses the log form for `v <= 0.1` with
/// `ln 2 ≈ 0.6931` and the direct form above); both are the same function.
pub fn longitudinal_scattering(
    cos_theta_i: f64,
    cos_theta_o: f64,
    sin_theta_i: f64,
    sin_theta_o: f64,
    v: f64,
) -> f64 {
    let a = cos_theta_i * cos_theta_o / v;
    let b = sin_theta_i * sin_theta_o / v;
    (log_bessel_i0(a) - b - (2.0 * v).ln() - log_sinh(1.0 / v)).exp()
}

/// Unpolarised Fresnel reflectance of a dielectric of index `eta` (> 1) entered from a medium
/// of index 1 at incidence cosine `cos_theta_i` (clamped to [0, 1]); pbrt's `FrDielectric`.
pub fn fresnel_dielectric(cos_theta_i: f64, eta: f64) -> f64 {
    let ci = cos_theta_i.clamp(0.0, 1.0);
    let sin_t2 = (1.0 - ci * ci) / (eta * eta);
    if sin_t2 >= 1.0 {
        return 1.0;
    }
    let ct = (1.0 - sin_t2).sqrt();
    let r_parl = (eta * ci - ct) / (eta * ci + ct);
    let r_perp = (ci - eta * ct) / (ci + eta * ct);
    0.5 * (r_parl * r_parl + r_perp * r_perp)
}

/// The logistic distribution of scale `s` (pbrt's `Logistic`), even in `x`.
pub fn logistic(x: f64, s: f64) -> f64 {
    let e = (-x.abs() / s).exp();
    e / (s * (1.0 + e) * (1.0 + e))
}

/// The logistic trimmed to [-π, π] and renormalised there (pbrt's `TrimmedLogistic`);
/// `x` is taken as given (0 outside [-π, π] is the caller's business: see [`azimuthal_scattering`]).
pub fn trimmed_logistic(x: f64, s: f64) -> f64 {
    // CDF(π) - CDF(-π) = tanh(π / 2s).
    logistic(x, s) / (0.5 * PI / s).tanh()
}

/// Wraps an angle into [-π, π).
fn wrap_pi(x: f64) -> f64 {
    x - TAU * ((x + PI) / TAU).floor()
}

/// `Φ(p, h) = 2p γ_t - 2γ_o + pπ`: the azimuthal deflection of lobe `p` (pbrt's `Phi`).
pub fn deflection(p: usize, gamma_o: f64, gamma_t: f64) -> f64 {
    let p = p as f64;
    2.0 * p * gamma_t - 2.0 * gamma_o + p * PI
}

/// pbrt's `Np`: the trimmed logistic of `φ - Φ(p, h)` wrapped into [-π, π].
pub fn azimuthal_scattering(phi: f64, p: usize, s: f64, gamma_o: f64, gamma_t: f64) -> f64 {
    trimmed_logistic(wrap_pi(phi - deflection(p, gamma_o, gamma_t)), s)
}

/// Inverse CDF of the logistic trimmed to [-π, π] (pbrt's `SampleTrimmedLogistic`).
fn sample_trimmed_logistic(u: f64, s: f64) -> f64 {
    let cdf = |x: f64| 1.0 / (1.0 + (-x / s).exp());
    let k = cdf(PI) - cdf(-PI);
    let x = -s * (1.0 / (u * k + cdf(-PI)) - 1.0).ln();
    if x.is_nan() { 0.0 } else { x.clamp(-PI, PI) }
}

/// A right-handed frame for [`ChiangFibre`]'s local coordinates: `x` the unit tangent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FibreFrame {
    /// Unit tangent (root to tip).
    pub x: DVec3,
    /// First normal-plane axis.
    pub y: DVec3,
    /// `x × y`.
    pub z: DVec3,
}

impl FibreFrame {
    /// The frame with `x = normalize(tangent)` and `y` the normalised part of `reference`
    /// perpendicular to it. `None` when `tangent` is zero or not finite, or `reference` is
    /// (nearly) parallel to it. For a circular fibre the choice of `y` changes no result
    /// (only `φ_i - φ_o` matters).
    pub fn new(tangent: DVec3, reference: DVec3) -> Option<FibreFrame> {
        let x = tangent.try_normalize()?;
        let perp = reference - reference.dot(x) * x;
        let len = perp.length();
        if !len.is_finite() || len <= 1e-9 * reference.length() {
            return None;
        }
        let y = perp / len;
        Some(FibreFrame {
            x,
            y,
            z: x.cross(y),
        })
    }

    /// A frame about `tangent` with some `y` (glam's `any_orthonormal_vector`).
    pub fn from_tangent(tangent: DVec3) -> Option<FibreFrame> {
        let x = tangent.try_normalize()?;
        let y = x.any_orthonormal_vector();
        Some(FibreFrame {
            x,
            y,
            z: x.cross(y),
        })
    }

    /// World direction to local coordinates.
    pub fn to_local(&self, w: DVec3) -> DVec3 {
        DVec3::new(w.dot(self.x), w.dot(self.y), w.dot(self.z))
    }

    /// Local coordinates to a world direction.
    pub fn to_world(&self, l: DVec3) -> DVec3 {
        l.x * self.x + l.y * self.y + l.z * self.z
    }
}

/// A [`ChiangFibre`] with every term that depends only on its parameters computed once
/// (pbrt's `HairBSDF` constructor): the longitudinal variances and their normalisations, the
/// logistic scale and the tilt rotations. Build it with [`ChiangFibre::prepare`] for many
/// evaluations; [`ChiangFibre`]'s own methods prepare one per call.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PreparedFibre {
    fibre: ChiangFibre,
    /// Longitudinal variances `v_p`.
    v: [f64; 4],
    /// `1 / v_p`.
    inv_v: [f64; 4],
    /// `-ln(2 v_p) - ln sinh(1 / v_p)`: the log of `M_p`'s normalisation.
    log_norm: [f64; 4],
    /// Logistic scale.
    s: f64,
    /// `1 / tanh(π / 2s)`: the normalisation of the logistic trimmed to [-π, π].
    trim: f64,
    /// `sin` and `cos` of the tilts of lobes 0..3.
    tilt_sin: [f64; 3],
    tilt_cos: [f64; 3],
}

/// What the lobes need of `wo` and `h`.
#[derive(Clone, Copy, Debug)]
struct Outgoing {
    sin_o: f64,
    cos_o: f64,
    /// `(wo.y, wo.z)`: the azimuth of `wo` as a vector.
    wo_yz: (f64, f64),
    gamma_o: f64,
    gamma_t: f64,
    /// Attenuations `A_p`.
    ap: [DVec3; 4],
}

impl PreparedFibre {
    /// The parameters.
    pub fn fibre(&self) -> &ChiangFibre {
        &self.fibre
    }

    /// The same fibre with another σ_a (nothing precomputed depends on σ_a).
    pub fn with_sigma_a(&self, sigma_a: DVec3) -> PreparedFibre {
        let mut p = *self;
        p.fibre.sigma_a = sigma_a;
        p
    }

    /// `(sin θ_o', |cos θ_o'|)` of lobe `p` after its tilt.
    fn tilted(&self, p: usize, sin_o: f64, cos_o: f64) -> (f64, f64) {
        if p >= P_MAX {
            return (sin_o, cos_o);
        }
        let (s, c) = (self.tilt_sin[p], self.tilt_cos[p]);
        (sin_o * c + cos_o * s, (cos_o * c - sin_o * s).abs())
    }

    /// [`longitudinal_scattering`] of lobe `p` with the precomputed normalisation.
    fn mp_lobe(&self, p: usize, ci: f64, co_p: f64, si: f64, so_p: f64) -> f64 {
        let a = ci * co_p * self.inv_v[p];
        let b = si * so_p * self.inv_v[p];
        scaled_i0(a, self.log_norm[p] - b)
    }

    /// Lobe `p`'s `M_p(θ_i, θ_o)` with its tilt and variance (see [`ChiangFibre::mp`]).
    pub fn mp(&self, p: usize, sin_theta_i: f64, sin_theta_o: f64) -> f64 {
        let p = p.min(P_MAX);
        let si = sin_theta_i.clamp(-1.0, 1.0);
        let so = sin_theta_o.clamp(-1.0, 1.0);
        let ci = (1.0 - si * si).max(0.0).sqrt();
        let co = (1.0 - so * so).max(0.0).sqrt();
        let (so_p, co_p) = self.tilted(p, so, co);
        self.mp_lobe(p, ci, co_p, si, so_p)
    }

    /// `(γ_t, T)` for a ray at `θ_o` and offset `h` (pbrt: `η' = sqrt(η² - sin²θ_o)/cos θ_o`,
    /// `sin γ_t = h/η'`, `sin θ_t = sin θ_o / η`).
    fn refraction(&self, so: f64, co: f64, h: f64) -> (f64, DVec3) {
        let eta = self.fibre.eta;
        let sin_t = so / eta;
        let cos_t = (1.0 - sin_t * sin_t).max(0.0).sqrt();
        let etap = (eta * eta - so * so).max(0.0).sqrt() / co;
        let sin_gt = if etap.is_finite() {
            (h / etap).clamp(-1.0, 1.0)
        } else {
            0.0
        };
        let cos_gt = (1.0 - sin_gt * sin_gt).max(0.0).sqrt();
        let t = (-self.fibre.sigma_a * (2.0 * cos_gt / cos_t)).exp();
        (sin_gt.asin(), t)
    }

    fn ap(&self, co: f64, h: f64, t: DVec3) -> [DVec3; 4] {
        let cos_gamma_o = (1.0 - h * h).max(0.0).sqrt();
        let f = fresnel_dielectric(co * cos_gamma_o, self.fibre.eta);
        let a0 = DVec3::splat(f);
        let a1 = (1.0 - f) * (1.0 - f) * t;
        let a2 = a1 * t * f;
        let rest = |a2: f64, t: f64| {
            let d = 1.0 - t * f;
            if d > 0.0 { a2 * f * t / d } else { 0.0 }
        };
        let a3 = DVec3::new(rest(a2.x, t.x), rest(a2.y, t.y), rest(a2.z, t.z));
        [a0, a1, a2, a3]
    }

    /// `A_p` (see [`ChiangFibre::attenuation`]).
    pub fn attenuation(&self, sin_theta_o: f64, h: f64) -> [DVec3; 4] {
        let so = sin_theta_o.clamp(-1.0, 1.0);
        let co = (1.0 - so * so).max(0.0).sqrt();
        let h = h.clamp(-1.0, 1.0);
        let (_, t) = self.refraction(so, co, h);
        self.ap(co, h, t)
    }

    fn outgoing(&self, wo: DVec3, h: f64) -> Outgoing {
        let so = wo.x.clamp(-1.0, 1.0);
        let co = (1.0 - so * so).max(0.0).sqrt();
        let h = h.clamp(-1.0, 1.0);
        let (gamma_t, t) = self.refraction(so, co, h);
        Outgoing {
            sin_o: so,
            cos_o: co,
            wo_yz: (wo.y, wo.z),
            gamma_o: h.asin(),
            gamma_t,
            ap: self.ap(co, h, t),
        }
    }

    /// `M_p N_p` of each lobe at `wi` (with `N_3 = 1/2π`), and `cos θ_i`.
    fn lobe_terms(&self, o: &Outgoing, wi: DVec3) -> ([f64; 4], f64) {
        let si = wi.x.clamp(-1.0, 1.0);
        let ci = (1.0 - si * si).max(0.0).sqrt();
        // φ_i - φ_o in one atan2, from the 2-D cross and dot products of the projections.
        let (oy, oz) = o.wo_yz;
        let phi = (oy * wi.z - oz * wi.y).atan2(oy * wi.y + oz * wi.z);
        let mut terms = [0.0f64; 4];
        for (p, term) in terms.iter_mut().enumerate().take(P_MAX) {
            let (so_p, co_p) = self.tilted(p, o.sin_o, o.cos_o);
            let m = self.mp_lobe(p, ci, co_p, si, so_p);
            if m > 0.0 {
                let x = wrap_pi(phi - deflection(p, o.gamma_o, o.gamma_t));
                *term = m * logistic(x, self.s) * self.trim;
            }
        }
        terms[P_MAX] = self.mp_lobe(P_MAX, ci, o.cos_o, si, o.sin_o) / TAU;
        (terms, ci)
    }

    /// `f(wo, wi) cos θ_i` (see [`ChiangFibre::eval_projected`]).
    pub fn eval_projected(&self, wo: DVec3, wi: DVec3, h: f64) -> DVec3 {
        let o = self.outgoing(wo, h);
        let (t, _) = self.lobe_terms(&o, wi);
        o.ap[0] * t[0] + o.ap[1] * t[1] + o.ap[2] * t[2] + o.ap[3] * t[3]
    }

    /// `f(wo, wi)` (see [`ChiangFibre::eval`]).
    pub fn eval(&self, wo: DVec3, wi: DVec3, h: f64) -> DVec3 {
        let o = self.outgoing(wo, h);
        let (t, ci) = self.lobe_terms(&o, wi);
        if ci > 0.0 {
            (o.ap[0] * t[0] + o.ap[1] * t[1] + o.ap[2] * t[2] + o.ap[3] * t[3]) / ci
        } else {
            DVec3::ZERO
        }
    }

    fn lobe_pdf_of(ap: &[DVec3; 4]) -> [f64; 4] {
        let y = ap.map(|a| a.dot(LUMINANCE));
        let sum: f64 = y.iter().sum();
        if sum > 0.0 && sum.is_finite() {
            y.map(|v| v / sum)
        } else {
            [0.0; 4]
        }
    }

    /// The lobe selection probabilities (see [`ChiangFibre::lobe_pdf`]).
    pub fn lobe_pdf(&self, sin_theta_o: f64, h: f64) -> [f64; 4] {
        Self::lobe_pdf_of(&self.attenuation(sin_theta_o, h))
    }

    /// The sampling density (see [`ChiangFibre::pdf`]).
    pub fn pdf(&self, wo: DVec3, wi: DVec3, h: f64) -> f64 {
        let o = self.outgoing(wo, h);
        let lp = Self::lobe_pdf_of(&o.ap);
        let (t, _) = self.lobe_terms(&o, wi);
        lp[0] * t[0] + lp[1] * t[1] + lp[2] * t[2] + lp[3] * t[3]
    }

    /// Importance sampling (see [`ChiangFibre::sample`]).
    pub fn sample(&self, wo: DVec3, h: f64, u: [f64; 4]) -> Option<(DVec3, DVec3, f64)> {
        let o = self.outgoing(wo, h);
        let lp = Self::lobe_pdf_of(&o.ap);
        let mut u0 = u[0];
        let mut p = 0;
        while p < P_MAX {
            if u0 < lp[p] {
                break;
            }
            u0 -= lp[p];
            p += 1;
        }
        // The lobe's axis: -wo turned by the tilt (signed cos: pbrt samples about the
        // unfolded axis; M_p depends on |cos θ_o'| only, so both agree).
        let (so_p, co_p) = if p < P_MAX {
            let (s, c) = (self.tilt_sin[p], self.tilt_cos[p]);
            (o.sin_o * c + o.cos_o * s, o.cos_o * c - o.sin_o * s)
        } else {
            (o.sin_o, o.cos_o)
        };
        let v = self.v[p];
        let u1 = u[1].clamp(0.0, 1.0);
        let cos_t = (1.0 + v * (u1 + (1.0 - u1) * (-2.0 / v).exp()).ln()).clamp(-1.0, 1.0);
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let cos_phi = (TAU * u[2]).cos();
        let si = (-cos_t * so_p + sin_t * cos_phi * co_p).clamp(-1.0, 1.0);
        let ci = (1.0 - si * si).max(0.0).sqrt();
        let dphi = if p < P_MAX {
            deflection(p, o.gamma_o, o.gamma_t) + sample_trimmed_logistic(u[3], self.s)
        } else {
            TAU * u[3]
        };
        let phi_i = o.wo_yz.1.atan2(o.wo_yz.0) + dphi;
        let wi = DVec3::new(si, ci * phi_i.cos(), ci * phi_i.sin());
        let (t, ci) = self.lobe_terms(&o, wi);
        let pdf = lp[0] * t[0] + lp[1] * t[1] + lp[2] * t[2] + lp[3] * t[3];
        if !(pdf > 0.0 && pdf.is_finite() && ci > 0.0) {
            return None;
        }
        let f = (o.ap[0] * t[0] + o.ap[1] * t[1] + o.ap[2] * t[2] + o.ap[3] * t[3]) / ci;
        if !f.is_finite() {
            return None;
        }
        Some((wi, f, pdf))
    }

    /// `N̄_p` with `panels` quadrature panels (see [`ChiangFibre::far_field_np`]).
    pub fn far_field_np_panels(
        &self,
        p: usize,
        phi: f64,
        sin_theta_o: f64,
        panels: usize,
    ) -> DVec3 {
        let p = p.min(P_MAX);
        let panels = panels.clamp(1, FAR_FIELD_MAX_PANELS);
        let so = sin_theta_o.clamp(-1.0, 1.0);
        let co = (1.0 - so * so).max(0.0).sqrt();
        let width = PI / panels as f64;
        let integrand = |gamma: f64| -> DVec3 {
            let h = gamma.sin();
            let (gamma_t, t) = self.refraction(so, co, h);
            let ap = self.ap(co, h, t);
            let d = if p < P_MAX {
                logistic(wrap_pi(phi - deflection(p, gamma, gamma_t)), self.s) * self.trim
            } else {
                1.0 / TAU
            };
            ap[p] * (d * gamma.cos())
        };
        let mut sum = DVec3::ZERO;
        let half = 0.5 * width;
        for k in 0..panels {
            let mid = -FRAC_PI_2 + (k as f64 + 0.5) * width;
            for (x, w) in GL8_X.iter().zip(GL8_W) {
                sum += (integrand(mid - half * x) + integrand(mid + half * x)) * (w * half);
            }
        }
        0.5 * sum
    }

    /// `N̄_p` (see [`ChiangFibre::far_field_np`]).
    pub fn far_field_np(&self, p: usize, phi: f64, sin_theta_o: f64) -> DVec3 {
        let panels = FAR_FIELD_MIN_PANELS
            .max((TAU / self.s).ceil() as usize)
            .min(FAR_FIELD_MAX_PANELS);
        self.far_field_np_panels(p, phi, sin_theta_o, panels)
    }

    /// `Σ_p M_p N̄_p` (see [`ChiangFibre::far_field`]).
    pub fn far_field(&self, sin_theta_i: f64, sin_theta_o: f64, phi: f64) -> DVec3 {
        (0..=P_MAX)
            .map(|p| self.mp(p, sin_theta_i, sin_theta_o) * self.far_field_np(p, phi, sin_theta_o))
            .sum()
    }
}

impl ChiangFibre {
    /// Checks every field (see the field docs for the ranges).
    pub fn validate(&self) -> Result<(), ChiangError> {
        let bad = |name, value: String, reason| {
            Err(ChiangError {
                name,
                value,
                reason,
            })
        };
        if !self.sigma_a.is_finite() || self.sigma_a.min_element() < 0.0 {
            return bad(
                "sigma_a",
                format!("{:?}", self.sigma_a),
                "must be finite and >= 0",
            );
        }
        if !(self.beta_m > 0.0 && self.beta_m <= 1.0) {
            return bad("beta_m", self.beta_m.to_string(), "must be in (0, 1]");
        }
        if !(self.beta_n > 0.0 && self.beta_n <= 1.0) {
            return bad("beta_n", self.beta_n.to_string(), "must be in (0, 1]");
        }
        if !self.alpha.is_finite() || self.alpha.abs() >= 0.25 * PI {
            return bad(
                "alpha",
                self.alpha.to_string(),
                "must be finite with |alpha| < pi/4 (radians)",
            );
        }
        if !(self.eta > 1.0 && self.eta.is_finite()) {
            return bad("eta", self.eta.to_string(), "must be finite and > 1");
        }
        Ok(())
    }

    /// The longitudinal variances `[v_0, v_1, v_2, v_3]` (pbrt):
    /// `v_0 = (0.726 β_m + 0.812 β_m² + 3.7 β_m²⁰)²`, `v_1 = v_0 / 4`, `v_2 = v_3 = 4 v_0`.
    pub fn longitudinal_variances(&self) -> [f64; 4] {
        let b = self.beta_m;
        let v0 = (0.726 * b + 0.812 * b * b + 3.7 * b.powi(20)).powi(2);
        [v0, 0.25 * v0, 4.0 * v0, 4.0 * v0]
    }

    /// The logistic scale `s = sqrt(π/8) (0.265 β_n + 1.194 β_n² + 5.372 β_n²²)` (pbrt).
    pub fn azimuthal_scale(&self) -> f64 {
        let b = self.beta_n;
        SQRT_PI_OVER_8 * (0.265 * b + 1.194 * b * b + 5.372 * b.powi(22))
    }

    /// The angle added to `θ_o` in lobe `p`'s `M_p`: `[-2α, α, 4α, 0]` (pbrt's `sin2kAlpha`
    /// rotations: `sin θ_o' = sin θ_o cos τ + cos θ_o sin τ`, `cos θ_o' = |cos(θ_o + τ)|`;
    /// the residual lobe is not tilted).
    pub fn lobe_tilts(&self) -> [f64; 4] {
        [-2.0 * self.alpha, self.alpha, 4.0 * self.alpha, 0.0]
    }

    /// Everything that depends only on the parameters, computed once.
    pub fn prepare(&self) -> PreparedFibre {
        let v = self.longitudinal_variances();
        let s = self.azimuthal_scale();
        let t = self.lobe_tilts();
        PreparedFibre {
            fibre: *self,
            v,
            inv_v: v.map(|v| 1.0 / v),
            log_norm: v.map(|v| -(2.0 * v).ln() - log_sinh(1.0 / v)),
            s,
            trim: 1.0 / (0.5 * PI / s).tanh(),
            tilt_sin: [t[0].sin(), t[1].sin(), t[2].sin()],
            tilt_cos: [t[0].cos(), t[1].cos(), t[2].cos()],
        }
    }

    /// Lobe `p`'s longitudinal term `M_p(θ_i, θ_o)` with its tilt and variance (p in 0..=3;
    /// larger `p` counts as 3): [`longitudinal_scattering`] of `θ_i` and the tilted `θ_o`.
    /// The sines are clamped to [-1, 1].
    pub fn mp(&self, p: usize, sin_theta_i: f64, sin_theta_o: f64) -> f64 {
        self.prepare().mp(p, sin_theta_i, sin_theta_o)
    }

    /// `A_p` for `p = 0..=3` (pbrt's `Ap`) at `sin θ_o` and offset `h`, with the single-pass
    /// transmittance `T = exp(-σ_a · 2 cos γ_t / cos θ_t)`:
    /// `A_0 = F`, `A_1 = (1-F)² T`, `A_2 = A_1 T F`, `A_3 = A_2 T F / (1 - T F)`, where `F` is
    /// the Fresnel reflectance at `cos θ_o cos γ_o`. For `σ_a = 0` they sum to 1.
    pub fn attenuation(&self, sin_theta_o: f64, h: f64) -> [DVec3; 4] {
        self.prepare().attenuation(sin_theta_o, h)
    }

    /// `f(wo, wi) cos θ_i = Σ_{p<3} M_p A_p N_p + M_3 A_3 / 2π` at offset `h` (local frame,
    /// unit `wo` toward the eye and `wi` toward the light; `h` clamped to [-1, 1]). This is
    /// what multiplies the irradiance from `wi` (see the module docs on the cosine).
    pub fn eval_projected(&self, wo: DVec3, wi: DVec3, h: f64) -> DVec3 {
        self.prepare().eval_projected(wo, wi, h)
    }

    /// The BSDF `f(wo, wi)` at offset `h`: [`Self::eval_projected`] divided by
    /// `cos θ_i = sqrt(1 - wi.x²)` (0 where `cos θ_i = 0`, a set of measure zero where `f`
    /// is unbounded). pbrt's `HairBSDF::f` up to the cosine (see the module docs).
    pub fn eval(&self, wo: DVec3, wi: DVec3, h: f64) -> DVec3 {
        self.prepare().eval(wo, wi, h)
    }

    /// pbrt's `ComputeApPdf`: the probability of choosing each lobe, `A_p`'s luminance
    /// ([`LUMINANCE`]) over their sum (all zero when the sum is not positive).
    pub fn lobe_pdf(&self, sin_theta_o: f64, h: f64) -> [f64; 4] {
        self.prepare().lobe_pdf(sin_theta_o, h)
    }

    /// Solid-angle density with which [`Self::sample`] picks `wi` (pbrt's `Pdf`):
    /// `Σ_{p<3} M_p pdf_p N_p + M_3 pdf_3 / 2π`.
    pub fn pdf(&self, wo: DVec3, wi: DVec3, h: f64) -> f64 {
        self.prepare().pdf(wo, wi, h)
    }

    /// pbrt's importance sampling: lobe `p` chosen by [`Self::lobe_pdf`] with `u[0]`, `θ_i` from
    /// `M_p` (a von Mises-Fisher lobe about the tilted mirror direction, `u[1]`, `u[2]`), `φ`
    /// from the trimmed logistic about `Φ(p, h)` (`u[3]`; uniform for `p = 3`). Returns
    /// `(wi, f(wo, wi), pdf(wo, wi))` in the local frame, or `None` where the pdf is 0 or not
    /// finite. `u` in [0, 1). The `M_p` inverse CDF is exact (pbrt clamps `u[1] >= 1e-5`),
    /// and the four numbers are independent (pbrt splits two into four by bit interleaving).
    pub fn sample(&self, wo: DVec3, h: f64, u: [f64; 4]) -> Option<(DVec3, DVec3, f64)> {
        self.prepare().sample(wo, h, u)
    }

    /// The far-field azimuthal term of lobe `p` (0..=3; larger counts as 3):
    /// `N̄_p(φ) = ½ ∫_{-1}^{1} A_p(h) D_p(φ - Φ(p, h)) dh` with `D_p` the wrapped trimmed
    /// logistic ([`azimuthal_scattering`]) for `p < 3` and `1/2π` for `p = 3`, at
    /// `sin θ_o` (`A_p` and `Φ` depend on `θ_o` through `cos θ_o` and `η'`, not on its sign).
    ///
    /// `N̄_p` is even in `φ` (the model is symmetric under `h -> -h`), so a GPU twin needs
    /// only `|φ_i - φ_o| ∈ [0, π]`. Integrated as `½ ∫ A_p D_p cos γ dγ` over
    /// `γ = asin h ∈ [-π/2, π/2]` (where `Φ` is smooth) by composite 8-point Gauss-Legendre
    /// with `max(256, ⌈2π/s⌉)` panels (at most [`FAR_FIELD_MAX_PANELS`]; panel width at most
    /// `s/2`, the lobe's narrowest
    /// scale in `γ`); doubling the panels changes the result by less than 1e-6 relative
    /// (tested; what is left comes from the kink the wrapped logistic has at `±π`).
    pub fn far_field_np(&self, p: usize, phi: f64, sin_theta_o: f64) -> DVec3 {
        self.prepare().far_field_np(p, phi, sin_theta_o)
    }

    /// [`Self::far_field_np`] with an explicit number of quadrature panels (clamped to
    /// `1..=FAR_FIELD_MAX_PANELS`).
    pub fn far_field_np_panels(
        &self,
        p: usize,
        phi: f64,
        sin_theta_o: f64,
        panels: usize,
    ) -> DVec3 {
        self.prepare()
            .far_field_np_panels(p, phi, sin_theta_o, panels)
    }

    /// The h-averaged BSDF times `cos θ_i` in angles: `Σ_p M_p(θ_i, θ_o) N̄_p(φ)`
    /// ([`Self::mp`], [`Self::far_field_np`]), `φ = φ_i - φ_o` (only `|φ|` matters).
    pub fn far_field(&self, sin_theta_i: f64, sin_theta_o: f64, phi: f64) -> DVec3 {
        self.prepare().far_field(sin_theta_i, sin_theta_o, phi)
    }

    /// Radiance toward `v` scattered by a fibre of tangent `t` (root to tip) lit by a light of
    /// unit irradiance from `l` (`l`, `v` unit directions away from the fibre):
    /// `½ ∫_{-1}^{1} f(h) |cos θ_i| dh` = [`Self::far_field`] with `sin θ_i = t·l`,
    /// `sin θ_o = t·v` and `φ` the angle between the projections of `l` and `v` on the normal
    /// plane (0 when either projection is shorter than 1e-9). Inputs are normalised in `f64`.
    pub fn far_field_radiance(&self, t: Vec3, l: Vec3, v: Vec3) -> DVec3 {
        let t = t.as_dvec3().normalize_or(DVec3::X);
        let l = l.as_dvec3().normalize_or(DVec3::Y);
        let v = v.as_dvec3().normalize_or(DVec3::Y);
        let si = t.dot(l).clamp(-1.0, 1.0);
        let so = t.dot(v).clamp(-1.0, 1.0);
        let lp = l - si * t;
        let vp = v - so * t;
        let phi = if lp.length() < 1e-9 || vp.length() < 1e-9 {
            0.0
        } else {
            lp.cross(vp).length().atan2(lp.dot(vp))
        };
        self.far_field(si, so, phi)
    }

    /// Directional albedo at `θ_o` (radians) and offset `h`:
    /// `∫_{S²} f(wo, wi; h) |cos θ_i| dω_i`, by jittered stratified sampling of `(θ_i, φ_i)`:
    /// `m x m` strata with `m = ⌈sqrt(samples)⌉`, uniform in `θ_i ∈ [-π/2, π/2]` with the
    /// Jacobian `cos θ_i` and in `φ_i`, one sample each, jitter from [`Pcg32`] seeded by `seed`.
    /// 1 for a white fibre (`σ_a = 0`) at every `h` if the model conserves energy (`Σ A_p = 1`,
    /// `M_p` and `N_p` normalised). With `h` fixed the lobes are narrow along the axes of the
    /// strata, which makes this converge much faster than [`Self::furnace`].
    pub fn furnace_at(&self, theta_o: f64, h: f64, samples: usize, seed: u64) -> DVec3 {
        let f = self.prepare();
        let m = ((samples.clamp(1, MAX_FURNACE_SAMPLES) as f64).sqrt().ceil() as usize).max(1);
        let wo = DVec3::new(theta_o.sin(), theta_o.cos(), 0.0);
        let mut rng = Pcg32::new(seed, 0x4655_524e);
        let mut sum = DVec3::ZERO;
        for b in 0..m {
            for c in 0..m {
                let th = -FRAC_PI_2 + PI * (b as f64 + rng.next_f64()) / m as f64;
                let ph = -PI + TAU * (c as f64 + rng.next_f64()) / m as f64;
                let (st, ct) = th.sin_cos();
                let wi = DVec3::new(st, ct * ph.cos(), ct * ph.sin());
                sum += f.eval_projected(wo, wi, h) * ct;
            }
        }
        sum * (PI * TAU / (m * m) as f64)
    }

    /// Directional albedo at `θ_o` (radians) averaged over the fibre's width:
    /// `½ ∫_{-1}^{1} ∫_{S²} f(wo, wi; h) |cos θ_i| dω_i dh`, by jittered stratified sampling of
    /// `(h, θ_i, φ_i)` (as [`Self::furnace_at`], plus uniform in `h`): `m x m` strata in
    /// `(θ_i, φ_i)` with `m = ⌊(8 samples)^⅓⌋` and `max(1, samples / m²)` in `h`, one sample
    /// each. Converges slowly for narrow lobes (β_n ≲ 0.2: the lobes are ridges across the
    /// strata in `(h, φ)`).
    pub fn furnace(&self, theta_o: f64, samples: usize, seed: u64) -> DVec3 {
        let f = self.prepare();
        let samples = samples.clamp(1, MAX_FURNACE_SAMPLES);
        let m = ((8.0 * samples as f64).cbrt().floor() as usize).max(1);
        let k = (samples / (m * m)).max(1);
        let wo = DVec3::new(theta_o.sin(), theta_o.cos(), 0.0);
        let mut rng = Pcg32::new(seed, 0x4655_524e);
        let mut sum = DVec3::ZERO;
        for a in 0..k {
            for b in 0..m {
                for c in 0..m {
                    let h = -1.0 + 2.0 * (a as f64 + rng.next_f64()) / k as f64;
                    let th = -FRAC_PI_2 + PI * (b as f64 + rng.next_f64()) / m as f64;
                    let ph = -PI + TAU * (c as f64 + rng.next_f64()) / m as f64;
                    let (st, ct) = th.sin_cos();
                    let wi = DVec3::new(st, ct * ph.cos(), ct * ph.sin());
                    sum += f.eval_projected(wo, wi, h) * ct;
                }
            }
        }
        // Mean over the strata times the measure of (θ, φ): π · 2π; the mean over h is ½∫dh.
        sum * (PI * TAU / (k * m * m) as f64)
    }
}
