// The hair model contract (shade/hair_model.wgsl) implemented by Marschner et al. 2003,
// evaluated analytically (shade/models/marschner.wgsl).
//
// Reads: @group(2) @binding(0) the model's parameters (uniform MarschnerModel).
// Writes: nothing; no entry point.

#import shade/models/marschner.wgsl

@group(2) @binding(0) var<uniform> hair_model: MarschnerModel;

fn hair_radiance(t: vec3<f32>, l: vec3<f32>, v: vec3<f32>, base_color: vec3<f32>, strand_random: f32) -> vec3<f32> {
    return marschner_radiance(hair_model, t, l, v, base_color, strand_random);
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
