//! CPU references of the hair shading models (twins of `wgsl/shade/models/*.wgsl`).
//!
//! Slow and obviously right: everything runs in `f64`, the cubic of Marschner's
//! azimuthal term is solved by bisection on its monotone pieces (not by the closed form
//! the GPU uses), and every function names its formula and source.
//!
//! # Conventions (Marschner et al. 2003; digest 002/003 §B.1.3)
//! `t` is the unit tangent (root to tip), `l` the unit direction to the light and `v` the
//! unit direction to the eye, both pointing away from the fibre.
//! - Longitudinal angles are measured from the normal plane: `sin θ_i = t·l`,
//!   `cos θ_i = |t × l|` (likewise for `θ_r` with `v`), `θ_h = (θ_i + θ_r)/2`,
//!   `θ_d = (θ_r - θ_i)/2`. The inputs are normalised again in `f64` first.
//! - Azimuths are measured in the normal plane from the fibre's major axis `a₁`: the frame is
//!   Dušek's (digest §A.1.5, eq. 3.4) `e₁ = normalize(t × ẑ)` (`t × x̂` when `t` is within
//!   about 0.06° of ±z), `e₂ = t × e₁`, turned about `t` by the strand's azimuth α:
//!   `a₁ = cos α e₁ + sin α e₂`, `a₂ = t × a₁`. `φ = φ_r - φ_i` is the relative azimuth; only
//!   `|φ| ∈ [0, π]` matters for a cross-section with mirror symmetry, and the eccentric
//!   TRT term needs `cos 2φ_h = cos(φ_i + φ_r)`. When `l` or `v` lies along `t` (projection
//!   shorter than 1e-5) the azimuth is undefined and taken as `φ = 0`, `cos 2φ_h = 1`.
//! - `cos θ_d` is clamped to at least [`MIN_COS_THETA_D`]: `1/cos²θ_d` is singular where
//!   `l = -t` and `v = t` (or the reverse).
//!
//! # What the functions return
//! [`marschner`], [`sadeghi`] and [`kajiya_kay`] return the **radiance scattered toward `v`
//! by a light of unit irradiance from `l`**: the scattering function times `cos θ_i`
//! (Marschner's `L̄_r = D ∫ S L_i cos θ_i dω_i` with `D = 1`). For Kajiya-Kay `cos θ_i` is
//! its diffuse `sin(t, l)`. [`marschner_bsdf`] is `S` alone (for reciprocity and energy).
//! The `*_radiance` functions have the exact shape and result of the WGSL functions.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use glam::{DVec3, Vec3};
use pelage_scene::{KajiyaKayParams, MarschnerParams, SadeghiParams};

/// Smallest `cos θ_d` used anywhere: keeps `1/cos²θ_d` and the Bravais index `η'` finite.
pub const MIN_COS_THETA_D: f64 = 1.0e-4;

/// Below this length a projection onto the normal plane counts as zero (azimuth undefined).
pub const MIN_PROJECTION: f64 = 1.0e-5;

/// Smallest `|2 dφ/dh|` used in the ray density (it is zero exactly at a caustic).
pub const MIN_DPHI_DH: f64 = 1.0e-6;

/// The angles of one (tangent, light, eye) configuration, in radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FibreAngles {
    /// `sin θ_i = t·l` (clamped to [-1, 1]).
    pub sin_theta_i: f64,
    /// `sin θ_r = t·v`.
    pub sin_theta_r: f64,
    /// `cos θ_i = |t × l|`.
    pub cos_theta_i: f64,
    /// `θ_h = (θ_i + θ_r)/2`.
    pub theta_h: f64,
    /// `θ_d = (θ_r - θ_i)/2`.
    pub theta_d: f64,
    /// `|φ_r - φ_i|`, in [0, π].
    pub phi: f64,
    /// `cos(φ_i + φ_r) = cos 2φ_h`, in the strand's rotated frame.
    pub cos_2phi_h: f64,
}

/// The fibre frame `(a₁, a₂)` of the module docs: Dušek's eq. 3.4 turned by `azimuth` about `t`.
pub fn fibre_frame(t: DVec3, azimuth: f64) -> (DVec3, DVec3) {
    let mut e1 = t.cross(DVec3::Z);
    if e1.length() < 1.0e-3 {
        e1 = t.cross(DVec3::X);
    }
    let e1 = e1.normalize_or(DVec3::X);
    let e2 = t.cross(e1);
    let (s, c) = azimuth.sin_cos();
    let a1 = c * e1 + s * e2;
    let a2 = -s * e1 + c * e2;
    (a1, a2)
}

