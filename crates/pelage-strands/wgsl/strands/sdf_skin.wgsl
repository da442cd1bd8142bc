// The skin of a body's distance field built in the bind pose (SdfSkin,
// pelage-strands/src/sdf_skin.rs): every frame, the joint matrices blended at each point of
// a lattice over the field's box, with the weights of the body's surface point nearest it.
//
// Reads:  per lattice point its four joints and weights (PointSkin, computed once on the
//         CPU); the frame's joint matrices (mat4x4<f32> each: a joint's world transform
//         times its inverse bind matrix: MeshSkin's buffer).
// Writes: `rows`, three vec4 per point, the rows of the blended matrix's upper 3x4
//         (p' = (dot(r0.xyz, p) + r0.w, ...)), point (i, j, k) at texels 3i..3i+2 of row
//         (j, k) of PITCH texels (copied into a 3D rgba32float texture after the pass).
// Dispatch: one invocation per lattice point, workgroup_size(64); x = min(groups, limit),
//         y = ceil(groups / x).
//
// A slot of weight 0 adds nothing (0 x NaN would be NaN); a joint index at or past JOINTS
// reads joint 0; a blend that is not finite (a NaN matrix written to the buffer) writes
// the identity, as the skin pass keeps such vertices at their bind pose.
// simulate.wgsl reads the texture (skin_rows) and solves for the bind-pose point.

#import shared/math.wgsl

// The lattice and the skin (SdfSkin::new).
override DIMS_X: u32;
override DIMS_Y: u32;
override DIMS_Z: u32;
override PITCH: u32;
override JOINTS: u32;

struct PointSkin {
    joints: vec4<u32>,
    weights: vec4<f32>,
}

@group(0) @binding(0) var<storage, read> skins: array<PointSkin>;
@group(0) @binding(1) var<storage, read> joint_matrices: array<mat4x4<f32>>;
@group(0) @binding(2) var<storage, read_write> rows: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.y * groups.x * 64u + gid.x;
    if i >= DIMS_X * DIMS_Y * DIMS_Z {
        return;
    }
    let s = skins[i];
    var m = mat4x4<f32>();
    for (var k = 0u; k < 4u; k++) {
        if s.weights[k] != 0.0 {
            m += joint_matrices[select(0u, s.joints[k], s.joints[k] < JOINTS)] * s.weights[k];
        }
    }
    var r0 = vec4<f32>(m[0].x, m[1].x, m[2].x, m[3].x);
    var r1 = vec4<f32>(m[0].y, m[1].y, m[2].y, m[3].y);
    var r2 = vec4<f32>(m[0].z, m[1].z, m[2].z, m[3].z);
    if !(all_finite4(r0) && all_finite4(r1) && all_finite4(r2)) {
        r0 = vec4<f32>(1.0, 0.0, 0.0, 0.0);
        r1 = vec4<f32>(0.0, 1.0, 0.0, 0.0);
        r2 = vec4<f32>(0.0, 0.0, 1.0, 0.0);
    }
    let x = i % DIMS_X;
    let y = (i / DIMS_X) % DIMS_Y;
    let z = i / (DIMS_X * DIMS_Y);
    let base = (z * DIMS_Y + y) * PITCH + 3u * x;
    rows[base] = r0;
    rows[base + 1u] = r1;
    rows[base + 2u] = r2;
}
