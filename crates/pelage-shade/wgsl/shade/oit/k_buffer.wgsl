// Stage 3, transparency: the k-buffer. Each pixel keeps its k nearest hair fragments
// in k 64-bit words (fragment_key in shade/oit/slots.wgsl: nearer is larger, an empty
// word, 0, is the farthest), inserted without locks by a cascade of atomicMax: each
// step keeps the larger value and carries the smaller one on. What falls off the end is
// behind all k kept ones; it goes to the approximate tail (shade/oit/tail.wgsl) instead
// of being dropped. The resolve is shade/oit/slots.wgsl's, plus the tail.
//
// Reads:  shade/hair.wgsl's inputs, the opaque depth, OitTile.
// Writes: fs_fill: `slots` (k words per pixel of the slice) and the tail.
//         fs_resolve: the colour target (blend One, OneMinusSrcAlpha), and clears
//         `slots` and the tail of its pixel for the next slice or frame.
// Draw:   fs_fill with the hair draw; fs_resolve with vs_fullscreen (3 vertices),
//         scissored to the slice.

#import shade/hair.wgsl
#import shade/oit/bindings.wgsl
#import shade/oit/slots.wgsl
#import shade/oit/tail.wgsl

@fragment
fn fs_fill(in: VertexOut) {
    if (!in_front_of_opaque(in.clip)) {
        discard;
    }
    let c = hair_shade(in);
    let pixel = tile_pixel(in.clip, tile);
    let base = pixel * tile.k;
    var carried = fragment_key(in.view_depth, c);
    for (var i = 0u; i < tile.k; i += 1u) {
        let old = atomicMax(&slots[base + i], carried);
        if (old == u64(0u)) {
            // The word was empty and took the carried value.
            return;
        }
        carried = min(old, carried);
    }
    tail_add(pixel, key_fragment(carried));
}

@fragment
fn fs_resolve(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = tile_pixel(frag, tile);
    let s = slots_composite(pixel * tile.k);
    return composite_output(composite_under(s, tail_take(pixel)));
}
