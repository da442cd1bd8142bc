// Stage 1: render strands interpolated from guide strands (the second pass of
// GuideStrands; the first bends the guides with strands/groom.wgsl).
//
// Reads:  the mesh (positions as tightly packed f32 x3, a u32 triangle list), one
//         StrandRoot per render strand (triangle, barycentrics, seed, length, width),
//         one GuideRecord per render strand (3 u32: four 16-bit guide indices, nearest
//         first, and three 10-bit weights; the last used weight is 1 minus the others),
//         the bent guides (`guides`: segments + 1 vec4 per guide, written by the first
//         pass this frame) and the frame's GrowUniforms (strand count, step, level of
//         detail; nothing of the wind). The interpolation's constants (K, CLUMP, NOISE:
//         GuideUniforms in guides.rs) are pipeline-overridable constants, fixed when the
//         pipeline is built.
// Writes: `vertices`, (segments / step + 1) vec4 per strand, one strand after the other:
//         xyz = position, w = strand parameter in [0, 1] (0 at the root, 1 at the tip);
//         and `drawn[strand].width`, the rest width times the level of detail's width
//         scale s(x) for x = (strand + 1/2) / strand_total.
// Dispatch: one invocation per drawn strand (strand_count, a prefix of the render
//         strands, whose roots are in random order), workgroup_size(64);
//         x = min(groups, limit), y = ceil(groups / x).
//
// At parameter s = i / segments, with r the root on the (flat) triangle and G_k the bent
// guides, G_0 the nearest:
//   blend(s) = r + sum_k w_k (G_k(s) - G_k(0)) + noise * length * s^2 * j
//   p(s)     = blend(s) + clump * s * (G_0(s) - blend(s))
// where j is a vector in [-1, 1]^3 drawn from the strand's seed. Offsets are blended in
// world space, so one guide gives copies of itself translated to the roots.
//
// What it costs on lavapipe (Mesa 22.3's llvmpipe): a storage load or store at a
// per-lane address is a loop over the 8 lanes of a SIMD row with a bounds test per
// component, and a branch on a uniform runs both sides under a mask. So the terms that
// add exactly 0 are not computed: p(0) is r, without reading the guides; guides past K,
// the noise when NOISE is 0 and the clumping when CLUMP is 0 are left out by `if`s on
// the constants, which the compiler removes with their loads and arithmetic. Each term
// that remains is computed as the formula above writes it: the same values.
// The CPU mirror of this file is `interpolate` in pelage-reference/src/guides.rs:
// change both together.

#import shared/strand.wgsl
#import strands/force.wgsl
#import strands/lod.wgsl

// The interpolation's constants (GuideUniforms in guides.rs): guides blended per
// strand (1 to 4), clumping toward the nearest guide in [0, 1], and per-strand noise, a
// fraction of the strand's length.
override K: u32;
override CLUMP: f32;
override NOISE: f32;

@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> indices: array<u32>;
@group(0) @binding(3) var<storage, read> roots: array<StrandRoot>;
@group(0) @binding(4) var<storage, read> records: array<u32>;
// Declared vec3 (stride 16, the buffer's vec4 layout): a load reads the three used
// components, not four.
@group(0) @binding(5) var<storage, read> guides: array<vec3<f32>>;
@group(0) @binding(6) var<storage, read_write> vertices: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> drawn: array<StrandRoot>;

// Salt of the hash the noise direction is drawn from.
const NOISE_SALT: u32 = 0x6a09e667u;

