//! Mirror of `wgsl/strands/guides.wgsl`: render strands interpolated from bent guides (the
//! guides themselves are bent by [`deform_groom`](crate::strands::deform_groom), the
//! mirror of the first pass, or simulated: [`crate::simulate`]). It evaluates the whole
//! formula at every vertex, all four guides, the noise and the clumping, where the shader
//! leaves out the terms that add exactly 0 (the root vertex's offsets, guides past `k`,
//! no noise, no clumping): the two agreeing checks that those terms are 0.
//!
//! The mirror chooses each render strand's guides and weights itself ([`choose_guides`]),
//! from the roots' positions, by the rule `GuideStrands` documents: the `k` guides whose
//! roots are nearest the strand's root (ties to the lower index), weighted by
//! `1/d_i − 1/d_(k+1)` (plain `1/d_i` without a `(k+1)`-th guide), normalised, the first
//! `k − 1` weights stored as 10-bit fractions of 1023 and the last 1 minus the others.

use glam::{Vec3, Vec4};
use pelage_scene::{GuideParams, HairParams, Mesh};

use crate::noise::{hash_to_unit, pcg_hash};
use crate::strands::{Drawn, Level, Root};

/// `NOISE_SALT` in WGSL.
const NOISE_SALT: u32 = 0x6a09_e667;

/// Largest 10-bit weight (a weight of 1).
const WEIGHT_ONE: u32 = 1023;

/// Distances are floored at this fraction of the mesh's bounding-box diagonal, so that a
/// root on a guide's root has a finite weight (as `GuideStrands` floors them).
const DISTANCE_FLOOR: f32 = 1e-7;

/// A render strand's guides (indices into the guide buffer, nearest first; slots past `k`
/// repeat the nearest) and their weights (0 past `k`), as `guides.wgsl` reads them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Choice {
    /// Guide indices.
    pub guides: [u32; 4],
    /// Weights, summing to 1.
    pub weights: [f32; 4],
}

/// The guides and weights a packed record (`[u32; 3]`: four 16-bit indices, nearest first,
/// low half first; then the first `k - 1` weights as 10-bit fractions, lowest bits first)
/// holds for `k` guides, as `guides.wgsl` decodes it: the `k`-th weight is 1 minus the
/// others (the rest 0).
pub fn decode_record(record: &[u32; 3], k: u32) -> Choice {
    let [r0, r1, r2] = *record;
    let guides = [r0 & 0xffff, r0 >> 16, r1 & 0xffff, r1 >> 16];
    let k = k.clamp(1, 4);
    let mut weights = [0.0f32; 4];
    let mut rest = 1.0f32;
    for n in 0..k - 1 {
        weights[n as usize] = ((r2 >> (10 * n)) & WEIGHT_ONE) as f32 / WEIGHT_ONE as f32;
        rest -= weights[n as usize];
    }
    weights[(k - 1) as usize] = rest;
    Choice { guides, weights }
}

/// `root`'s point on its (flat) triangle of `mesh`.
fn flat_root(mesh: &Mesh, root: &Root) -> Vec3 {
    let corner = |k: usize| mesh.positions[mesh.indices[root.triangle as usize * 3 + k] as usize];
    let bw = 1.0 - root.bary.x - root.bary.y;
    corner(0) * root.bary.x + corner(1) * root.bary.y + corner(2) * bw
}

/// The guides `k` gives for `params` and `guides` guides: `params.k`, at most the guide
/// count, at least 1.
pub fn guide_count(params: &GuideParams, guides: usize) -> u32 {
    params.k.min(guides as u32).clamp(1, 4)
}

