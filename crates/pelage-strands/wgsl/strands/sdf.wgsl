// A signed distance field of the mesh on a grid of nodes (BodySdf, pelage-strands/src/sdf.rs),
// rebuilt from the mesh buffers in one compute pass, on two levels: the fine grid (the
// field's nodes) and a coarse one (every COARSE_FACTOR-th node along each axis) over which
// sweeps carry the surface to the nodes far from it. The arrays the splats take extremes
// in start at 0 (buffer clears before the pass, not dispatches).
//  1. splat (per triangle, the fine level): the exact distance from the triangle to every
//     node of its box grown by `band` cells that lies within `band` cells of its plane,
//     with the side of the mesh's normal at the nearest point (the vertex normals
//     interpolated there) the node is on, as one key: the distance's bits (non-negative
//     floats order as their bits do) shifted up one, the side (1: inside) below;
//     atomicMax on its complement keeps the least key, so the nearest triangle's side
//     comes with its distance and the field is the same run after run (an exact tie
//     between sides: outside). A mesh of overlapping parts: a nearest point buried inside
//     another part (its corners' burial interpolated, > 0) that says "outside" says it of
//     its own part only, while the node may be inside the other: its key goes to a second
//     array, which gives a distance but no side;
//  2. splat_coarse (per triangle, the coarse level, one coarse cell around it): the same
//     nodes and distances (buried points left out), the key the distance in fixed point
//     above the triangle's index (INDEX_BITS below): the least key names the node's
//     nearest triangle (ties within a quantum, COARSE_RANGE cells / 2^(32 - INDEX_BITS):
//     the lowest index);
//  3. seed (per coarse node): the nearest point of the triangle its key names and the
//     mesh's normal there (packed);
//  4. sweep (per line of coarse nodes, along x, then y, then z): each node takes the
//     nearest of its point and those the line hands it from either end (vector
//     propagation: a node hands on whichever of its point and the one it was handed is
//     nearer the next node);
//  5. finish (per fine node): within the band (the least key at most `band` cells) the
//     splat's exact distance, negative where the nearest key that decides a side is
//     inside (else the nearest of both arrays, outside); beyond, the nearest of that and
//     the 8 surface points the coarse nodes around the node hold, signed by the side of
//     that point's normal the node is on; +far where nothing reached (every triangle
//     non-finite). Written to a buffer with the rows of the field's texture (a copy moves
//     it there: writing a 3D storage texture node by node costs more than the rest of
//     the build on some devices).
// The field: every node within `band` cells of the surface holds its exact signed
// distance (its nearest triangle's grown box and slab hold it). A farther node holds the
// distance to a point of the surface (so never less than the exact distance), the
// nearest one the sweeps brought to the coarse nodes around it: an approximation whose
// error the tests measure against the CPU mirror (pelage-reference/src/sdf.rs).
// A mesh with holes: the sign is the nearest surface point's normal side, so the field
// says "inside" only behind the surface near a node, and a hole's rim is a surface like
// any other (no flood fill, no winding number: an open mesh is not inside-out).
// Bindings: the mesh (positions and normals f32 x3, u32 triangle list), the level's keys
// (the fine level's two arrays one after the other), the field, the coarse points (two
// halves) and each vertex's burial.
//
// The grid a dispatch runs on and the halves it reads and writes are pipeline constants:
// BodySdf builds one pipeline per dispatch of the build, each specialised to its level
// and pass. (As uniforms, lavapipe (Mesa 22) inlined their values into the shader and
// compiled it again at every dispatch, about 0.9 ms each; read from a storage buffer,
// the splat and the finish ran 2.6 and 3.2 times slower, loading them per lane.)

#import shared/math.wgsl

// Coarse cells of distance the coarse keys' fixed point spans (farther: the largest
// quantum, any triangle as far; the sweeps carry nearer points there).
const COARSE_RANGE: f32 = 4.0;

struct SdfUniforms {
    origin: vec3<f32>,
    cell: f32,
    dims: vec3<u32>,
    triangle_count: u32,
    // Cells around a triangle's box and plane that it splats (the exact band).
    band: u32,
    // Distance written where no triangle reached.
    far: f32,
    // Fine nodes per coarse cell (the fine level; 1 at the coarse level).
    coarse: u32,
    // Texels per row of the field's buffer (the fine level).
    pitch: u32,
}

