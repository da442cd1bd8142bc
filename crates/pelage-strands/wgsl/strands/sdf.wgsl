// A signed distance field of the mesh on a grid of nodes (BodySdf, pelage-strands/src/sdf.rs),
// rebuilt from the mesh buffers by five entry points recorded in one compute pass:
//  1. clear (per node): distance bits to FAR_BITS, nearest triangle to none (0);
//  2. splat_distance (per triangle): the exact distance from the triangle to every node of
//     its box grown by `band` cells, atomicMin on the distance's bits (non-negative floats
//     order as their bit patterns do);
//  3. splat_nearest (per triangle): the same nodes again; where this triangle's distance is
//     the minimum (within NEAREST_ULPS), atomicMax on its index + 1, so ties go to the
//     highest index and the field is the same run after run;
//  4. jfa (per node, once per step, steps halving from the largest power of two below the
//     longest axis to 1, then 1 again: "JFA+1"): the nearest of the triangles the node and
//     its 26 neighbours `step` nodes away hold, by exact distance;
//  5. finish (per node): the exact distance to the triangle found, negative inside: inside
//     where (node - nearest point) points against the mesh's normal at the nearest point
//     (the vertex normals interpolated there: the face's side in its interior, the
//     smoothed normal at edges and corners). A node no triangle reached (every triangle
//     non-finite) is written +far: outside.
// Every node within `band` cells of the surface is exact (its nearest triangle's grown box
// holds it); farther nodes carry jump flooding's error (a nearer triangle missed).
// A mesh with holes: the sign is the nearest surface point's normal side, so the field
// says "inside" only behind the surface near a node, and a hole's rim is a surface like
// any other (no flood fill, no winding number: an open mesh is not inside-out).
// Bindings: the uniforms, the mesh (positions and normals f32 x3, u32 triangle list), the
// distance bits, the nearest triangle read and written (ping-pong), the field, the step.
// The CPU mirror (exact distances by brute force) is pelage-reference/src/sdf.rs.

#import shared/math.wgsl

// Bits of the largest finite f32: no distance yet.
const FAR_BITS: u32 = 0x7f7fffffu;
// Units in the last place a recomputed distance may differ from the minimum and still
// claim the node (the two splats compile to different pipelines).
const NEAREST_ULPS: u32 = 4u;

struct SdfUniforms {
    origin: vec3<f32>,
    cell: f32,
    dims: vec3<u32>,
    triangle_count: u32,
    // Cells around a triangle's box that it splats (the exact band).
    band: u32,
    // Distance written where no triangle reached.
    far: f32,
}

struct JfaStep {
    step: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<uniform> g: SdfUniforms;
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> normals: array<f32>;
@group(0) @binding(3) var<storage, read> indices: array<u32>;
@group(0) @binding(4) var<storage, read_write> dist_bits: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read> near_in: array<u32>;
@group(0) @binding(6) var<storage, read_write> near_out: array<atomic<u32>>;
@group(0) @binding(7) var field: texture_storage_3d<r32float, write>;
@group(0) @binding(8) var<uniform> jfa: JfaStep;

fn load_position(i: u32) -> vec3<f32> {
    return vec3<f32>(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
}

fn load_normal(i: u32) -> vec3<f32> {
    return vec3<f32>(normals[3u * i], normals[3u * i + 1u], normals[3u * i + 2u]);
}

// Barycentrics (u, v, w) of the point of triangle abc nearest p (Ericson, Real-Time
// Collision Detection 5.1.5; closest_on_triangle in simulate.rs); a degenerate
// triangle's nearest corner.
fn closest_bary(p: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec3<f32> {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return vec3<f32>(1.0, 0.0, 0.0);
    }
    let bp = p - b;
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return vec3<f32>(0.0, 1.0, 0.0);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return vec3<f32>(1.0 - v, v, 0.0);
    }
    let cp = p - c;
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return vec3<f32>(0.0, 0.0, 1.0);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return vec3<f32>(1.0 - w, 0.0, w);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return vec3<f32>(0.0, 1.0 - w, w);
    }
    let denom = va + vb + vc;
    if abs(denom) <= 1.17549435e-38 {
        let da = distance(p, a);
        let db = distance(p, b);
        let dc = distance(p, c);
        if da <= db && da <= dc {
            return vec3<f32>(1.0, 0.0, 0.0);
        }
        if db <= dc {
            return vec3<f32>(0.0, 1.0, 0.0);
        }
        return vec3<f32>(0.0, 0.0, 1.0);
    }
    let v = vb / denom;
    let w = vc / denom;
    return vec3<f32>(1.0 - v - w, v, w);
}

// A triangle's corners; `ok` false when one is not finite.
struct Triangle {
    a: vec3<f32>,
    b: vec3<f32>,
    c: vec3<f32>,
    ok: bool,
}

fn load_triangle(t: u32) -> Triangle {
    let a = load_position(indices[3u * t]);
    let b = load_position(indices[3u * t + 1u]);
    let c = load_position(indices[3u * t + 2u]);
    return Triangle(a, b, c, all_finite3(a) && all_finite3(b) && all_finite3(c));
}

// Distance from p to triangle `tri`.
fn triangle_distance(p: vec3<f32>, tri: Triangle) -> f32 {
    let bary = closest_bary(p, tri.a, tri.b, tri.c);
    return distance(p, tri.a * bary.x + tri.b * bary.y + tri.c * bary.z);
}

fn node_position(i: vec3<u32>) -> vec3<f32> {
    return g.origin + vec3<f32>(i) * g.cell;
}

fn node_index(i: vec3<u32>) -> u32 {
    return (i.z * g.dims.y + i.y) * g.dims.x + i.x;
}

