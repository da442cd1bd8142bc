//! Mirror of `wgsl/strands/simulate.wgsl` (stage 1 with dynamics), loop for loop: one
//! frame of every strand, its substeps, its constraints in the same order.
//!
//! The mirror takes the parameters ([`Step`]: the hair, the dynamics, the colliders, the
//! frame's time and time step, the level of detail) and works out the frame's substeps
//! itself, as `DynamicsParams` documents them: the step clamped to `max_frame`, cut into
//! `ceil(dt / (max_substep (1 + SUBSTEP_SLACK)))` equal substeps, velocities kept by
//! `exp(-damping h)` per substep, each stiffness `s` (given per `STIFFNESS_INTERVAL`)
//! taking `1 - (1 - s)^(h / STIFFNESS_INTERVAL)` per substep, the acceleration
//! `gravity + wind_response · F` with `F` the wind's force field alone.
//!
//! Not mirrored: the body's distance field (`DynamicsParams::sdf_resolution`); the mirror
//! collides with the spheres and capsules only, and is compared with simulations
//! without a field. Collisions with the field are checked against exact distances
//! instead ([`crate::sdf`], `crates/pelage-strands/tests/sdf.rs`).

use glam::{Vec3, Vec4};
use pelage_scene::{
    Collider, DynamicsParams, HairParams, MAX_COLLIDERS, Mesh, STIFFNESS_INTERVAL, SUBSTEP_SLACK,
};

use crate::strands::{
    Drawn, Field, Level, Root, force, perpendicular, quat_between, quat_mul, quat_rotate,
    safe_normalize,
};

/// `vec4`s of state per strand before its vertices (`STATE_HEADER` in WGSL): the root's
/// position (w = 1 once posed), normal and tangent in the last frame.
pub const STATE_HEADER: usize = 3;

/// One frame of a simulation, as the caller of `SimulateStrands` sets it up.
#[derive(Clone, Copy, Debug)]
pub struct Step<'a> {
    /// The parameters of the simulated strands (`StrandStage::params`): segments, strand
    /// count, the wind and its seed.
    pub hair: &'a HairParams,
    /// The dynamics in use.
    pub dynamics: &'a DynamicsParams,
    /// The colliders in use (the first `MAX_COLLIDERS`).
    pub colliders: &'a [Collider],
    /// The frame's time, seconds.
    pub time: f32,
    /// The time since the last frame (`time` minus the last frame's), or `None` when the
    /// strands start at rest in this frame's pose (the first frame, a reset, time going
    /// backwards).
    pub dt: Option<f32>,
    /// The level of detail drawn (every strand is simulated).
    pub level: Level,
}

/// A capsule (a sphere when `a == b`).
#[derive(Clone, Copy, Debug)]
struct Capsule {
    a: Vec3,
    b: Vec3,
    radius: f32,
}

/// What the frame's substeps are, from the dynamics and the step (see the module's docs).
#[derive(Clone, Copy, Debug)]
struct Substeps {
    count: u32,
    /// Length of each, seconds.
    h: f32,
    /// The time the first substep starts at.
    time0: f32,
    /// Velocity kept per substep.
    keep: f32,
    local_stiffness: f32,
    global_stiffness: f32,
}

/// The fraction of the way a substep of `h` takes for a stiffness `s` given per
/// `STIFFNESS_INTERVAL`: `1 - (1 - s)^(h / interval)`, in `f64`.
fn per_substep(s: f32, h: f32) -> f32 {
    let s = f64::from(s.clamp(0.0, 1.0));
    if h <= 0.0 {
        return s as f32;
    }
    let ratio = f64::from(h) / f64::from(STIFFNESS_INTERVAL);
    (1.0 - (1.0 - s).powf(ratio)) as f32
}

impl Substeps {
    fn new(dynamics: &DynamicsParams, time: f32, dt: Option<f32>) -> Self {
        let dt = dt
            .filter(|d| d.is_finite())
            .map(|d| d.clamp(0.0, dynamics.max_frame));
        let longest = dynamics.max_substep * (1.0 + SUBSTEP_SLACK);
        let count = dt.map_or(0, |dt| (dt / longest).ceil() as u32);
        let h = match (dt, count) {
            (Some(dt), 1..) => dt / count as f32,
            _ => 0.0,
        };
        Self {
            count,
            h,
            time0: time - h * count as f32,
            keep: (-dynamics.damping * h).exp(),
            local_stiffness: per_substep(dynamics.local_stiffness, h),
            global_stiffness: per_substep(dynamics.global_stiffness, h),
        }
    }
}

/// Rounds of collision and length projection per vertex and substep
/// (`COLLISION_PASSES` in WGSL).
const COLLISION_PASSES: u32 = 3;

/// WGSL `mix` on vectors: `a * (1 - t) + b * t`.
fn mix(a: Vec3, b: Vec3, t: f32) -> Vec3 {
    a * (1.0 - t) + b * t
}

