// The per-pixel 64-bit slots of the k-buffer and of random subsets: k words per pixel
// of the slice, each a fragment_key (below) or 0 when empty. The 64-bit words live
// here, not in shade/oit/common.wgsl, so the methods without them need no SHADER_INT64.
//
// Reads/writes: `slots` at @group(3) @binding(2). slots_composite empties the words it
// reads (the resolve runs after the fill, alone on its pixel, so a load and a store
// suffice: no 64-bit atomic that returns a value is needed).

#import shade/oit/bindings.wgsl

// A fragment as one 64-bit word that sorts by depth: the top 24 bits of the f32 view
// depth (relative precision 2^-15), then colour as square roots in 10 bits per channel
// and alpha in 10. The bitwise complement is stored, so nearer is larger and 0 (an
// empty word) is the farthest: atomicMax keeps the nearest.
fn fragment_key(depth: f32, c: vec4<f32>) -> u64 {
    let d = bitcast<u32>(max(depth, 0.0)) >> 8u;
    let rgb = vec3<u32>(round(sqrt(clamp(c.rgb, vec3<f32>(0.0), vec3<f32>(1.0))) * 1023.0));
    let a = u32(round(clamp(c.a, 0.0, 1.0) * 1023.0));
    let low = (rgb.g << 20u) | (rgb.b << 10u) | a;
    return ~((u64(d) << 40u) | (u64(rgb.r) << 30u) | u64(low));
}

// The colour and alpha of a word made by fragment_key.
fn key_fragment(key: u64) -> vec4<f32> {
    let k = ~key;
    let low = u32(k & u64(0xffffffffu));
    let r = f32(u32((k >> 30u) & u64(1023u))) / 1023.0;
    let g = f32((low >> 20u) & 1023u) / 1023.0;
    let b = f32((low >> 10u) & 1023u) / 1023.0;
    let a = f32(low & 1023u) / 1023.0;
    return vec4<f32>(vec3<f32>(r, g, b) * vec3<f32>(r, g, b), a);
}

const K_MAX: u32 = 64u;

@group(3) @binding(2) var<storage, read_write> slots: array<atomic<u64>>;

// The kept fragments of the pixel whose words start at `base`, sorted nearest first
// (insertion sort; the k-buffer's cascade leaves them nearly sorted already) and
// composited front to back. Empties the words for the next slice or frame.
fn slots_composite(base: u32) -> Composite {
    var keys: array<u64, K_MAX>;
    var n = 0u;
    for (var i = 0u; i < min(tile.k, K_MAX); i += 1u) {
        let key = atomicLoad(&slots[base + i]);
        atomicStore(&slots[base + i], u64(0u));
        if (key == u64(0u)) {
            continue;
        }
        var j = n;
        while (j > 0u && keys[j - 1u] < key) {
            keys[j] = keys[j - 1u];
            j -= 1u;
        }
        keys[j] = key;
        n += 1u;
    }
    var s = composite_start();
    for (var i = 0u; i < n; i += 1u) {
        s = composite_under(s, key_fragment(keys[i]));
    }
    return s;
}
