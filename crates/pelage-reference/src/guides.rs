//! Mirror of `wgsl/strands/guides.wgsl`: render strands interpolated from bent guides (the
//! guides themselves are bent by [`deform_groom`](crate::strands::deform_groom), the
//! mirror of the first pass). It evaluates the whole formula at every vertex, all four
//! guides, the noise and the clumping, where the shader leaves out the terms that add
//! exactly 0 (the root vertex's offsets, guides past `k`, no noise, no clumping): the two
//! agreeing checks that those terms are 0.

use glam::{Vec3, Vec4};
use pelage_scene::Mesh;
use pelage_strands::{
    GrowUniforms, GuideRecord, GuideUniforms, StrandRoot, hash_to_unit, pcg_hash,
};

/// `NOISE_SALT` in WGSL.
const NOISE_SALT: u32 = 0x6a09_e667;

/// The guides (buffer indices, nearest first) and weights `record` holds for `k` guides,
/// as `guides.wgsl` decodes them: four indices, and `k` weights of which the last is 1
/// minus the others (the rest 0).
pub fn decode_record(record: &GuideRecord, k: u32) -> ([u32; 4], [f32; 4]) {
    let [r0, r1, r2] = *record;
    let guides = [r0 & 0xffff, r0 >> 16, r1 & 0xffff, r1 >> 16];
    let k = k.clamp(1, 4);
    let mut weight = [0.0f32; 4];
    let mut rest = 1.0f32;
    for n in 0..k - 1 {
        weight[n as usize] = ((r2 >> (10 * n)) & 1023) as f32 / 1023.0;
        rest -= weight[n as usize];
    }
    weight[(k - 1) as usize] = rest;
    (guides, weight)
}

/// One render strand: `u.segments / u.step + 1` vertices (xyz position, w strand
/// parameter) from the bent `guides` (`u.segments + 1` per guide, in buffer order).
pub fn interpolate_strand(
    mesh: &Mesh,
    root: &StrandRoot,
    record: &GuideRecord,
    guides: &[Vec4],
    u: &GrowUniforms,
    g: &GuideUniforms,
) -> Vec<Vec4> {
    let corner = |k: usize| mesh.positions[mesh.indices[root.triangle as usize * 3 + k] as usize];
    let bw = 1.0 - root.bary.x - root.bary.y;
    let r = corner(0) * root.bary.x + corner(1) * root.bary.y + corner(2) * bw;

    let per_guide = u.segments + 1;
    let (indices, weight) = decode_record(record, g.k);
    let first = indices.map(|i| i * per_guide);
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
    let drift = Vec3::new(jx, jy, jz) * (g.noise * root.length);

    let step = u.step.max(1);
    (0..=u.segments / step)
        .map(|v| {
            let i = v * step;
            let s = i as f32 / u.segments as f32;
            // All four guides: a guide past k has weight 0 and adds 0 (the shader skips it).
            let nearest = point(first[0] + i);
            let mut blend = r;
            for (&start, &w) in first.iter().zip(&weight) {
                blend += (point(start + i) - point(start)) * w;
            }
            blend += drift * (s * s);
            let p = blend + (nearest - blend) * (g.clump * s);
            p.extend(s)
        })
        .collect()
}

/// The strands `u` draws (the first `u.strand_count`), in the layout of
/// `StrandBuffers::vertices`: the mirror of `wgsl/strands/guides.wgsl`.
pub fn interpolate(
    mesh: &Mesh,
    roots: &[StrandRoot],
    records: &[GuideRecord],
    guides: &[Vec4],
    u: &GrowUniforms,
    g: &GuideUniforms,
) -> Vec<Vec4> {
    roots
        .iter()
        .zip(records)
        .take(u.strand_count as usize)
        .flat_map(|(root, record)| interpolate_strand(mesh, root, record, guides, u, g))
        .collect()
}