/// `Pose` in WGSL: a root's position, normal and tangent, `ok` false when the mesh under
/// it is not finite.
#[derive(Clone, Copy, Debug)]
struct Pose {
    position: Vec3,
    normal: Vec3,
    tangent: Vec3,
    ok: bool,
}

/// `root_pose` in WGSL, on the current `mesh` (which may hold non-finite values).
fn root_pose(mesh: &Mesh, tri: u32, bary: glam::Vec2) -> Pose {
    let idx = |k: usize| mesh.indices[tri as usize * 3 + k] as usize;
    let (i1, i2, i3) = (idx(0), idx(1), idx(2));
    let (p1, p2, p3) = (mesh.positions[i1], mesh.positions[i2], mesh.positions[i3]);
    let (n1, n2, n3) = (mesh.normals[i1], mesh.normals[i2], mesh.normals[i3]);
    let bw = 1.0 - bary.x - bary.y;
    let ok = [p1, p2, p3, n1, n2, n3].iter().all(|v| v.is_finite());
    let position = p1 * bary.x + p2 * bary.y + p3 * bw;
    let normal = safe_normalize(n1 * bary.x + n2 * bary.y + n3 * bw, Vec3::Y);
    let tangent = perpendicular(normal, p2 - p1);
    Pose {
        position,
        normal,
        tangent,
        ok: ok && position.is_finite(),
    }
}

/// `to_world` in WGSL.
fn to_world(pose: &Pose, local: Vec3) -> Vec3 {
    pose.position
        + pose.tangent * local.x
        + pose.normal * local.y
        + pose.tangent.cross(pose.normal) * local.z
}