/// Each render strand's guides and weights, chosen once as `GuideStrands` chooses them
/// when it is built: the `k` guides (of `guide_roots`, the guides' rest root points in
/// buffer order) nearest its root on `mesh` (the rest pose it was built on), found by a
/// search over every guide, weighted by the rule of the module's docs with the weights
/// quantised as the record stores them.
pub fn choose_guides(mesh: &Mesh, roots: &[Root], guide_roots: &[Vec3], k: u32) -> Vec<Choice> {
    let (lo, hi) = mesh.bounds();
    let floor = DISTANCE_FLOOR * (hi - lo).length().max(f32::MIN_POSITIVE);
    let k = (k.clamp(1, 4) as usize).min(guide_roots.len());
    if k == 0 {
        // No guides: nothing to blend (every strand stays at its root).
        let none = Choice {
            guides: [0; 4],
            weights: [0.0; 4],
        };
        return vec![none; roots.len()];
    }
    roots
        .iter()
        .map(|root| {
            let at = flat_root(mesh, root);
            let mut by_distance: Vec<(u32, f32)> = guide_roots
                .iter()
                .enumerate()
                .map(|(i, g)| (i as u32, g.distance(at)))
                .collect();
            by_distance.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            let taken = &by_distance[..k];
            // The next guide's inverse distance, taken off every weight (0 without one).
            let beyond = by_distance.get(k).map_or(0.0, |&(_, d)| 1.0 / d.max(floor));
            let mut raw: Vec<f64> = taken
                .iter()
                .map(|&(_, d)| f64::from((1.0 / d.max(floor) - beyond).max(0.0)))
                .collect();
            let sum: f64 = raw.iter().sum();
            if !(sum > 0.0 && sum.is_finite()) {
                // Every taken guide as far as the next one: equal weights.
                raw.iter_mut().for_each(|w| *w = 1.0);
            }
            let sum: f64 = raw.iter().sum();
            let mut stored: Vec<u32> = raw[..k - 1]
                .iter()
                .map(|w| (w / sum * f64::from(WEIGHT_ONE)).round() as u32)
                .collect();
            // The last weight is 1 minus the others: never below 0.
            while stored.iter().sum::<u32>() > WEIGHT_ONE {
                if let Some(largest) = stored.iter_mut().max() {
                    *largest -= 1;
                }
            }
            let mut guides = [taken[0].0; 4];
            for (slot, &(g, _)) in guides.iter_mut().zip(taken) {
                *slot = g;
            }
            let mut weights = [0.0f32; 4];
            let mut rest = 1.0f32;
            for (w, &q) in weights.iter_mut().zip(&stored) {
                *w = q as f32 / WEIGHT_ONE as f32;
                rest -= *w;
            }
            weights[k - 1] = rest;
            Choice { guides, weights }
        })
        .collect()
}

/// One render strand: `segments / step + 1` vertices (xyz position, w strand parameter)
/// from the bent `guides` (`segments + 1` per guide, in buffer order).
fn interpolate_strand(
    mesh: &Mesh,
    root: &Root,
    choice: &Choice,
    guides: &[Vec4],
    drawn: Drawn,
    (clump, noise): (f32, f32),
) -> Vec<Vec4> {
    let r = flat_root(mesh, root);
    let per_guide = drawn.segments + 1;
    let first = choice.guides.map(|i| i * per_guide);
    let point = |i: u32| {
        guides
            .get(i as usize)
            .copied()
            .unwrap_or(Vec4::ZERO)
            .truncate()
    };

    let mut h = pcg_hash(root.seed ^ NOISE_SALT);
    let jx = 2.0 * hash_to_unit(h) - 1.0;
    h = pcg_hash(h);
    let jy = 2.0 * hash_to_unit(h) - 1.0;
    h = pcg_hash(h);
    let jz = 2.0 * hash_to_unit(h) - 1.0;
    let drift = Vec3::new(jx, jy, jz) * (noise * root.length);

    let step = drawn.step;
    (0..=drawn.segments / step)
        .map(|v| {
            let i = v * step;
            let s = i as f32 / drawn.segments as f32;
            // All four guides: a guide past k has weight 0 and adds 0 (the shader skips it).
            let nearest = point(first[0] + i);
            let mut blend = r;
            for (&start, &w) in first.iter().zip(&choice.weights) {
                blend += (point(start + i) - point(start)) * w;
            }
            blend += drift * (s * s);
            let p = blend + (nearest - blend) * (clump * s);
            p.extend(s)
        })
        .collect()
}

/// The render strands of `GuideStrands` at `level` on `mesh` (the pose the mesh buffers
/// hold this frame), in the layout of `StrandBuffers::vertices`: the first `level.strands`
/// of `roots` (at most `params.roots.count`; `params` are the render strands' parameters,
/// `GuideStrands::params_for`), each blending the bent `guides` (`growth.segments + 1`
/// points per guide, in buffer order) by its `choices` (one per root, made once on the
/// rest pose by [`choose_guides`]), with the clumping and the noise of `guide`.
pub fn interpolate(
    mesh: &Mesh,
    roots: &[Root],
    choices: &[Choice],
    guides: &[Vec4],
    params: &HairParams,
    guide: &GuideParams,
    level: Level,
) -> Vec<Vec4> {
    let drawn = Drawn::new(params, level);
    choices
        .iter()
        .zip(roots)
        .take(drawn.strands as usize)
        .flat_map(|(choice, root)| {
            interpolate_strand(
                mesh,
                root,
                choice,
                guides,
                drawn,
                (guide.clump, guide.noise),
            )
        })
        .collect()
}
