// The per-strand record stage 1 writes (StrandRoot in pelage-contract/src/strands.rs)
// and every later stage reads. Declares a struct only.

struct StrandRoot {
    triangle: u32,
    seed: u32,
    bary: vec2<f32>,
    length: f32,
    width: f32,
    // Gust phase as a fraction of phase_spread, in [0, 1).
    phase: f32,
    // Root direction jitter: tilt angle (radians) and azimuth (radians).
    tilt: f32,
    azimuth: f32,
    color: vec3<f32>,
    // The strand's region (0 = the base growth parameters); grow.wgsl reads its shape.
    region: u32,
}
