// The hair model contract (shade/hair_model.wgsl) implemented by Chiang et al. 2016 fibres
// with `dual_volume`: dual scattering per light (Zinke 2008, chiang.wgsl's
// chiang_dual_radiance, from stage 2's visibility) carries what the lights' light does in
// the hair, forward and back; the grid (chiang_volume_common_model.wgsl, its injection of
// the fibres' scattering of the lights weighted 0) carries the sky's light and the body's
// bounce.
//
// Reads: @group(2) @binding(0..4) (chiang_volume_common_model.wgsl).
// Writes: nothing; no entry point.

#import shade/models/chiang_volume_common_model.wgsl

// Dual scattering: the light stage 2 sees reaching the strand, through the hair in front.
fn hair_light(t: vec3<f32>, l: vec3<f32>, v: vec3<f32>, base_color: vec3<f32>, strand_random: f32, visibility: f32) -> vec3<f32> {
    return chiang_dual_radiance(chiang, t, l, v, base_color, visibility);
}
