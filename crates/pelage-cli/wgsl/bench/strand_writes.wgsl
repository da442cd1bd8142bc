// The benchmark's lower bound for strand expansion: the same writes as
// strands/grow.wgsl (one invocation per strand, its segments + 1 vec4s one after the
// other) with no arithmetic, so the stage's cost splits into memory layout and math.
//
// Reads:  nothing but the vertex count per strand (`per_strand`).
// Writes: `vertices`, strand-major, vertices[s * per_strand + i] = (i, 0, 0, 1).
// Dispatch: workgroup_size(64), one invocation per strand; x = min(groups, limit),
//           y = ceil(groups / x).

@group(0) @binding(0) var<uniform> per_strand: vec4<u32>;
@group(0) @binding(1) var<storage, read_write> vertices: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let strand = gid.y * groups.x * 64u + gid.x;
    let n = per_strand.x;
    if strand * n >= arrayLength(&vertices) {
        return;
    }
    for (var i = 0u; i < n; i++) {
        vertices[strand * n + i] = vec4<f32>(f32(i), 0.0, 0.0, 1.0);
    }
}
