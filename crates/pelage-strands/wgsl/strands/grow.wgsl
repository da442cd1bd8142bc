// Stage 1: grow strands from a triangle mesh.
//
// Reads:  the mesh (positions and normals as tightly packed f32 x3, a u32 triangle
//         list), one StrandRoot per strand (triangle, barycentrics, seed, length,
//         jitter, region), one RegionShape per region (the hair type each strand's
//         region grows with), plus the frame's GrowUniforms (gravity, wind, time).
// Writes: `vertices`, (segments / step + 1) vec4 per strand, one strand after the other:
//         xyz = position, w = strand parameter in [0, 1] (0 at the root, 1 at the tip);
//         and `drawn[strand].width`, the rest width times the level of detail's width
//         scale s(x) for x = (strand + 1/2) / strand_total.
// Dispatch: one invocation per grown strand (strand_count, a prefix of the groom: the
//         strands are in random order), workgroup_size(64); x = min(groups, limit),
//         y = ceil(groups / x).
//
// Every segment has the exact length `length / segments`: the tangent of each segment
// is a unit vector, so no force, wind or time can stretch a strand or make it NaN.
// Segment reduction grows every strand at full resolution and keeps every step-th vertex,
// so the kept vertices lie exactly on the full strand.
// The CPU mirror of this file is pelage-reference/src/strands.rs: change both together.

#import shared/math.wgsl
#import shared/strand.wgsl
#import strands/rotation.wgsl
#import strands/force.wgsl
#import strands/lod.wgsl

@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> normals: array<f32>;
@group(0) @binding(3) var<storage, read> indices: array<u32>;
@group(0) @binding(4) var<storage, read> roots: array<StrandRoot>;
@group(0) @binding(5) var<storage, read> regions: array<RegionShape>;
@group(0) @binding(6) var<storage, read_write> vertices: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> drawn: array<StrandRoot>;

// A region's strand shape (RegionShape in pelage-strands/src/grow.rs).
struct RegionShape {
    // 0 = straight, 1 = wavy, 2 = curly.
    kind: u32,
    // wavy: amplitude, frequency; curly: radius, pitch.
    a: f32,
    b: f32,
}

