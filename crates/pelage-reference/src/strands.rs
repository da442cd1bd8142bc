//! Mirrors of the stage 1 shaders, loop for loop: `wgsl/strands/grow.wgsl` (strands grown
//! from a mesh) and `wgsl/strands/groom.wgsl` (a groom file bent by the wind).

use std::f32::consts::PI;

use glam::{Vec3, Vec4};
use pelage_scene::Mesh;
use pelage_strands::{GrowUniforms, RegionShape, StrandRoot};

use crate::noise::{value_noise_1d, value_noise_3d};

/// `safe_normalize` in `wgsl/shared/math.wgsl`: `v` at unit length, or `fallback` when `v`
/// has a non-finite component or its largest component is below 1e-20.
pub fn safe_normalize(v: Vec3, fallback: Vec3) -> Vec3 {
    if !v.is_finite() {
        return fallback;
    }
    let largest = v.abs().max_element();
    if largest < 1e-20 {
        return fallback;
    }
    let u = v / largest;
    u / u.length()
}

/// Position, normal and tangent on the surface (the `Surface` struct in WGSL).
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    /// Point on the surface.
    pub position: Vec3,
    /// Unit normal.
    pub normal: Vec3,
    /// Unit tangent that turns with the triangle.
    pub tangent: Vec3,
}

fn pn_edge(pi: Vec3, pj: Vec3, ni: Vec3) -> Vec3 {
    let w = (pj - pi).dot(ni);
    (2.0 * pi + pj - w * ni) / 3.0
}

fn pn_edge_normal(pi: Vec3, pj: Vec3, ni: Vec3, nj: Vec3) -> Vec3 {
    let d = pj - pi;
    let dd = d.dot(d);
    let v = if dd > 0.0 {
        2.0 * d.dot(ni + nj) / dd
    } else {
        0.0
    };
    safe_normalize(ni + nj - v * d, ni)
}

/// `perpendicular` in WGSL.
pub fn perpendicular(n: Vec3, hint: Vec3) -> Vec3 {
    let fallback = if n.x.abs() > 0.9 { Vec3::Y } else { Vec3::X };
    let f = safe_normalize(fallback - fallback.dot(n) * n, Vec3::Z);
    safe_normalize(hint - hint.dot(n) * n, f)
}

/// `eval_surface` in WGSL: the surface at barycentrics `(u, v)` of triangle `tri`, PN when `pn`.
pub fn eval_surface(mesh: &Mesh, tri: u32, bary: glam::Vec2, pn: bool) -> Surface {
    let idx = |k: usize| mesh.indices[tri as usize * 3 + k] as usize;
    let (i1, i2, i3) = (idx(0), idx(1), idx(2));
    let (p1, p2, p3) = (mesh.positions[i1], mesh.positions[i2], mesh.positions[i3]);
    let n1 = safe_normalize(mesh.normals[i1], Vec3::Y);
    let n2 = safe_normalize(mesh.normals[i2], n1);
    let n3 = safe_normalize(mesh.normals[i3], n1);
    let (bu, bv) = (bary.x, bary.y);
    let bw = 1.0 - bu - bv;
    let (position, normal) = if pn {
        let p210 = pn_edge(p1, p2, n1);
        let p120 = pn_edge(p2, p1, n2);
        let p021 = pn_edge(p2, p3, n2);
        let p012 = pn_edge(p3, p2, n3);
        let p102 = pn_edge(p3, p1, n3);
        let p201 = pn_edge(p1, p3, n1);
        let e = (p210 + p120 + p021 + p012 + p102 + p201) / 6.0;
        let c = (p1 + p2 + p3) / 3.0;
        let p111 = e + (e - c) * 0.5;
        let position = p1 * (bu * bu * bu)
            + p2 * (bv * bv * bv)
            + p3 * (bw * bw * bw)
            + p210 * (3.0 * bu * bu * bv)
            + p120 * (3.0 * bu * bv * bv)
            + p201 * (3.0 * bu * bu * bw)
            + p021 * (3.0 * bv * bv * bw)
            + p012 * (3.0 * bv * bw * bw)
            + p102 * (3.0 * bu * bw * bw)
            + p111 * (6.0 * bu * bv * bw);
        let n110 = pn_edge_normal(p1, p2, n1, n2);
        let n011 = pn_edge_normal(p2, p3, n2, n3);
        let n101 = pn_edge_normal(p3, p1, n3, n1);
        let n = n1 * (bu * bu)
            + n2 * (bv * bv)
            + n3 * (bw * bw)
            + n110 * (bu * bv)
            + n011 * (bv * bw)
            + n101 * (bu * bw);
        (position, safe_normalize(n, n1))
    } else {
        (
            p1 * bu + p2 * bv + p3 * bw,
            safe_normalize(n1 * bu + n2 * bv + n3 * bw, n1),
        )
    };
    Surface {
        position,
        normal,
        tangent: perpendicular(normal, p2 - p1),
    }
}

