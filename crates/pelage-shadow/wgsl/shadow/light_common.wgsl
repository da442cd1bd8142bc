// Types shared by every shadow method that sees the hair from the light (the fit,
// the voxel passes, the shadow-map passes and their lookups). Declares structs and
// helpers only. The Rust twins are LightGridUniforms and LightGrid in
// pelage-shadow/src/fit.rs.

struct LightGridUniforms {
    // Light space: x and y across the light, z along it, away from the light.
    axis_x: vec3<f32>,
    resolution_x: u32,
    axis_y: vec3<f32>,
    resolution_y: u32,
    axis_z: vec3<f32>,
    // Cells along the light (voxel layers; 1 for shadow maps). The voxel volume holds
    // resolution_z + 1 layers (the last is the column total).
    resolution_z: u32,
    vertex_count: u32,
    segments: u32,
    strand_count: u32,
    // 0 = nearest, 1 = trilinear.
    splat: u32,
    // Added around the fitted bounds, world units.
    padding: f32,
    // Hair opacity, the extinction of one strand crossing (see voxel_splat.wgsl).
    opacity: f32,
    // Tip width as a fraction of the root width.
    tip_width: f32,
    // The lookup reads optical depth this many voxels toward the light, so a strand
    // does not shadow itself.
    bias_voxels: f32,
    // Fixed-point units per unit of optical depth (a power of two), and its inverse.
    fixed_scale: f32,
    inv_fixed_scale: f32,
    fit_invocations: u32,
    // Smallest cell edge, world units (keeps a flat groom from making zero-thick cells).
    min_cell: f32,
}

// The grid fitted to the hair this frame (written by the fit pass).
struct LightGrid {
    origin: vec3<f32>,
    _pad0: f32,
    cell: vec3<f32>,
    _pad1: f32,
    inv_cell: vec3<f32>,
    _pad2: f32,
}

fn to_light_space(u: LightGridUniforms, p: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(p, u.axis_x), dot(p, u.axis_y), dot(p, u.axis_z));
}

// Index of voxel (x, y, z); z-major layers so neighbouring columns are neighbours in memory.
fn voxel_index(u: LightGridUniforms, x: u32, y: u32, z: u32) -> u32 {
    return (z * u.resolution_y + y) * u.resolution_x + x;
}
