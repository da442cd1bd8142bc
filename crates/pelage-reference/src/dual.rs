//! Dual scattering (Zinke, Yuksel, Weber and Keyser 2008, "Dual Scattering Approximation
//! for Fast Multiple Scattering in Hair") over the far-field [`ChiangFibre`], in `f64`: the
//! CPU twin of `chiang_dual_radiance` in `crates/pelage-shade/wgsl/shade/models/chiang.wgsl`,
//! written from the paper's equations, with the fibre's energies integrated in closed form
//! in `φ` (not from the GPU's tables), so the tables and the shader can be audited against it.
//!
//! # The model
//! For light arriving at `θ_d` (here `θ_i`), each lobe `X` (R, TT, TRT and pbrt's residual)
//! sends the energy `a_f^X` forward (`|φ| > π/2`) and `a_b^X` backward:
//! `a_f^X = ∫_{|φ|>π/2} N̄_X dφ`, `a_b^X = ∫_{|φ|<π/2} N̄_X dφ` (pbrt's `∫ f |cos θ| dω`: the
//! `M_p` integrate to 1, so these are the lobes' shares of the albedo; with `σ_a = 0` they add
//! up to 1 at every `θ`). `a_f = Σ a_f^X`, `a_b = Σ a_b^X`; the mean shift and variance of
//! each set (Zinke's `α_f`, `β_f²`, `α_b`, `β_b²`) weight the lobes' `θ_h` shifts
//! `(α, -α/2, -2α, 0)` and variances `v_X / 4` by those energies.
//!
//! Stage 2 hands the shading stage `V = exp(-τ)`, `τ` the optical depth of the hair in front
//! (the opacity times the expected number of fibres crossed, so an opaque fibre counts 1).
//! `V` is the light that crossed no fibre; the rest crossed
//! `n = τ / (1 - V)` fibres on average (the mean of a Poisson count given that it is at least
//! one; `n -> 1` as `τ -> 0`, `n -> τ` in deep shadow). Then, per colour channel,
//! - forward transmittance `T_f = d_f a_f^n` of the light that crossed fibres (Zinke eq. 7);
//! - its spread `σ_f² = n β_f²`;
//! - `f_s^scatter = Σ_X M_X(β_X² + σ_f²) a_f^X / π`: the fibre's own lobes widened by `σ_f²`
//!   (in pbrt's units the `M_p` variance grows by `4 σ_f²`), times Zinke's `N_X^G =
//!   (2/π) ∫_{π/2}^{π} N_X dφ`;
//! - local back scattering `f_back(σ²) = A_b M_b(Δ_b, σ²) / π` with `A_b`, `Δ_b` and `σ_b`
//!   from Zinke's eqs. 13 to 15 (no clamp: `a_f < 1` always, since Fresnel reflects some
//!   light backward);
//! - `F = V (f_s + d_b f_back(σ_b²)) + (1 - V) T_f (f_s^scatter + π d_b f_back(σ_b² + σ_f²))`,
//!   Zinke's `F^direct + F^scatter` with `T_f - directFraction` read as "the light that did
//!   cross fibres" (`(1 - V) a_f^n`; `≥ 0`, equal to Zinke's `T_f` in deep shadow).
//!
//! `d_f = d_b = 0.7` (Zinke's density factors). Longitudinal lobes are pbrt's `M_p` with the
//! shift and variance in its units (twice the `θ_h` shift, four times the `θ_h` variance).

use std::f64::consts::{FRAC_PI_2, PI};

use glam::{DVec3, Vec3};

use crate::chiang::{ChiangFibre, P_MAX, deflection, longitudinal_scattering};

/// Zinke's forward density factor `d_f`.
pub const DENSITY_FORWARD: f64 = 0.7;
/// Zinke's backward density factor `d_b`.
pub const DENSITY_BACK: f64 = 0.7;

/// Gauss-Legendre panels over `γ_o ∈ [-π/2, π/2]` for the energies.
const ENERGY_PANELS: usize = 512;

/// Each lobe's forward and backward energy for light at one `θ` (per colour channel).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LobeEnergies {
    /// `a_f^X` for X = R, TT, TRT, residual.
    pub forward: [DVec3; 4],
    /// `a_b^X` for X = R, TT, TRT, residual.
    pub backward: [DVec3; 4],
}

impl LobeEnergies {
    /// `a_f = Σ_X a_f^X`.
    pub fn a_f(&self) -> DVec3 {
        self.forward.iter().sum()
    }

    /// `a_b = Σ_X a_b^X`.
    pub fn a_b(&self) -> DVec3 {
        self.backward.iter().sum()
    }
}

/// Zinke's back-scattering terms of one colour channel (eqs. 13 to 15), `θ_h` units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BackScattering {
    /// `A_b`: the energy scattered back by the hair around the shading point.
    pub a_b: f64,
    /// `Δ_b`: its mean longitudinal shift (radians, `θ_h`).
    pub delta_b: f64,
    /// `σ_b`: its longitudinal standard deviation (radians, `θ_h`).
    pub sigma_b: f64,
}