fn load_position(i: u32) -> vec3<f32> {
    return vec3<f32>(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    // An invocation past the drawn strands computes the last one and writes nothing:
    // loads and arithmetic under no mask, only the stores behind `drawn_strand` (on
    // lavapipe an early return costs more, every later load running under its mask).
    let id = gid.y * groups.x * 64u + gid.x;
    let drawn_strand = id < u.strand_count;
    let strand = min(id, max(u.strand_count, 1u) - 1u);
    let root = roots[strand];
    let x = (f32(strand) + 0.5) / f32(u.strand_total);
    let width = root.width * lod_scale(x, u.lod_lambda, u.lod_t_e, u.lod_s_max, u.lod_s_min);

    // The root on the triangle as the mesh is drawn (flat).
    let tri = root.triangle;
    let bw = 1.0 - root.bary.x - root.bary.y;
    let r = load_position(indices[3u * tri]) * root.bary.x
        + load_position(indices[3u * tri + 1u]) * root.bary.y
        + load_position(indices[3u * tri + 2u]) * bw;

    // The record: guide indices (nearest first) and weights summing to 1. Four guides
    // in named variables, never a private array indexed by a variable (which the
    // compiler keeps in memory: on lavapipe that cost as much as growing the strand).
    let r0 = records[3u * strand];
    let r1 = records[3u * strand + 1u];
    let r2 = records[3u * strand + 2u];
    let per_guide = u.segments + 1u;
    let a0 = (r0 & 0xffffu) * per_guide;
    let a1 = (r0 >> 16u) * per_guide;
    let a2 = (r1 & 0xffffu) * per_guide;
    let a3 = (r1 >> 16u) * per_guide;
    let k = clamp(K, 1u, 4u);
    let q0 = select(0.0, f32(r2 & 1023u) / 1023.0, k > 1u);
    let q1 = select(0.0, f32((r2 >> 10u) & 1023u) / 1023.0, k > 2u);
    let q2 = select(0.0, f32((r2 >> 20u) & 1023u) / 1023.0, k > 3u);
    let rest = 1.0 - q0 - q1 - q2;
    let w0 = select(q0, rest, k == 1u);
    let w1 = select(q1, rest, k == 2u);
    let w2 = select(q2, rest, k == 3u);
    let w3 = select(0.0, rest, k == 4u);
    // The guides' roots, read once (a guide past k is never read).
    let o0 = guides[a0];
    var o1 = vec3<f32>(0.0);
    var o2 = vec3<f32>(0.0);
    var o3 = vec3<f32>(0.0);
    if k > 1u {
        o1 = guides[a1];
    }
    if k > 2u {
        o2 = guides[a2];
    }
    if k > 3u {
        o3 = guides[a3];
    }

    // The noise direction, from the strand's seed.
    var drift = vec3<f32>(0.0);
    if NOISE != 0.0 {
        var h = pcg_hash(root.seed ^ NOISE_SALT);
        let jx = 2.0 * hash_to_unit(h) - 1.0;
        h = pcg_hash(h);
        let jy = 2.0 * hash_to_unit(h) - 1.0;
        h = pcg_hash(h);
        let jz = 2.0 * hash_to_unit(h) - 1.0;
        drift = vec3<f32>(jx, jy, jz) * (NOISE * root.length);
    }

    let segments = u.segments;
    let step = max(u.step, 1u);
    let base = strand * (segments / step + 1u);
    if drawn_strand {
        drawn[strand].width = width;
        // s = 0: every offset, the drift and the clumping are 0.
        vertices[base] = vec4<f32>(r, 0.0);
    }
    for (var v = 1u; v <= segments / step; v++) {
        let i = v * step;
        let s = f32(i) / f32(segments);
        let nearest = guides[a0 + i];
        var blend = r + (nearest - o0) * w0;
        if k > 1u {
            blend = blend + (guides[a1 + i] - o1) * w1;
        }
        if k > 2u {
            blend = blend + (guides[a2 + i] - o2) * w2;
        }
        if k > 3u {
            blend = blend + (guides[a3 + i] - o3) * w3;
        }
        if NOISE != 0.0 {
            blend = blend + drift * (s * s);
        }
        if CLUMP != 0.0 {
            blend = blend + (nearest - blend) * (CLUMP * s);
        }
        if drawn_strand {
            vertices[base + v] = vec4<f32>(blend, s);
        }
    }
}
