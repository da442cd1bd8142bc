// Depth of the opaque mesh seen from the light, for mesh_shadow.wgsl.
//
// Reads:  MeshShadowUniforms (view_proj), mesh positions (f32 x3) and the u32 triangle list.
// Writes: the depth attachment (no colour).
// Draw:   non-indexed, 3 * triangle_count vertices, vertex pulling.

#import shadow/mesh_shadow.wgsl

@group(0) @binding(0) var<uniform> light: MeshShadowUniforms;
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> indices: array<u32>;

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> @builtin(position) vec4<f32> {
    let i = indices[vi];
    let p = vec3<f32>(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
    return light.view_proj * vec4<f32>(p, 1.0);
}
