// The benchmark's yardstick: a plain copy, one vec4 per invocation. Its bandwidth
// (bytes read + written per second) is what every stage is compared against.
//
// Reads:  `source` (vec4 storage).
// Writes: `destination` (vec4 storage), destination[i] = source[i].
// Dispatch: workgroup_size(64), one invocation per vec4; x = min(groups, limit),
//           y = ceil(groups / x).

@group(0) @binding(0) var<storage, read> source: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> destination: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.y * groups.x * 64u + gid.x;
    if i >= arrayLength(&destination) {
        return;
    }
    destination[i] = source[i];
}
