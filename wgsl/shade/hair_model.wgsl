// The hair model contract: `hair_radiance(t, l, v, base_color, strand_random)`, the
// radiance toward v for a light of unit irradiance from l (both pointing away from
// the fibre). This file is the default implementation, Kajiya-Kay; a pass that
// imports it can be redirected to shade/models/marschner_model.wgsl,
// marschner_lut_model.wgsl or sadeghi_model.wgsl (HairModel in
// crates/pelage-shade/src/models.rs picks one and binds its resources).
//
// Reads: @group(2) @binding(0) the model's parameters (uniform KajiyaKayModel).
// Writes: nothing; no entry point.

#import shade/models/kajiya_kay.wgsl

@group(2) @binding(0) var<uniform> hair_model: KajiyaKayModel;

fn hair_radiance(t: vec3<f32>, l: vec3<f32>, v: vec3<f32>, base_color: vec3<f32>, strand_random: f32) -> vec3<f32> {
    return kajiya_kay_radiance(hair_model, t, l, v, base_color, strand_random);
}
