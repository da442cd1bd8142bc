// Stage 3, transparency: the A-buffer. Every hair fragment in front of the opaque
// mesh is appended to its pixel's linked list (shade/oit/ppll.wgsl); the resolve sorts
// the tile.k nearest per pixel and blends the rest approximately behind them.
//
// Reads:  shade/hair.wgsl's inputs, the opaque depth, OitTile.
// Writes: fs_fill: heads, nodes, counters. fs_resolve: the colour target (blend One,
//         OneMinusSrcAlpha); empties its pixel's list; pixel (0, y0) also closes the
//         slice's counters.
// Draw:   fs_fill with the hair draw; fs_resolve with vs_fullscreen, scissored to the slice.

#import shade/hair.wgsl
#import shade/oit/bindings.wgsl
#import shade/oit/ppll.wgsl

@fragment
fn fs_fill(in: VertexOut) {
    if (!in_front_of_opaque(in.clip)) {
        discard;
    }
    ppll_append(tile_pixel(in.clip, tile), in.view_depth, hair_shade(in));
}

@fragment
fn fs_resolve(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = tile_pixel(frag, tile);
    if (pixel == 0u) {
        ppll_finish_slice();
    }
    return composite_output(ppll_resolve(pixel));
}
