// shade/models/marschner.wgsl: Marschner et al. 2003 hair scattering, lobes R, TT and TRT,
// evaluated analytically. Twin of `marschner_radiance` in crates/pelage-reference/src/shading.rs
// (which documents every formula and its source; digest 002/003 sections A.1.5 and B.1.5).
// Reads nothing, writes nothing: pure functions and structs, no bindings, no entry point.
//
//   S = sum_p M_p(theta_h) N_p(eta'(theta_d), phi) / cos^2(theta_d)
//   M_p = 1/2 g(beta_p; theta_h - alpha_p)   (unit area over theta_r; see the reference)
//   N_p = sum over roots gamma of phi^(p, gamma) = phi (mod 2 pi), cubic approximation:
//         A(p, h) cos(gamma) / |2 (a - 3 b gamma^2)|,  a = 6pc/pi - 2, b = 8pc/pi^3,
//         c = asin(1/eta'), A with Bravais' eta', eta'' and absorption sigma_a / cos(theta_t)
//   N_TRT: eccentric index eta*(phi_h), caustics replaced by glints (seed 003, Algorithm 1).
// marschner_radiance returns (S + diffuse * base) * cos(theta_i): the radiance toward v for
// a light of unit irradiance from l. The cubic is solved in closed form here (the reference
// bisects).

#import shared/math.wgsl
#import shade/models/fibre.wgsl

// Mirrors `MarschnerUniforms` in crates/pelage-shade/src/models.rs (angles in radians).
struct MarschnerModel {
    // Longitudinal shifts alpha_R, alpha_TT, alpha_TRT.
    alpha: vec3<f32>,
    eta: f32,
    // Longitudinal widths beta_R, beta_TT, beta_TRT.
    beta: vec3<f32>,
    // Minor over major axis of the cross-section, in [0.85, 1].
    eccentricity: f32,
    // Absorption per unit radius.
    sigma_a: vec3<f32>,
    // Strand azimuth = azimuth_jitter * strand_random.
    azimuth_jitter: f32,
    // k_G, w_c (radians), delta eta', delta h_M of Algorithm 1.
    glint_scale: f32,
    caustic_width: f32,
    caustic_fade: f32,
    caustic_limit: f32,
    // Weight of the Kajiya-Kay diffuse term added to the lobes.
    diffuse: f32,
}

// Sizes of the lookup tables (see shade/models/marschner_lut.wgsl); mirrors
// `MarschnerLutInfo` in crates/pelage-shade/src/models.rs.
struct MarschnerLutInfo {
    // Texels per axis of the N tables (the M table has MARSCHNER_LUT_M_ROWS * size).
    size: u32,
    // Slices of the TRT table along cos(2 phi_h) (1 for a circular fibre).
    slices: u32,
    _pad0: u32,
    _pad1: u32,
}

// The M table of the lookup path has this many rows of `size` texels (it is 1-D, over
// theta_h, and cheap: 16 * size vec4).
const MARSCHNER_LUT_M_ROWS: u32 = 16u;

struct MarschnerLobes {
    r: vec3<f32>,
    tt: vec3<f32>,
    trt: vec3<f32>,
}

// What the azimuthal term of one lobe needs from theta_d.
struct MarschnerBravais {
    // eta' = sqrt(eta^2 - sin^2 theta_d) / cos theta_d
    eta1: f32,
    // eta'' = eta^2 / eta'
    eta2: f32,
    // cos theta_t = sqrt(1 - sin^2 theta_d / eta^2)
    cos_theta_t: f32,
    // c = asin(1 / eta')
    c: f32,
}

// Smallest |2 dphi/dh| in the ray density (zero exactly at a caustic).
const MARSCHNER_MIN_DPHI_DH: f32 = 1e-6;
const MARSCHNER_HALF_PI: f32 = 1.57079632679490;

// Unit-area Gaussian g(beta; x).
fn marschner_gaussian(beta: f32, x: f32) -> f32 {
    let y = x / beta;
    return exp(-0.5 * y * y) / (beta * 2.50662827463100);
}

// [M_R, M_TT, M_TRT] at theta_h.
fn marschner_m(m: MarschnerModel, theta_h: f32) -> vec3<f32> {
    return 0.5 * vec3<f32>(
        marschner_gaussian(m.beta.x, theta_h - m.alpha.x),
        marschner_gaussian(m.beta.y, theta_h - m.alpha.y),
        marschner_gaussian(m.beta.z, theta_h - m.alpha.z),
    );
}

