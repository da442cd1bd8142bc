// shade/models/chiang.wgsl: the hair fibre of Chiang et al. 2016 (pbrt-v3's hair BSDF) in
// the far field, single scattering and dual scattering (Zinke et al. 2008), read from the
// tables ChiangTables builds (shade/models/chiang_tables.wgsl). Twin of
// `pelage_reference::chiang::ChiangFibre::far_field_radiance` (crates/pelage-reference).
//
// Reads:  @group(2) @binding(0) chiang       (uniform ChiangModel)
//         @group(2) @binding(1) chiang_n     (storage, CHIANG_PHI x CHIANG_THETA x CHIANG_SIGMA
//                                             vec4: N_R, N_TT, N_TRT, N_residual)
//         @group(2) @binding(2) chiang_dual  (storage, CHIANG_THETA x CHIANG_SIGMA x 2 vec4:
//                                             forward and backward energy of each lobe)
// Writes: nothing; no entry point.
//
// Single scattering (Chiang eq. 3 with pbrt's Mp, Ap and Np, h integrated out):
//   L = sum_p M_p(theta_i, theta_o^(p); v_p) N_p(phi, theta_o, sigma_a)  per unit irradiance,
//   N_p = 1/2 int_{-1}^{1} A_p(h) D_p(phi - Phi(p, h)) dh,  N_3 = 1/2 int A_3(h) dh / (2 pi),
// where theta_o^(p) is theta_o turned by the cuticle tilt (by -2a, a, 4a for p = 0, 1, 2).
// The azimuthal terms depend on sigma_a per channel, so each channel reads the table at its
// own sigma_a: the colour (and with it sigma_a) may change from strand to strand.
//
// Dual scattering (chiang_dual_radiance), Zinke et al. 2008 with pbrt's lobes; CPU twin
// `pelage_reference::dual` (crates/pelage-reference/src/dual.rs), which states the model in
// full. Stage 2's visibility V = exp(-tau) of the light at the strand vertex, tau the
// opacity times the expected number of fibres crossed (an opaque fibre counts 1; the voxel
// grid's and the deep opacity maps' optical depth, shadow/voxel_splat.wgsl). V is the light
// that crossed no fibre; the rest crossed n = tau / (1 - V) fibres on average (a Poisson
// count given that it is at least one). Per channel, with a_f^X, a_b^X each lobe's forward
// and backward energy for light at theta_i (pbrt's int f |cos theta| d omega; they add up
// to 1 without absorption):
//   F = V (f_s + d_b f_back(sigma_b^2))
//     + (1 - V) d_f a_f^n (f_s^scatter + pi d_b f_back(sigma_b^2 + sigma_f^2)),
//   f_s^scatter = sum_X M_X(v_X + 4 sigma_f^2) a_f^X / pi (the fibre's lobes widened by
//   sigma_f^2 = n beta_f^2, times Zinke's N^G_X = (2/pi) int_{pi/2}^{pi} N_X dphi),
//   f_back(s2) = A_b M_b(Delta_b, s2) / pi,
// with A_b, Delta_b and sigma_b from Zinke's eqs. 13 to 15 (no clamp) and d_f = d_b = 0.7
// (Zinke's density factors). Longitudinal lobes are pbrt's Mp with the shift and variance
// in its units (twice the theta_h shift, four times the theta_h variance).

#import shared/math.wgsl
#import shade/models/fibre.wgsl

// Texels of the azimuthal table along phi in [0, pi], |theta| in [0, pi/2] and the
// absorption coordinate x = sigma / (sigma + 1) in [0, 1] (the ends are texel centres;
// x = 1 is sigma = infinity). Mirrored by `ChiangTables` in crates/pelage-shade/src/models.rs.
const CHIANG_PHI: u32 = 64u;
const CHIANG_THETA: u32 = 32u;
const CHIANG_SIGMA: u32 = 32u;
// Zinke's density factors.
const CHIANG_DF: f32 = 0.7;
const CHIANG_DB: f32 = 0.7;