/// The mean shift and variance of one channel's forward and backward energies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Moments {
    /// `a_f`.
    pub a_f: f64,
    /// `a_b`.
    pub a_b: f64,
    /// `α_f` (`θ_h` shift, radians).
    pub alpha_f: f64,
    /// `α_b`.
    pub alpha_b: f64,
    /// `β_f²` (`θ_h` variance).
    pub beta_f2: f64,
    /// `β_b²`.
    pub beta_b2: f64,
}

/// The integral of pbrt's logistic of scale `s` trimmed to [-π, π] and repeated with period
/// 2π, from `-π` to `x`.
fn periodic_logistic_cdf(x: f64, s: f64) -> f64 {
    let cdf = |y: f64| 1.0 / (1.0 + (-y / s).exp());
    let (lo, hi) = (cdf(-PI), cdf(PI));
    let periods = ((x + PI) / (2.0 * PI)).floor();
    let y = x - 2.0 * PI * periods;
    periods + (cdf(y) - lo) / (hi - lo)
}

/// `∫_a^b` of the periodic trimmed logistic.
fn logistic_mass(a: f64, b: f64, s: f64) -> f64 {
    periodic_logistic_cdf(b, s) - periodic_logistic_cdf(a, s)
}

/// pbrt's `M_p` for light at `(sin_i, cos_i)` toward `(sin_o, cos_o)` with `θ_o` turned by
/// `tilt` and variance `v`.
fn mp_tilted(sin_i: f64, cos_i: f64, sin_o: f64, cos_o: f64, tilt: f64, v: f64) -> f64 {
    let (s, c) = tilt.sin_cos();
    let so = sin_o * c + cos_o * s;
    let co = (cos_o * c - sin_o * s).abs();
    longitudinal_scattering(cos_i, co, sin_i, so, v)
}

impl ChiangFibre {
    /// The lobes' forward and backward energies at `|θ| = theta` (radians, the direction
    /// whose `A_p` the model uses), `φ` integrated in closed form (the logistic's CDF) and
    /// `h` by composite 8-point Gauss-Legendre over `γ_o` with 512 panels.
    pub fn lobe_energies(&self, theta: f64) -> LobeEnergies {
        let f = self.prepare();
        let s = self.azimuthal_scale();
        let (so, co) = theta.abs().min(FRAC_PI_2).sin_cos();
        let eta = self.eta;
        let etap = (eta * eta - so * so).max(0.0).sqrt() / co.max(1e-12);
        let mut forward = [DVec3::ZERO; 4];
        let mut backward = [DVec3::ZERO; 4];
        let width = PI / ENERGY_PANELS as f64;
        let half = 0.5 * width;
        let (xs, ws) = gl8();
        for k in 0..ENERGY_PANELS {
            let mid = -FRAC_PI_2 + (k as f64 + 0.5) * width;
            for (x, w) in xs.iter().zip(ws) {
                for gamma in [mid - half * x, mid + half * x] {
                    let h = gamma.sin();
                    let gamma_t = (h / etap).clamp(-1.0, 1.0).asin();
                    let ap = f.attenuation(so, h);
                    // ½ dh = ½ cos γ dγ.
                    let weight = 0.5 * gamma.cos() * w * half;
                    for p in 0..P_MAX {
                        let phi = deflection(p, gamma, gamma_t);
                        // Mass of the lobe centred at Φ over |φ| < π/2 and over the rest.
                        let back = logistic_mass(-FRAC_PI_2 - phi, FRAC_PI_2 - phi, s);
                        backward[p] += ap[p] * (weight * back);
                        forward[p] += ap[p] * (weight * (1.0 - back));
                    }
                    // The residual lobe is uniform in φ: half forward, half backward.
                    backward[P_MAX] += ap[P_MAX] * (0.5 * weight);
                    forward[P_MAX] += ap[P_MAX] * (0.5 * weight);
                }
            }
        }
        LobeEnergies { forward, backward }
    }

    /// The lobes' `θ_h` shifts `(α, -α/2, -2α, 0)` (pbrt's tilts `[-2α, α, 4α, 0]` halved
    /// with their sign turned) and variances `v_X / 4`.
    pub fn lobe_shifts_and_variances(&self) -> ([f64; 4], [f64; 4]) {
        let t = self.lobe_tilts();
        let v = self.longitudinal_variances();
        (t.map(|t| -0.5 * t), v.map(|v| 0.25 * v))
    }

    /// Channel `c`'s moments of `e` (see [`Moments`]).
    pub fn dual_moments(&self, e: &LobeEnergies, c: usize) -> Moments {
        let (shift, var) = self.lobe_shifts_and_variances();
        let ch = |v: DVec3| v.to_array()[c];
        let a_f: f64 = e.forward.iter().map(|v| ch(*v)).sum();
        let a_b: f64 = e.backward.iter().map(|v| ch(*v)).sum();
        let mean = |set: &[DVec3; 4], w: &[f64; 4], total: f64| {
            set.iter().zip(w).map(|(v, w)| ch(*v) * w).sum::<f64>() / total
        };
        Moments {
            a_f,
            a_b,
            alpha_f: mean(&e.forward, &shift, a_f),
            alpha_b: mean(&e.backward, &shift, a_b),
            beta_f2: mean(&e.forward, &var, a_f),
            beta_b2: mean(&e.backward, &var, a_b),
        }
    }