/// Angles of the module docs for unit `t`, `l`, `v` and the strand's frame azimuth.
///
/// The inputs are normalised again in `f64` first, so that `f32` vectors that are unit only
/// to rounding give the angles of the directions they stand for (`l = t` gives
/// `cos θ_i = 0` exactly). The GPU twin gets the same effect from `cos θ = |t × l|`.
pub fn fibre_angles(t: Vec3, l: Vec3, v: Vec3, strand_azimuth: f64) -> FibreAngles {
    let unit = |x: Vec3, fallback: DVec3| x.as_dvec3().normalize_or(fallback);
    let (t, l, v) = (unit(t, DVec3::Y), unit(l, DVec3::Z), unit(v, DVec3::Z));
    // sin θ = t·l and cos θ = |t × l|: no cancellation at grazing angles, and exactly 0
    // for l = ±t.
    let sin_theta_i = t.dot(l).clamp(-1.0, 1.0);
    let sin_theta_r = t.dot(v).clamp(-1.0, 1.0);
    let cos_theta_i = t.cross(l).length().min(1.0);
    let cos_theta_r = t.cross(v).length().min(1.0);
    let theta_i = sin_theta_i.atan2(cos_theta_i);
    let theta_r = sin_theta_r.atan2(cos_theta_r);
    let (a1, a2) = fibre_frame(t, strand_azimuth);
    // Light and eye in the normal plane, in (a₁, a₂) coordinates: (cos φ, sin φ) · cos θ.
    let (l1, l2) = (l.dot(a1), l.dot(a2));
    let (r1, r2) = (v.dot(a1), v.dot(a2));
    let nl = l1.hypot(l2);
    let nr = r1.hypot(r2);
    let (phi, cos_2phi_h) = if nl < MIN_PROJECTION || nr < MIN_PROJECTION {
        (0.0, 1.0)
    } else {
        // φ = φ_r - φ_i from the 2-D cross and dot products (atan2 keeps full precision
        // near 0 and π, where acos would not).
        let cross = l1 * r2 - l2 * r1;
        let dot = l1 * r1 + l2 * r2;
        let phi = cross.abs().atan2(dot);
        // cos(φ_i + φ_r) = cos φ_i cos φ_r - sin φ_i sin φ_r.
        let cos_sum = ((l1 * r1 - l2 * r2) / (nl * nr)).clamp(-1.0, 1.0);
        (phi, cos_sum)
    };
    FibreAngles {
        sin_theta_i,
        sin_theta_r,
        cos_theta_i,
        theta_h: 0.5 * (theta_i + theta_r),
        theta_d: 0.5 * (theta_r - theta_i),
        phi,
        cos_2phi_h,
    }
}

// ---------------------------------------------------------------------------------------
// Kajiya-Kay
// ---------------------------------------------------------------------------------------

/// The Kajiya-Kay specular cone term `max(0, -(t·l)(t·v) + sin(t,l) sin(t,v))`, the cosine
/// between `v` and the nearest direction of the cone of mirror directions around `t`
/// (Kajiya & Kay 1989 with `l`, `v` pointing away; digest 000/001 §000.1.4 reviewer note,
/// digest 002/003 §A.1.4 reviewer note; `ribbons.wgsl`'s `kajiya_kay`). Equals
/// `max(0, cos(θ_i + θ_r))`.
pub fn kajiya_kay_cone(t: DVec3, l: DVec3, v: DVec3) -> f64 {
    let tl = t.dot(l).clamp(-1.0, 1.0);
    let tv = t.dot(v).clamp(-1.0, 1.0);
    let sin_l = (1.0 - tl * tl).max(0.0).sqrt();
    let sin_v = (1.0 - tv * tv).max(0.0).sqrt();
    (-tl * tv + sin_l * sin_v).max(0.0)
}

/// `cone^exponent`, 0 where the cone term is 0 (avoids `0^x` corner cases).
fn cone_power(cone: f64, exponent: f64) -> f64 {
    if cone > 0.0 { cone.powf(exponent) } else { 0.0 }
}

/// Scheuermann's (2004) shifted tangent `normalize(t + shift · n)`, with `n` the normal of
/// the camera-facing ribbon, `normalize(v - (t·v) t)` (digest 002/003 §B.1.4). When `v` lies
/// along `t` the ribbon has no normal and `t` is returned; so it is for `shift = 0`.
pub fn shifted_tangent(t: DVec3, v: DVec3, shift: f64) -> DVec3 {
    if shift == 0.0 {
        return t;
    }
    let n = v - t.dot(v) * t;
    let len = n.length();
    if len < MIN_PROJECTION {
        return t;
    }
    (t + (shift / len) * n).normalize_or(t)
}

