// Every light-space shadow method, pass 1: fit the grid (or map) to the hair's
// light-space bounds, on the GPU.
//
// Reads:  LightGridUniforms, the strand vertices (vec4, xyz = position).
// Writes: `bounds` (6 x atomic<u32>, cleared to 0 before the pass): max of the
//         order-preserving key of x, y, z, then max of the inverted key (= min) of x, y, z;
//         `grid` (LightGrid) from the `finalize` entry point.
// Dispatch: `fit` with fit_invocations / 256 workgroups of 256 (a grid-stride loop
//         covers every vertex), then `finalize` with one workgroup of 1.

#import shadow/light_common.wgsl
#import shared/bounds.wgsl

@group(0) @binding(0) var<uniform> u: LightGridUniforms;
@group(0) @binding(1) var<storage, read> vertices: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> bounds: array<atomic<u32>, 6>;
@group(0) @binding(3) var<storage, read_write> grid: LightGrid;

@compute @workgroup_size(256)
fn fit(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    var keys = bounds_empty();
    for (var i = gid.x; i < u.vertex_count; i += u.fit_invocations) {
        keys = bounds_add(keys, to_light_space(u, vertices[i].xyz));
    }
    let all_keys = bounds_reduce(lid, keys);
    if lid == 0u {
        atomicMax(&bounds[0], all_keys.hi.x);
        atomicMax(&bounds[1], all_keys.hi.y);
        atomicMax(&bounds[2], all_keys.hi.z);
        atomicMax(&bounds[3], all_keys.lo.x);
        atomicMax(&bounds[4], all_keys.lo.y);
        atomicMax(&bounds[5], all_keys.lo.z);
    }
}

@compute @workgroup_size(1)
fn finalize() {
    let hi = bounds_hi(vec3<u32>(atomicLoad(&bounds[0]), atomicLoad(&bounds[1]), atomicLoad(&bounds[2])));
    let lo = bounds_lo(vec3<u32>(atomicLoad(&bounds[3]), atomicLoad(&bounds[4]), atomicLoad(&bounds[5])));
    var origin = lo - vec3<f32>(u.padding);
    var extent = hi - lo + vec3<f32>(2.0 * u.padding);
    // No vertices (or non-finite ones): a harmless unit grid at the origin.
    if u.vertex_count == 0u || !(all(extent >= vec3<f32>(0.0)) && all(extent < vec3<f32>(1e30))) {
        origin = vec3<f32>(0.0);
        extent = vec3<f32>(1.0);
    }
    let res = vec3<f32>(f32(u.resolution_x), f32(u.resolution_y), f32(u.resolution_z));
    let cell = max(extent / res, vec3<f32>(u.min_cell));
    // Centre the grid on the hair when min_cell made it larger than the bounds.
    grid.origin = origin - 0.5 * (cell * res - extent);
    grid.cell = cell;
    grid.inv_cell = 1.0 / cell;
}
