// Voxel shadows, pass 3: exclusive prefix sum of density along the light, in place.
//
// Reads:  LightGridUniforms; `volume` as u32 fixed-point density per voxel.
// Writes: `volume` as f32 bits: layer z holds the optical depth in front of voxel z
//         (the sum over layers < z, so no voxel shadows itself); layer resolution_z
//         holds the column's total, for points behind the hair. Sums saturate.
// Dispatch: one invocation per (x, y) column, workgroup_size(8, 8),
//         ceil(resolution_x / 8) x ceil(resolution_y / 8). Cost depends on the grid only.
// The CPU mirror is pelage-reference/src/voxel.rs (`exclusive_scan_column`).

#import shadow/light_common.wgsl

@group(0) @binding(0) var<uniform> u: LightGridUniforms;
@group(0) @binding(1) var<storage, read_write> volume: array<u32>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= u.resolution_x || gid.y >= u.resolution_y {
        return;
    }
    var running = 0u;
    for (var z = 0u; z <= u.resolution_z; z++) {
        let index = voxel_index(u, gid.x, gid.y, z);
        let density = volume[index];
        volume[index] = bitcast<u32>(f32(running) * u.inv_fixed_scale);
        running = select(running + density, 0xffffffffu, running > 0xffffffffu - density);
    }
}
