// Stage 3, transparency: Hunz 2016's random subsets. Strands fall into k subsets by a
// hash of their index; each pixel keeps the nearest fragment of each subset (one
// 64-bit atomicMax per fragment of fragment_key, shade/oit/common.wgsl), and
// the resolve sorts the k survivors and blends them. Fragments behind a subset's
// nearest are lost: the method's approximation.
//
// Reads:  shade/hair.wgsl's inputs, the opaque depth, OitTile.
// Writes: fs_fill: `slots` (k words per pixel of the slice). fs_resolve: the colour
//         target (blend One, OneMinusSrcAlpha); clears its pixel's words.
// Draw:   fs_fill with the hair draw; fs_resolve with vs_fullscreen, scissored to the slice.

#import shade/hair.wgsl
#import shade/oit/bindings.wgsl
#import shared/noise.wgsl

const K_MAX: u32 = 64u;

@group(3) @binding(2) var<storage, read_write> slots: array<atomic<u64>>;

@fragment
fn fs_fill(in: VertexOut) {
    if (!in_front_of_opaque(in.clip)) {
        discard;
    }
    let subset = pcg_hash(in.strand ^ 0x9e3779b9u) % tile.k;
    let key = fragment_key(in.view_depth, hair_shade(in));
    atomicMax(&slots[tile_pixel(in.clip, tile) * tile.k + subset], key);
}

@fragment
fn fs_resolve(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let base = tile_pixel(frag, tile) * tile.k;
    var keys: array<u64, K_MAX>;
    var n = 0u;
    for (var i = 0u; i < tile.k; i += 1u) {
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
    return composite_output(s);
}
