//! Ground-truth transmittance: rays traced through the real strand cylinders.
//!
//! Every strand segment is a cylinder of the strand's width with flat ends: the
//! points whose distance to the axis line is below `radius` and whose projection
//! onto the axis falls in `[0, 1)` of `a -> b`. The half-open range makes the
//! cylinders of one straight strand tile without overlap, so a ray through a
//! joint counts once. A ray that enters a cylinder multiplies the light by
//! `1 - opacity`; each cylinder counts at most once per ray.
//!
//! The exact test runs in `f64` (inputs are `f32`, so it is exact up to the final
//! roundings); a median-split BVH over radius-padded segment boxes only prunes,
//! and its boxes are padded a little further so it never rejects a true hit.
//!
//! Degenerate segments (non-finite end points, radius or opacity, radius <= 0, or
//! zero length) are never hit: a zero-length cylinder has no volume.
//!
//! Besides these any-hit transmittance queries, [`SegmentBvh::closest_hit`] and
//! [`SegmentBvh::occluded`] treat the cylinders as opaque surfaces for the path tracer
//! ([`crate::path_tracer`]): a ray hits a cylinder where it *enters* it, so a ray that starts
//! inside a cylinder does not hit that one.

use crate::noise::{hash_to_unit, pcg_hash};
use glam::{DVec3, Vec3, Vec4};

/// One strand segment as a cylinder from `a` to `b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// Start of the axis (projection parameter 0, included).
    pub a: Vec3,
    /// End of the axis (projection parameter 1, excluded).
    pub b: Vec3,
    /// Cylinder radius (half the strand width).
    pub radius: f32,
    /// Fraction of light a hit removes; clamped to [0, 1] when applied.
    pub opacity: f32,
    /// Strand the segment belongs to (a strand does not shadow itself).
    pub strand: u32,
}

impl Segment {
    /// Whether the segment can be hit at all (see the module docs on degenerate segments).
    pub fn is_valid(&self) -> bool {
        self.a.is_finite()
            && self.b.is_finite()
            && self.radius.is_finite()
            && self.radius > 0.0
            && self.opacity.is_finite()
            && (self.b - self.a).as_dvec3().length_squared() > 0.0
    }
}

/// Segments of strands stored as pelage's `StrandBuffers` vertices: `vertices` holds
/// `vertices_per_strand` vec4 per strand (xyz position, w = strand parameter in \[0, 1\] root->tip).
///
/// Width at a vertex = `root_widths[strand] * lerp(1, tip_width, w)`; a segment's radius is half
/// the mean of its two end widths. Segments come strand by strand, root to tip, so there are
/// `strands * (vertices_per_strand - 1)` of them, where `strands` is the number of whole strands in
/// `vertices` that also have a root width (extra vertices or widths are ignored). Fewer than two
/// vertices per strand gives no segments.
pub fn segments_from_strands(
    vertices: &[Vec4],
    vertices_per_strand: usize,
    root_widths: &[f32],
    tip_width: f32,
    opacity: f32,
) -> Vec<Segment> {
    if vertices_per_strand < 2 {
        return Vec::new();
    }
    let strands = (vertices.len() / vertices_per_strand).min(root_widths.len());
    let mut out = Vec::with_capacity(strands * (vertices_per_strand - 1));
    for (s, &root_width) in root_widths.iter().enumerate().take(strands) {
        let verts = &vertices[s * vertices_per_strand..(s + 1) * vertices_per_strand];
        let width = |v: Vec4| root_width * (1.0 + (tip_width - 1.0) * v.w);
        for pair in verts.windows(2) {
            out.push(Segment {
                a: pair[0].truncate(),
                b: pair[1].truncate(),
                radius: 0.25 * (width(pair[0]) + width(pair[1])),
                opacity,
                strand: s as u32,
            });
        }
    }
    out
}