/// Kajiya-Kay with Scheuermann's shifted highlights (see [`KajiyaKayParams`]):
/// ```text
/// diffuse · base · sin(t, l)                                  (Kajiya & Kay eq. for Ψ_d)
/// + specular · specular_color · cone(t₁, l, v)^shininess      (the cone specular)
/// + secondary_specular · secondary_color · base · cone(t₂, l, v)^secondary_shininess
/// ```
/// `t₁`, `t₂` are [`shifted_tangent`]s. The ambient term of `ribbons.wgsl` belongs to the
/// frame, not the model, and is not included. Defined for every unit `t`, `l`, `v`.
pub fn kajiya_kay(p: &KajiyaKayParams, t: Vec3, l: Vec3, v: Vec3, base_color: Vec3) -> Vec3 {
    let (t, l, v) = (t.as_dvec3(), l.as_dvec3(), v.as_dvec3());
    let base = base_color.as_dvec3();
    let tl = t.dot(l).clamp(-1.0, 1.0);
    let sin_l = (1.0 - tl * tl).max(0.0).sqrt();
    let t1 = shifted_tangent(t, v, f64::from(p.shift_primary));
    let t2 = shifted_tangent(t, v, f64::from(p.shift_secondary));
    let primary = cone_power(kajiya_kay_cone(t1, l, v), f64::from(p.shininess));
    let secondary = cone_power(kajiya_kay_cone(t2, l, v), f64::from(p.secondary_shininess));
    let out = base * (f64::from(p.diffuse) * sin_l)
        + p.specular_color.as_dvec3() * (f64::from(p.specular) * primary)
        + p.secondary_color.as_dvec3() * base * (f64::from(p.secondary_specular) * secondary);
    out.as_vec3()
}

// ---------------------------------------------------------------------------------------
// Marschner
// ---------------------------------------------------------------------------------------

/// Unit-area Gaussian `g(β; x) = exp(-x²/(2β²)) / (β sqrt(2π))` (Marschner eq. for g;
/// digest 002/003 §B.1.5 eq. 39).
pub fn gaussian(beta: f64, x: f64) -> f64 {
    (-0.5 * (x / beta) * (x / beta)).exp() / (beta * TAU.sqrt())
}

/// The longitudinal terms `[M_R, M_TT, M_TRT]` at `θ_h`:
/// `M_p = ½ g(β_p; θ_h - α_p)` with Marschner's Table 1 shifts and widths.
///
/// The ½ is a deliberate deviation from the printed `M_p = g(β_p; θ_h - α_p)`: for a fixed
/// `θ_i`, `dθ_h = dθ_r / 2`, so a Gaussian of unit area in `θ_h` has area 2 over the outgoing
/// `θ_r`, and the model would reflect twice the light that reaches it. Marschner's own smooth
/// cylinder, `S = δ(θ_r + θ_i) N / cos²θ_d` (§4.1), equals `δ(θ_h)/2 · N / cos²θ_d`; the ½ makes
/// the rough lobes converge to it as `β → 0`, and the white furnace test checks it.
pub fn marschner_m(p: &MarschnerParams, theta_h: f64) -> [f64; 3] {
    let alpha = p.lobe_shifts_deg().map(|a| f64::from(a).to_radians());
    let beta = p.lobe_widths_deg().map(|b| f64::from(b).to_radians());
    [0, 1, 2].map(|k| 0.5 * gaussian(beta[k], theta_h - alpha[k]))
}

/// Marschner's index of the eccentric fibre for TRT (Marschner §5.2.3; digest §B.1.5 eqs.
/// 58–59, with the `-η + 2` of η*₂ restored):
/// `η*₁ = 2(η-1)a² - η + 2`, `η*₂ = 2(η-1)a⁻² - η + 2`,
/// `η* = ½((η*₁ + η*₂) + cos(2φ_h)(η*₁ - η*₂))`. Equals `η` when `a = 1`.
pub fn eta_star(eta: f64, eccentricity: f64, cos_2phi_h: f64) -> f64 {
    let a2 = eccentricity * eccentricity;
    let e1 = 2.0 * (eta - 1.0) * a2 - eta + 2.0;
    let e2 = 2.0 * (eta - 1.0) / a2 - eta + 2.0;
    0.5 * ((e1 + e2) + cos_2phi_h * (e1 - e2))
}

/// Fresnel reflectance of unpolarised light with Bravais' indices (Marschner §4.2, eq. 53 of
/// the digest: `η'` for the perpendicular (s) component, `η''` for the parallel (p) one):
/// ```text
/// r_s = (cos γ_i - η' cos γ_t) / (cos γ_i + η' cos γ_t)
/// r_p = (η'' cos γ_i - cos γ_t) / (η'' cos γ_i + cos γ_t)
/// F = (r_s² + r_p²) / 2
/// ```
/// `γ_t` is the refracted angle `asin(sin γ_i / η')`. The same expression gives the internal
/// reflectance `F(η', 1, γ_t)` at the exit (swap the roles and the indices become `1/η'`,
/// `1/η''`: the ratios are identical), so `F_exit = F_entry` for one path.
pub fn fresnel_bravais(eta1: f64, eta2: f64, cos_gamma_i: f64, cos_gamma_t: f64) -> f64 {
    let rs = (cos_gamma_i - eta1 * cos_gamma_t) / (cos_gamma_i + eta1 * cos_gamma_t);
    let rp = (eta2 * cos_gamma_i - cos_gamma_t) / (eta2 * cos_gamma_i + cos_gamma_t);
    let f = 0.5 * (rs * rs + rp * rp);
    if f.is_finite() {
        f.clamp(0.0, 1.0)
    } else {
        1.0
    }
}

