// Deep opacity maps (Yuksel and Keyser 2008): implements the shadow contract
// (shadow/none.wgsl).
//
// Reads:  @group(1) map_bindings.wgsl (0 to 2, 6), the mesh shadow map (3 to 5) and
//         the opacity layers (7: layers 0 to 3, 8: layers 4 to 7).
// Writes: nothing.
//
// Channel k of a texel holds the opacity accumulated up to the end of layer k. A point
// in layer k interpolates between the accumulation at the start of its layer (the end
// of layer k - 1, or 0) and at its end, by its depth within the layer: the digest's
// correction of seed 000, which read the layer's own value. The last layer is taken to
// end at the back of the grid fitted to the hair. T = exp(-opacity), the
// same Poisson model as the voxel method, bilinear over 2x2 texels.

#import shadow/map_bindings.wgsl
#import shadow/mesh_shadow.wgsl

@group(1) @binding(7) var light_layers_0: texture_2d<f32>;
@group(1) @binding(8) var light_layers_1: texture_2d<f32>;

fn accumulated(t: vec2<i32>, k: u32) -> f32 {
    if k < 4u {
        return textureLoad(light_layers_0, t, 0)[k];
    }
    return textureLoad(light_layers_1, t, 0)[k - 4u];
}

// Opacity in front of map depth z at texel t.
fn opacity_at(t: vec2<i32>, z: f32) -> f32 {
    let size = map_size();
    if any(t < vec2<i32>(0)) || any(t >= size) {
        return 0.0;
    }
    let extent = map_depth_extent(light_grid_u, light_grid);
    let behind = (z - textureLoad(light_front_depth, t, 0).r) * extent;
    if behind <= 0.0 {
        return 0.0;
    }
    var k = 0u;
    while k + 1u < light_map.layers && behind >= layer_end(light_map, k, extent) {
        k += 1u;
    }
    var start = 0.0;
    var before = 0.0;
    if k > 0u {
        start = layer_end(light_map, k - 1u, extent);
        before = accumulated(t, k - 1u);
    }
    // The last layer runs to the back of the fitted grid.
    let back = (1.0 - textureLoad(light_front_depth, t, 0).r) * extent;
    let end = select(layer_end(light_map, k, extent), back, k + 1u >= light_map.layers);
    let f = clamp((behind - start) / max(end - start, 1e-12), 0.0, 1.0);
    return mix(before, accumulated(t, k), f);
}

fn hair_visibility(p: vec3<f32>) -> f32 {
    let m = map_coords(light_grid_u, light_grid, to_light_space(light_grid_u, p));
    let fp = footprint(m.xy * vec2<f32>(map_size()));
    let o00 = opacity_at(fp.texel, m.z);
    let o10 = opacity_at(fp.texel + vec2<i32>(1, 0), m.z);
    let o01 = opacity_at(fp.texel + vec2<i32>(0, 1), m.z);
    let o11 = opacity_at(fp.texel + vec2<i32>(1, 1), m.z);
    let o = mix(mix(o00, o10, fp.f.x), mix(o01, o11, fp.f.x), fp.f.y);
    return exp(-o);
}

fn light_visibility(p: vec3<f32>) -> f32 {
    return hair_visibility(p) * mesh_visibility(p);
}

// A point on the body: the same lookup (the layers hold the opacity in front of any
// depth; nothing is skipped).
fn surface_visibility(p: vec3<f32>) -> f32 {
    return light_visibility(p);
}
