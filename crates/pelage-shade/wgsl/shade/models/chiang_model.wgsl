// The hair model contract (shade/hair_model.wgsl) implemented by Chiang et al. 2016 fibres
// with single scattering (shade/models/chiang.wgsl). With dual scattering a hair pass binds
// shade/models/chiang_dual_model.wgsl instead: a shader holding both paths behind a uniform
// branch ran both on lavapipe (the opaque MSAA hair pass took 2x).
//
// Reads: @group(2) @binding(0..2) the model's parameters and tables (chiang.wgsl).
// Writes: nothing; no entry point.

#import shade/models/chiang_common_model.wgsl

// Single scattering times stage 2's visibility.
fn hair_light(t: vec3<f32>, l: vec3<f32>, v: vec3<f32>, base_color: vec3<f32>, strand_random: f32, visibility: f32) -> vec3<f32> {
    return chiang_radiance(chiang, t, l, v, base_color, strand_random) * visibility;
}