/// `axis_point` in WGSL: the point of `col`'s axis nearest `p`.
fn axis_point(col: &Capsule, p: Vec3) -> Vec3 {
    let axis = col.b - col.a;
    let len2 = axis.dot(axis);
    let s = if len2 > 0.0 {
        ((p - col.a).dot(axis) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    col.a + axis * s
}

/// `collide` in WGSL: `(p, prev)` pushed out of every collider, `prev` moved by
/// `friction` of the tangential motion.
fn collide(
    colliders: &[Capsule],
    p_in: Vec3,
    prev_in: Vec3,
    margin: f32,
    fallback: Vec3,
    friction: f32,
) -> (Vec3, Vec3) {
    let (mut p, mut prev) = (p_in, prev_in);
    for col in colliders {
        let nearest = axis_point(col, p);
        let r = col.radius + margin;
        let d = p - nearest;
        if d.dot(d) < r * r {
            let n = safe_normalize(d, fallback);
            p = nearest + n * r;
            let v = p - prev;
            prev += (v - n * v.dot(n)) * friction;
        }
    }
    (p, prev)
}

/// `onto_length_outside` in WGSL: `p` (at `len` from `parent`) moved along that sphere onto
/// the circle where it meets each collider it is inside.
fn onto_length_outside(
    colliders: &[Capsule],
    p_in: Vec3,
    parent: Vec3,
    len: f32,
    margin: f32,
) -> Vec3 {
    let mut p = p_in;
    for col in colliders {
        let center = axis_point(col, p);
        let r = col.radius + margin;
        let off = p - center;
        let w = center - parent;
        let d = w.length();
        if off.dot(off) < r * r && d > (r - len).abs() && d < r + len {
            let toward = w / d;
            let along = (d * d + len * len - r * r) / (2.0 * d);
            let o = parent + toward * along;
            p = o + perpendicular(toward, p - o) * (len * len - along * along).max(0.0).sqrt();
        }
    }
    p
}

/// One frame of `simulate.wgsl` for every strand: steps `state` (the layout of
/// `SimulateStrands::state`, as read back: per strand [`STATE_HEADER`] `vec4`s of root
/// pose, then its rest shape, positions and previous positions, `segments + 1` each) in
/// place on `mesh` (the pose the mesh buffers hold this frame) and returns the vertices
/// of the drawn strands (the layout of `StrandBuffers::vertices`) and the number of
/// strands held because their root's triangle is not finite.
pub fn simulate_frame(
    mesh: &Mesh,
    roots: &[Root],
    state: &mut [Vec4],
    frame: &Step<'_>,
) -> (Vec<Vec4>, u32) {
    let drawn = Drawn::new(frame.hair, frame.level);
    let sub = Substeps::new(frame.dynamics, frame.time, frame.dt);
    let reset = frame.dt.is_none();
    let d = frame.dynamics;
    // The wind's force field alone: `wind_response` turns it into an acceleration.
    let field = Field::new(frame.hair, Vec3::ZERO);
    let phase_spread = frame.hair.wind.phase_spread;
    let colliders: Vec<Capsule> = frame
        .colliders
        .iter()
        .take(MAX_COLLIDERS)
        .map(|c| {
            let (a, b) = c.axis();
            Capsule {
                a,
                b,
                radius: c.radius,
            }
        })
        .collect();
    let n = drawn.segments as usize + 1;
    let header = STATE_HEADER;
    let step = drawn.step as usize;
    let per_drawn = drawn.per_strand();
    let mut vertices = vec![Vec4::ZERO; drawn.strands as usize * per_drawn];
    let mut held = 0;
    let total = frame.hair.roots.count as usize;
    for (strand, root) in roots.iter().enumerate().take(total) {
        let base = strand * (header + 3 * n);
        let rest = base + header;
        let pos = rest + n;
        let prv = pos + n;
        let now = root_pose(mesh, root.triangle, root.bary);
        if !now.ok {
            held += 1;
        } else {
            let last = Pose {
                position: state[base].truncate(),
                normal: state[base + 1].truncate(),
                tangent: state[base + 2].truncate(),
                ok: true,
            };
            let jump = now.position - last.position;
            let mut at_rest = reset
                || state[base].w != 1.0
                || jump.dot(jump) > d.teleport_distance * d.teleport_distance;
            let margin = 0.5 * root.width;
            let segments = drawn.segments as f32;
            let mut i = 0;
            while i < sub.count && !at_rest {
                let s = (i + 1) as f32 / sub.count as f32;
                let normal = safe_normalize(mix(last.normal, now.normal, s), now.normal);
                let pose = Pose {
                    position: mix(last.position, now.position, s),
                    normal,
                    tangent: perpendicular(normal, mix(last.tangent, now.tangent, s)),
                    ok: true,
                };
                let t = sub.time0 + sub.h * (i + 1) as f32 + root.phase * phase_spread;
                let h2 = sub.h * sub.h;

                let x0 = to_world(&pose, state[rest].truncate());
                state[pos] = x0.extend(0.0);
                state[prv] = x0.extend(0.0);
                let mut parent = x0;
                let mut parent_prev = x0;
                let mut rest_parent = x0;
                let mut q = Vec4::new(0.0, 0.0, 0.0, 1.0);
                for k in 1..n {
                    let mut p = state[pos + k].truncate();
                    let mut prev = state[prv + k].truncate();
                    let a = d.gravity + force(&field, p, t) * d.wind_response;
                    let v = (p - prev) * sub.keep;
                    prev = p;
                    p = p + v + a * h2;
                    let rest_k = to_world(&pose, state[rest + k].truncate());
                    let reach = 1.0 - k as f32 / segments / d.global_range;
                    let held = mix(p, rest_k, sub.global_stiffness * reach.max(0.0));
                    prev += held - p;
                    p = held;
                    let rest_offset = rest_k - rest_parent;
                    let len = rest_offset.length();
                    let rest_dir = quat_rotate(q, safe_normalize(rest_offset, pose.normal));
                    let pulled = mix(p, parent + rest_dir * len, sub.local_stiffness);
                    prev += pulled - p;
                    p = pulled;
                    let mut dir = rest_dir;
                    let mut correction = Vec3::ZERO;
                    for round in 0..COLLISION_PASSES {
                        let friction = if round == 0 { d.friction } else { 0.0 };
                        let (mp, mprev) =
                            collide(&colliders, p, prev, margin, pose.normal, friction);
                        dir = safe_normalize(mp - parent, rest_dir);
                        let fixed = parent + dir * len;
                        correction += fixed - mp;
                        p = fixed;
                        prev = mprev;
                    }
                    p = onto_length_outside(&colliders, p, parent, len, margin);
                    dir = safe_normalize(p - parent, dir);
                    if k > 1 {
                        parent_prev += correction * d.length_damping;
                        state[prv + k - 1] = parent_prev.extend(0.0);
                    }
                    q = quat_mul(quat_between(rest_dir, dir), q);
                    q /= q.length();
                    if !p.is_finite() || !prev.is_finite() {
                        at_rest = true;
                    }
                    state[pos + k] = p.extend(0.0);
                    parent = p;
                    parent_prev = prev;
                    rest_parent = rest_k;
                }
                state[prv + n - 1] = parent_prev.extend(0.0);
                i += 1;
            }
            if at_rest {
                for k in 0..n {
                    let p = to_world(&now, state[rest + k].truncate());
                    state[pos + k] = p.extend(0.0);
                    state[prv + k] = p.extend(0.0);
                }
            }
            state[base] = now.position.extend(1.0);
            state[base + 1] = now.normal.extend(0.0);
            state[base + 2] = now.tangent.extend(0.0);
        }
        if strand >= drawn.strands as usize {
            continue;
        }
        let out = strand * per_drawn;
        for k in (0..n).step_by(step) {
            vertices[out + k / step] = state[pos + k]
                .truncate()
                .extend(k as f32 / drawn.segments as f32);
        }
    }
    (vertices, held)
}
