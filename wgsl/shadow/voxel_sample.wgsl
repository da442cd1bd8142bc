// Voxel shadows, measurement: the hair's transmittance at given points (the strand
// vertices, for comparison with the ray-traced reference).
//
// Reads:  the voxel lookup's @group(1) resources (voxel_lookup.wgsl), `points` (vec4, xyz).
// Writes: `transmittance`, exp(-optical depth) per point (hair only, no mesh shadow).
// Dispatch: one invocation per point, workgroup_size(64), x = min(groups, limit),
//         y = ceil(groups / x).

#import shadow/voxel_lookup.wgsl

@group(0) @binding(0) var<storage, read> points: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> transmittance: array<f32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.y * groups.x * 64u + gid.x;
    if i >= arrayLength(&transmittance) {
        return;
    }
    transmittance[i] = exp(-voxel_optical_depth(points[i].xyz));
}
