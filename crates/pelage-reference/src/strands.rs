//! Mirrors of the stage 1 shaders, loop for loop: `wgsl/strands/grow.wgsl` (strands grown
//! from a mesh) and `wgsl/strands/groom.wgsl` (a groom file bent by the wind).
//!
//! The mirrors take the parameters themselves (`HairParams`, the time, the level of detail
//! as plain numbers) and work out what the shaders' uniforms hold on their own: the strand
//! count, the step between kept vertices, the unit wind direction, the shape of each
//! region. So a mistake in how pelage-strands packs its uniforms shows as a difference
//! between the GPU and the mirror. Their only inputs made by pelage-strands are the roots
//! (sampled on the CPU: [`Root`]) and, for a groom, its rest points.

use std::f32::consts::PI;

use glam::{Vec2, Vec3, Vec4};
use pelage_scene::{HairParams, HairType, Mesh, SurfaceInterpolation, Transition};

use crate::noise::{value_noise_1d, value_noise_3d};

/// One strand's root and attributes, as the CPU sampled them (the fields of
/// `StrandRoot` in `wgsl/shared/strand.wgsl` that the mirrors read, in plain Rust).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Root {
    /// Triangle the root sits on.
    pub triangle: u32,
    /// The strand's own hash seed.
    pub seed: u32,
    /// Barycentrics of the triangle's first and second corner (the third is `1 - u - v`).
    pub bary: Vec2,
    /// Strand length, scene units.
    pub length: f32,
    /// Width at the root, scene units.
    pub width: f32,
    /// Gust phase as a fraction of `WindParams::phase_spread`.
    pub phase: f32,
    /// Tilt of the root direction away from the normal, radians.
    pub tilt: f32,
    /// Azimuth of that tilt around the normal, radians.
    pub azimuth: f32,
    /// Linear RGB colour.
    pub color: Vec3,
    /// The strand's region (0 for `[hair.growth]`, `k` for its `k`-th region).
    pub region: u32,
}

/// The level of detail of a frame, as plain numbers: the strands drawn (a prefix of the
/// groom) and the segments per drawn strand.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Level {
    /// Strands drawn.
    pub strands: u32,
    /// Segments per drawn strand (a divisor of `growth.segments`).
    pub segments: u32,
}

impl Level {
    /// Every strand and segment of `params`.
    pub fn full(params: &HairParams) -> Self {
        Self {
            strands: params.roots.count,
            segments: params.growth.segments,
        }
    }
}

/// What a stage 1 shader writes of a frame, worked out from the parameters: the strands
/// drawn (the level's, at most the groom's), the groom's segments and the step between
/// the vertices kept.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Drawn {
    /// Strands written.
    pub(crate) strands: u32,
    /// Segments of every strand of the groom.
    pub(crate) segments: u32,
    /// Every `step`-th vertex is written (at least 1).
    pub(crate) step: u32,
}

impl Drawn {
    /// `level` of the groom `params` describes. A level whose segment count does not
    /// divide the groom's (which `set_lod` refuses) keeps every vertex.
    pub(crate) fn new(params: &HairParams, level: Level) -> Self {
        let segments = params.growth.segments;
        let step = match level.segments {
            0 => 1,
            kept if segments.is_multiple_of(kept) => segments / kept,
            _ => 1,
        };
        Self {
            strands: level.strands.min(params.roots.count),
            segments,
            step,
        }
    }

    /// Vertices written per strand.
    pub(crate) fn per_strand(&self) -> usize {
        (self.segments / self.step) as usize + 1
    }
}

/// The force field of `strands/force.wgsl` for a frame: gravity and the gusting,
/// turbulent wind, from the parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Field {
    gravity: Vec3,
    strength: f32,
    /// Unit, or zero for no direction.
    direction: Vec3,
    gust_strength: f32,
    gust_frequency: f32,
    turbulence: f32,
    turbulence_scale: f32,
    turbulence_speed: f32,
    seed: u32,
}

