// Stage 1 for a groom read from a file (.hair or .tfx): the strands' rest shape, bent by
// the wind for a time t.
//
// Reads:  `rest`, (segments + 1) vec4 per strand, one strand after the other (xyz = the
//         rest position of the resampled groom, w unused), one StrandRoot per strand
//         (width, colour, gust phase), and the frame's GrowUniforms (wind, time, level
//         of detail; the shape and surface fields are not used, and gravity, which
//         force() adds, is zero: groom.rs's params_for zeroes it, the groom's rest
//         shape already hangs).
// Writes: `vertices`, (segments / step + 1) vec4 per strand, one strand after the other:
//         xyz = position, w = strand parameter in [0, 1] (0 at the root, 1 at the tip);
//         and `drawn[strand].width`, the rest width times the level of detail's width
//         scale s(x) for x = (strand + 1/2) / strand_total.
// Dispatch: one invocation per drawn strand (strand_count, a prefix of the groom: the
//         strands were shuffled on upload), workgroup_size(64); x = min(groups, limit),
//         y = ceil(groups / x).
//
// The root stays where the groom puts it. Walking from the root, segment i takes its rest
// direction turned by the rotation `q` accumulated so far, keeps its rest length, and the
// force at its end turns the direction the way grow.wgsl bends a growing strand
// (d' = normalize(d + force_weight * F)); that turn is composed into `q` for the rest of
// the strand. Until the first segment whose force is not zero the vertices are the rest
// points themselves, so with no force the groom comes out exactly as it went in (at t = 0
// in a scene without wind, say); with any force no segment is stretched and the curls of
// the groom ride along.
// The CPU mirror of this file is `deform_groom` in pelage-reference/src/strands.rs:
// change both together.

#import shared/math.wgsl
#import shared/strand.wgsl
#import strands/rotation.wgsl
#import strands/force.wgsl
#import strands/lod.wgsl

// Declared vec3 (the buffer's vec4 stride, w unused): a load fetches the three used
// components (on lavapipe each component at a per-lane address is a load of its own).
@group(0) @binding(1) var<storage, read> rest: array<vec3<f32>>;
@group(0) @binding(2) var<storage, read> roots: array<StrandRoot>;
@group(0) @binding(3) var<storage, read_write> vertices: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> drawn: array<StrandRoot>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let strand = gid.y * groups.x * 64u + gid.x;
    if strand >= u.strand_count {
        return;
    }
    let root = roots[strand];
    let x = (f32(strand) + 0.5) / f32(u.strand_total);
    drawn[strand].width = root.width * lod_scale(x, u.lod_lambda, u.lod_t_e, u.lod_s_max, u.lod_s_min);

    let segments = u.segments;
    let step = max(u.step, 1u);
    let first = strand * (segments + 1u);
    let base = strand * (segments / step + 1u);
    let t = u.time + root.phase * u.phase_spread;
    // Evaluated once per strand: it does not depend on the position.
    let base_force = uniform_force(t);
    var q = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    var p = rest[first];
    // The rest point at the start of segment i, carried so each point is read once.
    var rest_start = p;
    var d = vec3<f32>(0.0, 1.0, 0.0);
    // No force has turned the strand yet: its vertices are the rest points.
    var at_rest = true;
    vertices[base] = vec4<f32>(p, 0.0);
    for (var i = 0u; i < segments; i++) {
        let rest_end = rest[first + i + 1u];
        let offset = rest_end - rest_start;
        rest_start = rest_end;
        // A zero-length rest segment (points repeated in the file) keeps the last direction.
        d = quat_rotate(q, safe_normalize(offset, quat_rotate(vec4<f32>(-q.xyz, q.w), d)));
        if at_rest {
            p = rest_end;
        } else {
            p = p + d * length(offset);
        }
        if (i + 1u) % step == 0u {
            vertices[base + (i + 1u) / step] = vec4<f32>(p, f32(i + 1u) / f32(segments));
        }
        let push = force(p, t, base_force) * u.force_weight;
        at_rest = at_rest && all(push == vec3<f32>(0.0));
        let bent = safe_normalize(d + push, d);
        q = quat_mul(quat_between(d, bent), q);
        q = q / length(q);
        d = bent;
    }
}