/// An interval of the ray parameter with each end open or closed.
#[derive(Clone, Copy, Debug)]
struct Interval {
    lo: f64,
    lo_closed: bool,
    hi: f64,
    hi_closed: bool,
}

impl Interval {
    fn intersect(self, o: Interval) -> Interval {
        let (lo, lo_closed) = if o.lo > self.lo {
            (o.lo, o.lo_closed)
        } else if o.lo < self.lo {
            (self.lo, self.lo_closed)
        } else {
            (self.lo, self.lo_closed && o.lo_closed)
        };
        let (hi, hi_closed) = if o.hi < self.hi {
            (o.hi, o.hi_closed)
        } else if o.hi > self.hi {
            (self.hi, self.hi_closed)
        } else {
            (self.hi, self.hi_closed && o.hi_closed)
        };
        Interval {
            lo,
            lo_closed,
            hi,
            hi_closed,
        }
    }

    fn is_empty(&self) -> bool {
        !(self.lo < self.hi || (self.lo == self.hi && self.lo_closed && self.hi_closed))
    }
}

/// Below this squared sine of the angle between ray and axis the two are treated as
/// parallel (the distance to the axis is then constant along the ray). `f32` input
/// directions cannot resolve angles anywhere near this small.
const PARALLEL_SIN2: f64 = 1e-30;

/// Exact test in `f64`. `d` must be unit length, `max_t > 0` (may be infinite).
fn hits_f64(seg: &Segment, o: DVec3, d: DVec3, max_t: f64) -> bool {
    if !seg.is_valid() {
        return false;
    }
    let a = seg.a.as_dvec3();
    let e = seg.b.as_dvec3() - a;
    let ee = e.length_squared();
    let r = seg.radius as f64;
    let w = o - a;
    // Axis parameter of the ray point at t: s(t) = s0 + t * ds.
    let s0 = w.dot(e) / ee;
    let ds = d.dot(e) / ee;
    let mut iv = Interval {
        lo: 0.0,
        lo_closed: false,
        hi: max_t,
        hi_closed: true,
    };
    // s in [0, 1).
    if ds == 0.0 {
        if !(0.0..1.0).contains(&s0) {
            return false;
        }
    } else if ds > 0.0 {
        iv = iv.intersect(Interval {
            lo: -s0 / ds,
            lo_closed: true,
            hi: (1.0 - s0) / ds,
            hi_closed: false,
        });
    } else {
        iv = iv.intersect(Interval {
            lo: (1.0 - s0) / ds,
            lo_closed: false,
            hi: -s0 / ds,
            hi_closed: true,
        });
    }
    if iv.is_empty() {
        return false;
    }
    // Distance to the axis line below r: |wp + t dp|^2 < r^2, i.e. A t^2 + 2 B t + C < 0.
    let wp = w - e * s0;
    let dp = d - e * ds;
    let qa = dp.length_squared();
    let qb = wp.dot(dp);
    let qc = wp.length_squared() - r * r;
    if qa < PARALLEL_SIN2 {
        return qc < 0.0;
    }
    let disc = qb * qb - qa * qc;
    if disc <= 0.0 {
        return false;
    }
    let q = -(qb + disc.sqrt().copysign(qb));
    let (t0, t1) = (q / qa, qc / q);
    let inside = Interval {
        lo: t0.min(t1),
        lo_closed: false,
        hi: t0.max(t1),
        hi_closed: false,
    };
    !iv.intersect(inside).is_empty()
}

