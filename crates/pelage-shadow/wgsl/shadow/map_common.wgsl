// Types and helpers shared by the shadow-map methods (deep opacity maps, hair shadow
// map with PCF, ADSM): the map is the fitted LightGrid seen along z, one texel per
// (x, y) cell. Declares structs and functions only. The Rust twin of MapUniforms is
// in pelage-shadow/src/map.rs.

#import shadow/light_common.wgsl

struct MapUniforms {
    // Deep opacity layer ends: absolute depths behind the front-most hair (scene units),
    // or fractions of the hair's depth when ends_are_fractions is 1. Layer `layers - 1`
    // runs to the back.
    ends: array<vec4<f32>, 2>,
    layers: u32,
    ends_are_fractions: u32,
    // PCF kernel radius in texels.
    pcf_radius: i32,
    // Shadow map: a point this far behind the front-most hair is still lit (scene units).
    bias: f32,
    // ADSM: mean distance between fibres along the light (scene units).
    fiber_spacing: f32,
    // Ribbons drawn from the light are at least this many texels wide.
    min_texels: f32,
    _pad0: f32,
    _pad1: f32,
}

// Map coordinates of light-space point ls: xy in [0, 1] across the map (y down, as
// textures are addressed), z = depth in [0, 1] across the hair's depth.
fn map_coords(u: LightGridUniforms, grid: LightGrid, ls: vec3<f32>) -> vec3<f32> {
    let extent = grid.cell * vec3<f32>(f32(u.resolution_x), f32(u.resolution_y), f32(u.resolution_z));
    let f = (ls - grid.origin) / extent;
    return vec3<f32>(f.x, 1.0 - f.y, f.z);
}

// Depth of the fitted grid along the light, scene units.
fn map_depth_extent(u: LightGridUniforms, grid: LightGrid) -> f32 {
    return grid.cell.z * f32(u.resolution_z);
}

// End of deep opacity layer k behind the front-most hair, scene units.
fn layer_end(m: MapUniforms, k: u32, depth_extent: f32) -> f32 {
    if k + 1u >= m.layers {
        return 3.0e38;
    }
    let e = m.ends[k / 4u][k % 4u];
    return select(e, e * depth_extent, m.ends_are_fractions == 1u);
}
