// The hair model contract (shade/hair_model.wgsl) implemented by Chiang et al. 2016 fibres
// with dual scattering (Zinke 2008, shade/models/chiang.wgsl's chiang_dual_radiance) from
// stage 2's visibility. Single scattering is shade/models/chiang_model.wgsl.
//
// Reads: @group(2) @binding(0..2) the model's parameters and tables (chiang.wgsl).
// Writes: nothing; no entry point.

#import shade/models/chiang_common_model.wgsl

// Dual scattering: the light stage 2 sees reaching the strand, through the hair in front.
fn hair_light(t: vec3<f32>, l: vec3<f32>, v: vec3<f32>, base_color: vec3<f32>, strand_random: f32, visibility: f32) -> vec3<f32> {
    return chiang_dual_radiance(chiang, t, l, v, base_color, visibility);
}