// The level's grid (SdfLevel::constants in sdf.rs).
override ORIGIN_X: f32;
override ORIGIN_Y: f32;
override ORIGIN_Z: f32;
override CELL: f32;
override DIMS_X: u32;
override DIMS_Y: u32;
override DIMS_Z: u32;
override TRIANGLES: u32;
override BAND: u32;
override FAR: f32;
override COARSE: u32;
override PITCH: u32;
// Bits of a coarse key that hold the triangle's index (enough for every triangle).
override INDEX_BITS: u32;
// The coarse level's nodes per axis (the finish reads its points).
override COARSE_DIMS_X: u32;
override COARSE_DIMS_Y: u32;
override COARSE_DIMS_Z: u32;
// Which coarse points the dispatch reads and writes (offsets into `points`: its two
// halves, A at 0 and B past it) and, for a sweep, its axis.
override READ_HALF: u32 = 0u;
override WRITE_HALF: u32 = 0u;
override AXIS: u32 = 0u;

// The level as one value (every field a pipeline constant).
fn level() -> SdfUniforms {
    return SdfUniforms(
        vec3<f32>(ORIGIN_X, ORIGIN_Y, ORIGIN_Z),
        CELL,
        vec3<u32>(DIMS_X, DIMS_Y, DIMS_Z),
        TRIANGLES,
        BAND,
        FAR,
        COARSE,
        PITCH,
    );
}

fn coarse_dims() -> vec3<u32> {
    return vec3<u32>(COARSE_DIMS_X, COARSE_DIMS_Y, COARSE_DIMS_Z);
}

@group(0) @binding(0) var<storage, read> positions: array<f32>;
@group(0) @binding(1) var<storage, read> normals: array<f32>;
@group(0) @binding(2) var<storage, read> indices: array<u32>;
// Every buffer a pass writes is bound read-write in every pass, so that no dispatch
// changes how a buffer is used (on lavapipe a dispatch that did cost 0.8 ms even when it
// returned at once: a barrier).
@group(0) @binding(3) var<storage, read_write> keys: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> field: array<f32>;
@group(0) @binding(5) var<storage, read_write> points: array<vec4<u32>>;
// How deep each vertex lies inside another part of the mesh (burial in sdf.rs: > 0
// buried; every vertex < 0 for a mesh of one part).
@group(0) @binding(6) var<storage, read> burial: array<f32>;

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

fn node_position(i: vec3<u32>) -> vec3<f32> {
    return level().origin + vec3<f32>(i) * level().cell;
}

fn node_index(i: vec3<u32>) -> u32 {
    return (i.z * level().dims.y + i.y) * level().dims.x + i.x;
}

fn node_of(index: u32) -> vec3<u32> {
    let dims = level().dims;
    return vec3<u32>(index % dims.x, index / dims.x % dims.y, index / (dims.x * dims.y));
}

fn node_count() -> u32 {
    return level().dims.x * level().dims.y * level().dims.z;
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
    let top = vec3<f32>(level().dims - vec3<u32>(1u));
    let band = f32(level().band);
    let lo = (min(min(tri.a, tri.b), tri.c) - level().origin) / level().cell - vec3<f32>(band);
    let hi = (max(max(tri.a, tri.b), tri.c) - level().origin) / level().cell + vec3<f32>(band);
    let lo_node = vec3<u32>(clamp(ceil(lo), vec3<f32>(0.0), top));
    let hi_node = vec3<u32>(clamp(floor(hi), vec3<f32>(0.0), top));
    return NodeBox(lo_node, hi_node);
}

// True when the grown box misses the grid altogether.
fn box_misses(tri: Triangle) -> bool {
    let top = vec3<f32>(level().dims - vec3<u32>(1u));
    let band = f32(level().band);
    let lo = (min(min(tri.a, tri.b), tri.c) - level().origin) / level().cell - vec3<f32>(band);
    let hi = (max(max(tri.a, tri.b), tri.c) - level().origin) / level().cell + vec3<f32>(band);
    return any(hi < vec3<f32>(0.0)) || any(lo > top);
}

// A triangle's plane (unit normal, offset) for the splats' cull: a node farther than the
// band from the plane is farther than the band from the triangle. A degenerate
// triangle's normal is 0 (nothing culled).
struct Slab {
    n: vec3<f32>,
    offset: f32,
    half_width: f32,
}

