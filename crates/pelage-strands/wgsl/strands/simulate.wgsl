// Stage 1 with dynamics: every strand simulated by position-based dynamics, its root
// bound to a triangle of the (possibly moving) mesh.
//
// Reads:  the mesh (positions and normals as tightly packed f32 x3, a u32 triangle list),
//         one StrandRoot per strand (triangle, barycentrics, width, gust phase), the
//         frame's GrowUniforms (wind, time, level of detail; gravity, shape and surface
//         fields unused) and SimUniforms (substeps, stiffnesses, colliders); the body's
//         distance field (3D r32float, BodySdf) and, with SDF_SKIN, the skin's lattice of
//         blended joint matrices (3D rgba32float, SdfSkin) it is read through.
// Reads and writes: `state`, per strand STATE_HEADER + 3 (segments + 1) vec4 (see
//         `state_base`): the root's pose last frame, the rest shape in the root's frame,
//         and every vertex's position and previous position (Verlet).
// Writes: `held[0]` (atomicAdd): the strands held this frame because the mesh under
//         their root is not finite; `vertices`, (segments / step + 1) vec4 per drawn
//         strand (xyz = position, w = strand parameter in [0, 1]); `drawn[strand].width`,
//         the rest width times the level of detail's width scale.
// Dispatch: one invocation per strand of the groom (strand_total: every strand is
//         simulated, drawn or not), workgroup_size(64); x = min(groups, limit),
//         y = ceil(groups / x).
//
// One invocation walks its strand root to tip, substep after substep (Gauss-Seidel along
// the strand: deterministic, no atomics but the held counter). Each substep of h seconds:
//  1. the root's position and frame (normal, tangent from the triangle's first edge) are
//     interpolated between last frame's and this frame's pose;
//  2. Verlet: x' = x + (x - x_prev) exp(-damping h) + a h^2, a = gravity + wind_response
//     force(x, t) (strands/force.wgsl, the wind of the stateless methods);
//  3. root to tip, vertex k: global shape (pull toward its rest position carried by the
//     root's frame, stiffness falling to 0 at global_range), local shape (toward the rest
//     direction turned by the rotation accumulated from the segments before it, as
//     groom.wgsl turns a groom); both pulls move the previous position with the vertex,
//     so they shape the strand without giving it speed; then COLLISION_PASSES rounds of
//     collisions (out of every sphere and capsule; friction, in the first round only,
//     taking tangential velocity off; then out of the body's signed distance field when
//     there is one, along its gradient, read through the skin at the vertex's bind-pose
//     point when SDF_SKIN) and follow-the-leader (the vertex put at its rest
//     length from its parent), then onto_length_outside (at its length and out of the
//     colliders at once, where the rounds left it inside), and the parent's velocity is
//     corrected by -length_damping times the follow-the-leader corrections (Mueller et
//     al. 2012, "DFTL"). The root is pinned.
// Every segment thus leaves each substep at its rest length (to float rounding).
// A root that moved more than teleport_distance, a first frame, a reset or a non-finite
// vertex put the strand at rest in its new pose.
// The CPU mirror of this file is pelage-reference/src/simulate.rs: change both together.

#import shared/math.wgsl
#import shared/strand.wgsl
#import strands/rotation.wgsl
#import strands/force.wgsl
#import strands/lod.wgsl

const MAX_COLLIDERS: u32 = 16u;
// vec4s per strand before its vertices: root position (w = 1 once posed), normal, tangent.
const STATE_HEADER: u32 = 3u;
// Rounds of collision and length projection per vertex and substep (the mirror's
// COLLISION_PASSES).
const COLLISION_PASSES: u32 = 3u;

// A capsule from `a` to `b` of `radius` (a sphere when a = b), world space.
struct Collider {
    a: vec3<f32>,
    radius: f32,
    b: vec3<f32>,
    pad: f32,
}

