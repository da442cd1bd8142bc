// The per-pixel 64-bit slots of the k-buffer and of random subsets: k words per pixel
// of the slice, each a fragment_key (shade/oit/common.wgsl) or 0 when empty.
//
// Reads/writes: `slots` at @group(3) @binding(2). slots_composite empties the words it
// reads (the resolve runs after the fill, alone on its pixel, so a load and a store
// suffice: no 64-bit atomic that returns a value is needed).

#import shade/oit/bindings.wgsl

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
