// shared/bounds.wgsl: the bounds fit every grid over the hair shares (pelage-shadow's
// light-space grids, shadow/light_fit.wgsl, and the volume method's grid,
// pelage-shade's shade/volume.wgsl): each invocation keeps the largest order-preserving
// key of its points' coordinates and of their inverses (the smallest), a workgroup of
// 256 reduces them, and invocation 0 adds them to 6 u32 atomics with atomicMax (the
// importer's binding). Declares functions and two workgroup arrays; no bindings.

// Maps f32 to u32 so that unsigned order equals float order (NaN aside).
fn order_key(f: f32) -> u32 {
    let b = bitcast<u32>(f);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn from_order_key(k: u32) -> f32 {
    return bitcast<f32>(select(~k, k & 0x7fffffffu, (k & 0x80000000u) != 0u));
}

// The largest key of each coordinate (hi) and of each inverted key (lo: the smallest).
struct BoundsKeys {
    hi: vec3<u32>,
    lo: vec3<u32>,
}

fn bounds_empty() -> BoundsKeys {
    return BoundsKeys(vec3<u32>(0u), vec3<u32>(0u));
}

fn bounds_add(b: BoundsKeys, p: vec3<f32>) -> BoundsKeys {
    let k = vec3<u32>(order_key(p.x), order_key(p.y), order_key(p.z));
    return BoundsKeys(max(b.hi, k), max(b.lo, ~k));
}

var<workgroup> bounds_wg_max: array<vec3<u32>, 256>;
var<workgroup> bounds_wg_min: array<vec3<u32>, 256>;

// The keys over a workgroup of 256 invocations (every one must call it: it has
// barriers); `lid` the local invocation index.
fn bounds_reduce(lid: u32, b: BoundsKeys) -> BoundsKeys {
    bounds_wg_max[lid] = b.hi;
    bounds_wg_min[lid] = b.lo;
    workgroupBarrier();
    for (var stride = 128u; stride > 0u; stride >>= 1u) {
        if lid < stride {
            bounds_wg_max[lid] = max(bounds_wg_max[lid], bounds_wg_max[lid + stride]);
            bounds_wg_min[lid] = max(bounds_wg_min[lid], bounds_wg_min[lid + stride]);
        }
        workgroupBarrier();
    }
    return BoundsKeys(bounds_wg_max[0], bounds_wg_min[0]);
}

// The box's lowest corner from the atomics' three inverted keys.
fn bounds_lo(lo: vec3<u32>) -> vec3<f32> {
    return vec3<f32>(from_order_key(~lo.x), from_order_key(~lo.y), from_order_key(~lo.z));
}

// The box's highest corner from the atomics' three keys.
fn bounds_hi(hi: vec3<u32>) -> vec3<f32> {
    return vec3<f32>(from_order_key(hi.x), from_order_key(hi.y), from_order_key(hi.z));
}
