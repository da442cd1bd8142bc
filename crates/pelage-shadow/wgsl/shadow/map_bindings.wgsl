// The resources every shadow-map lookup binds at @group(1): bindings 0 to 2 and 6
// (3 to 5 are the mesh shadow map's, see mesh_shadow.wgsl), and the front-most
// depth fetch they share. Declares bindings and functions only.

#import shadow/map_common.wgsl

@group(1) @binding(0) var<uniform> light_grid_u: LightGridUniforms;
@group(1) @binding(1) var<storage, read> light_grid: LightGrid;
@group(1) @binding(2) var<uniform> light_map: MapUniforms;
// A depth texture bound as unfilterable float (WebGPU allows it): textureLoad from a
// texture_depth_2d has no GLSL translation, so that form would not run on GL.
@group(1) @binding(6) var light_front_depth: texture_2d<f32>;

// The 2x2 texels around map position `m` (in texels) and their bilinear weights.
struct Footprint {
    texel: vec2<i32>,
    f: vec2<f32>,
}

fn footprint(m: vec2<f32>) -> Footprint {
    let c = m - 0.5;
    return Footprint(vec2<i32>(floor(c)), c - floor(c));
}

fn map_size() -> vec2<i32> {
    return vec2<i32>(textureDimensions(light_front_depth));
}

// Front-most hair depth (map units) at a texel, clamped to the map; 1 (nothing) outside.
fn front_depth_at(t: vec2<i32>) -> f32 {
    let size = map_size();
    if any(t < vec2<i32>(0)) || any(t >= size) {
        return 1.0;
    }
    return textureLoad(light_front_depth, t, 0).r;
}
