// Stage 3, transparency: Hunz 2016's random subsets. Strands fall into k subsets by a
// hash of their index; each pixel keeps the nearest fragment of each subset (one
// 64-bit atomicMax per fragment of fragment_key, shade/oit/slots.wgsl), and
// the resolve sorts the k survivors and blends them. Fragments behind a subset's
// nearest are lost: the method's approximation.
//
// Reads:  shade/hair.wgsl's inputs, the opaque depth, OitTile.
// Writes: fs_fill: `slots` (k words per pixel of the slice). fs_resolve: the colour
//         target (blend One, OneMinusSrcAlpha); clears its pixel's words.
// Draw:   fs_fill with the hair draw; fs_resolve with vs_fullscreen, scissored to the slice.

#import shade/hair.wgsl
#import shade/oit/bindings.wgsl
#import shade/oit/slots.wgsl
#import shared/noise.wgsl

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
    return composite_output(slots_composite(tile_pixel(frag, tile) * tile.k));
}