// Marschner's eccentric TRT index eta*(phi_h) (eqs. 58-59 of the digest).
fn marschner_eta_star(eta: f32, eccentricity: f32, cos_2phi_h: f32) -> f32 {
    let a2 = eccentricity * eccentricity;
    let e1 = 2.0 * (eta - 1.0) * a2 - eta + 2.0;
    let e2 = 2.0 * (eta - 1.0) / a2 - eta + 2.0;
    return 0.5 * ((e1 + e2) + cos_2phi_h * (e1 - e2));
}

fn marschner_bravais(eta: f32, sin2_theta_d: f32, cos_theta_d: f32) -> MarschnerBravais {
    let s2 = min(sin2_theta_d, 1.0);
    let eta1 = sqrt(max(eta * eta - s2, 0.0)) / max(cos_theta_d, FIBRE_MIN_COS_THETA_D);
    return MarschnerBravais(
        eta1,
        eta * eta / eta1,
        sqrt(max(1.0 - s2 / (eta * eta), 0.0)),
        fibre_asin(min(1.0 / eta1, 1.0)),
    );
}

// Unpolarised Fresnel reflectance with Bravais' indices: eta' for s, eta'' for p.
fn marschner_fresnel(eta1: f32, eta2: f32, cos_i: f32, cos_t: f32) -> f32 {
    let rs = (cos_i - eta1 * cos_t) / (cos_i + eta1 * cos_t);
    let rp = (eta2 * cos_i - cos_t) / (eta2 * cos_i + cos_t);
    return clamp(0.5 * (rs * rs + rp * rp), 0.0, 1.0);
}

// A(p, h) of the path entering at gamma, per channel.
fn marschner_attenuation(p: u32, br: MarschnerBravais, sigma_a: vec3<f32>, gamma: f32) -> vec3<f32> {
    let h = sin(gamma);
    let sin_gt = clamp(h / br.eta1, -1.0, 1.0);
    let cos_gt = sqrt(max(1.0 - sin_gt * sin_gt, 0.0));
    let f = marschner_fresnel(br.eta1, br.eta2, max(cos(gamma), 0.0), cos_gt);
    let segment = 2.0 * cos_gt / max(br.cos_theta_t, 1e-6);
    let tr = exp(-sigma_a * segment);
    if (p == 0u) {
        return vec3<f32>(f);
    }
    if (p == 1u) {
        return (1.0 - f) * (1.0 - f) * tr;
    }
    return (1.0 - f) * (1.0 - f) * f * tr * tr;
}

// (a, b) with phi^(p, gamma) - p pi = a gamma - b gamma^3.
fn marschner_cubic(p: u32, c: f32) -> vec2<f32> {
    let pc = f32(p) * c;
    return vec2<f32>(6.0 * pc / PI - 2.0, 8.0 * pc / (PI * PI * PI));
}

// x wrapped into [-pi, pi).
fn marschner_wrap(x: f32) -> f32 {
    return x - TAU * floor((x + PI) / TAU);
}

struct MarschnerRoots {
    gamma: vec3<f32>,
    count: u32,
}

// Real roots of a g - b g^3 = goal with |g| <= pi/2 (b > 0), in closed form: the depressed
// cubic g^3 + P g + Q = 0, P = -a/b, Q = goal/b, by the hyperbolic / trigonometric
// formulas (no cancellation), then one Newton step away from folds.
fn marschner_solve(a: f32, b: f32, goal: f32) -> MarschnerRoots {
    var out = MarschnerRoots(vec3<f32>(0.0), 0u);
    var g = vec3<f32>(0.0);
    var n = 0u;
    let pp = -a / b;
    let qq = goal / b;
    if (pp > 1e-12) {
        // One real root.
        let s = sqrt(pp / 3.0);
        g.x = -2.0 * s * sinh(asinh(1.5 * qq / (pp * s)) / 3.0);
        n = 1u;
    } else if (pp > -1e-12) {
        g.x = -sign(qq) * pow(abs(qq), 1.0 / 3.0);
        n = 1u;
    } else {
        let s = sqrt(-pp / 3.0);
        // 4P^3 + 27Q^2 <= 0: three real roots.
        let arg = 1.5 * qq / (pp * s);
        if (abs(arg) <= 1.0) {
            let th = fibre_acos(arg) / 3.0;
            g = 2.0 * s * vec3<f32>(cos(th), cos(th - TAU / 3.0), cos(th - 2.0 * TAU / 3.0));
            n = 3u;
        } else {
            g.x = -2.0 * sign(qq) * s * cosh(acosh(abs(arg)) / 3.0);
            n = 1u;
        }
    }
    for (var k = 0u; k < n; k++) {
        var x = g[k];
        let fp = a - 3.0 * b * x * x;
        if (abs(fp) > 1e-2) {
            x = x - (a * x - b * x * x * x - goal) / fp;
        }
        if (abs(x) <= MARSCHNER_HALF_PI) {
            out.gamma[out.count] = x;
            out.count += 1u;
        }
    }
    return out;
}