struct SimUniforms {
    gravity: vec3<f32>,
    wind_response: f32,
    // Substeps this frame and their length, seconds.
    substeps: u32,
    h: f32,
    // Time at the start of the frame, seconds.
    time0: f32,
    // 1: every strand back to rest in this frame's pose.
    reset: u32,
    // Velocity kept per substep, exp(-damping h).
    keep: f32,
    local_stiffness: f32,
    global_stiffness: f32,
    global_range: f32,
    length_damping: f32,
    friction: f32,
    teleport_distance: f32,
    collider_count: u32,
    colliders: array<Collider, MAX_COLLIDERS>,
    // The body's signed distance field (BodySdf, strands/sdf.wgsl): world space to the
    // space it was built in, its node (0, 0, 0), cell and nodes per axis, 1 when on.
    sdf_from_world: mat4x4<f32>,
    sdf_origin: vec3<f32>,
    sdf_cell: f32,
    sdf_dims: vec3<u32>,
    sdf_on: u32,
    // The skin of a field built in the bind pose (SdfSkin, strands/sdf_skin.wgsl): its
    // lattice's point (0, 0, 0), cell and points per axis (bind pose); read when SDF_SKIN.
    skin_origin: vec3<f32>,
    skin_cell: f32,
    skin_dims: vec3<u32>,
    // How far beyond the field's surface the collisions keep a vertex besides `margin`,
    // in the field's cells (DynamicsParams::sdf_standoff): the interpolation's excess.
    sdf_standoff: f32,
}

// True when the field is read through a skin (SimulateStrands::skin_body_sdf): a
// pipeline constant, so that a simulation without one compiles none of it (as a uniform,
// lavapipe ran every simulation about twice as slowly).
override SDF_SKIN: bool = false;

@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> normals: array<f32>;
@group(0) @binding(3) var<storage, read> indices: array<u32>;
@group(0) @binding(4) var<storage, read> roots: array<StrandRoot>;
@group(0) @binding(5) var<uniform> sim: SimUniforms;
@group(0) @binding(6) var<storage, read_write> state: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> held: array<atomic<u32>>;
@group(0) @binding(8) var sdf: texture_3d<f32>;
// The skin's blended matrices: lattice point (i, j, k)'s three rows at texels 3i..3i+2.
@group(0) @binding(9) var sdf_skin: texture_3d<f32>;
@group(0) @binding(10) var<storage, read_write> vertices: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read_write> drawn: array<StrandRoot>;

// Newton steps of the skin's inverse at most, from where the vertex before settled (warm)
// and from the world point itself (cold: a strand's first vertex in a frame's first
// substep).
const SKIN_WARM_STEPS: u32 = 8u;
const SKIN_COLD_STEPS: u32 = 32u;

// The last settled world point, its bind-pose point (w = 1 when set) and the inverse of
// the skin's Jacobian there: where the next vertex of the strand starts.
var<private> skin_last_p: vec3<f32>;
var<private> skin_last_q: vec4<f32>;
var<private> skin_last_inv: mat3x3<f32>;
// The same for the strand's first vertex, kept from substep to substep.
var<private> skin_head_p: vec3<f32>;
var<private> skin_head_q: vec4<f32>;
var<private> skin_head_inv: mat3x3<f32>;