/// The quantities of one lobe's azimuthal term that depend on `θ_d` (Marschner §4.2).
#[derive(Clone, Copy, Debug)]
struct Bravais {
    /// `η' = sqrt(η² - sin²θ_d) / cos θ_d`.
    eta1: f64,
    /// `η'' = η² / η'`.
    eta2: f64,
    /// `cos θ_t = sqrt(1 - sin²θ_d / η²)`: the inclination of the path inside the fibre.
    cos_theta_t: f64,
    /// `c = asin(1/η')`.
    c: f64,
}

impl Bravais {
    fn new(eta: f64, sin_theta_d: f64) -> Self {
        let s2 = (sin_theta_d * sin_theta_d).min(1.0);
        let cos_theta_d = (1.0 - s2).max(0.0).sqrt().max(MIN_COS_THETA_D);
        let eta1 = (eta * eta - s2).max(0.0).sqrt() / cos_theta_d;
        Bravais {
            eta1,
            eta2: eta * eta / eta1,
            cos_theta_t: (1.0 - s2 / (eta * eta)).max(0.0).sqrt(),
            c: (1.0 / eta1).min(1.0).asin(),
        }
    }
}

/// Coefficients `(a, b)` of Marschner's cubic exit azimuth (eq. 46 of the digest), written
/// around `pπ`: `φ̂(p, γ) - pπ = ψ(γ) = a γ - b γ³`, `a = 6pc/π - 2`, `b = 8pc/π³`.
fn cubic(p: u32, c: f64) -> (f64, f64) {
    let pc = f64::from(p) * c;
    (6.0 * pc / PI - 2.0, 8.0 * pc / (PI * PI * PI))
}

/// `ψ - target` wrapped into `(-π, π]`.
fn wrap_pi(x: f64) -> f64 {
    let y = (x + PI).rem_euclid(TAU) - PI;
    if y <= -PI { y + TAU } else { y }
}

/// All `γ ∈ [-π/2, π/2]` with `a γ - b γ³ = target`, by bisection on the pieces between the
/// critical points `±sqrt(a / 3b)` (where the function is monotone).
fn cubic_roots(a: f64, b: f64, target: f64) -> Vec<f64> {
    let f = |g: f64| a * g - b * g * g * g - target;
    let mut cuts = vec![-FRAC_PI_2];
    if b > 0.0 && a > 0.0 {
        let gc = (a / (3.0 * b)).sqrt();
        if gc < FRAC_PI_2 {
            cuts.push(-gc);
            cuts.push(gc);
        }
    }
    cuts.push(FRAC_PI_2);
    let mut roots = Vec::new();
    for (k, w) in cuts.windows(2).enumerate() {
        let (mut lo, mut hi) = (w[0], w[1]);
        let (mut flo, fhi) = (f(lo), f(hi));
        if k == 0 && flo == 0.0 {
            roots.push(lo);
        }
        if fhi == 0.0 {
            roots.push(hi);
            continue;
        }
        if flo * fhi > 0.0 || flo == 0.0 {
            continue;
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            let fm = f(mid);
            if (fm < 0.0) == (flo < 0.0) {
                lo = mid;
                flo = fm;
            } else {
                hi = mid;
            }
        }
        roots.push(0.5 * (lo + hi));
    }
    roots
}

/// Attenuation `A(p, h)` of one path entering at `γ_i` (Marschner eq. for A; digest §B.1.5
/// eq. 54), per colour channel:
/// ```text
/// A(0,h) = F(γ_i)
/// A(1,h) = (1 - F)² T
/// A(2,h) = (1 - F)² F T²,    T = exp(-2 σ'_a cos γ_t),   σ'_a = σ_a / cos θ_t
/// ```
/// with `γ_t = asin(h/η')`, `F` from [`fresnel_bravais`] (entry and exit reflectances are
/// equal, see there) and the longitudinal path correction `1/cos θ_t` of Marschner §4.2.
fn attenuation(p: u32, br: &Bravais, sigma_a: DVec3, gamma_i: f64) -> DVec3 {
    let h = gamma_i.sin();
    let sin_gt = (h / br.eta1).clamp(-1.0, 1.0);
    let cos_gt = (1.0 - sin_gt * sin_gt).max(0.0).sqrt();
    let f = fresnel_bravais(br.eta1, br.eta2, gamma_i.cos().max(0.0), cos_gt);
    let segment = if br.cos_theta_t > 0.0 {
        2.0 * cos_gt / br.cos_theta_t
    } else {
        f64::INFINITY
    };
    let t = DVec3::new(
        (-sigma_a.x * segment).exp(),
        (-sigma_a.y * segment).exp(),
        (-sigma_a.z * segment).exp(),
    );
    match p {
        0 => DVec3::splat(f),
        1 => (1.0 - f) * (1.0 - f) * t,
        _ => (1.0 - f) * (1.0 - f) * f * t * t,
    }
}