/// Where the ray `o + t d` (`d` unit) first enters the cylinder of a valid `seg` for
/// `t` in `(0, max_t]`: `(t, s, h)` with `s` the axis parameter of the entry point and `h`
/// the fibre offset (see [`SegmentHit::h`]). `None` when it does not, or when `o` is inside
/// the cylinder (the entry is then at `t <= 0`).
fn entry_f64(seg: &Segment, o: DVec3, d: DVec3, max_t: f64) -> Option<(f64, f64, f64)> {
    let a = seg.a.as_dvec3();
    let e = seg.b.as_dvec3() - a;
    let ee = e.length_squared();
    let r = seg.radius as f64;
    let w = o - a;
    let s0 = w.dot(e) / ee;
    let ds = d.dot(e) / ee;
    // Axis range s in [0, 1) as a range of t.
    let (mut lo, mut hi) = if ds == 0.0 {
        if !(0.0..1.0).contains(&s0) {
            return None;
        }
        (f64::NEG_INFINITY, f64::INFINITY)
    } else if ds > 0.0 {
        (-s0 / ds, (1.0 - s0) / ds)
    } else {
        ((1.0 - s0) / ds, -s0 / ds)
    };
    // Inside the infinite cylinder: A t^2 + 2 B t + C < 0.
    let wp = w - e * s0;
    let dp = d - e * ds;
    let qa = dp.length_squared();
    let qb = wp.dot(dp);
    let qc = wp.length_squared() - r * r;
    if qa < PARALLEL_SIN2 {
        if qc >= 0.0 {
            return None;
        }
    } else {
        let disc = qb * qb - qa * qc;
        if disc <= 0.0 {
            return None;
        }
        let q = -(qb + disc.sqrt().copysign(qb));
        let (t0, t1) = (q / qa, qc / q);
        lo = lo.max(t0.min(t1));
        hi = hi.min(t0.max(t1));
    }
    if lo.is_nan() || hi.is_nan() || lo >= hi || lo <= 0.0 || lo > max_t {
        return None;
    }
    // h = x̂ · (d̂⊥ × q) / r with q any vector from the axis to the ray: e · (d × w) is
    // |e| |d⊥| times it.
    let h = if qa < PARALLEL_SIN2 {
        0.0
    } else {
        (e.dot(d.cross(w)) / (ee.sqrt() * qa.sqrt() * r)).clamp(-1.0, 1.0)
    };
    Some((lo, s0 + lo * ds, h))
}

/// A ray's entry into a strand cylinder, found by [`SegmentBvh::closest_hit`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentHit {
    /// Index of the segment in [`SegmentBvh::segments`].
    pub index: usize,
    /// A copy of the segment hit.
    pub segment: Segment,
    /// Distance from the ray origin to the entry point (the ray direction is normalised).
    pub t: f64,
    /// Axis parameter of the entry point's projection onto `a -> b`, in [0, 1].
    pub s: f64,
    /// The fibre offset of the ray, in [-1, 1], as [`crate::chiang`] defines it:
    /// `h = x̂ · (d̂⊥ × q) / radius`, where `x̂` is the unit axis `a -> b`, `d̂⊥` the unit
    /// part of the ray direction perpendicular to it and `q` the shortest vector from the
    /// axis line to the ray line. The entry point's outward normal then has azimuth
    /// `φ_o - asin h` about `x̂` (`φ_o` that of `-d`). 0 for a ray along the axis (it
    /// enters through a flat end).
    pub h: f64,
}

/// A checked ray: origin, unit direction and length, all in `f64`.
fn prepare_ray(origin: Vec3, dir: Vec3, max_t: f32) -> Option<(DVec3, DVec3, f64)> {
    let o = origin.as_dvec3();
    let d = dir.as_dvec3();
    let len = d.length();
    if !o.is_finite() || !d.is_finite() || len.is_nan() || len <= 0.0 || max_t.is_nan() {
        return None;
    }
    if max_t <= 0.0 {
        return None;
    }
    Some((o, d / len, max_t as f64))
}

/// Whether the ray `origin + t * dir / |dir|`, `t` in `(0, max_t]`, hits the cylinder of `seg`
/// (exact test, no BVH; `max_t` is a distance and may be infinite). False for a zero or
/// non-finite `dir`, a non-finite origin, `max_t` NaN or <= 0, and degenerate segments.
pub fn ray_hits_segment(seg: &Segment, origin: Vec3, dir: Vec3, max_t: f32) -> bool {
    match prepare_ray(origin, dir, max_t) {
        Some((o, d, t)) => hits_f64(seg, o, d, t),
        None => false,
    }
}

