// Hair shadow map with PCF: implements the shadow contract (shadow/none.wgsl).
//
// Reads:  @group(1) map_bindings.wgsl (0 to 2, 6) and the mesh shadow map (3 to 5).
// Writes: nothing.
//
// The hair is treated as opaque: a point more than `bias` behind the front-most hair
// of a texel is in shadow. PCF averages that test over (2r + 1)^2 texels.

#import shadow/map_bindings.wgsl
#import shadow/mesh_shadow.wgsl

fn hair_visibility(p: vec3<f32>) -> f32 {
    let m = map_coords(light_grid_u, light_grid, to_light_space(light_grid_u, p));
    let centre = vec2<i32>(floor(m.xy * vec2<f32>(map_size())));
    let extent = map_depth_extent(light_grid_u, light_grid);
    let r = light_map.pcf_radius;
    var lit = 0.0;
    var taps = 0.0;
    for (var dy = -r; dy <= r; dy++) {
        for (var dx = -r; dx <= r; dx++) {
            let behind = (m.z - front_depth_at(centre + vec2<i32>(dx, dy))) * extent;
            lit += select(0.0, 1.0, behind <= light_map.bias);
            taps += 1.0;
        }
    }
    return lit / taps;
}

fn light_visibility(p: vec3<f32>) -> f32 {
    return hair_visibility(p) * mesh_visibility(p);
}

// A point on the body: the same test (the body lies behind the front-most hair).
fn surface_visibility(p: vec3<f32>) -> f32 {
    return light_visibility(p);
}