/// Marschner's azimuthal term without caustic handling (digest §B.1.5 eq. 55):
/// `N_p(φ) = Σ_roots A(p, h) |2 dφ/dh|⁻¹`, the roots `γ_i` of `φ̂(p, γ_i) = φ (mod 2π)` from the
/// cubic approximation (eq. 46), `dφ/dh = (a - 3bγ²)/cos γ` (eq. 50), so each root adds
/// `A cos γ / |2(a - 3bγ²)|` (with `|2(a - 3bγ²)|` at least [`MIN_DPHI_DH`]).
fn n_raw(p: u32, br: &Bravais, sigma_a: DVec3, phi: f64) -> DVec3 {
    let (a, b) = cubic(p, br.c);
    let target = wrap_pi(phi - f64::from(p) * PI);
    let roots = if p == 0 {
        // ψ = -2γ: one root.
        let g = -0.5 * target;
        if g.abs() <= FRAC_PI_2 {
            vec![g]
        } else {
            Vec::new()
        }
    } else {
        cubic_roots(a, b, target)
    };
    let mut sum = DVec3::ZERO;
    for g in roots {
        let dpsi = (2.0 * (a - 3.0 * b * g * g)).abs().max(MIN_DPHI_DH);
        sum += attenuation(p, br, sigma_a, g) * (g.cos().max(0.0) / dpsi);
    }
    sum
}

/// `x - y` wrapped into `(-π, π]`.
fn angle_between(x: f64, y: f64) -> f64 {
    wrap_pi(x - y)
}

/// Cubic Hermite `smoothstep(e0, e1, x)`.
fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// `N_TRT` with the caustics replaced by glints, Algorithm 1 of seed 003 (digest §B.1.5,
/// after Marschner §5.2.2):
/// ```text
/// if η' < 2:  γ_c = sqrt(a / 3b) (eq. 57), h_c = sin γ_c,
///             Δh = min(Δh_M, 2 sqrt(2 w_c / |d²φ/dh²(h_c)|)),  t = 1,  φ_c = ψ(γ_c)
/// else:       h_c = 0, Δh = Δh_M,  t = 1 - smoothstep(2, 2 + Δη', η'),  φ_c = 0
/// L = N_TRT(φ) (1 - t G(φ - φ_c)/G(0)) (1 - t G(φ + φ_c)/G(0))
///     + t k_G A(2, h_c) Δh (G(φ - φ_c) + G(φ + φ_c))
/// ```
/// `G(x) = g(w_c; x)` with `x` wrapped into (-π, π]; `d²φ/dh² = ψ''(γ)/cos²γ = -6bγ/cos²γ` at
/// the fold (where `ψ' = 0`). The `h_c` of eq. 56, `sqrt((4 - η'²)/3)`, belongs to the exact
/// `φ(h)`; this uses the fold of the cubic that the roots come from, which has the same
/// validity limit `η' < 2` (`a > 0 ⟺ c > π/6 ⟺ η' < 2`).
fn n_trt(p: &MarschnerParams, br: &Bravais, sigma_a: DVec3, phi: f64) -> DVec3 {
    let raw = n_raw(2, br, sigma_a, phi);
    let w_c = f64::from(p.caustic_width_deg).to_radians();
    let (a, b) = cubic(2, br.c);
    let (gamma_c, delta_h, t, phi_c) = if br.eta1 < 2.0 && a > 0.0 {
        let gamma_c = (a / (3.0 * b)).sqrt().min(FRAC_PI_2);
        let cos_c = gamma_c.cos().max(1.0e-6);
        let d2 = (6.0 * b * gamma_c / (cos_c * cos_c)).max(1.0e-12);
        let delta_h = f64::from(p.caustic_limit).min(2.0 * (2.0 * w_c / d2).sqrt());
        let phi_c = gamma_c * (a - b * gamma_c * gamma_c);
        (gamma_c, delta_h, 1.0, phi_c)
    } else {
        let fade = 1.0 - smoothstep(2.0, 2.0 + f64::from(p.caustic_fade), br.eta1);
        (0.0, f64::from(p.caustic_limit), fade, 0.0)
    };
    let g0 = gaussian(w_c, 0.0);
    let g_minus = gaussian(w_c, angle_between(phi, phi_c));
    let g_plus = gaussian(w_c, angle_between(phi, -phi_c));
    let damped = raw * ((1.0 - t * g_minus / g0) * (1.0 - t * g_plus / g0));
    let glint = attenuation(2, br, sigma_a, gamma_c)
        * (t * f64::from(p.glint_scale) * delta_h * (g_minus + g_plus));
    damped + glint
}

