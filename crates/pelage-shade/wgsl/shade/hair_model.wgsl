// The hair model contract: `hair_radiance(t, l, v, base_color, strand_random)`, the
// radiance toward v for a light of unit irradiance from l (both pointing away from
// the fibre), and `hair_light(t, l, v, base_color, strand_random, visibility)`, the same
// for light that stage 2 sees reaching the fibre with `visibility` in [0, 1]: the
// single-scattering models multiply, a model with multiple scattering (Chiang's with dual
// scattering) estimates from it the fibres in front and the light they scatter forward;
// `hair_ambient(base_color)`, the hair's radiance per unit of `frame.ambient`; and
// `hair_scattered(t, v, p, base_color)`, light other fibres scattered toward this one that
// the per-light terms do not carry (Chiang's volume method; zero for the others). This
// file is the default implementation, Kajiya-Kay; a pass that
// imports it can be redirected to shade/models/marschner_model.wgsl,
// marschner_lut_model.wgsl, sadeghi_model.wgsl, chiang_model.wgsl or
// chiang_volume_model.wgsl (HairModel in
// crates/pelage-shade/src/models.rs picks one and binds its resources).
//
// Reads: @group(2) @binding(0) the model's parameters (uniform KajiyaKayModel).
// Writes: nothing; no entry point.

#import shade/models/kajiya_kay.wgsl

@group(2) @binding(0) var<uniform> hair_model: KajiyaKayModel;

fn hair_radiance(t: vec3<f32>, l: vec3<f32>, v: vec3<f32>, base_color: vec3<f32>, strand_random: f32) -> vec3<f32> {
    return kajiya_kay_radiance(hair_model, t, l, v, base_color, strand_random);
}

// Light from l reaching the fibre with stage 2's `visibility`: single scattering, shadowed.
fn hair_light(t: vec3<f32>, l: vec3<f32>, v: vec3<f32>, base_color: vec3<f32>, strand_random: f32, visibility: f32) -> vec3<f32> {
    return hair_radiance(t, l, v, base_color, strand_random) * visibility;
}

// Radiance of the hair under the ambient light, per unit of `frame.ambient`: the strand's
// colour (an artistic model: `ambient` is a fraction of the base colour, as it always was).
fn hair_ambient(base_color: vec3<f32>) -> vec3<f32> {
    return base_color;
}

// Light that other fibres scattered toward this one and that no term above carries
// (the volume method's orders >= 2), toward v at world position p: none for this model.
fn hair_scattered(t: vec3<f32>, v: vec3<f32>, p: vec3<f32>, base_color: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(0.0);
}
