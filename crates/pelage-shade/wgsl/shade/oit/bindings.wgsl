// The bindings every transparency method shares, at @group(3): the slice (OitTile)
// and the opaque scene's depth. Method files add theirs from @binding(2) on; the
// approximate tail (shade/oit/tail.wgsl) is @binding(8).

#import shade/oit/common.wgsl

@group(3) @binding(0) var<uniform> tile: OitTile;
// The depth texture bound as unfilterable float (WebGPU allows it): textureLoad from a
// texture_depth_2d has no GLSL translation, so that form would not run on GL.
@group(3) @binding(1) var opaque_depth: texture_2d<f32>;

// True when the fragment at `frag` (its @builtin(position)) is nearer than the opaque
// mesh. Tested in the shader, not only by the depth attachment: a fragment shader
// with storage writes may run its side effects before a late depth test rejects it.
fn in_front_of_opaque(frag: vec4<f32>) -> bool {
    let d = textureLoad(opaque_depth, vec2<i32>(frag.xy), 0).r;
    // Standard depth only: the methods importing this refuse reverse-Z targets
    // (reading OitTile::reverse_z here crashes lavapipe in the DBK and subsets passes).
    return frag.z < d;
}
