// Stage 3, opaque mesh: the surface the hair grows from, Lambert shaded, shadowed
// through the shadow contract (light_visibility, shadow/none.wgsl or its redirect).
//
// Reads:  Frame (uniform), mesh positions and normals (f32 x3 storage), the u32
//         triangle list (storage), MeshStyle (uniform).
// Writes: colour and depth of the render target.
// Draw:   non-indexed, 3 * triangle_count vertices; vertex_index pulls the index list.

#import shade/frame.wgsl
#import shadow/none.wgsl

struct MeshStyle {
    color: vec3<f32>,
    _pad: f32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> normals: array<f32>;
@group(0) @binding(3) var<storage, read> indices: array<u32>;
@group(0) @binding(4) var<uniform> style: MeshStyle;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) world: vec3<f32>,
}

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> VertexOut {
    let i = indices[vi];
    let p = vec3<f32>(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
    let n = vec3<f32>(normals[3u * i], normals[3u * i + 1u], normals[3u * i + 2u]);
    var out: VertexOut;
    out.clip = frame.view_proj * vec4<f32>(p, 1.0);
    out.normal = n;
    out.world = p;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    let n = normalize(in.normal);
    let lambert = max(dot(n, frame.to_light), 0.0) * light_visibility(in.world);
    let c = style.color * (frame.ambient + lambert * frame.light_color);
    return vec4<f32>(c, 1.0);
}
