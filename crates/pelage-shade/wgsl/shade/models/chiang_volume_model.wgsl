// The hair model contract (shade/hair_model.wgsl) implemented by Chiang et al. 2016 fibres
// with the volume method's multiple scattering (`volume`): single scattering per light
// (times stage 2's visibility); the grid (chiang_volume_common_model.wgsl) carries the
// lights' light scattered at least once, the sky's and the body's bounce.
//
// Reads: @group(2) @binding(0..4) (chiang_volume_common_model.wgsl).
// Writes: nothing; no entry point.

#import shade/models/chiang_volume_common_model.wgsl

// Single scattering times the visibility: the grid carries the rest.
fn hair_light(t: vec3<f32>, l: vec3<f32>, v: vec3<f32>, base_color: vec3<f32>, strand_random: f32, visibility: f32) -> vec3<f32> {
    return chiang_radiance(chiang, t, l, v, base_color, strand_random) * visibility;
}