/// One BVH node: a box, and either two children (`count == 0`, children at `first` and
/// `first + 1`) or a leaf of `count` segments from `first` in the reordered segments.
#[derive(Clone, Copy, Debug)]
struct Node {
    min: DVec3,
    max: DVec3,
    first: u32,
    count: u32,
}

/// Most segments in one leaf.
const LEAF_SIZE: usize = 4;

/// Bounding volume hierarchy over strand segments (median split on the longest centroid
/// axis, leaves of at most four segments), for exact transmittance queries.
#[derive(Clone, Debug)]
pub struct SegmentBvh {
    nodes: Vec<Node>,
    /// Valid segments in tree order, then the degenerate ones (in no leaf).
    segments: Vec<Segment>,
}

/// Box of a segment's cylinder: the axis box padded by the radius, plus a relative margin far
/// above `f64` rounding so the slab test never rejects a true hit.
fn segment_box(s: &Segment) -> (DVec3, DVec3) {
    let a = s.a.as_dvec3();
    let b = s.b.as_dvec3();
    let r = s.radius as f64;
    let mag = a.abs().max(b.abs()).max_element() + r;
    let pad = r + 1e-9 * (1.0 + mag);
    (a.min(b) - pad, a.max(b) + pad)
}

impl SegmentBvh {
    /// Builds the hierarchy. Degenerate segments are kept (at the end of [`Self::segments`])
    /// but are in no leaf, so they are never hit.
    pub fn build(segments: Vec<Segment>) -> SegmentBvh {
        let (valid, degenerate): (Vec<Segment>, Vec<Segment>) =
            segments.into_iter().partition(Segment::is_valid);
        let boxes: Vec<(DVec3, DVec3)> = valid.iter().map(segment_box).collect();
        let mut order: Vec<u32> = (0..valid.len() as u32).collect();
        let mut nodes = Vec::new();
        if !valid.is_empty() {
            nodes.push(Node {
                min: DVec3::ZERO,
                max: DVec3::ZERO,
                first: 0,
                count: 0,
            });
            let mut stack = vec![(0usize, 0usize, valid.len())];
            while let Some((node, start, end)) = stack.pop() {
                let mut min = DVec3::INFINITY;
                let mut max = DVec3::NEG_INFINITY;
                let mut cmin = DVec3::INFINITY;
                let mut cmax = DVec3::NEG_INFINITY;
                for &i in &order[start..end] {
                    let (lo, hi) = boxes[i as usize];
                    min = min.min(lo);
                    max = max.max(hi);
                    let c = 0.5 * (lo + hi);
                    cmin = cmin.min(c);
                    cmax = cmax.max(c);
                }
                nodes[node].min = min;
                nodes[node].max = max;
                if end - start <= LEAF_SIZE {
                    nodes[node].first = start as u32;
                    nodes[node].count = (end - start) as u32;
                    continue;
                }
                let extent = cmax - cmin;
                let axis = if extent.x >= extent.y && extent.x >= extent.z {
                    0
                } else if extent.y >= extent.z {
                    1
                } else {
                    2
                };
                let mid = start + (end - start) / 2;
                if extent[axis] > 0.0 {
                    let key = |i: &u32| {
                        let (lo, hi) = boxes[*i as usize];
                        lo[axis] + hi[axis]
                    };
                    order[start..end]
                        .select_nth_unstable_by(mid - start, |x, y| key(x).total_cmp(&key(y)));
                }
                let left = nodes.len();
                let blank = Node {
                    min: DVec3::ZERO,
                    max: DVec3::ZERO,
                    first: 0,
                    count: 0,
                };
                nodes.push(blank);
                nodes.push(blank);
                nodes[node].first = left as u32;
                nodes[node].count = 0;
                stack.push((left, start, mid));
                stack.push((left + 1, mid, end));
            }
        }
        let mut ordered: Vec<Segment> = order.iter().map(|&i| valid[i as usize]).collect();
        ordered.extend(degenerate);
        SegmentBvh {
            nodes,
            segments: ordered,
        }
    }