/// The azimuthal terms `[N_R, N_TT, N_TRT]` (per channel) at `θ_d` and `|φ|`, with
/// `cos 2φ_h` for the eccentric TRT index ([`eta_star`]).
pub fn marschner_n(p: &MarschnerParams, sin_theta_d: f64, phi: f64, cos_2phi_h: f64) -> [DVec3; 3] {
    let eta = f64::from(p.eta);
    let sigma_a = p.sigma_a.as_dvec3();
    let br = Bravais::new(eta, sin_theta_d);
    let eta_trt = eta_star(eta, f64::from(p.eccentricity), cos_2phi_h);
    let br_trt = Bravais::new(eta_trt, sin_theta_d);
    [
        n_raw(0, &br, sigma_a, phi),
        n_raw(1, &br, sigma_a, phi),
        n_trt(p, &br_trt, sigma_a, phi),
    ]
}

/// The three lobes `M_p N_p / cos²θ_d` of Marschner's scattering function at `angles`.
pub fn marschner_lobes(p: &MarschnerParams, angles: &FibreAngles) -> [DVec3; 3] {
    let m = marschner_m(p, angles.theta_h);
    let sin_theta_d = angles.theta_d.sin();
    let cos_theta_d = angles.theta_d.cos().max(MIN_COS_THETA_D);
    let n = marschner_n(p, sin_theta_d, angles.phi, angles.cos_2phi_h);
    let inv = 1.0 / (cos_theta_d * cos_theta_d);
    [0, 1, 2].map(|k| n[k] * (m[k] * inv))
}

/// Marschner's scattering function (Marschner et al. 2003 eq. for S; digest §B.1.5 eq. 37)
/// ```text
/// S = Σ_{p ∈ R, TT, TRT} M_p(θ_h) N_p(η'(θ_d), φ) / cos²θ_d
/// ```
/// without the `cos θ_i` factor; `strand_azimuth` turns the cross-section (radians).
/// Exactly reciprocal: swapping `l` and `v` keeps `θ_h`, `|φ|`, `cos 2φ_h` and negates `θ_d`,
/// which enters only through `sin²θ_d` and `cos θ_d`.
pub fn marschner_bsdf(
    p: &MarschnerParams,
    t: Vec3,
    l: Vec3,
    v: Vec3,
    strand_azimuth: f64,
) -> DVec3 {
    let angles = fibre_angles(t, l, v, strand_azimuth);
    let [r, tt, trt] = marschner_lobes(p, &angles);
    r + tt + trt
}

/// Marschner radiance for a light of unit irradiance: [`marschner_bsdf`] `· cos θ_i`.
pub fn marschner(p: &MarschnerParams, t: Vec3, l: Vec3, v: Vec3, strand_azimuth: f32) -> Vec3 {
    let angles = fibre_angles(t, l, v, f64::from(strand_azimuth));
    let [r, tt, trt] = marschner_lobes(p, &angles);
    ((r + tt + trt) * angles.cos_theta_i).as_vec3()
}

/// The twin of WGSL `marschner_radiance`: [`marschner`] with the strand azimuth
/// `azimuth_jitter · strand_random`, plus the diffuse term `diffuse · base · cos θ_i`.
pub fn marschner_radiance(
    p: &MarschnerParams,
    t: Vec3,
    l: Vec3,
    v: Vec3,
    base_color: Vec3,
    strand_random: f32,
) -> Vec3 {
    let azimuth = f64::from(p.azimuth_jitter) * f64::from(strand_random);
    let angles = fibre_angles(t, l, v, azimuth);
    let [r, tt, trt] = marschner_lobes(p, &angles);
    let diffuse = base_color.as_dvec3() * f64::from(p.diffuse);
    ((r + tt + trt + diffuse) * angles.cos_theta_i).as_vec3()
}

/// Unit vector at longitudinal angle `theta` and azimuth `phi` in the frame `(t, a₁, a₂)`.
fn direction(t: DVec3, a1: DVec3, a2: DVec3, theta: f64, phi: f64) -> DVec3 {
    theta.sin() * t + theta.cos() * (phi.cos() * a1 + phi.sin() * a2)
}

