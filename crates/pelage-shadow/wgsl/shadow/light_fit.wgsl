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

@group(0) @binding(0) var<uniform> u: LightGridUniforms;
@group(0) @binding(1) var<storage, read> vertices: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> bounds: array<atomic<u32>, 6>;
@group(0) @binding(3) var<storage, read_write> grid: LightGrid;

// Maps f32 to u32 so that unsigned order equals float order (NaN aside).
fn order_key(f: f32) -> u32 {
    let b = bitcast<u32>(f);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn from_order_key(k: u32) -> f32 {
    return bitcast<f32>(select(~k, k & 0x7fffffffu, (k & 0x80000000u) != 0u));
}

var<workgroup> wg_max: array<vec3<u32>, 256>;
var<workgroup> wg_min: array<vec3<u32>, 256>;

@compute @workgroup_size(256)
fn fit(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    var hi = vec3<u32>(0u);
    var lo = vec3<u32>(0u);
    for (var i = gid.x; i < u.vertex_count; i += u.fit_invocations) {
        let p = to_light_space(u, vertices[i].xyz);
        let k = vec3<u32>(order_key(p.x), order_key(p.y), order_key(p.z));
        hi = max(hi, k);
        lo = max(lo, ~k);
    }
    wg_max[lid] = hi;
    wg_min[lid] = lo;
    workgroupBarrier();
    for (var stride = 128u; stride > 0u; stride >>= 1u) {
        if lid < stride {
            wg_max[lid] = max(wg_max[lid], wg_max[lid + stride]);
            wg_min[lid] = max(wg_min[lid], wg_min[lid + stride]);
        }
        workgroupBarrier();
    }
    if lid == 0u {
        atomicMax(&bounds[0], wg_max[0].x);
        atomicMax(&bounds[1], wg_max[0].y);
        atomicMax(&bounds[2], wg_max[0].z);
        atomicMax(&bounds[3], wg_min[0].x);
        atomicMax(&bounds[4], wg_min[0].y);
        atomicMax(&bounds[5], wg_min[0].z);
    }
}

@compute @workgroup_size(1)
fn finalize() {
    let hi = vec3<f32>(
        from_order_key(atomicLoad(&bounds[0])),
        from_order_key(atomicLoad(&bounds[1])),
        from_order_key(atomicLoad(&bounds[2])),
    );
    let lo = vec3<f32>(
        from_order_key(~atomicLoad(&bounds[3])),
        from_order_key(~atomicLoad(&bounds[4])),
        from_order_key(~atomicLoad(&bounds[5])),
    );
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
