// Shared by the transparency methods (shade/oit/*.wgsl): the slice of the screen a
// pass covers, front-to-back compositing, and the
// full-screen triangle of the resolve passes. Pure functions and structs, no bindings.
//
// Per-pixel buffers hold `rows` rows of `width` pixels: the screen is drawn in
// horizontal slices when a buffer for the whole of it would pass the device's storage
// binding limit. Each slice is a scissored draw with its own OitTile.

struct OitTile {
    // First row of the slice, and its number of rows.
    y0: u32,
    rows: u32,
    // Width of the target in pixels.
    width: u32,
    // Fragments kept per pixel (k-buffer, subsets) or sorted at resolve (lists).
    k: u32,
    // Capacity of the node pool (linked lists), in nodes.
    capacity: u32,
    // Which WBOIT weight (0..=4: eq. 7, 8, 9, 10, constant).
    weight: u32,
    // DBK: thickness of the blended layer behind the nearest hair (view units).
    depth_shift: f32,
    // 1 when depth is reversed (nearer is larger: the camera's reverse-Z), else 0.
    reverse_z: u32,
}

// Index of the pixel under `frag` (its @builtin(position)) in the slice's buffers.
fn tile_pixel(frag: vec4<f32>, tile: OitTile) -> u32 {
    let x = u32(frag.x);
    let y = u32(frag.y) - tile.y0;
    return y * tile.width + x;
}

// Front-to-back compositing state: premultiplied colour so far, transmittance left.
struct Composite {
    color: vec3<f32>,
    transmittance: f32,
}

fn composite_start() -> Composite {
    return Composite(vec3<f32>(0.0), 1.0);
}

// Adds the fragment `c` (straight colour, alpha) behind what `s` holds.
fn composite_under(s: Composite, c: vec4<f32>) -> Composite {
    return Composite(s.color + s.transmittance * c.a * c.rgb, s.transmittance * (1.0 - c.a));
}

// What a resolve pass writes: blended with (One, OneMinusSrcAlpha) over the opaque
// colour it gives color + transmittance * opaque.
fn composite_output(s: Composite) -> vec4<f32> {
    return vec4<f32>(s.color, 1.0 - s.transmittance);
}

// A full-screen triangle: vertex 0, 1, 2 cover the viewport.
@vertex
fn vs_fullscreen(@builtin(vertex_index) vi: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}