impl Field {
    /// The wind of `params` (seeded by `roots.seed`) with `gravity` added.
    pub(crate) fn new(params: &HairParams, gravity: Vec3) -> Self {
        let w = &params.wind;
        let length = w.direction.length();
        let direction = if length > 0.0 && length.is_finite() {
            w.direction / length
        } else {
            Vec3::ZERO
        };
        Self {
            gravity,
            strength: w.strength,
            direction,
            gust_strength: w.gust_strength,
            gust_frequency: w.gust_frequency,
            turbulence: w.turbulence,
            turbulence_scale: w.turbulence_scale,
            turbulence_speed: w.turbulence_speed,
            seed: params.roots.seed,
        }
    }
}

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

/// `force` in WGSL (with `uniform_force`): the field at `p` for time `t`.
pub(crate) fn force(f: &Field, p: Vec3, t: f32) -> Vec3 {
    let gust = 1.0 + f.gust_strength * value_noise_1d(t * f.gust_frequency, f.seed ^ 0x9e37_79b9);
    let mut out = f.gravity + f.direction * (f.strength * gust);
    if f.turbulence > 0.0 {
        let q = p * f.turbulence_scale - f.direction * (t * f.turbulence_speed);
        let turb = Vec3::new(
            value_noise_3d(q, f.seed ^ 0x68e3_1da4),
            value_noise_3d(q, f.seed ^ 0xb529_7a4d),
            value_noise_3d(q, f.seed ^ 0x1b56_c4e9),
        );
        out += turb * f.turbulence;
    }
    out
}

/// The tangent at arc length `s` of a strand of `hair_type` whose straight direction is
/// `d` (`e1`, `e2` completing the frame), as `shaped_tangent` in `grow.wgsl`.
fn shaped_tangent(hair_type: HairType, d: Vec3, e1: Vec3, e2: Vec3, s: f32) -> Vec3 {
    match hair_type {
        HairType::Straight => d,
        HairType::Wavy {
            amplitude,
            frequency,
        } => {
            let k = 2.0 * PI * frequency;
            let theta = (k * amplitude * (k * s).cos()).atan();
            d * theta.cos() + e1 * theta.sin()
        }
        HairType::Curly { radius, pitch } => {
            let circumference = 2.0 * PI * radius;
            let turn_length = (circumference * circumference + pitch * pitch).sqrt();
            let theta = circumference.atan2(pitch);
            let phi = 2.0 * PI * s / turn_length;
            d * theta.cos() + (e1 * phi.cos() + e2 * phi.sin()) * theta.sin()
        }
    }
}

/// What one strand of grown fur is grown with in a frame.
struct Growth<'a> {
    drawn: Drawn,
    field: Field,
    pn: bool,
    force_weight: f32,
    time: f32,
    phase_spread: f32,
    /// The hair type of each region, region 0 first.
    shapes: &'a [HairType],
}

/// Grows one strand: `segments / step + 1` vertices (xyz position, w strand parameter),
/// every `step`-th vertex of the strand grown at full resolution, with the shape of its
/// region (the last region's for a region beyond them, as in WGSL).
fn grow_strand(mesh: &Mesh, root: &Root, g: &Growth<'_>) -> Vec<Vec4> {
    let shape = g
        .shapes
        .get(root.region as usize)
        .or(g.shapes.last())
        .copied()
        .unwrap_or(HairType::Straight);
    let surf = eval_surface(mesh, root.triangle, root.bary, g.pn);
    let side =
        surf.tangent * root.azimuth.cos() + surf.normal.cross(surf.tangent) * root.azimuth.sin();
    let mut d = safe_normalize(
        surf.normal * root.tilt.cos() + side * root.tilt.sin(),
        surf.normal,
    );
    let mut e1 = perpendicular(d, surf.tangent);
    let mut e2 = d.cross(e1);

    let Drawn { segments, step, .. } = g.drawn;
    let seg_len = root.length / segments as f32;
    let t = g.time + root.phase * g.phase_spread;
    let mut p = surf.position;
    let mut out = Vec::with_capacity(g.drawn.per_strand());
    out.push(p.extend(0.0));
    for i in 0..segments {
        let s = (i as f32 + 0.5) * seg_len;
        let tangent = shaped_tangent(shape, d, e1, e2, s);
        p += tangent * seg_len;
        if (i + 1) % step == 0 {
            out.push(p.extend((i + 1) as f32 / segments as f32));
        }
        let d_next = safe_normalize(d + force(&g.field, p, t) * g.force_weight, d);
        e1 = perpendicular(d_next, e1);
        e2 = d_next.cross(e1);
        d = d_next;
    }
    out
}

