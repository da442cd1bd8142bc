// The force field of stage 1 (gravity, gusting wind and turbulence for a time t) and the
// uniforms that set it, shared by the two stage 1 passes: strands/grow.wgsl (strands
// grown from a mesh) and strands/groom.wgsl (strands of a groom file, bent by the wind).
//
// Reads:  the frame's GrowUniforms at group 0, binding 0 (GrowUniforms in
//         pelage-strands/src/grow.rs).
// Writes: nothing. Declares the uniforms, their binding and functions; no entry point.
//
// The CPU mirror of these functions is `force` in pelage-reference/src/strands.rs.

#import shared/noise.wgsl

struct GrowUniforms {
    // Strands grown this frame, and in the groom.
    strand_count: u32,
    segments: u32,
    strand_total: u32,
    // Every step-th vertex is written.
    step: u32,
    // Stochastic simplification: lambda, t_e, s_max, s_min.
    lod_lambda: f32,
    lod_t_e: f32,
    lod_s_max: f32,
    lod_s_min: f32,
    // 0 = flat, 1 = PN triangle.
    surface: u32,
    force_weight: f32,
    time: f32,
    gravity: vec3<f32>,
    wind_strength: f32,
    // Unit wind direction (zero for none).
    wind_direction: vec3<f32>,
    gust_strength: f32,
    gust_frequency: f32,
    turbulence: f32,
    turbulence_scale: f32,
    turbulence_speed: f32,
    seed: u32,
    // Spread of per-strand gust phases, seconds.
    phase_spread: f32,
}

@group(0) @binding(0) var<uniform> u: GrowUniforms;

// The part of the force field that is the same along a strand: gravity and the gusting
// wind at time t (already offset by the strand's phase).
fn uniform_force(t: f32) -> vec3<f32> {
    let gust = 1.0 + u.gust_strength * value_noise_1d(t * u.gust_frequency, u.seed ^ 0x9e3779b9u);
    return u.gravity + u.wind_direction * (u.wind_strength * gust);
}

// The force field at point p for time t, given uniform_force(t) as `base`.
fn force(p: vec3<f32>, t: f32, base: vec3<f32>) -> vec3<f32> {
    var f = base;
    if u.turbulence > 0.0 {
        let q = p * u.turbulence_scale - u.wind_direction * (t * u.turbulence_speed);
        let turb = vec3<f32>(
            value_noise_3d(q, u.seed ^ 0x68e31da4u),
            value_noise_3d(q, u.seed ^ 0xb5297a4du),
            value_noise_3d(q, u.seed ^ 0x1b56c4e9u),
        );
        f = f + turb * u.turbulence;
    }
    return f;
}
