//! Mirror of `wgsl/strands/simulate.wgsl` (stage 1 with dynamics), loop for loop: one
//! frame of every strand, its substeps, its constraints in the same order.
//!
//! Not mirrored: the body's distance field (`SimUniforms::sdf_on`, `BodySdf`); the mirror
//! collides with the spheres and capsules only, and is compared with simulations
//! without a field. Collisions with the field are checked against exact distances
//! instead ([`crate::sdf`], `crates/pelage-strands/tests/sdf.rs`).

use glam::{Vec3, Vec4};
use pelage_scene::Mesh;
use pelage_strands::{ColliderUniform, GrowUniforms, STATE_HEADER, SimUniforms, StrandRoot};

use crate::strands::{force, perpendicular, quat_between, quat_mul, quat_rotate, safe_normalize};

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
fn axis_point(col: &ColliderUniform, p: Vec3) -> Vec3 {
    let axis = col.b - col.a;
    let len2 = axis.dot(axis);
    let s = if len2 > 0.0 {
        ((p - col.a).dot(axis) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    col.a + axis * s
}

/// `collide` in WGSL: `(p, prev)` pushed out of every collider of `sim`, `prev` moved
/// by `friction` of the tangential motion.
fn collide(
    sim: &SimUniforms,
    p_in: Vec3,
    prev_in: Vec3,
    margin: f32,
    fallback: Vec3,
    friction: f32,
) -> (Vec3, Vec3) {
    let (mut p, mut prev) = (p_in, prev_in);
    for col in sim.colliders.iter().take(sim.collider_count as usize) {
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
fn onto_length_outside(sim: &SimUniforms, p_in: Vec3, parent: Vec3, len: f32, margin: f32) -> Vec3 {
    let mut p = p_in;
    for col in sim.colliders.iter().take(sim.collider_count as usize) {
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
/// `SimulateStrands::state`, as read back) in place on `mesh` (the pose the mesh
/// buffers hold this frame) and returns the vertices of the drawn strands (the layout of
/// `StrandBuffers::vertices`) and the number of strands held because their root's
/// triangle is not finite.
pub fn simulate_frame(
    mesh: &Mesh,
    roots: &[StrandRoot],
    state: &mut [Vec4],
    u: &GrowUniforms,
    sim: &SimUniforms,
) -> (Vec<Vec4>, u32) {
    let n = u.segments as usize + 1;
    let header = STATE_HEADER as usize;
    let step = u.step.max(1) as usize;
    let per_drawn = u.segments as usize / step + 1;
    let mut vertices = vec![Vec4::ZERO; u.strand_count as usize * per_drawn];
    let mut held = 0;
    for (strand, root) in roots.iter().enumerate().take(u.strand_total as usize) {
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
            let mut at_rest = sim.reset == 1
                || state[base].w != 1.0
                || jump.dot(jump) > sim.teleport_distance * sim.teleport_distance;
            let margin = 0.5 * root.width;
            let segments = u.segments as f32;
            let mut sub = 0;
            while sub < sim.substeps && !at_rest {
                let s = (sub + 1) as f32 / sim.substeps as f32;
                let normal = safe_normalize(mix(last.normal, now.normal, s), now.normal);
                let pose = Pose {
                    position: mix(last.position, now.position, s),
                    normal,
                    tangent: perpendicular(normal, mix(last.tangent, now.tangent, s)),
                    ok: true,
                };
                let t = sim.time0 + sim.h * (sub + 1) as f32 + root.phase * u.phase_spread;
                let h2 = sim.h * sim.h;

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
                    let a = sim.gravity + force(u, p, t) * sim.wind_response;
                    let v = (p - prev) * sim.keep;
                    prev = p;
                    p = p + v + a * h2;
                    let rest_k = to_world(&pose, state[rest + k].truncate());
                    let reach = 1.0 - k as f32 / segments / sim.global_range;
                    let held = mix(p, rest_k, sim.global_stiffness * reach.max(0.0));
                    prev += held - p;
                    p = held;
                    let rest_offset = rest_k - rest_parent;
                    let len = rest_offset.length();
                    let rest_dir = quat_rotate(q, safe_normalize(rest_offset, pose.normal));
                    let pulled = mix(p, parent + rest_dir * len, sim.local_stiffness);
                    prev += pulled - p;
                    p = pulled;
                    let mut dir = rest_dir;
                    let mut correction = Vec3::ZERO;
                    for round in 0..COLLISION_PASSES {
                        let friction = if round == 0 { sim.friction } else { 0.0 };
                        let (mp, mprev) = collide(sim, p, prev, margin, pose.normal, friction);
                        dir = safe_normalize(mp - parent, rest_dir);
                        let fixed = parent + dir * len;
                        correction += fixed - mp;
                        p = fixed;
                        prev = mprev;
                    }
                    p = onto_length_outside(sim, p, parent, len, margin);
                    dir = safe_normalize(p - parent, dir);
                    if k > 1 {
                        parent_prev += correction * sim.length_damping;
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
                sub += 1;
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
        if strand >= u.strand_count as usize {
            continue;
        }
        let out = strand * per_drawn;
        for k in (0..n).step_by(step) {
            vertices[out + k / step] = state[pos + k]
                .truncate()
                .extend(k as f32 / u.segments as f32);
        }
    }
    (vertices, held)
}
