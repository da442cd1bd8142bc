// The shadow contract, and its trivial implementation: no shadows.
//
// Every shading pass imports this file and calls `light_visibility(p)`: the
// fraction of the light that reaches world point p on a fibre (1 = fully lit), read
// past the fibre's own neighbourhood where a method needs that to keep a strand from
// shadowing itself; or `surface_visibility(p)`: the same for a point on an opaque
// surface (the body under the hair), with nothing skipped. A shadow
// method implements the same function in its own file, declaring its resources
// at @group(1), and the shading pass redirects this import to that file
// (pelage_gpu::ShaderBinding). Reads nothing, writes nothing.

fn light_visibility(p: vec3<f32>) -> f32 {
    return 1.0;
}

fn surface_visibility(p: vec3<f32>) -> f32 {
    return 1.0;
}