    /// Dual-scattering radiance toward `v` for a light of unit irradiance from `l` that
    /// stage 2 sees reaching the fibre (tangent `t`) with `visibility` (see the module docs).
    pub fn dual_radiance(&self, t: Vec3, l: Vec3, v: Vec3, visibility: f64) -> DVec3 {
        let td = t.as_dvec3().normalize_or(DVec3::X);
        let ld = l.as_dvec3().normalize_or(DVec3::Y);
        let vd = v.as_dvec3().normalize_or(DVec3::Y);
        let si = td.dot(ld).clamp(-1.0, 1.0);
        let so = td.dot(vd).clamp(-1.0, 1.0);
        let ci = (1.0 - si * si).max(0.0).sqrt();
        let co = (1.0 - so * so).max(0.0).sqrt();
        let f_s = self.far_field_radiance(t, l, v);
        let e = self.lobe_energies(si.abs().asin());
        let vis = visibility.clamp(0.0, 1.0);
        let n = crossings(vis);
        let tilts = self.lobe_tilts();
        let v_lobe = self.longitudinal_variances();
        let mut out = [0.0f64; 3];
        for (c, o) in out.iter_mut().enumerate() {
            let m = self.dual_moments(&e, c);
            let b = back_scattering(&m);
            let back =
                |var_h: f64| b.a_b * mp_tilted(si, ci, so, co, -2.0 * b.delta_b, 4.0 * var_h) / PI;
            let direct = vis * (f_s.to_array()[c] + DENSITY_BACK * back(b.sigma_b * b.sigma_b));
            let sigma_f2 = n * m.beta_f2;
            let t_f = DENSITY_FORWARD * m.a_f.powf(n);
            let fs_scatter: f64 = (0..=P_MAX)
                .map(|x| {
                    let af_x = e.forward[x].to_array()[c];
                    mp_tilted(si, ci, so, co, tilts[x], v_lobe[x] + 4.0 * sigma_f2) * af_x / PI
                })
                .sum();
            let scatter = (1.0 - vis)
                * t_f
                * (fs_scatter + PI * DENSITY_BACK * back(b.sigma_b * b.sigma_b + sigma_f2));
            *o = direct + scatter;
        }
        DVec3::from_array(out)
    }
}

/// The mean number of fibres crossed by the light that crossed any, `n = τ / (1 - V)` with
/// `V = exp(-τ)` (1 in the limit `V -> 1`).
pub fn crossings(visibility: f64) -> f64 {
    let vis = visibility.clamp(0.0, 1.0);
    let tau = -vis.max(1e-30).ln();
    // tau / (1 - exp(-tau)) = 1 + tau / 2 + O(tau²) near 0 (the shader's branch).
    if tau < 1e-4 {
        1.0 + 0.5 * tau
    } else {
        tau / (1.0 - vis)
    }
}

/// Zinke's eqs. 13 to 15 for one channel's moments.
pub fn back_scattering(m: &Moments) -> BackScattering {
    let af2 = m.a_f * m.a_f;
    let inv = 1.0 - af2;
    let ab = m.a_b;
    let ab2 = ab * ab;
    let ab3 = ab2 * ab;
    let a_b = ab * af2 / inv + ab3 * af2 / (inv * inv * inv);
    let delta_b = m.alpha_b * (1.0 - 2.0 * ab2 / (inv * inv))
        + m.alpha_f * (2.0 * inv * inv + 4.0 * af2 * ab2) / (inv * inv * inv);
    let beta_f = m.beta_f2.sqrt();
    let beta_b = m.beta_b2.sqrt();
    let sigma_b = (1.0 + DENSITY_BACK * af2)
        * (ab * (2.0 * m.beta_f2 + m.beta_b2).sqrt()
            + ab3 * (2.0 * m.beta_f2 + 3.0 * m.beta_b2).sqrt())
        / (ab + ab3 * (2.0 * beta_f + 3.0 * beta_b));
    BackScattering {
        a_b,
        delta_b,
        sigma_b,
    }
}

/// Eight-point Gauss-Legendre on [-1, 1], positive half.
fn gl8() -> ([f64; 4], [f64; 4]) {
    (
        [
            0.183_434_642_495_649_8,
            0.525_532_409_916_329,
            0.796_666_477_413_626_7,
            0.960_289_856_497_536_3,
        ],
        [
            0.362_683_783_378_362,
            0.313_706_645_877_887_3,
            0.222_381_034_453_374_5,
            0.101_228_536_290_376_3,
        ],
    )
}