    /// All segments given to [`Self::build`]: the valid ones in tree order, then the degenerate ones.
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// Calls `f` for every cylinder the ray hits (each once), skipping `exclude_strand`.
    fn for_each_hit(
        &self,
        origin: Vec3,
        dir: Vec3,
        max_t: f32,
        exclude_strand: Option<u32>,
        mut f: impl FnMut(&Segment),
    ) {
        let Some((o, d, tmax)) = prepare_ray(origin, dir, max_t) else {
            return;
        };
        if self.nodes.is_empty() {
            return;
        }
        let mut stack: Vec<u32> = Vec::with_capacity(64);
        stack.push(0);
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            if !ray_box(o, d, tmax, node.min, node.max) {
                continue;
            }
            if node.count == 0 {
                stack.push(node.first);
                stack.push(node.first + 1);
                continue;
            }
            let first = node.first as usize;
            for seg in &self.segments[first..first + node.count as usize] {
                if exclude_strand == Some(seg.strand) {
                    continue;
                }
                if hits_f64(seg, o, d, tmax) {
                    f(seg);
                }
            }
        }
    }

    /// Transmittance along the ray `origin + t * dir / |dir|`, `t` in `(0, max_t]` (`max_t` is a
    /// distance and may be `f32::INFINITY`): the product of `1 - opacity` (clamped to [0, 1]) over
    /// every cylinder hit, each counted once. Segments whose `strand` equals `exclude_strand` are
    /// ignored. A zero or non-finite `dir`, a non-finite origin or `max_t` NaN or <= 0 gives 1.0.
    pub fn transmittance(
        &self,
        origin: Vec3,
        dir: Vec3,
        max_t: f32,
        exclude_strand: Option<u32>,
    ) -> f32 {
        let mut t = 1.0f64;
        self.for_each_hit(origin, dir, max_t, exclude_strand, |s| {
            t *= 1.0 - s.opacity.clamp(0.0, 1.0) as f64;
        });
        t as f32
    }

    /// The cylinders the ray `origin + t · dir / |dir|`, `t` in `(0, max_t]`, enters: as
    /// [`Self::hit_count`] without the cylinders that contain `origin` (the ray leaves
    /// those; [`Self::occluded`] does not count them either), so a ray from a fibre's axis
    /// counts the other fibres it crosses (the same strand's farther segments included).
    pub fn crossings(&self, origin: Vec3, dir: Vec3, max_t: f32) -> u32 {
        let Some((o, d, t_max)) = prepare_ray(origin, dir, max_t) else {
            return 0;
        };
        let mut n = 0u32;
        // An entry at t > 0, as `occluded` finds them: none into a cylinder holding `o`.
        self.for_each_hit(origin, dir, max_t, None, |seg| {
            n += u32::from(entry_f64(seg, o, d, t_max).is_some());
        });
        n
    }

    /// Number of cylinder hits along the same ray as [`Self::transmittance`] (for tests and diagnostics).
    pub fn hit_count(
        &self,
        origin: Vec3,
        dir: Vec3,
        max_t: f32,
        exclude_strand: Option<u32>,
    ) -> u32 {
        let mut n = 0u32;
        self.for_each_hit(origin, dir, max_t, exclude_strand, |_| n += 1);
        n
    }
}

/// Nodes a traversal stack can hold: the median split halves every range, so a tree over
/// fewer than 2^32 segments is at most 34 deep, and a depth-first stack never holds more
/// than depth + 1 nodes.
const STACK_SIZE: usize = 64;

