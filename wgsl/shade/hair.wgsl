// Stage 3, hair: strands expanded into camera-facing ribbons in the vertex shader
// and shaded (Kajiya-Kay), shadowed through the shadow contract (light_visibility,
// shadow/none.wgsl or its redirect, evaluated per strand vertex). Shared by every
// hair pass: the opaque one (shade/ribbons.wgsl) and each transparency method
// (shade/oit/*.wgsl) import this file and add their fragment entry points.
//
// Reads:  Frame (uniform), the strand vertices (vec4: xyz position, w strand
//         parameter) and StrandRoot attributes written by stage 1, RibbonStyle (uniform).
// Writes: nothing itself; vs_main feeds the importing file's fragment shader.
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
    // Opacity of a strand that covers its whole ribbon (alpha for the OIT methods).
    opacity: f32,
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
    // Fraction of the drawn ribbon the strand really covers (< 1 where the ribbon was
    // widened to min_pixels): scales alpha so thin distant strands fade, not thicken.
    @location(5) coverage: f32,
    // Distance along the view axis (clip w), interpolated perspective-correctly: the
    // sort key of the transparency methods.
    @location(6) view_depth: f32,
    @location(7) @interpolate(flat) strand: u32,
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
    let true_half_width = 0.5 * root.width * mix(1.0, style.tip_width, here.w);
    let half_width = max(true_half_width, 0.5 * style.min_pixels * frame.pixel_scale * distance);
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
    out.coverage = select(1.0, clamp(true_half_width / half_width, 0.0, 1.0), half_width > 0.0);
    out.view_depth = out.clip.w;
    out.strand = strand;
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

// The shaded colour of a hair fragment (linear RGB, not premultiplied) and its alpha
// (opacity times coverage).
fn hair_shade(in: VertexOut) -> vec4<f32> {
    let t = safe_normalize(in.tangent, vec3<f32>(0.0, 1.0, 0.0));
    let v = safe_normalize(frame.eye - in.world, vec3<f32>(0.0, 0.0, 1.0));
    let kk = kajiya_kay(t, frame.to_light, v);
    let occlusion = mix(1.0 - style.root_occlusion, 1.0, in.v);
    let light = frame.light_color * in.visibility;
    let lit = in.color * (frame.ambient + style.diffuse * kk.x * light)
        + style.specular_color * (style.specular * kk.y) * light;
    return vec4<f32>(lit * occlusion, style.opacity * in.coverage);
}
