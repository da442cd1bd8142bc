// The shadow-map methods, passes 2 and 3: the hair rasterised from the light.
//
// Reads:  LightGridUniforms and the LightGrid fitted this frame (light_fit.wgsl),
//         the strand vertices and StrandRoot widths, MapUniforms; fs_opacity also
//         reads the front-most depth written by the depth pass.
// Writes: vs_main + depth only: the front-most hair depth from the light;
//         vs_main + fs_opacity: deep opacity layers, additively blended: a fragment
//         in layer k adds its opacity to layers k..last (channels of two RGBA targets).
// Draw:   non-indexed, 6 vertices per segment (strand_count * segments * 6).
//
// Strands become ribbons across the light at least `min_texels` wide; a fragment
// carries opacity * width / drawn width, so a ribbon widened to reach the texel grid
// deposits the same total opacity as the strand.

#import shared/math.wgsl
#import shared/strand.wgsl
#import shared/ribbon.wgsl
#import shadow/map_common.wgsl

@group(0) @binding(0) var<uniform> u: LightGridUniforms;
@group(0) @binding(1) var<storage, read> grid: LightGrid;
@group(0) @binding(2) var<storage, read> vertices: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> roots: array<StrandRoot>;
@group(0) @binding(4) var<uniform> map: MapUniforms;
// A depth texture bound as unfilterable float (WebGPU allows it): textureLoad from a
// texture_depth_2d has no GLSL translation, so that form would not run on GL.
@group(0) @binding(5) var front_depth: texture_2d<f32>;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    // Opacity this fragment deposits.
    @location(0) alpha: f32,
}

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> VertexOut {
    let c = ribbon_corner(vi, u.segments);
    let strand = c.strand;
    let here = vertices[c.here];
    let prev = vertices[c.prev].xyz;
    let next = vertices[c.next].xyz;

    let ls = to_light_space(u, here.xyz);
    // Tangent across the light; a strand pointing straight at the light gets any side.
    let t = to_light_space(u, next) - to_light_space(u, prev);
    var side = vec2<f32>(-t.y, t.x);
    let len = length(side);
    side = select(vec2<f32>(1.0, 0.0), side / len, len > 1e-20);

    let width = roots[strand].width * mix(1.0, u.tip_width, here.w);
    let texel = max(grid.cell.x, grid.cell.y);
    let drawn = max(width, map.min_texels * texel);
    let p = ls + vec3<f32>(side * (0.5 * drawn * c.side), 0.0);

    let m = map_coords(u, grid, p);
    var out: VertexOut;
    out.clip = vec4<f32>(m.x * 2.0 - 1.0, 1.0 - m.y * 2.0, clamp(m.z, 0.0, 1.0), 1.0);
    out.alpha = u.opacity * width / drawn;
    return out;
}

struct Layers {
    @location(0) first: vec4<f32>,
    @location(1) second: vec4<f32>,
}

@fragment
fn fs_opacity(in: VertexOut) -> Layers {
    let z0 = textureLoad(front_depth, vec2<i32>(in.clip.xy), 0).r;
    let extent = map_depth_extent(u, grid);
    let behind = max(in.clip.z - z0, 0.0) * extent;
    var layer = 0u;
    while layer + 1u < map.layers && behind >= layer_end(map, layer, extent) {
        layer += 1u;
    }
    var out: Layers;
    for (var j = 0u; j < 4u; j++) {
        out.first[j] = select(0.0, in.alpha, j >= layer && j < map.layers);
        out.second[j] = select(0.0, in.alpha, j + 4u >= layer && j + 4u < map.layers);
    }
    return out;
}
