// Stage 3, the opaque method: hair ribbons (shade/hair.wgsl) written depth tested,
// alpha ignored. The baseline of the transparency methods, and the one that uses MSAA.
//
// Reads:  what shade/hair.wgsl reads.
// Writes: colour and depth of the render target.
// Draw:   as shade/hair.wgsl: strand_count * segments * 6 vertices.

#import shade/hair.wgsl

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    return vec4<f32>(hair_shade(in).rgb, 1.0);
}
