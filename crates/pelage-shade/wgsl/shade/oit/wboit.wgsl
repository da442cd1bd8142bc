// Stage 3, transparency: weighted blended OIT (McGuire and Bavoil 2013). One hair pass
// adds premultiplied colour times a depth weight into an accumulation target and
// multiplies (1 - alpha) into a revealage target (fixed-function blending, no
// atomics); the resolve divides out the weights and blends the average over the
// opaque colour with the total revealage.
//
// Reads:  shade/hair.wgsl's inputs, OitTile (the weight function).
// Writes: fs_accum: location 0 accumulation (Rgba16Float, blend One, One), location 1
//         revealage (R16Float, blend Zero, OneMinusSrc); depth tested, not written.
//         fs_resolve: the colour target (blend One, OneMinusSrcAlpha).
// Draw:   fs_accum with the hair draw; fs_resolve with vs_fullscreen.

#import shade/hair.wgsl
#import shade/oit/common.wgsl

@group(3) @binding(0) var<uniform> tile: OitTile;
@group(3) @binding(1) var accumulation: texture_2d<f32>;
@group(3) @binding(2) var revealage: texture_2d<f32>;

// The paper's eq. 7-10 (z: view depth, d: window depth), and a constant for comparison.
fn wboit_weight(a: f32, z: f32, d: f32) -> f32 {
    switch tile.weight {
        case 0u: {
            return a * clamp(10.0 / (1e-5 + pow(z / 5.0, 2.0) + pow(z / 200.0, 6.0)), 1e-2, 3e3);
        }
        case 1u: {
            return a * clamp(10.0 / (1e-5 + pow(z / 10.0, 3.0) + pow(z / 200.0, 6.0)), 1e-2, 3e3);
        }
        case 2u: {
            return a * clamp(0.03 / (1e-5 + pow(z / 200.0, 4.0)), 1e-2, 3e3);
        }
        case 3u: {
            // d runs from 0 at the near plane to 1 at the far one, whichever way depth is stored.
            let from_near = select(d, 1.0 - d, tile.reverse_z != 0u);
            return a * max(1e-2, 3e3 * pow(1.0 - from_near, 3.0));
        }
        default: {
            return a;
        }
    }
}

struct Accumulated {
    @location(0) accumulation: vec4<f32>,
    @location(1) revealage: vec4<f32>,
}

@fragment
fn fs_accum(in: VertexOut) -> Accumulated {
    let c = hair_shade(in);
    let w = wboit_weight(c.a, max(in.view_depth, 0.0), in.clip.z);
    var out: Accumulated;
    // As the paper's listing: premultiplied colour and alpha, times w (which holds alpha too).
    out.accumulation = vec4<f32>(c.rgb * c.a, c.a) * w;
    out.revealage = vec4<f32>(c.a);
    return out;
}

@fragment
fn fs_resolve(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let p = vec2<i32>(frag.xy);
    let accum = textureLoad(accumulation, p, 0);
    let reveal = textureLoad(revealage, p, 0).r;
    let average = accum.rgb / clamp(accum.a, 1e-5, 5e4);
    return vec4<f32>(average * (1.0 - reveal), 1.0 - reveal);
}