fn splat_slab(tri: Triangle) -> Slab {
    let n = cross(tri.b - tri.a, tri.c - tri.a);
    let len = length(n);
    var unit = vec3<f32>(0.0);
    if len > 0.0 && len < 3.4e38 {
        unit = n / len;
    }
    // A hundredth of a cell more than the band: rounding never culls a node at the band.
    return Slab(unit, dot(unit, tri.a), (f32(level().band) + 0.01) * level().cell);
}

fn outside_slab(slab: Slab, p: vec3<f32>) -> bool {
    return abs(dot(slab.n, p) - slab.offset) > slab.half_width;
}

// The mesh's normal at barycentrics `bary` of triangle `t` (its vertex normals).
fn triangle_normal(t: u32, bary: vec3<f32>) -> vec3<f32> {
    return load_normal(indices[3u * t]) * bary.x
        + load_normal(indices[3u * t + 1u]) * bary.y
        + load_normal(indices[3u * t + 2u]) * bary.z;
}

// How deep each corner of triangle `t` lies inside another part of the mesh (> 0:
// buried); a point's depth is their interpolation at its barycentrics (the junction of
// two parts taken as straight across a triangle).
fn corner_burial(t: u32) -> vec3<f32> {
    return vec3<f32>(burial[indices[3u * t]], burial[indices[3u * t + 1u]], burial[indices[3u * t + 2u]]);
}

// A splat's key at a node: its distance's bits shifted up one, 1 below where the node is
// inside (the least key is the nearest triangle's, and outside on a tie).
fn splat_key(d: f32, inside: bool) -> u32 {
    return (bitcast<u32>(d) << 1u) | select(0u, 1u, inside);
}

// The least key splatted at node `i` (0xffffffff: none), from the complement the splats
// take the maximum of (the buffer starts at 0).
fn least_key(i: u32) -> u32 {
    return ~atomicLoad(&keys[i]);
}

// The distance of a key.
fn key_distance(key: u32) -> f32 {
    return bitcast<f32>(key >> 1u);
}

@compute @workgroup_size(64)
fn splat(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let t = flat_id(gid, groups);
    if t >= level().triangle_count {
        return;
    }
    let tri = load_triangle(t);
    if !tri.ok || box_misses(tri) {
        return;
    }
    let bx = splat_box(tri);
    let slab = splat_slab(tri);
    let na = load_normal(indices[3u * t]);
    let nb = load_normal(indices[3u * t + 1u]);
    let nc = load_normal(indices[3u * t + 2u]);
    let buried = corner_burial(t);
    for (var z = bx.lo.z; z <= bx.hi.z; z++) {
        for (var y = bx.lo.y; y <= bx.hi.y; y++) {
            for (var x = bx.lo.x; x <= bx.hi.x; x++) {
                let n = vec3<u32>(x, y, z);
                let p = node_position(n);
                if outside_slab(slab, p) {
                    continue;
                }
                let bary = closest_bary(p, tri.a, tri.b, tri.c);
                let q = tri.a * bary.x + tri.b * bary.y + tri.c * bary.z;
                let normal = na * bary.x + nb * bary.y + nc * bary.z;
                let d = distance(p, q);
                let depth = dot(buried, bary);
                // A buried point's "outside" is the outside of its own part only: a node
                // nearer it than it is deep in another part is in that part (a distance
                // moves no faster than the point), and says "inside"; else its distance
                // goes to the second half of the keys, which decides no side (the finish).
                let inside = dot(p - q, normal) < 0.0 || depth > d;
                let key = ~splat_key(d, inside);
                let i = node_index(n) + select(0u, node_count(), !inside && depth > 0.0);
                // Most nodes already hold a nearer triangle's key: a load skips the atomic.
                if key > atomicLoad(&keys[i]) {
                    atomicMax(&keys[i], key);
                }
            }
        }
    }
}

// A coarse key: the distance in fixed point above the triangle's index (the least key
// is the nearest triangle's; never 0xffffffff, the empty complement's).
fn coarse_key(d: f32, t: u32) -> u32 {
    let levels = (1u << (32u - INDEX_BITS)) - 2u;
    let q = min(d / (COARSE_RANGE * level().cell), 1.0) * f32(levels);
    return (min(u32(q), levels) << INDEX_BITS) | t;
}