impl SegmentBvh {
    /// The nearest cylinder entry along `origin + t * dir / |dir|`, `t` in `(0, max_t]`
    /// (`max_t` may be infinite), treating the cylinders as opaque surfaces: a cylinder is hit
    /// where the ray enters it (through its side or a flat end); a cylinder that contains
    /// `origin` is not hit. With `skip = Some((strand, min_t))`, entries into segments of
    /// `strand` at `t < min_t` are ignored (the path tracer's guard against a fibre hitting
    /// itself at its joints). `None` for a zero or non-finite `dir`, a non-finite origin,
    /// `max_t` NaN or <= 0, or no hit.
    pub fn closest_hit(
        &self,
        origin: DVec3,
        dir: DVec3,
        max_t: f64,
        skip: Option<(u32, f64)>,
    ) -> Option<SegmentHit> {
        self.first_entry(origin, dir, max_t, skip, false)
    }

    /// Whether [`Self::closest_hit`] would find any hit (stops at the first one found).
    pub fn occluded(
        &self,
        origin: DVec3,
        dir: DVec3,
        max_t: f64,
        skip: Option<(u32, f64)>,
    ) -> bool {
        self.first_entry(origin, dir, max_t, skip, true).is_some()
    }

    fn first_entry(
        &self,
        origin: DVec3,
        dir: DVec3,
        max_t: f64,
        skip: Option<(u32, f64)>,
        any: bool,
    ) -> Option<SegmentHit> {
        let len = dir.length();
        if self.nodes.is_empty()
            || !origin.is_finite()
            || !dir.is_finite()
            || len <= 0.0
            || max_t.is_nan()
            || max_t <= 0.0
        {
            return None;
        }
        let d = dir / len;
        let o = origin;
        let mut best: Option<SegmentHit> = None;
        let mut t_max = max_t;
        let mut stack = [0u32; STACK_SIZE];
        let mut sp = 0usize;
        if slab_near(o, d, t_max, &self.nodes[0]).is_some() {
            stack[0] = 0;
            sp = 1;
        }
        while sp > 0 {
            sp -= 1;
            let node = &self.nodes[stack[sp] as usize];
            if slab_near(o, d, t_max, node).is_none() {
                continue;
            }
            if node.count == 0 {
                let (l, r) = (node.first, node.first + 1);
                let nl = slab_near(o, d, t_max, &self.nodes[l as usize]);
                let nr = slab_near(o, d, t_max, &self.nodes[r as usize]);
                // Push the farther child first so the nearer one is visited first.
                let order = match (nl, nr) {
                    (Some(a), Some(b)) if a <= b => [Some(r), Some(l)],
                    (Some(_), Some(_)) => [Some(l), Some(r)],
                    (Some(_), None) => [None, Some(l)],
                    (None, Some(_)) => [None, Some(r)],
                    (None, None) => [None, None],
                };
                for n in order.into_iter().flatten() {
                    if let Some(slot) = stack.get_mut(sp) {
                        *slot = n;
                        sp += 1;
                    }
                }
                continue;
            }
            let first = node.first as usize;
            for (k, seg) in self.segments[first..first + node.count as usize]
                .iter()
                .enumerate()
            {
                let Some((t, s, h)) = entry_f64(seg, o, d, t_max) else {
                    continue;
                };
                if let Some((strand, min_t)) = skip {
                    if seg.strand == strand && t < min_t {
                        continue;
                    }
                }
                t_max = t;
                best = Some(SegmentHit {
                    index: first + k,
                    segment: *seg,
                    t,
                    s: s.clamp(0.0, 1.0),
                    h,
                });
                if any {
                    return best;
                }
            }
        }
        best
    }
}

