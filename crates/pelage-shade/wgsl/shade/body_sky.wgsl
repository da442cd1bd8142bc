// The body's sky contract: `body_sky(p, n, ambient)`, the irradiance (per channel) on the
// body at world point p, of outward unit normal n, from the sky whose irradiance on an
// open plane is `ambient` (frame.ambient), with whatever light the hair scatters toward
// the body that the lights' own terms (mesh.wgsl) leave out. This file is the default:
// the sky unoccluded, `ambient`. shade/mesh.wgsl imports it; the volume method redirects
// it to shade/body_sky_volume.wgsl (the sky through the hair, from its grid; `Common` in
// crates/pelage-shade/src/draw.rs binds the hair model's group 2 for it).
//
// Reads: nothing. Writes: nothing; no entry point.

fn body_sky(p: vec3<f32>, n: vec3<f32>, ambient: f32) -> vec3<f32> {
    return vec3<f32>(ambient);
}