@compute @workgroup_size(64)
fn splat_coarse(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let t = flat_id(gid, groups);
    if t >= level().triangle_count {
        return;
    }
    let tri = load_triangle(t);
    if !tri.ok || box_misses(tri) {
        return;
    }
    let bx = splat_box(tri);
    let slab = splat_slab(tri);
    let buried = corner_burial(t);
    for (var z = bx.lo.z; z <= bx.hi.z; z++) {
        for (var y = bx.lo.y; y <= bx.hi.y; y++) {
            for (var x = bx.lo.x; x <= bx.hi.x; x++) {
                let n = vec3<u32>(x, y, z);
                let p = node_position(n);
                if outside_slab(slab, p) {
                    continue;
                }
                let bary = closest_bary(p, tri.a, tri.b, tri.c);
                // A buried point is no point of the body's surface: it seeds no node.
                if dot(buried, bary) > 0.0 {
                    continue;
                }
                let q = tri.a * bary.x + tri.b * bary.y + tri.c * bary.z;
                let key = ~coarse_key(distance(p, q), t);
                let i = node_index(n);
                if key > atomicLoad(&keys[i]) {
                    atomicMax(&keys[i], key);
                }
            }
        }
    }
}

// A coarse node's surface point: xyz the point's bits, w the mesh's normal there packed
// (pack4x8snorm with w = 1: a point; all 0: none).
@compute @workgroup_size(64)
fn seed(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = flat_id(gid, groups);
    if i >= node_count() {
        return;
    }
    let key = atomicLoad(&keys[i]);
    var out = vec4<u32>(0u);
    if key != 0u {
        let t = ~key & ((1u << INDEX_BITS) - 1u);
        let tri = load_triangle(t);
        let bary = closest_bary(node_position(node_of(i)), tri.a, tri.b, tri.c);
        let q = tri.a * bary.x + tri.b * bary.y + tri.c * bary.z;
        let n = safe_normalize(triangle_normal(t, bary), vec3<f32>(0.0));
        out = vec4<u32>(bitcast<vec3<u32>>(q), pack4x8snorm(vec4<f32>(n, 1.0)));
    }
    write_point(i, out);
}

// Writes coarse node `i`'s surface point (into the pass's write half).
fn write_point(i: u32, point: vec4<u32>) {
    points[WRITE_HALF + i] = point;
}

// Coarse node `i`'s surface point as the pass's read half holds it.
fn point_in(i: u32) -> vec4<u32> {
    return points[READ_HALF + i];
}


// The nearer to `p` of the surface points `a` and `b` (w = 0: none); on a tie the larger
// bits, so the field is the same run after run.
fn nearer_point(p: vec3<f32>, a: vec4<u32>, b: vec4<u32>) -> vec4<u32> {
    if b.w == 0u {
        return a;
    }
    if a.w == 0u {
        return b;
    }
    let oa = p - bitcast<vec3<f32>>(a.xyz);
    let ob = p - bitcast<vec3<f32>>(b.xyz);
    let da = dot(oa, oa);
    let db = dot(ob, ob);
    if db < da || (db == da && (b.x > a.x || (b.x == a.x && b.y > a.y))) {
        return b;
    }
    return a;
}

// One invocation per line of coarse nodes along axis `AXIS` (0: x, 1: y, 2: z): each
// node of the line takes the nearest of its own point and the points the line carries
// to it from either end (a sweep each way: vector propagation, after Danielsson 1980).
// Three passes, x then y then z, carry every seed through the grid.
@compute @workgroup_size(64)
fn sweep(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let line = flat_id(gid, groups);
    // The line's axis and the two across it.
    let a = AXIS;
    let b = (a + 1u) % 3u;
    let c = (a + 2u) % 3u;
    let dims = level().dims;
    if line >= dims[b] * dims[c] {
        return;
    }
    var first = vec3<u32>(0u);
    first[b] = line % dims[b];
    first[c] = line / dims[b];
    var along = vec3<u32>(0u);
    along[a] = 1u;
    let n = dims[a];
    // Index steps between neighbours along the line.
    let stride = node_index(along);
    let base = node_index(first);
    // Forward: from the line's start. A node hands on whichever of its own point and
    // what it was handed is nearer the next node.
    var carry = vec4<u32>(0u);
    let ahead = level().cell * vec3<f32>(along);
    for (var k = 0u; k < n; k++) {
        let i = base + k * stride;
        let p = node_position(first + along * k);
        let own = point_in(i);
        write_point(i, nearer_point(p, own, carry));
        carry = nearer_point(p + ahead, own, carry);
    }
    // Backward: from its end, against what the forward sweep left.
    carry = vec4<u32>(0u);
    for (var k = n; k > 0u; k--) {
        let i = base + (k - 1u) * stride;
        let p = node_position(first + along * (k - 1u));
        let own = point_in(i);
        write_point(i, nearer_point(p, points[WRITE_HALF + i], nearer_point(p, own, carry)));
        carry = nearer_point(p - ahead, own, carry);
    }
}

