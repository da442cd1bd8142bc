// Copies a texture pixel for pixel into a viewport of its size: one triangle covering
// the viewport (examples/viewer.rs draws pelage's image and its composed window with it).
//
// Reads:  `src`, any float texture; texel = the fragment's position in the viewport.
// Writes: the colour target, rgb of the texel with alpha 1. Source and target both
//         sRGB (or viewed as sRGB): the bytes come out as they went in.
// Draw:   3 vertices, no vertex buffers.
@group(0) @binding(0) var src: texture_2d<f32>;
struct Vertex { @builtin(position) clip: vec4<f32>, @location(0) uv: vec2<f32> }
@vertex
fn vs(@builtin(vertex_index) i: u32) -> Vertex {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)); // (0,0), (2,0), (0,2); y down
    return Vertex(vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.0, 1.0), uv);
}
@fragment
fn fs(v: Vertex) -> @location(0) vec4<f32> {
    let texel = vec2<i32>(v.uv * vec2<f32>(textureDimensions(src)));
    return vec4<f32>(textureLoad(src, texel, 0).rgb, 1.0);
}
