// shade/models/marschner_lut_lookup.wgsl: Marschner's model read from the lookup tables
// built by shade/models/marschner_lut.wgsl (seed 003 Algorithm 2, with linear, bilinear and
// trilinear filtering done by hand on storage buffers).
// Pure functions plus the tables' bindings, no entry point. A shading pass that includes it
// binds `MarschnerLut` (crates/pelage-shade/src/models.rs) at group 2:
//
// Reads:  @group(2) @binding(0) marschner_lut_m    (storage, 16N vec4: M over theta_h)
//         @group(2) @binding(1) marschner_lut_n0   (storage, N x N vec4: N_R, N_TT)
//         @group(2) @binding(2) marschner_lut_n1   (storage, N x N x K vec4: N_TRT)
//         @group(2) @binding(3) marschner_lut_info (uniform MarschnerLutInfo)
// Writes: nothing.
//
// marschner_radiance_lut has the shape and meaning of marschner_radiance (radiance toward v
// for a light of unit irradiance from l, diffuse term included): the angles are computed as
// in the analytic path, the factor cos(theta_i) / cos^2(theta_d) exactly, and only M_p and
// N_p come from the tables. `m` should hold the parameters the tables were built from
// (only its azimuth_jitter and diffuse are read here).

#import shared/math.wgsl
#import shade/models/fibre.wgsl
#import shade/models/marschner.wgsl

@group(2) @binding(0) var<storage, read> marschner_lut_m: array<vec4<f32>>;
@group(2) @binding(1) var<storage, read> marschner_lut_n0: array<vec4<f32>>;
@group(2) @binding(2) var<storage, read> marschner_lut_n1: array<vec4<f32>>;
@group(2) @binding(3) var<uniform> marschner_lut_info: MarschnerLutInfo;

// Continuous texel coordinate of x in [lo, hi] over n texels: (index, fraction).
fn marschner_lut_axis(x: f32, lo: f32, hi: f32, n: u32) -> vec2<f32> {
    let last = f32(max(n, 2u) - 1u);
    let u = clamp((x - lo) / (hi - lo), 0.0, 1.0) * last;
    let i = min(floor(u), last - 1.0);
    return vec2<f32>(i, u - i);
}

// [M_R, M_TT, M_TRT] at theta_h.
fn marschner_lut_m_at(theta_h: f32) -> vec3<f32> {
    let count = MARSCHNER_LUT_M_ROWS * marschner_lut_info.size;
    let ax = marschner_lut_axis(theta_h, -0.5 * PI, 0.5 * PI, count);
    let i = u32(ax.x);
    return mix(marschner_lut_m[i], marschner_lut_m[i + 1u], ax.y).xyz;
}

// (N_R, N_TT) at phi in [0, pi] and cos theta_d.
fn marschner_lut_n0_at(phi: f32, cos_theta_d: f32) -> vec4<f32> {
    let n = marschner_lut_info.size;
    let ax = marschner_lut_axis(phi, 0.0, PI, n);
    let ay = marschner_lut_axis(cos_theta_d, 0.0, 1.0, n);
    let i = u32(ax.x) + u32(ay.x) * n;
    let a = mix(marschner_lut_n0[i], marschner_lut_n0[i + 1u], ax.y);
    let b = mix(marschner_lut_n0[i + n], marschner_lut_n0[i + n + 1u], ax.y);
    return mix(a, b, ay.y);
}

fn marschner_lut_n1_slice(first: u32, ax: vec2<f32>, ay: vec2<f32>) -> vec4<f32> {
    let n = marschner_lut_info.size;
    let i = first + u32(ax.x) + u32(ay.x) * n;
    let a = mix(marschner_lut_n1[i], marschner_lut_n1[i + 1u], ax.y);
    let b = mix(marschner_lut_n1[i + n], marschner_lut_n1[i + n + 1u], ax.y);
    return mix(a, b, ay.y);
}

// N_TRT at phi, cos theta_d and cos 2phi_h.
fn marschner_lut_n1_at(phi: f32, cos_theta_d: f32, cos_2phi_h: f32) -> vec3<f32> {
    let n = marschner_lut_info.size;
    let ax = marschner_lut_axis(phi, 0.0, PI, n);
    let ay = marschner_lut_axis(cos_theta_d, 0.0, 1.0, n);
    let slices = marschner_lut_info.slices;
    if (slices <= 1u) {
        return marschner_lut_n1_slice(0u, ax, ay).xyz;
    }
    let az = marschner_lut_axis(cos_2phi_h, -1.0, 1.0, slices);
    let k = u32(az.x);
    let a = marschner_lut_n1_slice(k * n * n, ax, ay);
    let b = marschner_lut_n1_slice((k + 1u) * n * n, ax, ay);
    return mix(a, b, az.y).xyz;
}

fn marschner_radiance_lut(
    m: MarschnerModel,
    t: vec3<f32>,
    l: vec3<f32>,
    v: vec3<f32>,
    base_color: vec3<f32>,
    strand_random: f32,
) -> vec3<f32> {
    let a = fibre_angles(t, l, v, m.azimuth_jitter * strand_random);
    let mm = marschner_lut_m_at(a.theta_h) * (a.cos_theta_i / (a.cos_theta_d * a.cos_theta_d));
    let n0 = marschner_lut_n0_at(a.phi, a.cos_theta_d);
    let n1 = marschner_lut_n1_at(a.phi, a.cos_theta_d, a.cos_2phi_h);
    return mm.x * vec3<f32>(n0.x) + mm.y * n0.yzw + mm.z * n1 + base_color * (m.diffuse * a.cos_theta_i);
}