// A surface point of the coarse level (xyz) and the mesh's normal there (w = 1: a point;
// 0: none).
struct Candidate {
    q: vec3<f32>,
    n: vec4<f32>,
}

fn candidate(c: vec3<u32>) -> Candidate {
    let point = point_in((c.z * coarse_dims().y + c.y) * coarse_dims().x + c.x);
    return Candidate(bitcast<vec3<f32>>(point.xyz), unpack4x8snorm(point.w));
}

// The signed distance so far, `best` (x: distance, y: < 0 inside), against candidate `c`.
fn nearer(p: vec3<f32>, best: vec2<f32>, c: Candidate) -> vec2<f32> {
    let d = distance(p, c.q);
    if c.n.w > 0.5 && d < best.x {
        return vec2<f32>(d, dot(p - c.q, c.n.xyz));
    }
    return best;
}

// One invocation per coarse node c: the fine nodes of the cell from COARSE_FACTOR c (those
// in the grid), with the 8 coarse nodes around them read once.
@compute @workgroup_size(64)
fn finish(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let cell = flat_id(gid, groups);
    let cdims = coarse_dims();
    if cell >= cdims.x * cdims.y * cdims.z {
        return;
    }
    let cnode = vec3<u32>(cell % cdims.x, cell / cdims.x % cdims.y, cell / (cdims.x * cdims.y));
    let lo = min(cnode, cdims - vec3<u32>(2u));
    let c0 = candidate(lo);
    let c1 = candidate(lo + vec3<u32>(1u, 0u, 0u));
    let c2 = candidate(lo + vec3<u32>(0u, 1u, 0u));
    let c3 = candidate(lo + vec3<u32>(1u, 1u, 0u));
    let c4 = candidate(lo + vec3<u32>(0u, 0u, 1u));
    let c5 = candidate(lo + vec3<u32>(1u, 0u, 1u));
    let c6 = candidate(lo + vec3<u32>(0u, 1u, 1u));
    let c7 = candidate(lo + vec3<u32>(1u, 1u, 1u));
    let first = cnode * level().coarse;
    let last = min(first + vec3<u32>(level().coarse - 1u), level().dims - vec3<u32>(1u));
    for (var z = first.z; z <= last.z; z++) {
        for (var y = first.y; y <= last.y; y++) {
            for (var x = first.x; x <= last.x; x++) {
                let node = vec3<u32>(x, y, z);
                let key = least_key(node_index(node));
                let buried_key = least_key(node_index(node) + node_count());
                // (distance, side): within the band the splat's exact distance, inside
                // where the nearest vote that decides a side says so, else outside at the
                // nearest of every vote (a buried point's included: the node is outside
                // the parts around it, at most that far from their surface).
                var best = vec2<f32>(level().far, 1.0);
                if key != 0xffffffffu && (key & 1u) == 1u {
                    best = vec2<f32>(key_distance(key), -1.0);
                } else if min(key, buried_key) != 0xffffffffu {
                    best = vec2<f32>(key_distance(min(key, buried_key)), 1.0);
                }
                let reached = best.x < level().far;
                let splat_d = best.x;
                if !reached || splat_d > f32(level().band) * level().cell {
                    // Beyond the band: the nearest of the surface points the coarse nodes
                    // around hold, on the side of its normal.
                    let p = node_position(node);
                    best = nearer(p, best, c0);
                    best = nearer(p, best, c1);
                    best = nearer(p, best, c2);
                    best = nearer(p, best, c3);
                    best = nearer(p, best, c4);
                    best = nearer(p, best, c5);
                    best = nearer(p, best, c6);
                    best = nearer(p, best, c7);
                }
                let value = select(best.x, -best.x, best.y < 0.0);
                field[(z * level().dims.y + y) * level().pitch + x] = value;
            }
        }
    }
}