/// Directional albedo of Marschner's model for light at `theta_i` (radians) from the
/// azimuth `phi_i` of the strand frame turned by `strand_azimuth`:
/// ```text
/// ρ(θ_i) = ∫_{4π} S(ω_i, ω_r) cos θ_r dω_r = ∫_{-π/2}^{π/2} ∫_{-π}^{π} S cos²θ_r dφ_r dθ_r
/// ```
/// (the outgoing power per unit length over the intercepted incident power: a fibre
/// presents the width `D cos θ` to both directions; `dω = cos θ dθ dφ`). Midpoint rule over
/// `n_theta × n_phi` strata of `θ_r` and `φ_r`. Energy conservation means `ρ ≤ 1` for
/// `σ_a = 0`. Returned per lobe `[R, TT, TRT]`.
pub fn marschner_albedo_lobes(
    p: &MarschnerParams,
    theta_i: f64,
    phi_i: f64,
    strand_azimuth: f64,
    n_theta: usize,
    n_phi: usize,
) -> [DVec3; 3] {
    let t = DVec3::Y;
    let (a1, a2) = fibre_frame(t, strand_azimuth);
    let l = direction(t, a1, a2, theta_i, phi_i).as_vec3();
    let d_theta = PI / n_theta as f64;
    let d_phi = TAU / n_phi as f64;
    let mut sum = [DVec3::ZERO; 3];
    for i in 0..n_theta {
        let theta_r = -FRAC_PI_2 + (i as f64 + 0.5) * d_theta;
        let weight = theta_r.cos() * theta_r.cos() * d_theta * d_phi;
        for j in 0..n_phi {
            let phi_r = phi_i - PI + (j as f64 + 0.5) * d_phi;
            let v = direction(t, a1, a2, theta_r, phi_r).as_vec3();
            let angles = fibre_angles(t.as_vec3(), l, v, strand_azimuth);
            let lobes = marschner_lobes(p, &angles);
            for k in 0..3 {
                sum[k] += lobes[k] * weight;
            }
        }
    }
    sum
}

/// Directional albedo `ρ(θ_i)` (see [`marschner_albedo_lobes`]) summed over the lobes, with
/// `samples` strata in `θ_r` and `2 · samples` in `φ_r`, light at azimuth 0 of an unturned
/// strand. Used with `σ_a = 0` for the white furnace test.
pub fn marschner_albedo(p: &MarschnerParams, theta_i: f64, samples: usize) -> Vec3 {
    let n = samples.max(1);
    let [r, tt, trt] = marschner_albedo_lobes(p, theta_i, 0.0, 0.0, n, 2 * n);
    (r + tt + trt).as_vec3()
}

// ---------------------------------------------------------------------------------------
// Sadeghi
// ---------------------------------------------------------------------------------------

/// Unit-height Gaussian `g'(w; x) = exp(-x²/(2w²))` (Sadeghi et al. 2010 eq. 21/61).
pub fn unit_height_gaussian(width: f64, x: f64) -> f64 {
    (-0.5 * (x / width) * (x / width)).exp()
}

/// The three lobes `[R, TT, TRT]` of Sadeghi's pseudo scattering function (Sadeghi et al.
/// 2010 eqs. 20–24; digest 002/003 §B.1.6 eqs. 60–64, digest 000/001 §000.1.6):
/// ```text
/// f_p = C_p I_p M'_p(θ_h) N'_p(φ) / cos²θ_d,   M'_p = g'(β_p; θ_h - α_p)
/// N'_R = cos(φ/2),  N'_TT = g'(γ_TT; π - φ),  N'_TRT = cos(φ/2) + I_G g'(γ_G; G_angle - φ)
/// ```
/// `φ ∈ [0, π]`, `glint_angle` = G_angle in radians. TT and TRT are tinted by `base`.
fn sadeghi_lobes(
    p: &SadeghiParams,
    angles: &FibreAngles,
    base: DVec3,
    glint_angle: f64,
) -> [DVec3; 3] {
    let rad = |d: f32| f64::from(d).to_radians();
    let phi = angles.phi;
    let cos_theta_d = angles.theta_d.cos().max(MIN_COS_THETA_D);
    let inv = 1.0 / (cos_theta_d * cos_theta_d);
    let m = |shift: f32, width: f32| unit_height_gaussian(rad(width), angles.theta_h - rad(shift));
    let n_r = (0.5 * phi).cos();
    let n_tt = unit_height_gaussian(rad(p.azimuthal_width_tt_deg), PI - phi);
    let n_trt = (0.5 * phi).cos()
        + f64::from(p.glint_intensity)
            * unit_height_gaussian(rad(p.glint_width_deg), glint_angle - phi);
    [
        p.color_r.as_dvec3()
            * (f64::from(p.intensity_r) * m(p.shift_r_deg, p.width_r_deg) * n_r * inv),
        p.color_tt.as_dvec3()
            * base
            * (f64::from(p.intensity_tt) * m(p.shift_tt_deg, p.width_tt_deg) * n_tt * inv),
        p.color_trt.as_dvec3()
            * base
            * (f64::from(p.intensity_trt) * m(p.shift_trt_deg, p.width_trt_deg) * n_trt * inv),
    ]
}

