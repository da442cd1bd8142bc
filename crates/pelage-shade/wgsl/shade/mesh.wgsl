// Stage 3, opaque mesh: the surface the hair grows from, Lambert shaded by every light,
// each light with a shadow shadowed through the shadow contract (surface_visibility,
// shadow/none.wgsl or its redirect, bound to that light's shadow), and by the sky
// through the body's sky contract (body_sky, shade/body_sky.wgsl or its redirect: the
// volume method's grid). Drawn once per light with a shadow: the first draw (style.base)
// the sky, light style.shadowed and the lights from style.unshadowed_from on (those
// without a shadow); each further draw adds its own light, blended one + one.
//
// Reads:  Frame (uniform), mesh positions and normals (f32 x3 storage), the u32
//         triangle list (storage), MeshStyle (uniform); group 1 the shadow method's,
//         group 2 the body sky's (the hair model's, with the volume method).
// Writes: colour and depth of the render target.
// Draw:   non-indexed, 3 * triangle_count vertices; vertex_index pulls the index list.

#import shade/frame.wgsl
#import shade/body_sky.wgsl
#import shadow/none.wgsl

struct MeshStyle {
    color: vec3<f32>,
    base: u32,
    shadowed: u32,
    unshadowed_from: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> normals: array<f32>;
@group(0) @binding(3) var<storage, read> indices: array<u32>;
@group(0) @binding(4) var<uniform> style: MeshStyle;

struct VertexOut {
    // Invariant: the further lights' draws (another pipeline, the same computation) test
    // their depth Equal against the first draw's.
    @builtin(position) @invariant clip: vec4<f32>,
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
    let base = style.base == 1u;
    var lit = vec3<f32>(0.0);
    if (base) {
        lit = body_sky(in.world, n, frame.ambient);
    }
    for (var i = 0u; i < min(frame.light_count, MAX_LIGHTS); i += 1u) {
        let shadowed = i == style.shadowed;
        if (!shadowed && !(base && i >= style.unshadowed_from)) {
            continue;
        }
        let l = frame.lights[i];
        var irradiance = frame_irradiance(l, in.world) * max(dot(n, frame_to_light(l, in.world)), 0.0);
        // The shadow contract is bound to this draw's light.
        if (shadowed) {
            irradiance *= surface_visibility(in.world);
        }
        lit += irradiance;
    }
    // Alpha 1 from the first draw; a further draw adds colour only (its write mask).
    return vec4<f32>(style.color * lit, 1.0);
}