/// Grown fur at `time` and `level` (`GrowStrands` with `params`), in the layout of
/// `StrandBuffers::vertices`: the first `level.strands` of `roots` (at most
/// `roots.count`), each grown under `growth.gravity` and the wind with its region's hair
/// type, keeping `level.segments + 1` of its `growth.segments + 1` vertices.
pub fn grow_strands(
    mesh: &Mesh,
    roots: &[Root],
    params: &HairParams,
    time: f32,
    level: Level,
) -> Vec<Vec4> {
    let shapes: Vec<HairType> = params
        .growth
        .resolved_regions()
        .iter()
        .map(|g| g.hair_type)
        .collect();
    let growth = Growth {
        drawn: Drawn::new(params, level),
        field: Field::new(params, params.growth.gravity),
        pn: params.growth.surface == SurfaceInterpolation::PnTriangle,
        force_weight: params.growth.force_weight,
        time,
        phase_spread: params.wind.phase_spread,
        shapes: &shapes,
    };
    roots
        .iter()
        .take(growth.drawn.strands as usize)
        .flat_map(|r| grow_strand(mesh, r, &growth))
        .collect()
}

/// The width stage 1 gives strand `index` of a groom of `strand_total` strands drawn with
/// the level of detail's width scale `zone` (seed 002's `s(x)` at `x = (index + ½) /
/// strand_total`, times its rest width), as the drawn roots hold it.
pub fn drawn_width(root: &Root, index: u32, strand_total: u32, zone: &Transition) -> f32 {
    root.width * zone.scale((index as f32 + 0.5) / strand_total.max(1) as f32)
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
/// (`segments + 1`, root first) bent by the wind `field` at the strand's time;
/// `segments / step + 1` vertices (xyz position, w strand parameter).
fn deform_groom_strand(
    rest: &[Vec3],
    root: &Root,
    drawn: Drawn,
    field: &Field,
    (time, phase_spread, force_weight): (f32, f32, f32),
) -> Vec<Vec4> {
    let Drawn { segments, step, .. } = drawn;
    let t = time + root.phase * phase_spread;
    let rest_at = |i: u32| rest.get(i as usize).copied().unwrap_or(Vec3::ZERO);
    let mut q = Vec4::new(0.0, 0.0, 0.0, 1.0);
    let mut p = rest_at(0);
    let mut d = Vec3::Y;
    // No force has turned the strand yet: its vertices are the rest points.
    let mut at_rest = true;
    let mut out = Vec::with_capacity(drawn.per_strand());
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
        let push = force(field, p, t) * force_weight;
        at_rest = at_rest && push == Vec3::ZERO;
        let bent = safe_normalize(d + push, d);
        q = quat_mul(quat_between(d, bent), q);
        q /= q.length();
        d = bent;
    }
    out
}

/// A groom bent by the wind at `time` and `level` (`GroomStrands` with `params`, the
/// parameters its strands amount to), in the layout of `StrandBuffers::vertices`: the
/// first `level.strands` strands (at most `roots.count`) of the groom whose rest points
/// are `rest` (`growth.segments + 1` per strand, in the order of `roots`). The wind bends
/// a groom; gravity does not (a groom hangs as it was made).
pub fn deform_groom(
    rest: &[Vec3],
    roots: &[Root],
    params: &HairParams,
    time: f32,
    level: Level,
) -> Vec<Vec4> {
    let drawn = Drawn::new(params, level);
    let field = Field::new(params, Vec3::ZERO);
    let per_strand = drawn.segments as usize + 1;
    let frame = (time, params.wind.phase_spread, params.growth.force_weight);
    rest.chunks(per_strand)
        .zip(roots)
        .take(drawn.strands as usize)
        .flat_map(|(points, root)| deform_groom_strand(points, root, drawn, &field, frame))
        .collect()
}