fn load_position(i: u32) -> vec3<f32> {
    return vec3<f32>(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
}

fn load_normal(i: u32) -> vec3<f32> {
    return vec3<f32>(normals[3u * i], normals[3u * i + 1u], normals[3u * i + 2u]);
}

// A root's pose: position, unit normal and unit tangent; `ok` false when the mesh under
// it holds a non-finite value.
struct Pose {
    position: vec3<f32>,
    normal: vec3<f32>,
    tangent: vec3<f32>,
    ok: bool,
}

// The flat surface at barycentrics (u, v, w = 1 - u - v) of triangle `tri`: position,
// normal, and the tangent from the triangle's first edge.
fn root_pose(tri: u32, bary: vec2<f32>) -> Pose {
    let i1 = indices[3u * tri];
    let i2 = indices[3u * tri + 1u];
    let i3 = indices[3u * tri + 2u];
    let p1 = load_position(i1);
    let p2 = load_position(i2);
    let p3 = load_position(i3);
    let n1 = load_normal(i1);
    let n2 = load_normal(i2);
    let n3 = load_normal(i3);
    let bw = 1.0 - bary.x - bary.y;
    var pose: Pose;
    pose.ok = all_finite3(p1) && all_finite3(p2) && all_finite3(p3) && all_finite3(n1)
        && all_finite3(n2) && all_finite3(n3);
    pose.position = p1 * bary.x + p2 * bary.y + p3 * bw;
    pose.normal = safe_normalize(n1 * bary.x + n2 * bary.y + n3 * bw, vec3<f32>(0.0, 1.0, 0.0));
    pose.tangent = perpendicular(pose.normal, p2 - p1);
    pose.ok = pose.ok && all_finite3(pose.position);
    return pose;
}

// A point given in a root's frame (x along the tangent, y along the normal, z along
// tangent x normal) in world space.
fn to_world(pose: Pose, local: vec3<f32>) -> vec3<f32> {
    return pose.position + pose.tangent * local.x + pose.normal * local.y
        + cross(pose.tangent, pose.normal) * local.z;
}

// A vertex and its previous position, as collisions move them.
struct Moved {
    p: vec3<f32>,
    prev: vec3<f32>,
}

// The point of collider `col`'s axis nearest `p` (its centre for a sphere).
fn axis_point(col: Collider, p: vec3<f32>) -> vec3<f32> {
    let axis = col.b - col.a;
    let len2 = dot(axis, axis);
    var s = 0.0;
    if len2 > 0.0 {
        s = clamp(dot(p - col.a, axis) / len2, 0.0, 1.0);
    }
    return col.a + axis * s;
}

// The body's field at a world point: the signed distance (trilinear between the eight
// nodes around it) and its gradient (the trilinear's own, in world space). A point
// outside the grid, or not finite, is far outside (`d` = 3.4e38, no gradient).
struct BodySample {
    d: f32,
    grad: vec3<f32>,
}

fn sdf_node(i: vec3<u32>) -> f32 {
    return textureLoad(sdf, vec3<i32>(i), 0).x;
}

// The skin's blended 3x4 matrix at bind-pose point `q` (its rows r0..r2: trilinear between
// the 8 lattice points around it, `q` clamped into the lattice) and the rows' derivatives
// along x, y and z (per scene unit; 0 across a face `q` was clamped to).
struct SkinBlend {
    r0: vec4<f32>,
    r1: vec4<f32>,
    r2: vec4<f32>,
    x0: vec4<f32>,
    x1: vec4<f32>,
    x2: vec4<f32>,
    y0: vec4<f32>,
    y1: vec4<f32>,
    y2: vec4<f32>,
    z0: vec4<f32>,
    z1: vec4<f32>,
    z2: vec4<f32>,
}

fn skin_texel(i: vec3<u32>, row: u32) -> vec4<f32> {
    return textureLoad(sdf_skin, vec3<i32>(vec3<u32>(3u * i.x + row, i.y, i.z)), 0);
}

fn skin_blend(q: vec3<f32>) -> SkinBlend {
    let top = vec3<f32>(sim.skin_dims - vec3<u32>(1u));
    let unclamped = (q - sim.skin_origin) / sim.skin_cell;
    let x = clamp(unclamped, vec3<f32>(0.0), top);
    let inside = vec3<f32>(x == unclamped) / sim.skin_cell;
    let i = min(vec3<u32>(floor(x)), sim.skin_dims - vec3<u32>(2u));
    let f = x - vec3<f32>(i);
    var b: SkinBlend;
    for (var c = 0u; c < 8u; c++) {
        let o = vec3<u32>(c & 1u, (c >> 1u) & 1u, c >> 2u);
        let one = o == vec3<u32>(1u);
        let w3 = select(1.0 - f, f, one);
        let s3 = select(vec3<f32>(-1.0), vec3<f32>(1.0), one) * inside;
        let w = w3.x * w3.y * w3.z;
        let dw = vec3<f32>(s3.x * w3.y * w3.z, w3.x * s3.y * w3.z, w3.x * w3.y * s3.z);
        let t0 = skin_texel(i + o, 0u);
        let t1 = skin_texel(i + o, 1u);
        let t2 = skin_texel(i + o, 2u);
        b.r0 += t0 * w;
        b.r1 += t1 * w;
        b.r2 += t2 * w;
        b.x0 += t0 * dw.x;
        b.x1 += t1 * dw.x;
        b.x2 += t2 * dw.x;
        b.y0 += t0 * dw.y;
        b.y1 += t1 * dw.y;
        b.y2 += t2 * dw.y;
        b.z0 += t0 * dw.z;
        b.z1 += t1 * dw.z;
        b.z2 += t2 * dw.z;
    }
    return b;
}

// The bind-pose point `q` the skin takes to world point `p` (A(q) q = p, A the blended
// matrix there), by Newton steps from `start` on the map q -> A(q) q (its Jacobian: the
// blend's linear part plus the blend's change along each axis applied to q), and the
// Jacobian's inverse there (how q follows p); `ok` when A(q) q came within SKIN_ACCEPT
// field cells of p. A step taken from within SKIN_ONE_STEP field cells is the last: from
// there its error is of the order of that distance squared over the lattice's cell.
struct Unskinned {
    q: vec3<f32>,
    inv: mat3x3<f32>,
    ok: bool,
}

// Settled: A(q) q within this many field cells of p. Accepted: within this many. One
// step: a step from within this many ends the search.
const SKIN_SETTLED: f32 = 1e-3;
const SKIN_ACCEPT: f32 = 0.05;
const SKIN_ONE_STEP: f32 = 0.1;

fn unskin(p: vec3<f32>, start: vec3<f32>, steps: u32) -> Unskinned {
    var out: Unskinned;
    out.q = start;
    out.ok = false;
    var miss = 3.4e38;
    // A last step taken from within SKIN_ONE_STEP: accepted without a look after it.
    var last_step = false;
    for (var k = 0u; k <= steps; k++) {
        let b = skin_blend(out.q);
        let q1 = vec4<f32>(out.q, 1.0);
        let r = p - vec3<f32>(dot(b.r0, q1), dot(b.r1, q1), dot(b.r2, q1));
        // The Jacobian's columns: the linear part's, plus the blend's change along that
        // axis applied to q.
        let c0 = vec3<f32>(b.r0.x, b.r1.x, b.r2.x) + vec3<f32>(dot(b.x0, q1), dot(b.x1, q1), dot(b.x2, q1));
        let c1 = vec3<f32>(b.r0.y, b.r1.y, b.r2.y) + vec3<f32>(dot(b.y0, q1), dot(b.y1, q1), dot(b.y2, q1));
        let c2 = vec3<f32>(b.r0.z, b.r1.z, b.r2.z) + vec3<f32>(dot(b.z0, q1), dot(b.z1, q1), dot(b.z2, q1));
        let det = dot(c0, cross(c1, c2));
        if !(abs(det) > 1e-12) {
            return out;
        }
        // The inverse of the matrix with columns c0, c1, c2 has rows c1 x c2, c2 x c0,
        // c0 x c1 over its determinant.
        out.inv = transpose(mat3x3<f32>(cross(c1, c2), cross(c2, c0), cross(c0, c1))) * (1.0 / det);
        miss = length(r);
        if miss <= SKIN_SETTLED * sim.sdf_cell || k == steps {
            break;
        }
        out.q = out.q + out.inv * r;
        if miss <= SKIN_ONE_STEP * sim.sdf_cell {
            last_step = true;
            break;
        }
    }
    out.ok = (last_step || miss <= SKIN_ACCEPT * sim.sdf_cell) && all_finite3(out.q);
    return out;
}

// The last sample read from the field in this invocation: its world point and distance
// (`field_last_d` < 0 before the first, after one inside the body or outside the grid).
// The reading (this frame's field) changes at most FIELD_LIPSCHITZ times as fast as the
// point moves (the trilinear reading of a distance field's nodes at most sqrt(3) times:
// each axis's difference is at most a cell's; through a skin a little more where it
// stretches), so a point whose bound, that sample's distance less FIELD_LIPSCHITZ times
// the way from it, is at least `margin` cannot be within `margin` of the body:
// body_sample answers with the bound and reads nothing (no collision, as the reading
// itself would say).
var<private> field_last_p: vec3<f32>;
var<private> field_last_d: f32 = -1.0;
const FIELD_LIPSCHITZ: f32 = 2.0;

// A lower bound of the body's distance at `p_world` from the last sample read (-1 when
// there is none).
fn field_bound(p_world: vec3<f32>) -> f32 {
    if field_last_d < 0.0 {
        return -1.0;
    }
    return field_last_d - FIELD_LIPSCHITZ * length(p_world - field_last_p);
}

// The body's field at `p_world` as the collision step with `margin` needs it: the sample
// (body_sample_at), or a lower bound of the distance that is at least `margin`.
fn body_sample(p_world: vec3<f32>, margin: f32) -> BodySample {
    let bound = field_bound(p_world);
    if bound >= margin {
        return BodySample(bound, vec3<f32>(0.0));
    }
    let s = body_sample_at(p_world);
    field_last_p = p_world;
    field_last_d = select(-1.0, s.d, s.d < 3.0e38);
    return s;
}

// Settles the bind-pose point of world point `p_world` through the skin (unskin), from
// where the last one settled moved to first order (or from `p_world` itself, cold), and
// keeps it for body_sample_at; a point that does not settle reads far outside until the
// next. Once per vertex and substep, before its collisions: the lattice is read here only.
fn skin_settle(p_world: vec3<f32>) {
    let p = (sim.sdf_from_world * vec4<f32>(p_world, 1.0)).xyz;
    if !all_finite3(p) {
        skin_last_q.w = 0.0;
        return;
    }
    var start = p;
    var steps = SKIN_COLD_STEPS;
    if skin_last_q.w == 1.0 {
        start = skin_last_q.xyz + skin_last_inv * (p - skin_last_p);
        steps = SKIN_WARM_STEPS;
    }
    let u = unskin(p, start, steps);
    if !u.ok {
        skin_last_q.w = 0.0;
        return;
    }
    skin_last_p = p;
    skin_last_q = vec4<f32>(u.q, 1.0);
    skin_last_inv = u.inv;
}

fn body_sample_at(p_world: vec3<f32>) -> BodySample {
    var out = BodySample(3.4e38, vec3<f32>(0.0));
    var p = (sim.sdf_from_world * vec4<f32>(p_world, 1.0)).xyz;
    // A skinned body: the field's point is where the skin takes `p` from; gradients go
    // back through the transpose of the Jacobian's inverse.
    var back = mat3x3<f32>(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0, 0.0, 1.0));
    // Through a skin: to first order from where the vertex's bind-pose point was last
    // settled (skin_settle; the rounds of collision and length projection move a vertex
    // by a fraction of a strand width from there).
    if SDF_SKIN {
        if skin_last_q.w != 1.0 || !all_finite3(p) {
            return out;
        }
        p = skin_last_q.xyz + skin_last_inv * (p - skin_last_p);
        back = transpose(skin_last_inv);
    }
    let x = (p - sim.sdf_origin) / sim.sdf_cell;
    let top = vec3<f32>(sim.sdf_dims - vec3<u32>(1u));
    if !all_finite3(x) || any(x < vec3<f32>(0.0)) || any(x > top) {
        return out;
    }
    let i = min(vec3<u32>(floor(x)), sim.sdf_dims - vec3<u32>(2u));
    let f = x - vec3<f32>(i);
    let c000 = sdf_node(i);
    let c100 = sdf_node(i + vec3<u32>(1u, 0u, 0u));
    let c010 = sdf_node(i + vec3<u32>(0u, 1u, 0u));
    let c110 = sdf_node(i + vec3<u32>(1u, 1u, 0u));
    let c001 = sdf_node(i + vec3<u32>(0u, 0u, 1u));
    let c101 = sdf_node(i + vec3<u32>(1u, 0u, 1u));
    let c011 = sdf_node(i + vec3<u32>(0u, 1u, 1u));
    let c111 = sdf_node(i + vec3<u32>(1u, 1u, 1u));
    let c00 = mix(c000, c100, f.x);
    let c10 = mix(c010, c110, f.x);
    let c01 = mix(c001, c101, f.x);
    let c11 = mix(c011, c111, f.x);
    out.d = mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
    // A distance field moves at most as fast as the point: the true distance here is at
    // most a node's plus the way to it. Where the field bends within the cell (a crease
    // between the body's parts, inside near its middle) the interpolation can say more
    // than that, even "outside"; the least of these bounds is never below the true
    // distance (the nodes are exact or farther), so taking it only moves the value
    // toward the truth. The gradient stays the interpolation's.
    let h = sim.sdf_cell;
    let g = 1.0 - f;
    var lip = c000 + h * length(f);
    lip = min(lip, c100 + h * length(vec3<f32>(g.x, f.y, f.z)));
    lip = min(lip, c010 + h * length(vec3<f32>(f.x, g.y, f.z)));
    lip = min(lip, c110 + h * length(vec3<f32>(g.x, g.y, f.z)));
    lip = min(lip, c001 + h * length(vec3<f32>(f.x, f.y, g.z)));
    lip = min(lip, c101 + h * length(vec3<f32>(g.x, f.y, g.z)));
    lip = min(lip, c011 + h * length(vec3<f32>(f.x, g.y, g.z)));
    lip = min(lip, c111 + h * length(g));
    out.d = min(out.d, lip);
    let gx = mix(mix(c100 - c000, c110 - c010, f.y), mix(c101 - c001, c111 - c011, f.y), f.z);
    let gy = mix(mix(c010 - c000, c110 - c100, f.x), mix(c011 - c001, c111 - c101, f.x), f.z);
    let gz = mix(mix(c001 - c000, c101 - c100, f.x), mix(c011 - c010, c111 - c110, f.x), f.y);
    // The field's space turns rigidly from world space: its gradient turns back with
    // the transpose. Through a skin, the gradient is the inverse's transpose times the
    // field's, and the distance scales by how the skin stretches lengths along it
    // (first order: 1 where the rig is rigid).
    let grad = vec3<f32>(gx, gy, gz) / sim.sdf_cell;
    let gp = back * grad;
    let stretch = length(gp);
    if stretch > 0.0 {
        out.d = out.d * (length(grad) / stretch);
    }
    let r = mat3x3<f32>(sim.sdf_from_world[0].xyz, sim.sdf_from_world[1].xyz, sim.sdf_from_world[2].xyz);
    out.grad = transpose(r) * gp;
    return out;
}

