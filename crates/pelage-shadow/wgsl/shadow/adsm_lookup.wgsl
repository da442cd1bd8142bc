// Approximated deep shadow maps (TressFX): implements the shadow contract
// (shadow/none.wgsl).
//
// Reads:  @group(1) map_bindings.wgsl (0 to 2, 6) and the mesh shadow map (3 to 5).
// Writes: nothing.
//
// The fibres in front of a point are its depth behind the front-most hair divided by
// the fibre spacing; T = (1 - opacity)^fibres, averaged over the PCF kernel.

#import shadow/map_bindings.wgsl
#import shadow/mesh_shadow.wgsl

fn hair_visibility(p: vec3<f32>) -> f32 {
    let m = map_coords(light_grid_u, light_grid, to_light_space(light_grid_u, p));
    let centre = vec2<i32>(floor(m.xy * vec2<f32>(map_size())));
    let extent = map_depth_extent(light_grid_u, light_grid);
    let per_fibre = log2(max(1.0 - light_grid_u.opacity, 1e-6));
    let r = light_map.pcf_radius;
    var sum = 0.0;
    var taps = 0.0;
    for (var dy = -r; dy <= r; dy++) {
        for (var dx = -r; dx <= r; dx++) {
            let behind = max((m.z - front_depth_at(centre + vec2<i32>(dx, dy))) * extent, 0.0);
            sum += exp2(per_fibre * behind / light_map.fiber_spacing);
            taps += 1.0;
        }
    }
    return sum / taps;
}

fn light_visibility(p: vec3<f32>) -> f32 {
    return hair_visibility(p) * mesh_visibility(p);
}

// A point on the body: the same lookup.
fn surface_visibility(p: vec3<f32>) -> f32 {
    return light_visibility(p);
}