/// Slab test against a node's box: the entry distance (clamped to 0) when the ray meets the
/// closed box for some `t` in `[0, max_t]`.
fn slab_near(o: DVec3, d: DVec3, max_t: f64, node: &Node) -> Option<f64> {
    let mut near = 0.0f64;
    let mut far = max_t;
    for i in 0..3 {
        if d[i] == 0.0 {
            if o[i] < node.min[i] || o[i] > node.max[i] {
                return None;
            }
            continue;
        }
        let inv = 1.0 / d[i];
        let t1 = (node.min[i] - o[i]) * inv;
        let t2 = (node.max[i] - o[i]) * inv;
        near = near.max(t1.min(t2));
        far = far.min(t1.max(t2));
        if near > far {
            return None;
        }
    }
    Some(near)
}

/// Slab test: whether the ray meets the closed box for some `t` in `[0, max_t]`.
fn ray_box(o: DVec3, d: DVec3, max_t: f64, min: DVec3, max: DVec3) -> bool {
    let mut near = 0.0f64;
    let mut far = max_t;
    for i in 0..3 {
        if d[i] == 0.0 {
            if o[i] < min[i] || o[i] > max[i] {
                return false;
            }
            continue;
        }
        let t1 = (min[i] - o[i]) / d[i];
        let t2 = (max[i] - o[i]) / d[i];
        near = near.max(t1.min(t2));
        far = far.min(t1.max(t2));
        if near > far {
            return false;
        }
    }
    true
}

/// Golden angle in radians: successive disc samples turn by it (Vogel spiral).
const GOLDEN_ANGLE: f32 = 2.399_963_3;

/// Offsets of `rays` points spread uniformly over a disc of `radius` spanned by `u` and `v`:
/// a Vogel spiral with one stratum of equal area per ray (jittered inside it by a hash of
/// `seed` and the ray index) and a start angle hashed from `seed`. One ray is the centre.
fn disc_offsets(u: Vec3, v: Vec3, radius: f32, rays: u32, seed: u32) -> Vec<Vec3> {
    let rays = rays.max(1);
    if rays == 1 {
        return vec![Vec3::ZERO];
    }
    let start = std::f32::consts::TAU * hash_to_unit(pcg_hash(seed));
    (0..rays)
        .map(|i| {
            let jitter = hash_to_unit(pcg_hash(seed ^ pcg_hash(i.wrapping_add(0x9e37_79b9))));
            let r = radius * ((i as f32 + jitter) / rays as f32).sqrt();
            let phi = start + GOLDEN_ANGLE * i as f32;
            r * (phi.cos() * u + phi.sin() * v)
        })
        .collect()
}

/// A usable disc radius: non-finite or negative means 0.
fn clean_radius(r: f32) -> f32 {
    if r.is_finite() { r.max(0.0) } else { 0.0 }
}

/// Average transmittance of `rays` parallel rays toward a DIRECTIONAL light (`to_light` = vector
/// from scene to light, normalised here), their origins spread uniformly over a disc of
/// `disc_radius` around `point`, perpendicular to `to_light` (stratified Vogel spiral hashed from
/// `seed`; deterministic). `rays` of 0 or 1 means the single central ray; a non-finite or negative
/// `disc_radius` means 0. A zero or non-finite `to_light` or `point` gives 1.0.
pub fn directional_transmittance(
    bvh: &SegmentBvh,
    point: Vec3,
    to_light: Vec3,
    disc_radius: f32,
    rays: u32,
    seed: u32,
    exclude_strand: Option<u32>,
) -> f32 {
    let Some(dir) = to_light.try_normalize() else {
        return 1.0;
    };
    if !point.is_finite() {
        return 1.0;
    }
    let (u, v) = dir.any_orthonormal_pair();
    let offsets = disc_offsets(u, v, clean_radius(disc_radius), rays, seed);
    let sum: f64 = offsets
        .iter()
        .map(|&off| bvh.transmittance(point + off, dir, f32::INFINITY, exclude_strand) as f64)
        .sum();
    (sum / offsets.len() as f64) as f32
}