// How far from the body's field the collisions keep a vertex whose margin from the
// colliders is `margin`: the field's standoff (its cells) farther.
fn body_margin_of(margin: f32) -> f32 {
    return margin + sim.sdf_standoff * sim.sdf_cell;
}

// `p` pushed out of every collider to `margin` beyond its surface (along the direction
// from the nearest point of its axis; `fallback` when on the axis), and `prev` moved along
// the contact's tangent plane by `friction` of the tangential motion (the first round of
// a substep only: a later round's contact is the same one, and its friction applied again
// would hinge on whether rounding left the vertex a hair inside).
fn collide(p_in: vec3<f32>, prev_in: vec3<f32>, margin: f32, fallback: vec3<f32>, friction: f32) -> Moved {
    var m = Moved(p_in, prev_in);
    for (var c = 0u; c < min(sim.collider_count, MAX_COLLIDERS); c++) {
        let col = sim.colliders[c];
        let nearest = axis_point(col, m.p);
        let r = col.radius + margin;
        let d = m.p - nearest;
        if dot(d, d) < r * r {
            let n = safe_normalize(d, fallback);
            m.p = nearest + n * r;
            let v = m.p - m.prev;
            m.prev = m.prev + (v - n * dot(v, n)) * friction;
        }
    }
    // The body's own shape: out along the field's gradient to `margin` and the
    // standoff from its surface.
    if sim.sdf_on == 1u {
        let body_margin = body_margin_of(margin);
        let s = body_sample(m.p, body_margin);
        if s.d < body_margin {
            let n = safe_normalize(s.grad, fallback);
            m.p = m.p + n * (body_margin - s.d);
            let v = m.p - m.prev;
            m.prev = m.prev + (v - n * dot(v, n)) * friction;
        }
    }
    return m;
}

