// Stage 3, hair: strands expanded into camera-facing ribbons in the vertex shader
// and shaded by the hair model contract (hair_light, shade/hair_model.wgsl or its
// redirect: Kajiya-Kay, Marschner, Sadeghi) for every light, shadowed per strand
// vertex by stage 2's visibility buffer. Shared by every
// hair pass: the opaque one (shade/ribbons.wgsl) and each transparency method
// (shade/oit/*.wgsl) import this file and add their fragment entry points.
//
// Reads:  Frame (uniform), the strand vertices (vec4: xyz position, w strand
//         parameter) and StrandRoot attributes written by stage 1, RibbonStyle (uniform),
//         per-vertex light visibility written by stage 2.
// Writes: nothing itself; vs_main feeds the importing file's fragment shader.
// Draw:   non-indexed, 6 vertices per segment: strand_count * segments * 6
//         (two triangles per segment; no vertex buffers, everything is pulled).

#import shared/math.wgsl
#import shared/strand.wgsl
#import shared/ribbon.wgsl
#import shade/frame.wgsl
#import shade/hair_model.wgsl
#import shared/noise.wgsl

struct RibbonStyle {
    segments: u32,
    // Width at the tip as a fraction of the root width.
    tip_width: f32,
    // Ribbons are at least this many pixels wide (keeps thin strands from vanishing between samples).
    min_pixels: f32,
    // Darkening at the root (0 = none, 1 = black), a stand-in for self-shadowing.
    root_occlusion: f32,
    // Opacity of a strand that covers its whole ribbon (alpha for the OIT methods).
    opacity: f32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> vertices: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> roots: array<StrandRoot>;
@group(0) @binding(3) var<uniform> style: RibbonStyle;
// Light reaching each strand vertex, per light: stage 2's shadow methods write light i's
// values at [i * frame.visibility_stride + vertex] (LightVisibility in pelage-shadow).
@group(0) @binding(4) var<storage, read> light_visibility_buffer: array<f32>;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) tangent: vec3<f32>,
    @location(2) color: vec3<f32>,
    @location(3) v: f32,
    // Light reaching the strand's centre line here, per light (1 where there is no shadow).
    @location(4) visibility: vec4<f32>,
    // Fraction of the drawn ribbon the strand really covers (< 1 where the ribbon was
    // widened to min_pixels): scales alpha so thin distant strands fade, not thicken.
    @location(5) coverage: f32,
    // Distance along the view axis (clip w), interpolated perspective-correctly: the
    // sort key of the transparency methods.
    @location(6) view_depth: f32,
    @location(7) @interpolate(flat) strand: u32,
    // Per-strand random number in [0, 1) for the shading model (azimuth, glint angle).
    @location(8) @interpolate(flat) strand_random: f32,
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
    // Shadows are looked up per strand vertex by stage 2, not per fragment:
    // transmittance varies slowly along a strand.
    out.visibility = vec4<f32>(1.0);
    if (frame.visibility_stride > 0u) {
        for (var i = 0u; i < min(frame.light_count, MAX_LIGHTS); i += 1u) {
            out.visibility[i] = light_visibility_buffer[i * frame.visibility_stride + c.here];
        }
    }
    out.coverage = select(1.0, clamp(true_half_width / half_width, 0.0, 1.0), half_width > 0.0);
    out.view_depth = out.clip.w;
    out.strand = strand;
    out.strand_random = f32(pcg_hash(root.seed ^ 0x68bc21ebu) >> 8u) * (1.0 / 16777216.0);
    return out;
}

fn perpendicular_any(t: vec3<f32>) -> vec3<f32> {
    var a = vec3<f32>(1.0, 0.0, 0.0);
    if abs(t.x) > 0.9 {
        a = vec3<f32>(0.0, 1.0, 0.0);
    }
    return safe_normalize(cross(t, a), vec3<f32>(0.0, 0.0, 1.0));
}

// The shaded colour of a hair fragment (linear RGB, not premultiplied) and its alpha
// (opacity times coverage).
fn hair_shade(in: VertexOut) -> vec4<f32> {
    let t = safe_normalize(in.tangent, vec3<f32>(0.0, 1.0, 0.0));
    let v = safe_normalize(frame.eye - in.world, vec3<f32>(0.0, 0.0, 1.0));
    // Root occlusion stands for what no light's shadow sees: the ambient light's occlusion
    // by the body and the hair near the roots, always; and the lights' self-shadowing when
    // stage 2 draws no shadow (with a shadow method on, the visibility already holds it).
    let occlusion = mix(1.0 - style.root_occlusion, 1.0, in.v);
    let direct_occlusion = select(occlusion, 1.0, frame.visibility_stride > 0u);
    var lit = vec3<f32>(0.0);
    for (var i = 0u; i < min(frame.light_count, MAX_LIGHTS); i += 1u) {
        let l = frame.lights[i];
        let irradiance = frame_irradiance(l, in.world);
        lit += hair_light(t, frame_to_light(l, in.world), v, in.color, in.strand_random, in.visibility[i]) * irradiance;
    }
    // Light scattered by other fibres that the terms above leave out (the volume method's
    // grid, which carries its own shadowing; zero for the other models and methods).
    let scattered = hair_scattered(t, v, in.world, in.color);
    return vec4<f32>(hair_ambient(in.color) * (frame.ambient * occlusion) + lit * direct_occlusion + scattered, style.opacity * in.coverage);
}
