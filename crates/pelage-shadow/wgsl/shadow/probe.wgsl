// A shadow method's light_visibility at given points: the strand vertices, for
// the hair pass (LightVisibility, one light's slice of the visibility buffer) and for
// comparison with the ray-traced reference (TransmittanceProbe); or, entry point
// `surface`, its surface_visibility (points on the body).
//
// Reads:  the method's @group(1) resources, through the shadow contract
//         (shadow/none.wgsl, redirected to the method's lookup); `points` (vec4, xyz).
// Writes: `visibility`, light_visibility(point) (surface_visibility(point)) per point.
// Dispatch: one invocation per point, workgroup_size(64); x = min(groups, limit),
//         y = ceil(groups / x).

#import shadow/none.wgsl

@group(0) @binding(0) var<storage, read> points: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> visibility: array<f32>;

// The point this invocation evaluates, or -1 past the end.
fn probe_point(gid: vec3<u32>, groups: vec3<u32>) -> i32 {
    let i = gid.y * groups.x * 64u + gid.x;
    if i >= arrayLength(&visibility) || i >= arrayLength(&points) {
        return -1;
    }
    return i32(i);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = probe_point(gid, groups);
    if i >= 0 {
        visibility[i] = light_visibility(points[i].xyz);
    }
}

@compute @workgroup_size(64)
fn surface(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = probe_point(gid, groups);
    if i >= 0 {
        visibility[i] = surface_visibility(points[i].xyz);
    }
}