// N_p without caustic handling: the sum over the roots of A cos(gamma) / |2 dpsi/dgamma|.
fn marschner_n_raw(p: u32, br: MarschnerBravais, sigma_a: vec3<f32>, phi: f32) -> vec3<f32> {
    let ab = marschner_cubic(p, br.c);
    let goal = marschner_wrap(phi - f32(p) * PI);
    var roots: MarschnerRoots;
    if (p == 0u) {
        roots = MarschnerRoots(vec3<f32>(-0.5 * goal, 0.0, 0.0), 1u);
    } else {
        roots = marschner_solve(ab.x, ab.y, goal);
    }
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < roots.count; k++) {
        let g = roots.gamma[k];
        let d = max(abs(2.0 * (ab.x - 3.0 * ab.y * g * g)), MARSCHNER_MIN_DPHI_DH);
        sum += marschner_attenuation(p, br, sigma_a, g) * (max(cos(g), 0.0) / d);
    }
    return sum;
}

// N_TRT with the caustics replaced by glints (seed 003, Algorithm 1).
fn marschner_n_trt(m: MarschnerModel, br: MarschnerBravais, phi: f32) -> vec3<f32> {
    let raw = marschner_n_raw(2u, br, m.sigma_a, phi);
    let w_c = m.caustic_width;
    let ab = marschner_cubic(2u, br.c);
    var gamma_c = 0.0;
    var delta_h = m.caustic_limit;
    var fade = 1.0;
    var phi_c = 0.0;
    if (br.eta1 < 2.0 && ab.x > 0.0) {
        gamma_c = min(sqrt(ab.x / (3.0 * ab.y)), MARSCHNER_HALF_PI);
        let cos_c = max(cos(gamma_c), 1e-6);
        let d2 = max(6.0 * ab.y * gamma_c / (cos_c * cos_c), 1e-12);
        delta_h = min(m.caustic_limit, 2.0 * sqrt(2.0 * w_c / d2));
        phi_c = gamma_c * (ab.x - ab.y * gamma_c * gamma_c);
    } else {
        fade = 1.0 - smoothstep(2.0, 2.0 + m.caustic_fade, br.eta1);
    }
    let g0 = marschner_gaussian(w_c, 0.0);
    let g_minus = marschner_gaussian(w_c, marschner_wrap(phi - phi_c));
    let g_plus = marschner_gaussian(w_c, marschner_wrap(phi + phi_c));
    let damped = raw * ((1.0 - fade * g_minus / g0) * (1.0 - fade * g_plus / g0));
    let glint = marschner_attenuation(2u, br, m.sigma_a, gamma_c)
        * (fade * m.glint_scale * delta_h * (g_minus + g_plus));
    return damped + glint;
}

// [N_R, N_TT, N_TRT] at sin^2(theta_d), cos(theta_d), |phi| and cos(2 phi_h).
fn marschner_n(
    m: MarschnerModel,
    sin2_theta_d: f32,
    cos_theta_d: f32,
    phi: f32,
    cos_2phi_h: f32,
) -> MarschnerLobes {
    let br = marschner_bravais(m.eta, sin2_theta_d, cos_theta_d);
    let eta_trt = marschner_eta_star(m.eta, m.eccentricity, cos_2phi_h);
    let br_trt = marschner_bravais(eta_trt, sin2_theta_d, cos_theta_d);
    return MarschnerLobes(
        marschner_n_raw(0u, br, m.sigma_a, phi),
        marschner_n_raw(1u, br, m.sigma_a, phi),
        marschner_n_trt(m, br_trt, phi),
    );
}

// The three lobes M_p N_p / cos^2(theta_d) (the scattering function, without cos theta_i).
fn marschner_lobes(m: MarschnerModel, a: FibreAngles) -> MarschnerLobes {
    let mm = marschner_m(m, a.theta_h);
    let n = marschner_n(m, a.sin_theta_d * a.sin_theta_d, a.cos_theta_d, a.phi, a.cos_2phi_h);
    let inv = 1.0 / (a.cos_theta_d * a.cos_theta_d);
    return MarschnerLobes(n.r * (mm.x * inv), n.tt * (mm.y * inv), n.trt * (mm.z * inv));
}

fn marschner_radiance(
    m: MarschnerModel,
    t: vec3<f32>,
    l: vec3<f32>,
    v: vec3<f32>,
    base_color: vec3<f32>,
    strand_random: f32,
) -> vec3<f32> {
    let a = fibre_angles(t, l, v, m.azimuth_jitter * strand_random);
    let lobes = marschner_lobes(m, a);
    return (lobes.r + lobes.tt + lobes.trt + base_color * m.diffuse) * a.cos_theta_i;
}