/// `force` in WGSL.
pub fn force(u: &GrowUniforms, p: Vec3, t: f32) -> Vec3 {
    let gust = 1.0 + u.gust_strength * value_noise_1d(t * u.gust_frequency, u.seed ^ 0x9e37_79b9);
    let mut f = u.gravity + u.wind_direction * (u.wind_strength * gust);
    if u.turbulence > 0.0 {
        let q = p * u.turbulence_scale - u.wind_direction * (t * u.turbulence_speed);
        let turb = Vec3::new(
            value_noise_3d(q, u.seed ^ 0x68e3_1da4),
            value_noise_3d(q, u.seed ^ 0xb529_7a4d),
            value_noise_3d(q, u.seed ^ 0x1b56_c4e9),
        );
        f += turb * u.turbulence;
    }
    f
}

fn shaped_tangent(shape: &RegionShape, d: Vec3, e1: Vec3, e2: Vec3, s: f32) -> Vec3 {
    match shape.kind {
        1 => {
            let k = 2.0 * PI * shape.b;
            let theta = (k * shape.a * (k * s).cos()).atan();
            d * theta.cos() + e1 * theta.sin()
        }
        2 => {
            let circumference = 2.0 * PI * shape.a;
            let turn_length = (circumference * circumference + shape.b * shape.b).sqrt();
            let theta = circumference.atan2(shape.b);
            let phi = 2.0 * PI * s / turn_length;
            d * theta.cos() + (e1 * phi.cos() + e2 * phi.sin()) * theta.sin()
        }
        _ => d,
    }
}

/// Grows one strand: `segments / step + 1` vertices (xyz position, w strand parameter),
/// every `step`-th vertex of the strand grown at full resolution, with the shape of its
/// region among `shapes` (the last for a region beyond them, as in WGSL).
pub fn grow_strand(
    mesh: &Mesh,
    root: &StrandRoot,
    u: &GrowUniforms,
    shapes: &[RegionShape],
) -> Vec<Vec4> {
    let shape = shapes
        .get(root.region as usize)
        .or(shapes.last())
        .copied()
        .unwrap_or_default();
    let surf = eval_surface(mesh, root.triangle, root.bary, u.surface == 1);
    let side =
        surf.tangent * root.azimuth.cos() + surf.normal.cross(surf.tangent) * root.azimuth.sin();
    let mut d = safe_normalize(
        surf.normal * root.tilt.cos() + side * root.tilt.sin(),
        surf.normal,
    );
    let mut e1 = perpendicular(d, surf.tangent);
    let mut e2 = d.cross(e1);

    let segments = u.segments;
    let seg_len = root.length / segments as f32;
    let t = u.time + root.phase * u.phase_spread;
    let mut p = surf.position;
    let step = u.step.max(1);
    let mut out = Vec::with_capacity((segments / step) as usize + 1);
    out.push(p.extend(0.0));
    for i in 0..segments {
        let s = (i as f32 + 0.5) * seg_len;
        let tangent = shaped_tangent(&shape, d, e1, e2, s);
        p += tangent * seg_len;
        if (i + 1) % step == 0 {
            out.push(p.extend((i + 1) as f32 / segments as f32));
        }
        let d_next = safe_normalize(d + force(u, p, t) * u.force_weight, d);
        e1 = perpendicular(d_next, e1);
        e2 = d_next.cross(e1);
        d = d_next;
    }
    out
}

/// Grows the strands `u` grows (the first `u.strand_count`), in the layout of
/// `StrandBuffers::vertices`, each region with its shape in `shapes`
/// (`GrowStrands::region_shapes`).
pub fn grow_strands(
    mesh: &Mesh,
    roots: &[StrandRoot],
    u: &GrowUniforms,
    shapes: &[RegionShape],
) -> Vec<Vec4> {
    roots
        .iter()
        .take(u.strand_count as usize)
        .flat_map(|r| grow_strand(mesh, r, u, shapes))
        .collect()
}

