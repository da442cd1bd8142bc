// shade/models/chiang_tables.wgsl: builds the tables of shade/models/chiang.wgsl once per
// (eta, beta_n): the far-field azimuthal terms of Chiang et al. 2016 with h integrated out,
// and, from them, each lobe's forward and backward energy for dual scattering.
//
// Reads:  model (uniform ChiangModel: eta and the logistic scale s are used).
// Writes: table_n    (CHIANG_PHI x CHIANG_THETA x CHIANG_SIGMA vec4), texel (i, j, k) at
//                    (k * CHIANG_THETA + j) * CHIANG_PHI + i: at phi_i in [0, pi],
//                    theta_j = |theta_o| in [0, pi/2], x_k = sigma / (sigma + 1) in [0, 1]:
//                    (N_R, N_TT, N_TRT, N_3), N_p = 1/2 int_{-1}^{1} A_p(h) D_p(phi - Phi(p, h)) dh,
//                    N_3 = 1/2 int A_3(h) dh / (2 pi) (pbrt's Ap, Phi and trimmed logistic D).
//         table_dual (CHIANG_THETA x CHIANG_SIGMA x 2 vec4), at 2 (k * CHIANG_THETA + j):
//                    forward energies 2 int_{pi/2}^{pi} N_p dphi, then at + 1 the backward
//                    ones 2 int_0^{pi/2} N_p dphi (p = R, TT, TRT, residual).
// Dispatch: entry `azimuthal`: workgroups of 64 x 1 x 1 over (CHIANG_PHI, CHIANG_THETA,
//           CHIANG_SIGMA), i.e. (1, 32, 32); then entry `energies`, after it: workgroups of
//           8 x 8 over (CHIANG_THETA, CHIANG_SIGMA), i.e. (4, 4, 1).
// The h integral runs over gamma_o = asin(h) (dh = cos gamma_o d gamma_o: Phi is smooth in
// gamma_o) with CHIANG_H_SAMPLES midpoints; the phi integrals are of the linear
// interpolant of table_n, exactly as the lookup reads it.

#import shared/math.wgsl
#import shade/models/fibre.wgsl
#import shade/models/chiang.wgsl

@group(0) @binding(0) var<uniform> model: ChiangModel;
@group(0) @binding(1) var<storage, read_write> table_n: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> table_dual: array<vec4<f32>>;

const CHIANG_H_SAMPLES: u32 = 512u;

// pbrt's logistic distribution of scale s, trimmed to [-pi, pi].
fn chiang_logistic(x: f32, s: f32) -> f32 {
    let e = exp(-abs(x) / s);
    return e / (s * (1.0 + e) * (1.0 + e));
}

fn chiang_logistic_cdf(x: f32, s: f32) -> f32 {
    return 1.0 / (1.0 + exp(-x / s));
}

fn chiang_trimmed_logistic(x: f32, s: f32) -> f32 {
    return chiang_logistic(x, s) / (chiang_logistic_cdf(PI, s) - chiang_logistic_cdf(-PI, s));
}

// x wrapped into [-pi, pi].
fn chiang_wrap(x: f32) -> f32 {
    return x - TAU * floor((x + PI) / TAU);
}

fn texel(i: u32, n: u32, lo: f32, hi: f32) -> f32 {
    return mix(lo, hi, f32(i) / f32(n - 1u));
}

@compute @workgroup_size(64, 1, 1)
fn azimuthal(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= CHIANG_PHI || gid.y >= CHIANG_THETA || gid.z >= CHIANG_SIGMA) {
        return;
    }
    let phi = texel(gid.x, CHIANG_PHI, 0.0, PI);
    let theta = texel(gid.y, CHIANG_THETA, 0.0, 0.5 * PI);
    let x = texel(gid.z, CHIANG_SIGMA, 0.0, 1.0);
    let sin_o = sin(theta);
    let cos_o = max(cos(theta), 1e-4);
    let eta = model.eta;
    let s = model.s;
    // Bravais' index for the projected path, and the refracted longitudinal angle.
    let etap = sqrt(max(eta * eta - sin_o * sin_o, 0.0)) / cos_o;
    let sin_t = sin_o / eta;
    let cos_t = fibre_cos_from_sin(sin_t);
    var out = vec4<f32>(0.0);
    let step = PI / f32(CHIANG_H_SAMPLES);
    for (var k = 0u; k < CHIANG_H_SAMPLES; k += 1u) {
        let gamma_o = -0.5 * PI + (f32(k) + 0.5) * step;
        let h = sin(gamma_o);
        let cos_gamma_o = cos(gamma_o);
        let sin_gamma_t = clamp(h / etap, -1.0, 1.0);
        let gamma_t = fibre_asin(sin_gamma_t);
        let cos_gamma_t = fibre_cos_from_sin(sin_gamma_t);
        var tr = 0.0;
        if (x < 1.0) {
            let sigma = x / (1.0 - x);
            tr = exp(-sigma * 2.0 * cos_gamma_t / cos_t);
        }
        let f = chiang_fresnel(cos_o * cos_gamma_o, eta);
        let a0 = f;
        let a1 = (1.0 - f) * (1.0 - f) * tr;
        let a2 = a1 * tr * f;
        let a3 = a2 * f * tr / max(1.0 - tr * f, 1e-6);
        // 1/2 of dh = cos(gamma_o) d gamma_o.
        let w = 0.5 * cos_gamma_o * step;
        let d0 = chiang_trimmed_logistic(chiang_wrap(phi - (-2.0 * gamma_o)), s);
        let d1 = chiang_trimmed_logistic(chiang_wrap(phi - (2.0 * gamma_t - 2.0 * gamma_o + PI)), s);
        let d2 = chiang_trimmed_logistic(chiang_wrap(phi - (4.0 * gamma_t - 2.0 * gamma_o + TAU)), s);
        out += w * vec4<f32>(a0 * d0, a1 * d1, a2 * d2, a3 * (1.0 / TAU));
    }
    table_n[(gid.z * CHIANG_THETA + gid.y) * CHIANG_PHI + gid.x] = out;
}

@compute @workgroup_size(8, 8, 1)
fn energies(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= CHIANG_THETA || gid.y >= CHIANG_SIGMA) {
        return;
    }
    let first = (gid.y * CHIANG_THETA + gid.x) * CHIANG_PHI;
    // Integrals of the piecewise linear N over [0, pi/2] and [pi/2, pi].
    var back = vec4<f32>(0.0);
    var front = vec4<f32>(0.0);
    let dphi = PI / f32(CHIANG_PHI - 1u);
    for (var i = 0u; i + 1u < CHIANG_PHI; i += 1u) {
        let p0 = f32(i) * dphi;
        let p1 = p0 + dphi;
        let n0 = table_n[first + i];
        let n1 = table_n[first + i + 1u];
        let half = 0.5 * PI;
        if (p1 <= half) {
            back += 0.5 * (n0 + n1) * dphi;
        } else if (p0 >= half) {
            front += 0.5 * (n0 + n1) * dphi;
        } else {
            // The interval holding pi/2: split the trapezoid there.
            let u = (half - p0) / dphi;
            let nm = mix(n0, n1, u);
            back += 0.5 * (n0 + nm) * (half - p0);
            front += 0.5 * (nm + n1) * (p1 - half);
        }
    }
    let at = 2u * (gid.y * CHIANG_THETA + gid.x);
    table_dual[at] = 2.0 * front;
    table_dual[at + 1u] = 2.0 * back;
}