fn node_of(index: u32) -> vec3<u32> {
    return vec3<u32>(index % g.dims.x, index / g.dims.x % g.dims.y, index / (g.dims.x * g.dims.y));
}

fn node_count() -> u32 {
    return g.dims.x * g.dims.y * g.dims.z;
}

fn flat_id(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.y * groups.x * 64u + gid.x;
}

// The nodes of a triangle's box grown by `band` cells, clamped to the grid: lo, hi inclusive.
struct NodeBox {
    lo: vec3<u32>,
    hi: vec3<u32>,
}

fn splat_box(tri: Triangle) -> NodeBox {
    let top = vec3<f32>(g.dims - vec3<u32>(1u));
    let band = f32(g.band);
    let lo = (min(min(tri.a, tri.b), tri.c) - g.origin) / g.cell - vec3<f32>(band);
    let hi = (max(max(tri.a, tri.b), tri.c) - g.origin) / g.cell + vec3<f32>(band);
    let lo_node = vec3<u32>(clamp(ceil(lo), vec3<f32>(0.0), top));
    let hi_node = vec3<u32>(clamp(floor(hi), vec3<f32>(0.0), top));
    return NodeBox(lo_node, hi_node);
}

// True when the grown box misses the grid altogether.
fn box_misses(tri: Triangle) -> bool {
    let top = vec3<f32>(g.dims - vec3<u32>(1u));
    let band = f32(g.band);
    let lo = (min(min(tri.a, tri.b), tri.c) - g.origin) / g.cell - vec3<f32>(band);
    let hi = (max(max(tri.a, tri.b), tri.c) - g.origin) / g.cell + vec3<f32>(band);
    return any(hi < vec3<f32>(0.0)) || any(lo > top);
}

@compute @workgroup_size(64)
fn clear(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = flat_id(gid, groups);
    if i >= node_count() {
        return;
    }
    atomicStore(&dist_bits[i], FAR_BITS);
    atomicStore(&near_out[i], 0u);
}

@compute @workgroup_size(64)
fn splat_distance(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let t = flat_id(gid, groups);
    if t >= g.triangle_count {
        return;
    }
    let tri = load_triangle(t);
    if !tri.ok || box_misses(tri) {
        return;
    }
    let bx = splat_box(tri);
    for (var z = bx.lo.z; z <= bx.hi.z; z++) {
        for (var y = bx.lo.y; y <= bx.hi.y; y++) {
            for (var x = bx.lo.x; x <= bx.hi.x; x++) {
                let n = vec3<u32>(x, y, z);
                let d = triangle_distance(node_position(n), tri);
                atomicMin(&dist_bits[node_index(n)], bitcast<u32>(d));
            }
        }
    }
}

@compute @workgroup_size(64)
fn splat_nearest(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let t = flat_id(gid, groups);
    if t >= g.triangle_count {
        return;
    }
    let tri = load_triangle(t);
    if !tri.ok || box_misses(tri) {
        return;
    }
    let bx = splat_box(tri);
    for (var z = bx.lo.z; z <= bx.hi.z; z++) {
        for (var y = bx.lo.y; y <= bx.hi.y; y++) {
            for (var x = bx.lo.x; x <= bx.hi.x; x++) {
                let n = vec3<u32>(x, y, z);
                let d = triangle_distance(node_position(n), tri);
                let i = node_index(n);
                if bitcast<u32>(d) <= atomicLoad(&dist_bits[i]) + NEAREST_ULPS {
                    atomicMax(&near_out[i], t + 1u);
                }
            }
        }
    }
}

@compute @workgroup_size(64)
fn flood(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = flat_id(gid, groups);
    if i >= node_count() {
        return;
    }
    let node = node_of(i);
    let p = node_position(node);
    var best = near_in[i];
    var best_d = 3.4e38;
    if best != 0u {
        best_d = triangle_distance(p, load_triangle(best - 1u));
    }
    let step = i32(jfa.step);
    let dims = vec3<i32>(g.dims);
    for (var dz = -1; dz <= 1; dz++) {
        for (var dy = -1; dy <= 1; dy++) {
            for (var dx = -1; dx <= 1; dx++) {
                let q = vec3<i32>(node) + vec3<i32>(dx, dy, dz) * step;
                if any(q < vec3<i32>(0)) || any(q >= dims) {
                    continue;
                }
                let t = near_in[node_index(vec3<u32>(q))];
                if t == 0u || t == best {
                    continue;
                }
                let d = triangle_distance(p, load_triangle(t - 1u));
                if d < best_d || (d == best_d && t > best) {
                    best = t;
                    best_d = d;
                }
            }
        }
    }
    atomicStore(&near_out[i], best);
}

@compute @workgroup_size(64)
fn finish(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = flat_id(gid, groups);
    if i >= node_count() {
        return;
    }
    let node = node_of(i);
    let t = near_in[i];
    var value = g.far;
    if t != 0u {
        let p = node_position(node);
        let tri = load_triangle(t - 1u);
        let bary = closest_bary(p, tri.a, tri.b, tri.c);
        let q = tri.a * bary.x + tri.b * bary.y + tri.c * bary.z;
        let n = load_normal(indices[3u * (t - 1u)]) * bary.x
            + load_normal(indices[3u * (t - 1u) + 1u]) * bary.y
            + load_normal(indices[3u * (t - 1u) + 2u]) * bary.z;
        value = distance(p, q);
        if dot(p - q, n) < 0.0 {
            value = -value;
        }
    }
    textureStore(field, vec3<i32>(node), vec4<f32>(value, 0.0, 0.0, 0.0));
}
