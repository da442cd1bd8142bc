// Stage 3, hair: strands expanded into camera-facing ribbons in the vertex shader,
// Kajiya-Kay shaded, shadowed through the shadow contract (light_visibility,
// shadow/none.wgsl or its redirect, evaluated per strand vertex), depth tested.
//
// Reads:  Frame (uniform), the strand vertices (vec4: xyz position, w strand
//         parameter) and StrandRoot attributes written by stage 1, RibbonStyle (uniform).
// Writes: colour and depth of the render target.
// Draw:   non-indexed, 6 vertices per segment: strand_count * segments * 6
//         (two triangles per segment; no vertex buffers, everything is pulled).

#import shared/math.wgsl
#import shared/strand.wgsl
#import shared/ribbon.wgsl
#import shade/frame.wgsl
#import shadow/none.wgsl

struct RibbonStyle {
    segments: u32,
    // Width at the tip as a fraction of the root width.
    tip_width: f32,
    // Ribbons are at least this many pixels wide (keeps thin strands from vanishing between samples).
    min_pixels: f32,
    // Darkening at the root (0 = none, 1 = black), a stand-in for self-shadowing.
    root_occlusion: f32,
    diffuse: f32,
    specular: f32,
    // Kajiya-Kay specular exponent.
    shininess: f32,
    _pad: f32,
    specular_color: vec3<f32>,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> vertices: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> roots: array<StrandRoot>;
@group(0) @binding(3) var<uniform> style: RibbonStyle;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) tangent: vec3<f32>,
    @location(2) color: vec3<f32>,
    @location(3) v: f32,
    // Light reaching the strand's centre line here, from the shadow contract.
    @location(4) visibility: f32,
}


@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> VertexOut {
    let c = ribbon_corner(vi, style.segments);
    let strand = c.strand;
    let here = vertices[c.here];
    // Vertex tangent from the neighbours, so consecutive segments share their edge.
    let prev = vertices[c.prev].xyz;
    let next = vertices[c.next].xyz;
    let tangent = safe_normalize(next - prev, vec3<f32>(0.0, 1.0, 0.0));

    let root = roots[strand];
    let to_eye = frame.eye - here.xyz;
    let distance = length(to_eye);
    var half_width = 0.5 * root.width * mix(1.0, style.tip_width, here.w);
    half_width = max(half_width, 0.5 * style.min_pixels * frame.pixel_scale * distance);
    let side = safe_normalize(cross(tangent, to_eye), perpendicular_any(tangent));
    let world = here.xyz + side * (half_width * c.side);

    var out: VertexOut;
    out.clip = frame.view_proj * vec4<f32>(world, 1.0);
    out.world = world;
    out.tangent = tangent;
    out.color = root.color;
    out.v = here.w;
    // Shadows are looked up per strand vertex, not per fragment: transmittance varies
    // slowly along a strand, and this runs 6 times per segment instead of once per
    // covered sample.
    out.visibility = light_visibility(here.xyz);
    return out;
}

fn perpendicular_any(t: vec3<f32>) -> vec3<f32> {
    var a = vec3<f32>(1.0, 0.0, 0.0);
    if abs(t.x) > 0.9 {
        a = vec3<f32>(0.0, 1.0, 0.0);
    }
    return safe_normalize(cross(t, a), vec3<f32>(0.0, 0.0, 1.0));
}

// Kajiya-Kay (1989) with l and v both pointing away from the surface: the diffuse term
// is sin(t, l); the specular term is the cosine between v and the cone of mirror
// directions around the tangent, cos = -(t.l)(t.v) + sin(t, l) sin(t, v). Defined for
// every direction (no half vector, so no singularity when the camera faces the light).
fn kajiya_kay(t: vec3<f32>, l: vec3<f32>, v: vec3<f32>) -> vec2<f32> {
    let tl = clamp(dot(t, l), -1.0, 1.0);
    let tv = clamp(dot(t, v), -1.0, 1.0);
    let sin_l = sqrt(max(1.0 - tl * tl, 0.0));
    let sin_v = sqrt(max(1.0 - tv * tv, 0.0));
    let cone = max(-tl * tv + sin_l * sin_v, 0.0);
    return vec2<f32>(sin_l, pow(cone, style.shininess));
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    let t = safe_normalize(in.tangent, vec3<f32>(0.0, 1.0, 0.0));
    let v = safe_normalize(frame.eye - in.world, vec3<f32>(0.0, 0.0, 1.0));
    let kk = kajiya_kay(t, frame.to_light, v);
    let occlusion = mix(1.0 - style.root_occlusion, 1.0, in.v);
    let light = frame.light_color * in.visibility;
    let lit = in.color * (frame.ambient + style.diffuse * kk.x * light)
        + style.specular_color * (style.specular * kk.y) * light;
    return vec4<f32>(lit * occlusion, 1.0);
}