fn load_position(i: u32) -> vec3<f32> {
    return vec3<f32>(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
}

fn load_normal(i: u32) -> vec3<f32> {
    return vec3<f32>(normals[3u * i], normals[3u * i + 1u], normals[3u * i + 2u]);
}

struct Surface {
    position: vec3<f32>,
    normal: vec3<f32>,
    // A unit vector in the tangent plane that turns with the triangle.
    tangent: vec3<f32>,
}

// PN triangle edge control point (Vlachos et al. 2001): 1/3 of the way from pi to pj,
// projected onto the tangent plane at pi.
fn pn_edge(pi: vec3<f32>, pj: vec3<f32>, ni: vec3<f32>) -> vec3<f32> {
    let w = dot(pj - pi, ni);
    return (2.0 * pi + pj - w * ni) / 3.0;
}

// PN triangle mid-edge normal coefficient.
fn pn_edge_normal(pi: vec3<f32>, pj: vec3<f32>, ni: vec3<f32>, nj: vec3<f32>) -> vec3<f32> {
    let d = pj - pi;
    let dd = dot(d, d);
    var v = 0.0;
    if dd > 0.0 {
        v = 2.0 * dot(d, ni + nj) / dd;
    }
    return safe_normalize(ni + nj - v * d, ni);
}

// Position, normal and tangent at barycentrics (u, v, w = 1 - u - v) of a triangle
// whose corners p1, p2, p3 belong to u, v, w.
fn eval_surface(tri: u32, bary: vec2<f32>) -> Surface {
    let i1 = indices[3u * tri];
    let i2 = indices[3u * tri + 1u];
    let i3 = indices[3u * tri + 2u];
    let p1 = load_position(i1);
    let p2 = load_position(i2);
    let p3 = load_position(i3);
    let n1 = safe_normalize(load_normal(i1), vec3<f32>(0.0, 1.0, 0.0));
    let n2 = safe_normalize(load_normal(i2), n1);
    let n3 = safe_normalize(load_normal(i3), n1);
    let bu = bary.x;
    let bv = bary.y;
    let bw = 1.0 - bu - bv;

    var s: Surface;
    if u.surface == 1u {
        let p210 = pn_edge(p1, p2, n1);
        let p120 = pn_edge(p2, p1, n2);
        let p021 = pn_edge(p2, p3, n2);
        let p012 = pn_edge(p3, p2, n3);
        let p102 = pn_edge(p3, p1, n3);
        let p201 = pn_edge(p1, p3, n1);
        let e = (p210 + p120 + p021 + p012 + p102 + p201) / 6.0;
        let c = (p1 + p2 + p3) / 3.0;
        let p111 = e + (e - c) * 0.5;
        s.position = p1 * (bu * bu * bu) + p2 * (bv * bv * bv) + p3 * (bw * bw * bw)
            + p210 * (3.0 * bu * bu * bv) + p120 * (3.0 * bu * bv * bv)
            + p201 * (3.0 * bu * bu * bw) + p021 * (3.0 * bv * bv * bw)
            + p012 * (3.0 * bv * bw * bw) + p102 * (3.0 * bu * bw * bw)
            + p111 * (6.0 * bu * bv * bw);
        let n110 = pn_edge_normal(p1, p2, n1, n2);
        let n011 = pn_edge_normal(p2, p3, n2, n3);
        let n101 = pn_edge_normal(p3, p1, n3, n1);
        let n = n1 * (bu * bu) + n2 * (bv * bv) + n3 * (bw * bw)
            + n110 * (bu * bv) + n011 * (bv * bw) + n101 * (bu * bw);
        s.normal = safe_normalize(n, n1);
    } else {
        s.position = p1 * bu + p2 * bv + p3 * bw;
        s.normal = safe_normalize(n1 * bu + n2 * bv + n3 * bw, n1);
    }
    s.tangent = perpendicular(s.normal, p2 - p1);
    return s;
}

// The unit tangent of the segment whose midpoint lies at arc length s, for a strand
// of shape `shape` whose growth direction is d with transported frame (e1, e2).
fn shaped_tangent(shape: RegionShape, d: vec3<f32>, e1: vec3<f32>, e2: vec3<f32>, s: f32) -> vec3<f32> {
    if shape.kind == 1u {
        let k = 2.0 * PI * shape.b;
        let theta = atan(k * shape.a * cos(k * s));
        return d * cos(theta) + e1 * sin(theta);
    }
    if shape.kind == 2u {
        let circumference = 2.0 * PI * shape.a;
        let turn_length = sqrt(circumference * circumference + shape.b * shape.b);
        let theta = atan2(circumference, shape.b);
        let phi = 2.0 * PI * s / turn_length;
        return d * cos(theta) + (e1 * cos(phi) + e2 * sin(phi)) * sin(theta);
    }
    return d;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let strand = gid.y * groups.x * 64u + gid.x;
    if strand >= u.strand_count {
        return;
    }
    let root = roots[strand];
    // A region beyond the buffer (never written by the CPU) reads the last one.
    let shape = regions[min(root.region, arrayLength(&regions) - 1u)];
    let x = (f32(strand) + 0.5) / f32(u.strand_total);
    drawn[strand].width = root.width * lod_scale(x, u.lod_lambda, u.lod_t_e, u.lod_s_max, u.lod_s_min);
    let surf = eval_surface(root.triangle, root.bary);

    // Root direction: the normal tilted by the strand's jitter.
    let side = surf.tangent * cos(root.azimuth) + cross(surf.normal, surf.tangent) * sin(root.azimuth);
    var d = safe_normalize(surf.normal * cos(root.tilt) + side * sin(root.tilt), surf.normal);
    var e1 = perpendicular(d, surf.tangent);
    var e2 = cross(d, e1);

    let segments = u.segments;
    let seg_len = root.length / f32(segments);
    let t = u.time + root.phase * u.phase_spread;
    let step = max(u.step, 1u);
    let base = strand * (segments / step + 1u);
    // Evaluated once per strand: it does not depend on the position.
    let base_force = uniform_force(t);
    var p = surf.position;
    vertices[base] = vec4<f32>(p, 0.0);
    for (var i = 0u; i < segments; i++) {
        let s = (f32(i) + 0.5) * seg_len;
        let tangent = shaped_tangent(shape, d, e1, e2, s);
        p = p + tangent * seg_len;
        if (i + 1u) % step == 0u {
            vertices[base + (i + 1u) / step] = vec4<f32>(p, f32(i + 1u) / f32(segments));
        }
        // Bend the growth direction for the next segment, then carry the frame along.
        let d_next = safe_normalize(d + force(p, t, base_force) * u.force_weight, d);
        e1 = perpendicular(d_next, e1);
        e2 = cross(d_next, e1);
        d = d_next;
    }
}
