// Shadow of the opaque mesh: a depth map from the light, sampled with PCF.
// Shared by every shadow method's lookup; declares its resources at @group(1),
// bindings 3 to 5 (bindings 0 to 2 belong to the method).
// The Rust twin of MeshShadowUniforms is in pelage-shadow/src/mesh_shadow.rs.

struct MeshShadowUniforms {
    // World to the light's clip space (orthographic, z in [0, 1]).
    view_proj: mat4x4<f32>,
    // One texel in uv units.
    texel: f32,
    // PCF kernel radius in texels: 0 = one tap, 1 = 3x3, 2 = 5x5.
    pcf_radius: i32,
    // Depth bias in clip-space z.
    bias: f32,
    // 0 = no mesh shadows.
    enabled: u32,
}

@group(1) @binding(3) var<uniform> mesh_shadow: MeshShadowUniforms;
@group(1) @binding(4) var mesh_shadow_map: texture_depth_2d;
@group(1) @binding(5) var mesh_shadow_sampler: sampler_comparison;

// Fraction of the light the mesh lets through to p (1 = lit), percentage-closer filtered.
fn mesh_visibility(p: vec3<f32>) -> f32 {
    let clip = mesh_shadow.view_proj * vec4<f32>(p, 1.0);
    let uv = clip.xy * vec2<f32>(0.5, -0.5) + vec2<f32>(0.5);
    let depth = clip.z - mesh_shadow.bias;
    // Sample unconditionally (uniform control flow), then discard what does not apply.
    var lit = 0.0;
    var taps = 0.0;
    for (var dy = -mesh_shadow.pcf_radius; dy <= mesh_shadow.pcf_radius; dy++) {
        for (var dx = -mesh_shadow.pcf_radius; dx <= mesh_shadow.pcf_radius; dx++) {
            let offset = vec2<f32>(f32(dx), f32(dy)) * mesh_shadow.texel;
            lit += textureSampleCompareLevel(mesh_shadow_map, mesh_shadow_sampler, uv + offset, depth);
            taps += 1.0;
        }
    }
    let inside = all(uv >= vec2<f32>(0.0)) && all(uv <= vec2<f32>(1.0)) && depth <= 1.0;
    if mesh_shadow.enabled == 0u || !inside {
        return 1.0;
    }
    return lit / taps;
}