/// The width stage 1 gives strand `index` (its rest width times the level of detail's
/// width scale), as `GrowStrands` writes it into the roots buffer.
pub fn drawn_width(root: &StrandRoot, index: u32, u: &GrowUniforms) -> f32 {
    let zone = pelage_scene::Transition {
        lambda: u.lod_lambda,
        t_e: u.lod_t_e,
        s_max: u.lod_s_max,
        s_min: u.lod_s_min,
    };
    root.width * zone.scale((index as f32 + 0.5) / u.strand_total.max(1) as f32)
}

/// `quat_rotate` in `wgsl/strands/groom.wgsl`: `v` turned by the unit quaternion `q`
/// (xyz = vector part, w = scalar part).
pub(crate) fn quat_rotate(q: Vec4, v: Vec3) -> Vec3 {
    let axis = q.truncate();
    v + 2.0 * axis.cross(axis.cross(v) + q.w * v)
}

/// `quat_mul` in WGSL: the rotation `a` after `b`.
pub(crate) fn quat_mul(a: Vec4, b: Vec4) -> Vec4 {
    let (av, bv) = (a.truncate(), b.truncate());
    (a.w * bv + b.w * av + av.cross(bv)).extend(a.w * b.w - av.dot(bv))
}

/// `quat_between` in WGSL: the shortest rotation taking unit `a` to unit `b`.
pub(crate) fn quat_between(a: Vec3, b: Vec3) -> Vec4 {
    let w = 1.0 + a.dot(b);
    if w < 1e-6 {
        let hint = if a.x.abs() > 0.9 { Vec3::Y } else { Vec3::X };
        return safe_normalize(a.cross(hint), Vec3::Z).extend(0.0);
    }
    let q = a.cross(b).extend(w);
    q / q.length()
}

/// Mirror of `main` in `wgsl/strands/groom.wgsl` for one strand: its rest points
/// (`u.segments + 1`, root first) bent by the force field of `u` at the strand's time;
/// `u.segments / u.step + 1` vertices (xyz position, w strand parameter).
pub fn deform_groom_strand(rest: &[Vec3], root: &StrandRoot, u: &GrowUniforms) -> Vec<Vec4> {
    let segments = u.segments;
    let step = u.step.max(1);
    let t = u.time + root.phase * u.phase_spread;
    let rest_at = |i: u32| rest.get(i as usize).copied().unwrap_or(Vec3::ZERO);
    let mut q = Vec4::new(0.0, 0.0, 0.0, 1.0);
    let mut p = rest_at(0);
    let mut d = Vec3::Y;
    // No force has turned the strand yet: its vertices are the rest points.
    let mut at_rest = true;
    let mut out = Vec::with_capacity((segments / step) as usize + 1);
    out.push(p.extend(0.0));
    for i in 0..segments {
        let offset = rest_at(i + 1) - rest_at(i);
        let conjugate = (-q.truncate()).extend(q.w);
        d = quat_rotate(q, safe_normalize(offset, quat_rotate(conjugate, d)));
        if at_rest {
            p = rest_at(i + 1);
        } else {
            p += d * offset.length();
        }
        if (i + 1) % step == 0 {
            out.push(p.extend((i + 1) as f32 / segments as f32));
        }
        let push = force(u, p, t) * u.force_weight;
        at_rest = at_rest && push == Vec3::ZERO;
        let bent = safe_normalize(d + push, d);
        q = quat_mul(quat_between(d, bent), q);
        q /= q.length();
        d = bent;
    }
    out
}

/// Deforms the strands `u` draws (the first `u.strand_count`) of a groom whose rest
/// points are `rest` (`u.segments + 1` per strand, in the order of `roots`), in the
/// layout of `StrandBuffers::vertices`: the mirror of `wgsl/strands/groom.wgsl`.
pub fn deform_groom(rest: &[Vec3], roots: &[StrandRoot], u: &GrowUniforms) -> Vec<Vec4> {
    let per_strand = u.segments as usize + 1;
    rest.chunks(per_strand)
        .zip(roots)
        .take(u.strand_count as usize)
        .flat_map(|(points, root)| deform_groom_strand(points, root, u))
        .collect()
}
