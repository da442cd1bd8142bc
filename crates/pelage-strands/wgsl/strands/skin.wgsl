// Stage 1's input: linear blend skinning of the mesh into its buffers.
//
// Reads:  SkinUniforms (vertex and joint counts); the bind pose (positions and normals as
//         tightly packed f32 x3); per vertex four joint indices (vec4<u32>) and four
//         weights (vec4<f32>, normalised on the CPU); the frame's joint matrices
//         (mat4x4<f32> each: a joint's world transform times its inverse bind matrix).
// Writes: the mesh buffers' positions and normals (f32 x3), which growth, guides and the
//         simulation read after this pass; `non_finite[0]` (atomicAdd): the vertices whose
//         skinned position or normal was not finite this frame (a NaN or infinite matrix
//         of a joint they weigh), written at their bind pose instead.
// Dispatch: one invocation per vertex, workgroup_size(64); x = min(groups, limit),
//         y = ceil(groups / x).
//
// Position: p' = (sum_k w_k M_k) (p, 1), over the slots of non-zero weight. Normal: the cofactor matrix of the blended
// matrix's upper 3x3 (its inverse transpose times its determinant: exact under
// non-uniform scale and shear, no division) times n, normalised. A joint index at or past
// the joint count reads joint 0 (the CPU refuses such skins; this only keeps a bad engine
// buffer in bounds).
// The CPU mirror of this file is pelage-reference/src/skin.rs.

#import shared/math.wgsl

struct SkinUniforms {
    vertex_count: u32,
    joint_count: u32,
}

@group(0) @binding(0) var<uniform> u: SkinUniforms;
@group(0) @binding(1) var<storage, read> bind_positions: array<f32>;
@group(0) @binding(2) var<storage, read> bind_normals: array<f32>;
@group(0) @binding(3) var<storage, read> joints: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> weights: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> joint_matrices: array<mat4x4<f32>>;
@group(0) @binding(6) var<storage, read_write> positions: array<f32>;
@group(0) @binding(7) var<storage, read_write> normals: array<f32>;
@group(0) @binding(8) var<storage, read_write> non_finite: array<atomic<u32>>;

fn bind_position(i: u32) -> vec3<f32> {
    return vec3<f32>(bind_positions[3u * i], bind_positions[3u * i + 1u], bind_positions[3u * i + 2u]);
}

fn bind_normal(i: u32) -> vec3<f32> {
    return vec3<f32>(bind_normals[3u * i], bind_normals[3u * i + 1u], bind_normals[3u * i + 2u]);
}

fn joint(j: u32) -> mat4x4<f32> {
    return joint_matrices[select(0u, j, j < u.joint_count)];
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let v = gid.y * groups.x * 64u + gid.x;
    if v >= u.vertex_count {
        return;
    }
    let j = joints[v];
    let w = weights[v];
    // A slot of weight 0 adds nothing, whatever its joint holds (0 x NaN would be NaN).
    var m = mat4x4<f32>();
    for (var k = 0u; k < 4u; k++) {
        if w[k] != 0.0 {
            m += joint(j[k]) * w[k];
        }
    }
    let p0 = bind_position(v);
    let n0 = bind_normal(v);
    let p = (m * vec4<f32>(p0, 1.0)).xyz;
    let c0 = m[0].xyz;
    let c1 = m[1].xyz;
    let c2 = m[2].xyz;
    // cofactor(M) n = (c1 x c2) (n.x) + (c2 x c0) n.y + (c0 x c1) n.z, as columns.
    let cn = cross(c1, c2) * n0.x + cross(c2, c0) * n0.y + cross(c0, c1) * n0.z;
    let n = cn * inverseSqrt(max(dot(cn, cn), 1e-30));
    var out_p = p;
    var out_n = n;
    if !(all_finite3(p) && all_finite3(n)) {
        out_p = p0;
        out_n = n0;
        atomicAdd(&non_finite[0], 1u);
    }
    positions[3u * v] = out_p.x;
    positions[3u * v + 1u] = out_p.y;
    positions[3u * v + 2u] = out_p.z;
    normals[3u * v] = out_n.x;
    normals[3u * v + 1u] = out_n.y;
    normals[3u * v + 2u] = out_n.z;
}
