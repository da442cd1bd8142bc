// Voxel shadows, lookup: implements the shadow contract (shadow/none.wgsl) for the
// shading passes, which redirect their import of shadow/none.wgsl here.
//
// Reads:  @group(1): LightGridUniforms (0), LightGrid (1), the scanned optical depth
//         volume as f32 (2), and the mesh shadow map (3 to 5, shadow/mesh_shadow.wgsl).
// Writes: nothing.
//
// light_visibility(p) = exp(-optical depth of the hair toward the light) x mesh visibility;
// surface_visibility(p) the same without the bias below.
// The optical depth is interpolated trilinearly: bilinear across the light between
// column centres, linear along it between layer faces, read `bias_voxels` voxels toward
// the light so a strand does not shadow itself. Outside the grid's columns it is 0;
// behind the hair it is the column's total.

#import shadow/light_common.wgsl
#import shadow/mesh_shadow.wgsl

@group(1) @binding(0) var<uniform> voxel: LightGridUniforms;
@group(1) @binding(1) var<storage, read> voxel_grid: LightGrid;
@group(1) @binding(2) var<storage, read> voxel_depth: array<f32>;

// Optical depth stored at column (x, y), face z; 0 outside the columns, faces clamped.
fn voxel_face(x: i32, y: i32, z: i32) -> f32 {
    if x < 0 || y < 0 || x >= i32(voxel.resolution_x) || y >= i32(voxel.resolution_y) {
        return 0.0;
    }
    let zc = clamp(z, 0, i32(voxel.resolution_z));
    return voxel_depth[voxel_index(voxel, u32(x), u32(y), u32(zc))];
}

// Optical depth of the hair between the light and world point p moved `bias` voxels
// toward the light.
fn voxel_optical_depth(p: vec3<f32>, bias: f32) -> f32 {
    let g = (to_light_space(voxel, p) - voxel_grid.origin) * voxel_grid.inv_cell;
    let c = vec3<f32>(g.x - 0.5, g.y - 0.5, g.z - bias);
    let base = vec3<i32>(floor(c));
    let f = c - floor(c);
    var tau = 0.0;
    for (var corner = 0u; corner < 8u; corner++) {
        let o = vec3<i32>(i32(corner & 1u), i32((corner >> 1u) & 1u), i32((corner >> 2u) & 1u));
        let w = select(1.0 - f.x, f.x, o.x == 1) * select(1.0 - f.y, f.y, o.y == 1) * select(1.0 - f.z, f.z, o.z == 1);
        tau += w * voxel_face(base.x + o.x, base.y + o.y, base.z + o.z);
    }
    return tau;
}

fn light_visibility(p: vec3<f32>) -> f32 {
    return exp(-voxel_optical_depth(p, voxel.bias_voxels)) * mesh_visibility(p);
}

// A point on the body: no strand of its own to skip, all the hair in front counts (with
// the bias, the skin under a layer of hair `bias_voxels` thick would see the light
// unshadowed).
fn surface_visibility(p: vec3<f32>) -> f32 {
    return exp(-voxel_optical_depth(p, 0.0)) * mesh_visibility(p);
}