/// Sadeghi radiance for a light of unit irradiance and a white strand: the pseudo
/// scattering function of [`SadeghiParams`] `· cos θ_i`, with the glint half angle
/// `glint_angle` (radians). No diffuse term.
pub fn sadeghi(p: &SadeghiParams, t: Vec3, l: Vec3, v: Vec3, glint_angle: f32) -> Vec3 {
    let angles = fibre_angles(t, l, v, 0.0);
    let [r, tt, trt] = sadeghi_lobes(p, &angles, DVec3::ONE, f64::from(glint_angle));
    ((r + tt + trt) * angles.cos_theta_i).as_vec3()
}

/// The twin of WGSL `sadeghi_radiance`: the lobes with TT and TRT tinted by `base_color`,
/// the glint half angle `mix(glint_angle_min, glint_angle_max, strand_random)`, plus the
/// diffuse term `diffuse · base · cos θ_i`, all times `cos θ_i`.
pub fn sadeghi_radiance(
    p: &SadeghiParams,
    t: Vec3,
    l: Vec3,
    v: Vec3,
    base_color: Vec3,
    strand_random: f32,
) -> Vec3 {
    let angles = fibre_angles(t, l, v, 0.0);
    let lo = f64::from(p.glint_angle_min_deg).to_radians();
    let hi = f64::from(p.glint_angle_max_deg).to_radians();
    let glint = lo + (hi - lo) * f64::from(strand_random);
    let base = base_color.as_dvec3();
    let [r, tt, trt] = sadeghi_lobes(p, &angles, base, glint);
    ((r + tt + trt + base * f64::from(p.diffuse)) * angles.cos_theta_i).as_vec3()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cubic_roots_solve_the_cubic() {
        for &(a, b, target) in &[
            (0.68, 0.36, 0.2),
            (0.68, 0.36, -0.35),
            (-0.8, 0.2, 1.0),
            (-2.0, 0.0, 0.5),
        ] {
            let roots = cubic_roots(a, b, target);
            assert!(!roots.is_empty(), "{a} {b} {target}");
            for g in roots {
                let r = a * g - b * g * g * g - target;
                assert!(r.abs() < 1e-12, "residual {r}");
            }
        }
        // Three roots inside the fold, one outside it.
        assert_eq!(cubic_roots(0.68, 0.36, 0.2).len(), 3);
        assert_eq!(cubic_roots(0.68, 0.36, 0.4).len(), 0);
    }

    #[test]
    fn n_integrates_to_mean_attenuation() {
        // ∫ N_p dφ = ½ ∫ A(p, h) dh (change of variables, Marschner eq. 48), checked for R.
        let br = Bravais::new(1.55, 0.3);
        let n = 20_000;
        let mut integral = 0.0;
        for j in 0..n {
            let phi = -PI + (j as f64 + 0.5) * TAU / n as f64;
            integral += n_raw(0, &br, DVec3::ZERO, phi).x * TAU / n as f64;
        }
        let mut mean = 0.0;
        for j in 0..n {
            let h = -1.0 + (j as f64 + 0.5) * 2.0 / n as f64;
            mean += attenuation(0, &br, DVec3::ZERO, h.asin()).x * 2.0 / n as f64;
        }
        assert!(
            (integral - 0.5 * mean).abs() < 1e-4,
            "{integral} vs {}",
            0.5 * mean
        );
    }

    #[test]
    fn glint_scale_one_keeps_the_caustic_energy() {
        // ∫ N_TRT dφ with the caustics replaced, against ½ ∫ A(2, h) dh without them.
        for sin_theta_d in [0.0, 0.3, 0.5, 0.7] {
            let br = Bravais::new(1.55, sin_theta_d);
            let n = 200_000;
            let mut raw = 0.0;
            for j in 0..n {
                let h = -1.0 + (j as f64 + 0.5) * 2.0 / n as f64;
                raw += 0.5 * attenuation(2, &br, DVec3::ZERO, h.asin()).x * 2.0 / n as f64;
            }
            let mut line = format!("sin θ_d {sin_theta_d}: ½∫A dh = {raw:.5}");
            for k_g in [0.0, 0.5, 1.0, 2.0, 5.0] {
                let p = MarschnerParams {
                    glint_scale: k_g,
                    ..Default::default()
                };
                let mut e = 0.0;
                for j in 0..n {
                    let phi = -PI + (j as f64 + 0.5) * TAU / n as f64;
                    e += n_trt(&p, &br, DVec3::ZERO, phi).x * TAU / n as f64;
                }
                line += &format!(", k_G {k_g}: {e:.5}");
                if k_g == 1.0 {
                    assert!((e - raw).abs() < 0.2 * raw, "{line}");
                }
            }
            println!("{line}");
        }
    }
}
