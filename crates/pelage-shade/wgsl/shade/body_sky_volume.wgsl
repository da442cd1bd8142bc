// The body's sky contract (shade/body_sky.wgsl) implemented by the volume method: the
// irradiance on the body read from the grid (shade/volume.wgsl filled it this frame,
// before the mesh pass), so the skin under the hair sees the sky the hair leaves it, and
// with `volume` the lights' light the hair scattered toward it. The path tracer's skin
// sees the same (crates/pelage-reference/src/path_tracer.rs).
//
// With L(w) = (phi + 3 Phi . w) / (4 pi) the radiance travelling along w (the grid's
// order-1 harmonics, volume_common.wgsl), the irradiance on a surface of outward normal n
// from the light arriving (w . n < 0) is
//   E = int_{w.n<0} L(w) |w . n| dw = phi / 4 - Phi . n / 2,
// per channel, never below 0 (an order-1 radiance can ring negative). The sky alone,
// uniform: phi = 4 ambient, Phi = 0, E = ambient; the light the body itself reflects
// (a Lambertian's, phi = 2 pi L, Phi = pi L n) adds nothing. Outside the grid's cube
// (a body larger than the hair) and before the grid is filled: the sky unoccluded.
//
// Reads: @group(2) @binding(3..4) the grid (volume_field.wgsl).
// Writes: nothing; no entry point.

#import shade/models/volume_field.wgsl

fn body_sky(p: vec3<f32>, n: vec3<f32>, ambient: f32) -> vec3<f32> {
    if !volume_filled() || !volume_contains(p) {
        return vec3<f32>(ambient);
    }
    let s = volume_sample(p);
    let half_n = 0.5 * n;
    return max(
        vec3<f32>(0.0),
        vec3<f32>(
            0.25 * s.r.x - dot(s.r.yzw, half_n),
            0.25 * s.g.x - dot(s.g.yzw, half_n),
            0.25 * s.b.x - dot(s.b.yzw, half_n),
        ),
    );
}
