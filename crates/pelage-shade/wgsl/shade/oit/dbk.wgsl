// Stage 3, transparency: Hunz 2016's DBK-buffer. Three hair passes and a resolve:
//   fs_nearest:  the nearest hair depth per pixel (atomicMax of its complement);
//   fs_fill:     fragments within tile.depth_shift behind it go to the linked list
//                (shade/oit/ppll.wgsl), the rest are discarded;
//   fs_fallback: the rest, drawn as opaque hair (depth tested and written) into the
//                colour target: the strands behind the blended layer;
//   fs_resolve:  sorts and blends the list over that.
//
// Reads:  shade/hair.wgsl's inputs, the opaque depth, OitTile.
// Writes: `nearest` (one word per pixel of the slice), heads, nodes, counters, the
//         colour and depth targets; fs_resolve clears its pixel's words.
// Draw:   fs_nearest, fs_fill, fs_fallback with the hair draw; fs_resolve with
//         vs_fullscreen, scissored to the slice.

#import shade/hair.wgsl
#import shade/oit/bindings.wgsl
#import shade/oit/ppll.wgsl

@group(3) @binding(5) var<storage, read_write> nearest: array<atomic<u32>>;

@fragment
fn fs_nearest(in: VertexOut) {
    if (!in_front_of_opaque(in.clip)) {
        discard;
    }
    atomicMax(&nearest[tile_pixel(in.clip, tile)], ~bitcast<u32>(max(in.view_depth, 0.0)));
}

// The far end of the blended layer at this pixel.
fn dbk_layer_end(pixel: u32) -> f32 {
    return bitcast<f32>(~atomicLoad(&nearest[pixel])) + tile.depth_shift;
}

@fragment
fn fs_fill(in: VertexOut) {
    let pixel = tile_pixel(in.clip, tile);
    if (!in_front_of_opaque(in.clip) || in.view_depth > dbk_layer_end(pixel)) {
        discard;
    }
    ppll_append(pixel, in.view_depth, hair_shade(in));
}

@fragment
fn fs_fallback(in: VertexOut) -> @location(0) vec4<f32> {
    if (in.view_depth <= dbk_layer_end(tile_pixel(in.clip, tile))) {
        discard;
    }
    return vec4<f32>(hair_shade(in).rgb, 1.0);
}

@fragment
fn fs_resolve(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = tile_pixel(frag, tile);
    if (pixel == 0u) {
        ppll_finish_slice();
    }
    atomicStore(&nearest[pixel], 0u);
    return composite_output(ppll_resolve(pixel));
}