// `p` (at distance `len` from `parent`) moved along that sphere to the nearest point
// outside every collider (+ margin) it is inside: onto the circle where the two spheres
// meet (for a capsule, the sphere around the axis point nearest `p`). The rounds of
// collision and follow-the-leader alternate two projections that need not meet in
// COLLISION_PASSES rounds where a strand folds against a body; this lands on both. A
// vertex whose sphere of reach does not cross the collider's surface stays where it is.
fn onto_length_outside(p_in: vec3<f32>, parent: vec3<f32>, len: f32, margin: f32) -> vec3<f32> {
    var p = p_in;
    for (var c = 0u; c < min(sim.collider_count, MAX_COLLIDERS); c++) {
        let col = sim.colliders[c];
        let center = axis_point(col, p);
        let r = col.radius + margin;
        let off = p - center;
        let w = center - parent;
        let d = length(w);
        if dot(off, off) < r * r && d > abs(r - len) && d < r + len {
            let toward = w / d;
            let along = (d * d + len * len - r * r) / (2.0 * d);
            let o = parent + toward * along;
            p = o + perpendicular(toward, p - o) * sqrt(max(len * len - along * along, 0.0));
        }
    }
    // The body's field, taken as its tangent plane at `p`: the point of the sphere
    // around `parent` at height `margin` and the standoff above that plane nearest `p`.
    if sim.sdf_on == 1u {
        let body_margin = body_margin_of(margin);
        let s = body_sample(p, body_margin);
        if s.d < body_margin {
            let n = safe_normalize(s.grad, vec3<f32>(0.0, 1.0, 0.0));
            let h = dot(n, p - parent) + body_margin - s.d;
            if abs(h) < len {
                p = parent + n * h + perpendicular(n, p - parent) * sqrt(len * len - h * h);
            }
        }
    }
    return p;
}

