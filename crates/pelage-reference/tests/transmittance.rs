//! Tests of the ground-truth transmittance ray tracer.

use std::time::Instant;

use glam::{Vec3, Vec4};
use pelage_reference::noise::{hash_to_unit, pcg_hash};
use pelage_reference::transmittance::{
    Segment, SegmentBvh, directional_transmittance, point_transmittance, ray_hits_segment,
    rmse_p95, segments_from_strands, transmittance_at_vertices,
};

/// Small deterministic RNG on top of `pcg_hash`.
struct Rng(u32);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 = pcg_hash(self.0);
        hash_to_unit(self.0)
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }
    fn vec3(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }
    fn unit(&mut self) -> Vec3 {
        loop {
            let v = self.vec3(-1.0, 1.0);
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }
}

fn seg(a: Vec3, b: Vec3, radius: f32, opacity: f32, strand: u32) -> Segment {
    Segment {
        a,
        b,
        radius,
        opacity,
        strand,
    }
}

/// A segment along x from -1 to 1 at the origin, radius 0.1.
fn crossing(opacity: f32) -> SegmentBvh {
    SegmentBvh::build(vec![seg(
        Vec3::new(-1.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        0.1,
        opacity,
        0,
    )])
}

#[test]
fn perpendicular_crossing_and_radius_threshold() {
    let bvh = crossing(0.3);
    let o = Vec3::new(0.2, 0.0, -5.0);
    let t = bvh.transmittance(o, Vec3::Z, f32::INFINITY, None);
    assert!((t - 0.7).abs() < 1e-6, "{t}");
    // Passing at 1.01 radius misses, at 0.99 radius hits (offset along y, perpendicular to axis and ray).
    let miss = Vec3::new(0.2, 0.101, -5.0);
    let hit = Vec3::new(0.2, 0.099, -5.0);
    assert_eq!(bvh.hit_count(miss, Vec3::Z, f32::INFINITY, None), 0);
    assert_eq!(bvh.transmittance(miss, Vec3::Z, f32::INFINITY, None), 1.0);
    assert_eq!(bvh.hit_count(hit, Vec3::Z, f32::INFINITY, None), 1);
    // Non-unit direction: same answer.
    assert_eq!(bvh.hit_count(hit, Vec3::Z * 7.5, f32::INFINITY, None), 1);
    // Oblique ray at distance 0.099 of the axis (closest point at the origin).
    let d = Vec3::new(1.0, 0.0, 1.0).normalize();
    let o2 = Vec3::new(0.0, 0.099, 0.0) - 3.0 * d;
    assert_eq!(bvh.hit_count(o2, d, f32::INFINITY, None), 1);
    let o3 = Vec3::new(0.0, 0.101, 0.0) - 3.0 * d;
    assert_eq!(bvh.hit_count(o3, d, f32::INFINITY, None), 0);
}

#[test]
fn stacked_parallel_strands_multiply() {
    let alpha = 0.2f32;
    for n in [1u32, 2, 5, 17] {
        let segs: Vec<Segment> = (0..n)
            .map(|i| {
                let z = i as f32 * 0.5;
                seg(
                    Vec3::new(-1.0, 0.0, z),
                    Vec3::new(1.0, 0.0, z),
                    0.05,
                    alpha,
                    i,
                )
            })
            .collect();
        let bvh = SegmentBvh::build(segs);
        let o = Vec3::new(0.0, 0.0, -1.0);
        assert_eq!(bvh.hit_count(o, Vec3::Z, f32::INFINITY, None), n);
        let t = bvh.transmittance(o, Vec3::Z, f32::INFINITY, None);
        let expected = (1.0 - alpha as f64).powi(n as i32) as f32;
        assert!((t - expected).abs() < 1e-6, "n={n}: {t} vs {expected}");
    }
}

#[test]
fn joint_counts_once() {
    // One straight strand of two segments along x, joint at x = 1.
    let bvh = SegmentBvh::build(vec![
        seg(Vec3::ZERO, Vec3::X, 0.1, 0.5, 3),
        seg(Vec3::X, Vec3::new(2.0, 0.0, 0.0), 0.1, 0.5, 3),
    ]);
    let o = Vec3::new(1.0, 0.0, -2.0);
    assert_eq!(bvh.hit_count(o, Vec3::Z, f32::INFINITY, None), 1);
    assert!((bvh.transmittance(o, Vec3::Z, f32::INFINITY, None) - 0.5).abs() < 1e-6);
    // A ray along the strand axis passes through both cylinders: each counts once.
    let along = Vec3::new(-1.0, 0.01, 0.0);
    assert_eq!(bvh.hit_count(along, Vec3::X, f32::INFINITY, None), 2);
    // Flat ends: just beyond the tip (x = 2) or before the root (x = 0) is outside.
    assert_eq!(
        bvh.hit_count(Vec3::new(2.0, 0.0, -2.0), Vec3::Z, f32::INFINITY, None),
        0
    );
    assert_eq!(
        bvh.hit_count(Vec3::new(0.0, 0.0, -2.0), Vec3::Z, f32::INFINITY, None),
        1
    );
    assert_eq!(
        bvh.hit_count(Vec3::new(-0.001, 0.0, -2.0), Vec3::Z, f32::INFINITY, None),
        0
    );
}

#[test]
fn exclude_strand_removes_its_hits() {
    let bvh = SegmentBvh::build(vec![
        seg(
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            0.1,
            0.5,
            7,
        ),
        seg(
            Vec3::new(-1.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
            0.1,
            0.5,
            8,
        ),
    ]);
    let o = Vec3::new(0.0, 0.0, -1.0);
    assert_eq!(bvh.hit_count(o, Vec3::Z, f32::INFINITY, None), 2);
    assert_eq!(bvh.hit_count(o, Vec3::Z, f32::INFINITY, Some(7)), 1);
    assert_eq!(bvh.hit_count(o, Vec3::Z, f32::INFINITY, Some(8)), 1);
    assert_eq!(bvh.hit_count(o, Vec3::Z, f32::INFINITY, Some(9)), 2);
    assert!((bvh.transmittance(o, Vec3::Z, f32::INFINITY, Some(7)) - 0.5).abs() < 1e-6);
}

#[test]
fn max_t_and_behind_origin() {
    let bvh = crossing(0.5);
    // Segment (surface at z = -0.1..0.1) ahead at distance 2; limit 1.5 stops before it.
    let o = Vec3::new(0.0, 0.0, -2.0);
    assert_eq!(bvh.hit_count(o, Vec3::Z, 1.5, None), 0);
    assert_eq!(bvh.hit_count(o, Vec3::Z, 1.95, None), 1);
    assert_eq!(
        bvh.hit_count(o, Vec3::Z * 10.0, 1.95, None),
        1,
        "max_t is a distance"
    );
    // Segment behind the origin.
    assert_eq!(
        bvh.hit_count(Vec3::new(0.0, 0.0, 2.0), Vec3::Z, f32::INFINITY, None),
        0
    );
    // Origin inside the cylinder: the part with t > 0 counts.
    assert_eq!(
        bvh.hit_count(Vec3::new(0.0, 0.0, 0.05), Vec3::Z, f32::INFINITY, None),
        1
    );
    assert_eq!(bvh.hit_count(Vec3::ZERO, Vec3::Z, 1e-3, None), 1);
    // Bad rays and degenerate segments give no hits and no NaN.
    assert_eq!(bvh.transmittance(o, Vec3::ZERO, 10.0, None), 1.0);
    assert_eq!(
        bvh.transmittance(o, Vec3::new(f32::NAN, 0.0, 1.0), 10.0, None),
        1.0
    );
    assert_eq!(bvh.transmittance(o, Vec3::Z, f32::NAN, None), 1.0);
    assert_eq!(bvh.transmittance(o, Vec3::Z, 0.0, None), 1.0);
    let degenerate = SegmentBvh::build(vec![
        seg(Vec3::ZERO, Vec3::ZERO, 0.1, 0.5, 0),
        seg(Vec3::ZERO, Vec3::X, 0.0, 0.5, 1),
        seg(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::X, 0.1, 0.5, 2),
        seg(Vec3::ZERO, Vec3::X, 0.1, f32::NAN, 3),
    ]);
    assert_eq!(degenerate.segments().len(), 4);
    let t = degenerate.transmittance(Vec3::new(0.0, 0.0, -1.0), Vec3::Z, f32::INFINITY, None);
    assert_eq!(t, 1.0);
    let empty = SegmentBvh::build(Vec::new());
    assert_eq!(empty.transmittance(o, Vec3::Z, f32::INFINITY, None), 1.0);
}

#[test]
fn bvh_matches_brute_force() {
    let mut rng = Rng(12345);
    let segs: Vec<Segment> = (0..5000)
        .map(|i| {
            let a = rng.vec3(-1.0, 1.0);
            let b = a + rng.unit() * rng.range(0.0, 0.5);
            seg(a, b, rng.range(0.005, 0.06), 0.1, i / 10)
        })
        .collect();
    let bvh = SegmentBvh::build(segs.clone());
    assert_eq!(bvh.segments().len(), segs.len());
    let mut total = 0u64;
    for i in 0..2000u32 {
        let mut o = rng.vec3(-1.5, 1.5);
        let mut d = rng.unit() * rng.range(0.1, 3.0);
        // Awkward cases for the slab test: axis-aligned directions, origins on segment ends.
        if i % 5 == 0 {
            d = [Vec3::X, Vec3::NEG_Y, Vec3::Z][(i / 5 % 3) as usize];
        }
        if i % 7 == 0 {
            let s = segs[(rng.next() * segs.len() as f32) as usize];
            o = if i % 2 == 0 { s.a } else { s.b };
        }
        let max_t = if i % 3 == 0 {
            f32::INFINITY
        } else {
            rng.range(0.0, 3.0)
        };
        let exclude = (i % 2 == 0).then(|| (rng.next() * 500.0) as u32);
        let brute = segs
            .iter()
            .filter(|s| exclude != Some(s.strand) && ray_hits_segment(s, o, d, max_t))
            .count() as u32;
        assert_eq!(bvh.hit_count(o, d, max_t, exclude), brute, "ray {i}");
        total += brute as u64;
    }
    // The scene is dense enough that the comparison means something.
    assert!(total > 2000 * 3, "only {total} hits");
}

#[test]
fn disc_average_matches_band_fraction() {
    // A wide strand crossing the central ray perpendicularly; the disc is twice its radius.
    let r = 0.05f32;
    let big_r = 2.0 * r;
    let alpha = 0.6f32;
    let bvh = SegmentBvh::build(vec![seg(
        Vec3::new(-1.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 1.0),
        r,
        alpha,
        0,
    )]);
    let (r64, big64) = (r as f64, big_r as f64);
    let area =
        2.0 * (r64 * (big64 * big64 - r64 * r64).sqrt() + big64 * big64 * (r64 / big64).asin());
    let fraction = area / (std::f64::consts::PI * big64 * big64);
    let expected = (1.0 - alpha as f64 * fraction) as f32;
    // Tolerance: with 4096 stratified rays the covered fraction is off by well under 0.002.
    for seed in [0u32, 1, 99] {
        let t = directional_transmittance(&bvh, Vec3::ZERO, Vec3::Z, big_r, 4096, seed, None);
        assert!(
            (t - expected).abs() < 2e-3,
            "seed {seed}: {t} vs {expected}"
        );
        // Point light far away along +z: almost parallel rays, nearly the same answer.
        let p = point_transmittance(
            &bvh,
            Vec3::ZERO,
            Vec3::new(0.0, 0.0, 1e4),
            big_r,
            4096,
            seed,
            None,
        );
        assert!(
            (p - expected).abs() < 3e-3,
            "point, seed {seed}: {p} vs {expected}"
        );
    }
    // One ray is the central ray.
    let t1 = directional_transmittance(&bvh, Vec3::ZERO, Vec3::Z, big_r, 1, 5, None);
    assert!((t1 - (1.0 - alpha)).abs() < 1e-6);
    // Deterministic.
    let a = directional_transmittance(&bvh, Vec3::ZERO, Vec3::Z, big_r, 8, 42, None);
    let b = directional_transmittance(&bvh, Vec3::ZERO, Vec3::Z, big_r, 8, 42, None);
    assert_eq!(a, b);
}

#[test]
fn point_light_stops_at_the_light() {
    let bvh = crossing(0.5);
    let p = Vec3::new(0.0, 0.0, -2.0);
    // Light beyond the strand: shadowed; light before it: not.
    let beyond = point_transmittance(&bvh, p, Vec3::new(0.0, 0.0, 2.0), 0.0, 4, 0, None);
    assert!((beyond - 0.5).abs() < 1e-6);
    let before = point_transmittance(&bvh, p, Vec3::new(0.0, 0.0, -1.0), 0.0, 4, 0, None);
    assert_eq!(before, 1.0);
    assert_eq!(point_transmittance(&bvh, p, p, 0.1, 4, 0, None), 1.0);
}

#[test]
fn segments_from_strands_tapers() {
    let vps = 5;
    let strands = 3;
    let mut verts = Vec::new();
    for s in 0..strands {
        for k in 0..vps {
            let w = k as f32 / (vps - 1) as f32;
            verts.push(Vec4::new(s as f32, 0.0, w, w));
        }
    }
    let root_widths = [0.1f32, 0.2, 0.4];
    let tip = 0.25;
    let segs = segments_from_strands(&verts, vps, &root_widths, tip, 0.7);
    assert_eq!(segs.len(), strands * (vps - 1));
    for (i, s) in segs.iter().enumerate() {
        let strand = i / (vps - 1);
        let k = i % (vps - 1);
        let w0 = k as f32 / (vps - 1) as f32;
        let w1 = (k + 1) as f32 / (vps - 1) as f32;
        let width = |w: f32| root_widths[strand] * (1.0 + (tip - 1.0) * w);
        let expected = 0.5 * 0.5 * (width(w0) + width(w1));
        assert!(
            (s.radius - expected).abs() < 1e-7,
            "{i}: {} vs {expected}",
            s.radius
        );
        assert_eq!(s.strand, strand as u32);
        assert_eq!(s.opacity, 0.7);
        assert_eq!(s.a, verts[strand * vps + k].truncate());
        assert_eq!(s.b, verts[strand * vps + k + 1].truncate());
    }
    // Radius shrinks root to tip.
    assert!(segs[0].radius > segs[vps - 2].radius);
    assert!(segments_from_strands(&verts, 1, &root_widths, tip, 0.7).is_empty());
}

#[test]
fn vertices_exclude_their_own_strand() {
    // Two strands along x at z = 0 and z = 1; light along +z.
    let vps = 3;
    let mut verts = Vec::new();
    for z in [0.0f32, 1.0] {
        for k in 0..vps {
            let w = k as f32 / (vps - 1) as f32;
            verts.push(Vec4::new(-0.5 + 0.5 * k as f32, 0.0, z, w));
        }
    }
    let segs = segments_from_strands(&verts, vps, &[0.2, 0.2], 1.0, 0.4);
    let bvh = SegmentBvh::build(segs);
    let t = transmittance_at_vertices(&bvh, &verts, vps, Vec3::Z, 0.0, 1);
    assert_eq!(t.len(), verts.len());
    // Lower strand's first two vertices are shadowed by the upper one (the tip vertex is past
    // the upper strand's half-open end); the upper strand sees nothing.
    assert!(
        (t[0] - 0.6).abs() < 1e-6 && (t[1] - 0.6).abs() < 1e-6,
        "{t:?}"
    );
    assert_eq!(t[2], 1.0);
    assert!(t[3..].iter().all(|&x| x == 1.0), "{t:?}");
}

#[test]
fn rmse_p95_known_values() {
    assert_eq!(rmse_p95(&[1.0], &[1.0, 2.0]), None);
    assert_eq!(rmse_p95(&[], &[]), None);
    let (rmse, p95) = rmse_p95(&[0.0, 0.0, 0.0, 0.0], &[1.0, -1.0, 1.0, -1.0]).unwrap();
    assert!((rmse - 1.0).abs() < 1e-7 && p95 == 1.0);
    // |a-b| = 1..=20 (in hundredths): rmse = sqrt(mean(k^2)) / 100, p95 = 19th smallest.
    let a: Vec<f32> = (1..=20).map(|k| k as f32 / 100.0).collect();
    let b = vec![0.0f32; 20];
    let (rmse, p95) = rmse_p95(&a, &b).unwrap();
    let mean_sq: f64 = (1..=20).map(|k| (k * k) as f64).sum::<f64>() / 20.0;
    assert!((rmse as f64 - mean_sq.sqrt() / 100.0).abs() < 1e-6);
    assert_eq!(p95, 0.19);
    // 100 values 0..99: p95 is the 95th smallest = 94.
    let a: Vec<f32> = (0..100).map(|k| k as f32).collect();
    let (_, p95) = rmse_p95(&a, &vec![0.0; 100]).unwrap();
    assert_eq!(p95, 94.0);
}

#[test]
fn performance_smoke() {
    // 100k segments: 6250 random-walk strands of 16 segments in a 2-unit ball, hair-like radii.
    let mut rng = Rng(777);
    let vps = 17;
    let strands = 6250;
    let mut verts = Vec::with_capacity(strands * vps);
    for _ in 0..strands {
        let mut p = rng.unit() * 1.0;
        let mut dir = p.normalize();
        for k in 0..vps {
            verts.push(p.extend(k as f32 / (vps - 1) as f32));
            dir = (dir + 0.3 * rng.unit()).normalize();
            p += dir * 0.04;
        }
    }
    let widths = vec![0.004f32; strands];
    let start = Instant::now();
    let segs = segments_from_strands(&verts, vps, &widths, 0.3, 0.3);
    assert_eq!(segs.len(), 100_000);
    let bvh = SegmentBvh::build(segs);
    let built = start.elapsed();
    let samples = 10_000;
    let to_light = Vec3::new(0.3, 1.0, 0.2).normalize();
    let start = Instant::now();
    let mut sum = 0.0f64;
    for i in 0..samples {
        let v = verts[(i * 7919) % verts.len()];
        let strand = ((i * 7919) % verts.len() / vps) as u32;
        sum += directional_transmittance(
            &bvh,
            v.truncate(),
            to_light,
            0.004,
            8,
            i as u32,
            Some(strand),
        ) as f64;
    }
    let traced = start.elapsed();
    println!(
        "transmittance perf: build 100k segments {:.3} s, trace {} x 8 rays {:.3} s, mean T {:.4}",
        built.as_secs_f64(),
        samples,
        traced.as_secs_f64(),
        sum / samples as f64
    );
    assert!(sum.is_finite());
}

/// `crossings` counts the cylinders a ray enters, not the one it starts in: from the axis
/// of one segment across two parallel others, two; along its own segment, none; and it
/// agrees with `occluded` on whether any is entered.
#[test]
fn crossings_leave_the_cylinder_the_ray_starts_in() {
    let segment = |x: f32, strand: u32| Segment {
        a: Vec3::new(x, -1.0, 0.0),
        b: Vec3::new(x, 1.0, 0.0),
        radius: 0.05,
        opacity: 1.0,
        strand,
    };
    let bvh = SegmentBvh::build(vec![segment(0.0, 0), segment(0.5, 1), segment(1.0, 2)]);
    let origin = Vec3::ZERO;
    assert_eq!(bvh.crossings(origin, Vec3::X, f32::INFINITY), 2);
    assert_eq!(bvh.crossings(origin, Vec3::NEG_X, f32::INFINITY), 0);
    assert_eq!(bvh.crossings(origin, Vec3::X, 0.7), 1);
    assert_eq!(bvh.crossings(origin, Vec3::Y, f32::INFINITY), 0);
    for dir in [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::new(1.0, 0.2, 0.02)] {
        let occluded = bvh.occluded(
            origin.as_dvec3(),
            dir.as_dvec3().normalize(),
            f64::INFINITY,
            None,
        );
        assert_eq!(
            occluded,
            bvh.crossings(origin, dir, f32::INFINITY) > 0,
            "{dir}"
        );
    }
}
