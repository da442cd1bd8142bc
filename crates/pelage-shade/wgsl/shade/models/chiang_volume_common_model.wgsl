// What the two models that read the volume method's grid share (the hair model contract,
// shade/hair_model.wgsl, for Chiang et al. 2016 fibres): hair_radiance, hair_ambient and
// hair_scattered, the fibre's response to the light in the grid the passes of
// shade/volume.wgsl filled this frame: the sky's light (orders >= 1; the sky's order 1 is
// the grid's unscattered sky, so hair_ambient is zero), the light the body reflects, and
// with `volume` the lights' light scattered at least once (with the fibre's own
// scattering, orders >= 2). Each model imports this file and adds its own hair_light:
// chiang_volume_model.wgsl (single scattering) and chiang_dual_volume_model.wgsl (dual
// scattering, which then carries the lights' scattering instead of the grid).
//
// Reads: @group(2) @binding(0..2) the model's parameters and tables (chiang.wgsl),
//        @group(2) @binding(3..4) the grid's uniform and fluence (volume_field.wgsl).
// Writes: nothing; no entry point.
//
// Response: with L(w) = (phi + 3 Phi . w) / (4 pi) the radiance travelling along w, read
// trilinearly at p, the light leaving toward v is, by reciprocity, the light the fibre
// would scatter from v weighed by the incoming radiance:
//   L_o = A(theta_v) / (4 pi) (phi + 3 Phi' . q),  q = t (t.v) + g(theta_v) (v - t (t.v))
// per channel (A and g of the fibre's own sigma_a, volume_common.wgsl), Phi' the flux
// shortened to |Phi'| <= phi / 3 (volume_response: order-1 harmonics ring negative
// beyond that, and a clamp at zero would lose the light the fibre scatters backward).

#import shade/models/chiang.wgsl
#import shade/models/volume_common.wgsl
#import shade/models/volume_field.wgsl

fn hair_radiance(t: vec3<f32>, l: vec3<f32>, v: vec3<f32>, base_color: vec3<f32>, strand_random: f32) -> vec3<f32> {
    return chiang_radiance(chiang, t, l, v, base_color, strand_random);
}

// None: the grid carries all of the sky's light (shade/volume.wgsl's injection), its
// single scattering included (hair_scattered reads the sky's unscattered fluence and flux,
// shadowed by the grid's hair and body, so root occlusion does not apply).
fn hair_ambient(base_color: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(0.0);
}

fn hair_scattered(t: vec3<f32>, v: vec3<f32>, p: vec3<f32>, base_color: vec3<f32>) -> vec3<f32> {
    if !volume_filled() {
        return vec3<f32>(0.0);
    }
    let s = volume_sample(p);
    let x = volume_sigma_coordinates(chiang_sigma_a(chiang, base_color));
    let sin_o = clamp(dot(t, v), -1.0, 1.0);
    let cos_o = min(length(cross(t, v)), 1.0);
    let fibre = volume_fibre_at(fibre_angle(abs(sin_o), cos_o), x);
    let along = t * sin_o;
    let across = v - along;
    let qr = along + fibre.g.x * across;
    let qg = along + fibre.g.y * across;
    let qb = along + fibre.g.z * across;
    let radiance = vec3<f32>(
        volume_response(s.r, qr),
        volume_response(s.g, qg),
        volume_response(s.b, qb),
    );
    return fibre.albedo * radiance * (0.25 * INV_PI);
}

// phi + 3 Phi' . q, with Phi' the flux shortened to at most phi / 3 where it is longer:
// the longest flux an order-1 radiance (phi + 3 Phi . w) / (4 pi) has without going
// negative in some direction. Energy (phi) is kept; only the direction is softened, so
// the response is never clamped (|q| <= 1).
fn volume_response(c: vec4<f32>, q: vec3<f32>) -> f32 {
    let phi = max(c.x, 0.0);
    let len = length(c.yzw);
    let flux = select(c.yzw, c.yzw * (phi / (3.0 * len)), 3.0 * len > phi);
    return max(0.0, phi + 3.0 * dot(flux, q));
}
