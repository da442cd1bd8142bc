// shade/models/marschner_lut.wgsl: builds the lookup tables of Marschner's model (after
// seed 003 section 3.3.4 / Nguyen & Donnelly, GPU Gems 2 ch. 23; digest 002/003 B.1.5) from
// the analytic functions of shade/models/marschner.wgsl, so each table holds exactly the
// analytic values at its texels. Rebuild whenever the model's parameters change.
//
// Reads:  model (MarschnerModel, uniform), info (MarschnerLutInfo: size N, slices K).
// Writes: lut_m  (16N vec4): at theta_h in [-pi/2, pi/2]: xyz = M_R, M_TT, M_TRT, w = 0;
//         lut_n0 (N x N vec4): at (phi in [0, pi], cos theta_d in [0, 1]):
//                 x = N_R, yzw = N_TT (rgb);
//         lut_n1 (N x N x K vec4): at (phi, cos theta_d, cos 2phi_h in [-1, 1]; K = 1 means
//                 cos 2phi_h = 1, a circular fibre): xyz = N_TRT (rgb), w = 0.
//         Texel i of an axis of n texels sits at i/(n-1) of its range (the ends are texel
//         centres); N0/N1 texel (i, j, k) lives at index (k * N + j) * N + i.
// Dispatch: workgroups of 8 x 8 x 1 over (N, 16, 1) for lut_m (row y holds texels y*N..),
//         and over (N, N, 1 + K) at z >= 1: z = 1 fills lut_n0, z = 2 + k slice k of lut_n1.
//         One dispatch of (N/8, N/8 rounded up, 2 + K) workgroups covers both (N >= 16 is
//         needed for the 16 rows of lut_m; MarschnerLut enforces it).
// Deviations from seed 003, measured in crates/pelage-shade/tests/models.rs: M depends on
// theta_h only and is tabulated in 1-D (the singular cos(theta_i)/cos^2(theta_d) factor is
// applied exactly by the lookup, not interpolated); the azimuthal axis is phi, not cos phi
// (cos phi squeezes the R and TRT peaks near phi = 0 and TT near pi into a few texels);
// cos theta_d spans [0, 1]; N_TRT has a third axis for the eccentric fibre.

#import shared/math.wgsl
#import shade/models/fibre.wgsl
#import shade/models/marschner.wgsl

@group(0) @binding(0) var<uniform> model: MarschnerModel;
@group(0) @binding(1) var<uniform> info: MarschnerLutInfo;
@group(0) @binding(2) var<storage, read_write> lut_m: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> lut_n0: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> lut_n1: array<vec4<f32>>;

// Position of texel i of n along [lo, hi] (the ends are texel centres).
fn lut_coordinate(i: u32, n: u32, lo: f32, hi: f32) -> f32 {
    let u = f32(i) / f32(max(n, 2u) - 1u);
    return mix(lo, hi, u);
}

@compute @workgroup_size(8, 8, 1)
fn build(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = info.size;
    if (gid.x >= n || gid.y >= n || gid.z >= 2u + info.slices) {
        return;
    }
    if (gid.z == 0u) {
        if (gid.y < MARSCHNER_LUT_M_ROWS) {
            let i = gid.y * n + gid.x;
            let theta_h = lut_coordinate(i, MARSCHNER_LUT_M_ROWS * n, -0.5 * PI, 0.5 * PI);
            lut_m[i] = vec4<f32>(marschner_m(model, theta_h), 0.0);
        }
        return;
    }
    let texel = gid.y * n + gid.x;
    let phi = lut_coordinate(gid.x, n, 0.0, PI);
    let cos_theta_d = lut_coordinate(gid.y, n, 0.0, 1.0);
    let sin2_theta_d = max((1.0 - cos_theta_d) * (1.0 + cos_theta_d), 0.0);
    if (gid.z == 1u) {
        let br = marschner_bravais(model.eta, sin2_theta_d, cos_theta_d);
        let r = marschner_n_raw(0u, br, model.sigma_a, phi);
        let tt = marschner_n_raw(1u, br, model.sigma_a, phi);
        lut_n0[texel] = vec4<f32>(r.x, tt);
        return;
    }
    let k = gid.z - 2u;
    var cos_2phi_h = 1.0;
    if (info.slices > 1u) {
        cos_2phi_h = lut_coordinate(k, info.slices, -1.0, 1.0);
    }
    let eta_trt = marschner_eta_star(model.eta, model.eccentricity, cos_2phi_h);
    let br = marschner_bravais(eta_trt, sin2_theta_d, cos_theta_d);
    lut_n1[k * n * n + texel] = vec4<f32>(marschner_n_trt(model, br, phi), 0.0);
}