/// Average transmittance toward a POINT light at `light`: rays from points spread over a disc of
/// `disc_radius` around `point` (perpendicular to `light - point`, sampled as in
/// [`directional_transmittance`]) to the light position, each with `max_t` = its distance to the
/// light. A light at `point`, or non-finite input, gives 1.0.
pub fn point_transmittance(
    bvh: &SegmentBvh,
    point: Vec3,
    light: Vec3,
    disc_radius: f32,
    rays: u32,
    seed: u32,
    exclude_strand: Option<u32>,
) -> f32 {
    if !point.is_finite() || !light.is_finite() {
        return 1.0;
    }
    let Some(axis) = (light - point).try_normalize() else {
        return 1.0;
    };
    let (u, v) = axis.any_orthonormal_pair();
    let offsets = disc_offsets(u, v, clean_radius(disc_radius), rays, seed);
    let sum: f64 = offsets
        .iter()
        .map(|&off| {
            let origin = point + off;
            let to = light - origin;
            let dist = to.length();
            if dist > 0.0 {
                bvh.transmittance(origin, to, dist, exclude_strand) as f64
            } else {
                1.0
            }
        })
        .sum();
    (sum / offsets.len() as f64) as f32
}

/// Transmittance at every strand vertex toward a directional light, excluding each vertex's own
/// strand (vertex `i` is on strand `i / vertices_per_strand`; with `vertices_per_strand` 0 nothing
/// is excluded). Each vertex uses [`directional_transmittance`] with its index as seed. Returns
/// one value per vertex, in the vertices' order.
pub fn transmittance_at_vertices(
    bvh: &SegmentBvh,
    vertices: &[Vec4],
    vertices_per_strand: usize,
    to_light: Vec3,
    disc_radius: f32,
    rays: u32,
) -> Vec<f32> {
    transmittance_at_every_nth_vertex(
        bvh,
        vertices,
        vertices_per_strand,
        to_light,
        disc_radius,
        rays,
        1,
    )
}

/// [`transmittance_at_vertices`] at vertices `0, stride, 2 stride, ...` only (a stride of 0
/// is taken as 1), each exactly as there (its own strand excluded, its index in `vertices`
/// the seed): a dense groom's statistics from a sample of its vertices. Returns one value per
/// sampled vertex, in their order.
pub fn transmittance_at_every_nth_vertex(
    bvh: &SegmentBvh,
    vertices: &[Vec4],
    vertices_per_strand: usize,
    to_light: Vec3,
    disc_radius: f32,
    rays: u32,
    stride: usize,
) -> Vec<f32> {
    vertices
        .iter()
        .enumerate()
        .step_by(stride.max(1))
        .map(|(i, v)| {
            let exclude = (vertices_per_strand > 0).then(|| (i / vertices_per_strand) as u32);
            directional_transmittance(
                bvh,
                v.truncate(),
                to_light,
                disc_radius,
                rays,
                i as u32,
                exclude,
            )
        })
        .collect()
}

/// Root-mean-square difference and the 95th percentile (nearest rank: the `ceil(0.95 n)`-th
/// smallest) of `|a - b|` of two equal-length slices. `None` when the lengths differ or the
/// slices are empty. A NaN in the input makes the RMSE NaN.
pub fn rmse_p95(a: &[f32], b: &[f32]) -> Option<(f32, f32)> {
    if a.len() != b.len() || a.is_empty() {
        return None;
    }
    let mut diffs: Vec<f64> = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*x as f64 - *y as f64).abs())
        .collect();
    let rmse = (diffs.iter().map(|d| d * d).sum::<f64>() / diffs.len() as f64).sqrt();
    diffs.sort_by(f64::total_cmp);
    let rank = (95 * diffs.len()).div_ceil(100);
    let p95 = diffs[rank.clamp(1, diffs.len()) - 1];
    Some((rmse as f32, p95 as f32))
}