// Index of strand `strand`'s first state vec4 (its root position); its rest shape follows
// at + STATE_HEADER, positions at + STATE_HEADER + n, previous positions at
// + STATE_HEADER + 2n, n = segments + 1.
fn state_base(strand: u32) -> u32 {
    return strand * (STATE_HEADER + 3u * (u.segments + 1u));
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let strand = gid.y * groups.x * 64u + gid.x;
    if strand >= u.strand_total {
        return;
    }
    let root = roots[strand];
    let n = u.segments + 1u;
    let base = state_base(strand);
    let rest = base + STATE_HEADER;
    let pos = rest + n;
    let prv = pos + n;
    let now = root_pose(root.triangle, root.bary);

    if !now.ok {
        // The mesh under the root is not finite: the strand keeps its last pose.
        atomicAdd(&held[0], 1u);
    } else {
        var last: Pose;
        last.position = state[base].xyz;
        last.normal = state[base + 1u].xyz;
        last.tangent = state[base + 2u].xyz;
        last.ok = true;
        let jump = now.position - last.position;
        var at_rest = sim.reset == 1u || state[base].w != 1.0
            || dot(jump, jump) > sim.teleport_distance * sim.teleport_distance;
        let margin = 0.5 * root.width;
        let segments = f32(u.segments);
        for (var substep = 0u; substep < sim.substeps && !at_rest; substep++) {
            let s = f32(substep + 1u) / f32(sim.substeps);
            var pose: Pose;
            pose.position = mix(last.position, now.position, s);
            pose.normal = safe_normalize(mix(last.normal, now.normal, s), now.normal);
            pose.tangent = perpendicular(pose.normal, mix(last.tangent, now.tangent, s));
            let t = sim.time0 + sim.h * f32(substep + 1u) + root.phase * u.phase_spread;
            let base_force = uniform_force(t);
            let h2 = sim.h * sim.h;

            let x0 = to_world(pose, state[rest].xyz);
            state[pos] = vec4<f32>(x0, 0.0);
            state[prv] = vec4<f32>(x0, 0.0);
            var parent = x0;
            var parent_prev = x0;
            var rest_parent = x0;
            var q = vec4<f32>(0.0, 0.0, 0.0, 1.0);
            // The skin's inverse starts where it settled for the first vertex last
            // substep (or cold), and each later vertex where the one before it did.
            if SDF_SKIN {
                skin_last_p = skin_head_p;
                skin_last_q = skin_head_q;
                skin_last_inv = skin_head_inv;
            }
            for (var k = 1u; k < n; k++) {
                // Verlet.
                var p = state[pos + k].xyz;
                var prev = state[prv + k].xyz;
                let a = sim.gravity + force(p, t, base_force) * sim.wind_response;
                let v = (p - prev) * sim.keep;
                prev = p;
                p = p + v + a * h2;
                // Global shape: toward the rest position in the root's frame.
                let rest_k = to_world(pose, state[rest + k].xyz);
                let reach = 1.0 - f32(k) / segments / sim.global_range;
                let held = mix(p, rest_k, sim.global_stiffness * max(reach, 0.0));
                prev = prev + (held - p);
                p = held;
                // Local shape: toward the rest direction turned like the segments before.
                let rest_offset = rest_k - rest_parent;
                let len = length(rest_offset);
                let rest_dir = quat_rotate(q, safe_normalize(rest_offset, pose.normal));
                // The pull moves the previous position with it: it bends the strand
                // without giving it speed (a pull that became velocity, as every other
                // correction does, set the free half of a strand kinking).
                let pulled = mix(p, parent + rest_dir * len, sim.local_stiffness);
                prev = prev + (pulled - p);
                p = pulled;
                // Collisions, then follow the leader, COLLISION_PASSES times: each
                // collision fixes what the length projection before it pushed back in.
                // Through a skin, the vertex's bind-pose point first (the rounds read
                // the field from it).
                if SDF_SKIN && sim.sdf_on == 1u {
                    skin_settle(p);
                }
                var m = Moved(p, prev);
                var dir = rest_dir;
                var correction = vec3<f32>(0.0);
                for (var round = 0u; round < COLLISION_PASSES; round++) {
                    m = collide(m.p, m.prev, margin, pose.normal, select(0.0, sim.friction, round == 0u));
                    dir = safe_normalize(m.p - parent, rest_dir);
                    let on_length = parent + dir * len;
                    correction = correction + (on_length - m.p);
                    m.p = on_length;
                }
                m.p = onto_length_outside(m.p, parent, len, margin);
                dir = safe_normalize(m.p - parent, dir);
                p = m.p;
                prev = m.prev;
                // DFTL: the parent's velocity loses length_damping of this correction.
                if k > 1u {
                    parent_prev = parent_prev + correction * sim.length_damping;
                    state[prv + k - 1u] = vec4<f32>(parent_prev, 0.0);
                }
                q = quat_mul(quat_between(rest_dir, dir), q);
                q = q / length(q);
                if !all_finite3(p) || !all_finite3(prev) {
                    at_rest = true;
                }
                state[pos + k] = vec4<f32>(p, 0.0);
                parent = p;
                parent_prev = prev;
                rest_parent = rest_k;
                if SDF_SKIN && k == 1u {
                    skin_head_p = skin_last_p;
                    skin_head_q = skin_last_q;
                    skin_head_inv = skin_last_inv;
                }
            }
            state[prv + n - 1u] = vec4<f32>(parent_prev, 0.0);
        }
        if at_rest {
            for (var k = 0u; k < n; k++) {
                let p = to_world(now, state[rest + k].xyz);
                state[pos + k] = vec4<f32>(p, 0.0);
                state[prv + k] = vec4<f32>(p, 0.0);
            }
        }
        state[base] = vec4<f32>(now.position, 1.0);
        state[base + 1u] = vec4<f32>(now.normal, 0.0);
        state[base + 2u] = vec4<f32>(now.tangent, 0.0);
    }

    if strand >= u.strand_count {
        return;
    }
    let x = (f32(strand) + 0.5) / f32(u.strand_total);
    drawn[strand].width = root.width * lod_scale(x, u.lod_lambda, u.lod_t_e, u.lod_s_max, u.lod_s_min);
    let step = max(u.step, 1u);
    let drawn_base = strand * (u.segments / step + 1u);
    for (var k = 0u; k < n; k += step) {
        vertices[drawn_base + k / step] = vec4<f32>(state[pos + k].xyz, f32(k) / f32(u.segments));
    }
}
