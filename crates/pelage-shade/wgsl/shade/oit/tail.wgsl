// The approximate tail of the bounded methods: fragments a pixel cannot keep are not
// dropped but summed order-independently (alpha-weighted colour, alpha, and optical
// depth -ln(1 - alpha)) in fixed point, and composited behind the kept ones as one
// layer of their mean colour and total opacity 1 - exp(-sum of optical depths).
//
// Reads/writes: `tail` at @group(3) @binding(8), 5 words per pixel of the slice.
// Sums saturate nowhere: at TAIL_SCALE = 4096 a pixel can take 2^20 fragments of
// alpha 1 (optical depth is clamped at alpha 0.999) before a word wraps.

const TAIL_SCALE: f32 = 4096.0;
const TAIL_WORDS: u32 = 5u;
const TAIL_MAX_ALPHA: f32 = 0.999;

@group(3) @binding(8) var<storage, read_write> tail: array<atomic<u32>>;

fn tail_add(pixel: u32, c: vec4<f32>) {
    let a = clamp(c.a, 0.0, TAIL_MAX_ALPHA);
    let base = pixel * TAIL_WORDS;
    let weighted = clamp(c.rgb, vec3<f32>(0.0), vec3<f32>(1.0)) * a;
    atomicAdd(&tail[base], u32(weighted.r * TAIL_SCALE + 0.5));
    atomicAdd(&tail[base + 1u], u32(weighted.g * TAIL_SCALE + 0.5));
    atomicAdd(&tail[base + 2u], u32(weighted.b * TAIL_SCALE + 0.5));
    atomicAdd(&tail[base + 3u], u32(a * TAIL_SCALE + 0.5));
    atomicAdd(&tail[base + 4u], u32(-log(1.0 - a) * TAIL_SCALE + 0.5));
}

// The tail of `pixel` as one fragment (mean colour, total alpha), and clears it for
// the next frame.
fn tail_take(pixel: u32) -> vec4<f32> {
    let base = pixel * TAIL_WORDS;
    let r = f32(atomicExchange(&tail[base], 0u));
    let g = f32(atomicExchange(&tail[base + 1u], 0u));
    let b = f32(atomicExchange(&tail[base + 2u], 0u));
    let a = f32(atomicExchange(&tail[base + 3u], 0u));
    let depth = f32(atomicExchange(&tail[base + 4u], 0u)) / TAIL_SCALE;
    if (a <= 0.0) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(vec3<f32>(r, g, b) / a, 1.0 - exp(-depth));
}
