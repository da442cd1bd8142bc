// Stochastic simplification's width scale (seed 002 eqs. 4.6 and 4.7), the WGSL twin of
// pelage_scene::Transition::scale: change both together. Declares functions only.
//
// s(x) = s_min + (s_max - s_min) * i(x), where i(x) is 1 before the transition zone
// [lambda - t_e, lambda + t_e], 0 after it, and linear inside; x in [0, 1] is a strand's
// place in the (random) priority order.

fn lod_enlargement(x: f32, lambda: f32, t_e: f32) -> f32 {
    if x <= lambda - t_e {
        return 1.0;
    }
    if x >= lambda + t_e {
        return 0.0;
    }
    return (lambda + t_e - x) / (2.0 * t_e);
}

fn lod_scale(x: f32, lambda: f32, t_e: f32, s_max: f32, s_min: f32) -> f32 {
    return s_min + (s_max - s_min) * lod_enlargement(x, lambda, t_e);
}
