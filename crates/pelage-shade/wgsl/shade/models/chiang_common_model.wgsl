// The parts of the hair model contract (shade/hair_model.wgsl) that Chiang et al. 2016
// fibres with single scattering (chiang_model.wgsl) and with dual scattering
// (chiang_dual_model.wgsl) share: the fibre's radiance for one light, the ambient term and
// no grid. Each of the two imports this file and adds its own hair_light.
//
// Reads: @group(2) @binding(0..2) the model's parameters and tables (chiang.wgsl).
// Writes: nothing; no entry point.

#import shade/models/chiang.wgsl

fn hair_radiance(t: vec3<f32>, l: vec3<f32>, v: vec3<f32>, base_color: vec3<f32>, strand_random: f32) -> vec3<f32> {
    return chiang_radiance(chiang, t, l, v, base_color, strand_random);
}

// Radiance of the hair under the ambient light, per unit of `frame.ambient`. `ambient` is
// the irradiance the mesh's colour multiplies (a uniform sky of radiance ambient / pi, as
// for a Lambertian mesh of albedo pi * mesh_color), and Chiang's colour is what a dense
// volume of these fibres reflects under uniform light: colour * ambient / pi, the colour
// being the one the fibre's sigma_a stands for (Chiang eq. 9 inverted).
fn hair_ambient(base_color: vec3<f32>) -> vec3<f32> {
    let sigma = chiang_sigma_a(chiang, base_color);
    return exp(-sqrt(sigma) * chiang.color_scale) * INV_PI;
}

// Light that other fibres scattered toward this one and that no term above carries
// (the volume method's orders >= 2), toward v at world position p: none for this model.
fn hair_scattered(t: vec3<f32>, v: vec3<f32>, p: vec3<f32>, base_color: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(0.0);
}