// Mirrors `ChiangUniforms` in crates/pelage-shade/src/models.rs.
struct ChiangModel {
    // Absorption per unit fibre radius, when from_color is 0.
    sigma_a: vec3<f32>,
    // 1: sigma_a from each strand's colour (Chiang eq. 9); 0: the fixed sigma_a.
    from_color: u32,
    // Longitudinal variances v_R, v_TT, v_TRT (the residual lobe uses v_TRT), pbrt's units.
    v: vec3<f32>,
    eta: f32,
    // sin(2^k alpha) and cos(2^k alpha) for k = 0, 1, 2 (alpha the cuticle tilt).
    sin_2k_alpha: vec3<f32>,
    // Scale of the logistic azimuthal lobes.
    s: f32,
    cos_2k_alpha: vec3<f32>,
    // The denominator of Chiang's colour inversion for beta_n.
    color_scale: f32,
    // 1: dual scattering; 0: single scattering. Read by the test kernel chiang_eval.wgsl
    // only: a hair pass binds chiang_dual_model.wgsl or chiang_model.wgsl instead of
    // branching on it (a shader holding both paths ran both on lavapipe: 2x).
    dual: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(2) @binding(0) var<uniform> chiang: ChiangModel;
@group(2) @binding(1) var<storage, read> chiang_n: array<vec4<f32>>;
@group(2) @binding(2) var<storage, read> chiang_dual: array<vec4<f32>>;

// sigma_a that makes hair of `color` appear that colour (Chiang et al. 2016 eq. 9).
fn chiang_sigma_from_color(color: vec3<f32>, scale: f32) -> vec3<f32> {
    let c = clamp(color, vec3<f32>(1e-4), vec3<f32>(1.0));
    let y = log(c) / scale;
    return y * y;
}

fn chiang_sigma_a(m: ChiangModel, base_color: vec3<f32>) -> vec3<f32> {
    if (m.from_color != 0u) {
        return chiang_sigma_from_color(base_color, m.color_scale);
    }
    return m.sigma_a;
}

// Modified Bessel function of the first kind, order 0 (pbrt's ten-term series).
fn chiang_i0(x: f32) -> f32 {
    var val = 0.0;
    var x2i = 1.0;
    var ifact = 1.0;
    var i4 = 1.0;
    for (var i = 0; i < 10; i += 1) {
        if (i > 1) {
            ifact *= f32(i);
        }
        val += x2i / (i4 * ifact * ifact);
        x2i *= x * x;
        i4 *= 4.0;
    }
    return val;
}

fn chiang_log_i0(x: f32) -> f32 {
    if (x > 12.0) {
        return x + 0.5 * (-log(TAU) + log(1.0 / x) + 1.0 / (8.0 * x));
    }
    return log(chiang_i0(x));
}

// pbrt's longitudinal lobe Mp: unit integral of Mp cos(theta_i) over theta_i.
fn chiang_mp(cos_i: f32, cos_o: f32, sin_i: f32, sin_o: f32, v: f32) -> f32 {
    let a = cos_i * cos_o / v;
    let b = sin_i * sin_o / v;
    if (v <= 0.1) {
        return exp(chiang_log_i0(a) - b - 1.0 / v + 0.6931 + log(1.0 / (2.0 * v)));
    }
    return exp(-b) * chiang_i0(a) / (sinh(1.0 / v) * 2.0 * v);
}

// Unpolarised Fresnel reflectance of a dielectric of index eta entered from air.
fn chiang_fresnel(cos_i: f32, eta: f32) -> f32 {
    let c = clamp(cos_i, 0.0, 1.0);
    let sin_t = fibre_cos_from_sin(c) / eta;
    if (sin_t >= 1.0) {
        return 1.0;
    }
    let cos_t = fibre_cos_from_sin(sin_t);
    let r_parl = (eta * c - cos_t) / (eta * c + cos_t);
    let r_perp = (c - eta * cos_t) / (c + eta * cos_t);
    return 0.5 * (r_parl * r_parl + r_perp * r_perp);
}

// Continuous texel coordinate of x in [lo, hi] over n texels: (index, fraction).
fn chiang_axis(x: f32, lo: f32, hi: f32, n: u32) -> vec2<f32> {
    let last = f32(n - 1u);
    let u = clamp((x - lo) / (hi - lo), 0.0, 1.0) * last;
    let i = min(floor(u), last - 1.0);
    return vec2<f32>(i, u - i);
}

// The absorption coordinate of sigma (>= 0): sigma / (sigma + 1).
fn chiang_sigma_coordinate(sigma: f32) -> f32 {
    return sigma / (sigma + 1.0);
}

// (N_R, N_TT, N_TRT, N_residual) at phi in [0, pi], |theta_o| and the absorption
// coordinate x, trilinear.
fn chiang_n_at(phi: f32, theta: f32, x: f32) -> vec4<f32> {
    let ap = chiang_axis(phi, 0.0, PI, CHIANG_PHI);
    let at = chiang_axis(theta, 0.0, 0.5 * PI, CHIANG_THETA);
    let ax = chiang_axis(x, 0.0, 1.0, CHIANG_SIGMA);
    let i = u32(ap.x) + CHIANG_PHI * (u32(at.x) + CHIANG_THETA * u32(ax.x));
    let row = CHIANG_PHI;
    let slice = CHIANG_PHI * CHIANG_THETA;
    let a0 = mix(chiang_n[i], chiang_n[i + 1u], ap.y);
    let a1 = mix(chiang_n[i + row], chiang_n[i + row + 1u], ap.y);
    let b0 = mix(chiang_n[i + slice], chiang_n[i + slice + 1u], ap.y);
    let b1 = mix(chiang_n[i + slice + row], chiang_n[i + slice + row + 1u], ap.y);
    return mix(mix(a0, a1, at.y), mix(b0, b1, at.y), ax.y);
}

// Forward (first) and backward (second) energies (R, TT, TRT, residual) of light arriving
// at |theta| with absorption coordinate x, bilinear.
struct ChiangEnergies {
    forward: vec4<f32>,
    backward: vec4<f32>,
}

fn chiang_dual_at(theta: f32, x: f32) -> ChiangEnergies {
    let at = chiang_axis(theta, 0.0, 0.5 * PI, CHIANG_THETA);
    let ax = chiang_axis(x, 0.0, 1.0, CHIANG_SIGMA);
    let i = 2u * (u32(at.x) + CHIANG_THETA * u32(ax.x));
    let row = 2u;
    let slice = 2u * CHIANG_THETA;
    var e: ChiangEnergies;
    e.forward = mix(
        mix(chiang_dual[i], chiang_dual[i + row], at.y),
        mix(chiang_dual[i + slice], chiang_dual[i + slice + row], at.y),
        ax.y,
    );
    e.backward = mix(
        mix(chiang_dual[i + 1u], chiang_dual[i + row + 1u], at.y),
        mix(chiang_dual[i + slice + 1u], chiang_dual[i + slice + row + 1u], at.y),
        ax.y,
    );
    return e;
}

// The angles one evaluation needs.
struct ChiangAngles {
    sin_i: f32,
    cos_i: f32,
    sin_o: f32,
    cos_o: f32,
    // |theta_o| and |theta_i| in [0, pi/2].
    theta_o: f32,
    theta_i: f32,
    // |phi_i - phi_o| in [0, pi].
    phi: f32,
}

fn chiang_angles(t: vec3<f32>, l: vec3<f32>, v: vec3<f32>) -> ChiangAngles {
    var a: ChiangAngles;
    a.sin_i = clamp(dot(t, l), -1.0, 1.0);
    a.sin_o = clamp(dot(t, v), -1.0, 1.0);
    a.cos_i = min(length(cross(t, l)), 1.0);
    a.cos_o = min(length(cross(t, v)), 1.0);
    a.theta_o = fibre_angle(abs(a.sin_o), a.cos_o);
    a.theta_i = fibre_angle(abs(a.sin_i), a.cos_i);
    a.phi = fibre_azimuths(t, l, v, 0.0).x;
    return a;
}

// Mp of lobe p's tilt (theta_o turned by -2a, a, 4a for p = 0, 1, 2), variance v.
fn chiang_mp_lobe(m: ChiangModel, a: ChiangAngles, p: u32, v: f32) -> f32 {
    var so = a.sin_o;
    var co = a.cos_o;
    if (p == 0u) {
        so = a.sin_o * m.cos_2k_alpha.y - a.cos_o * m.sin_2k_alpha.y;
        co = a.cos_o * m.cos_2k_alpha.y + a.sin_o * m.sin_2k_alpha.y;
    } else if (p == 1u) {
        so = a.sin_o * m.cos_2k_alpha.x + a.cos_o * m.sin_2k_alpha.x;
        co = a.cos_o * m.cos_2k_alpha.x - a.sin_o * m.sin_2k_alpha.x;
    } else if (p == 2u) {
        so = a.sin_o * m.cos_2k_alpha.z + a.cos_o * m.sin_2k_alpha.z;
        co = a.cos_o * m.cos_2k_alpha.z - a.sin_o * m.sin_2k_alpha.z;
    }
    return chiang_mp(a.cos_i, abs(co), a.sin_i, so, v);
}

// The longitudinal lobe with its theta_h shift `shift` (radians) and theta_h variance `var_h`,
// in pbrt's units: theta_o turned by -2 shift, variance 4 var_h.
fn chiang_mp_shifted(a: ChiangAngles, shift: f32, var_h: f32) -> f32 {
    let s2 = sin(2.0 * shift);
    let c2 = cos(2.0 * shift);
    let so = a.sin_o * c2 - a.cos_o * s2;
    let co = a.cos_o * c2 + a.sin_o * s2;
    return chiang_mp(a.cos_i, abs(co), a.sin_i, so, 4.0 * var_h);
}

// Single scattering: the radiance toward v for a light of unit irradiance from l.
fn chiang_single(m: ChiangModel, a: ChiangAngles, sigma: vec3<f32>) -> vec3<f32> {
    let x = vec3<f32>(
        chiang_sigma_coordinate(sigma.x),
        chiang_sigma_coordinate(sigma.y),
        chiang_sigma_coordinate(sigma.z),
    );
    let nr = chiang_n_at(a.phi, a.theta_o, x.x);
    let ng = chiang_n_at(a.phi, a.theta_o, x.y);
    let nb = chiang_n_at(a.phi, a.theta_o, x.z);
    let m0 = chiang_mp_lobe(m, a, 0u, m.v.x);
    let m1 = chiang_mp_lobe(m, a, 1u, m.v.y);
    let m2 = chiang_mp_lobe(m, a, 2u, m.v.z);
    let m3 = chiang_mp_lobe(m, a, 3u, m.v.z);
    let r = m0 * nr.x + m1 * nr.y + m2 * nr.z + m3 * nr.w;
    let g = m0 * ng.x + m1 * ng.y + m2 * ng.z + m3 * ng.w;
    let b = m0 * nb.x + m1 * nb.y + m2 * nb.z + m3 * nb.w;
    return max(vec3<f32>(r, g, b), vec3<f32>(0.0));
}

// Chiang's far-field fibre, single scattering, in the shape of every hair model:
// the radiance toward v for a light of unit irradiance from l.
fn chiang_radiance(
    m: ChiangModel,
    t: vec3<f32>,
    l: vec3<f32>,
    v: vec3<f32>,
    base_color: vec3<f32>,
    strand_random: f32,
) -> vec3<f32> {
    return chiang_single(m, chiang_angles(t, l, v), chiang_sigma_a(m, base_color));
}

// The mean number of fibres crossed by the light that crossed any: n = tau / (1 - V) for
// V = exp(-tau) (the mean of a Poisson count given that it is at least one), 1 as V -> 1.
fn chiang_crossings(visibility: f32, tau: f32) -> f32 {
    if (tau < 1e-4) {
        // tau / (1 - exp(-tau)) = 1 + tau / 2 + O(tau^2), without the cancellation.
        return 1.0 + 0.5 * tau;
    }
    return tau / (1.0 - visibility);
}

// One channel of dual scattering (see the file's comment): energies e of the fibre for
// light at theta_i, f_s the single scattering of this channel, n the fibres crossed.
fn chiang_dual_channel(
    m: ChiangModel,
    a: ChiangAngles,
    e: ChiangEnergies,
    f_s: f32,
    visibility: f32,
    n: f32,
) -> f32 {
    // Lobe shifts and variances in theta_h: R at alpha, TT at -alpha/2, TRT at -2 alpha,
    // the residual at 0; variances v_p / 4.
    let alpha = asin(clamp(m.sin_2k_alpha.x, -1.0, 1.0));
    let shift = vec4<f32>(alpha, -0.5 * alpha, -2.0 * alpha, 0.0);
    let var_h = 0.25 * vec4<f32>(m.v.x, m.v.y, m.v.z, m.v.z);
    // a_f, a_b > 0: Fresnel sends some light each way at every angle and absorption.
    let af = dot(e.forward, vec4<f32>(1.0));
    let ab = dot(e.backward, vec4<f32>(1.0));
    let alpha_f = dot(e.forward, shift) / af;
    let alpha_b = dot(e.backward, shift) / ab;
    let beta_f2 = dot(e.forward, var_h) / af;
    let beta_b2 = dot(e.backward, var_h) / ab;
    let beta_f = sqrt(beta_f2);
    let beta_b = sqrt(beta_b2);
    // Zinke eqs. 13 to 15: back scattering in the neighbourhood of the shading point
    // (a_f < 1 always: a_f + a_b <= 1 with a_b > 0).
    let af2 = af * af;
    let af_inv = 1.0 - af2;
    let ab2 = ab * ab;
    let ab3 = ab2 * ab;
    let a_b = ab * af2 / af_inv + ab3 * af2 / (af_inv * af_inv * af_inv);
    let delta_b = alpha_b * (1.0 - 2.0 * ab2 / (af_inv * af_inv))
        + alpha_f * (2.0 * af_inv * af_inv + 4.0 * af2 * ab2) / (af_inv * af_inv * af_inv);
    let sigma_b = (1.0 + CHIANG_DB * af2)
        * (ab * sqrt(2.0 * beta_f2 + beta_b2) + ab3 * sqrt(2.0 * beta_f2 + 3.0 * beta_b2))
        / (ab + ab3 * (2.0 * beta_f + 3.0 * beta_b));
    let sigma_b2 = sigma_b * sigma_b;
    let back_direct = a_b * chiang_mp_shifted(a, delta_b, sigma_b2) * INV_PI;
    let f_direct = visibility * (f_s + CHIANG_DB * back_direct);
    if (visibility >= 1.0) {
        return f_direct;
    }
    // The light that crossed fibres: Zinke's forward transmittance d_f a_f^n of this
    // channel, spread by n scatterings (sigma_f^2 = n beta_f^2).
    let t_f = CHIANG_DF * pow(af, n);
    let sigma_f2 = n * beta_f2;
    let back_scatter = a_b * chiang_mp_shifted(a, delta_b, sigma_b2 + sigma_f2) * INV_PI;
    // Zinke's f_s^scatter: each lobe widened by sigma_f^2 (4 sigma_f^2 in pbrt's variance)
    // times N^G_X = (2/pi) int_{pi/2}^{pi} N_X dphi = a_f^X / pi.
    let widen = 4.0 * sigma_f2;
    let fs_scatter = (chiang_mp_lobe(m, a, 0u, m.v.x + widen) * e.forward.x
        + chiang_mp_lobe(m, a, 1u, m.v.y + widen) * e.forward.y
        + chiang_mp_lobe(m, a, 2u, m.v.z + widen) * e.forward.z
        + chiang_mp_lobe(m, a, 3u, m.v.z + widen) * e.forward.w) * INV_PI;
    return f_direct + (1.0 - visibility) * t_f * (fs_scatter + PI * CHIANG_DB * back_scatter);
}

// Dual scattering: the radiance toward v for a light of unit irradiance from l that stage 2
// sees reaching the strand with `visibility` (in [0, 1]).
fn chiang_dual_radiance(
    m: ChiangModel,
    t: vec3<f32>,
    l: vec3<f32>,
    v: vec3<f32>,
    base_color: vec3<f32>,
    visibility: f32,
) -> vec3<f32> {
    let a = chiang_angles(t, l, v);
    let sigma = chiang_sigma_a(m, base_color);
    let f_s = chiang_single(m, a, sigma);
    let vis = clamp(visibility, 0.0, 1.0);
    // Optical depth of the hair in front: V = exp(-tau) (at most 69, V = 1e-30).
    let tau = -log(max(vis, 1e-30));
    let n = chiang_crossings(vis, tau);
    let x = vec3<f32>(
        chiang_sigma_coordinate(sigma.x),
        chiang_sigma_coordinate(sigma.y),
        chiang_sigma_coordinate(sigma.z),
    );
    let er = chiang_dual_at(a.theta_i, x.x);
    let eg = chiang_dual_at(a.theta_i, x.y);
    let eb = chiang_dual_at(a.theta_i, x.z);
    return vec3<f32>(
        chiang_dual_channel(m, a, er, f_s.x, vis, n),
        chiang_dual_channel(m, a, eg, f_s.y, vis, n),
        chiang_dual_channel(m, a, eb, f_s.z, vis, n),
    );
}
