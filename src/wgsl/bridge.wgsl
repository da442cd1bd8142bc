// The bridge between a caller's targets and a transparency method that cannot draw them
// (src/bridge.rs): multisampled targets (every transparency method draws single-sampled)
// or reversed depth (the k-buffer, A-buffer, DBK and random subsets compare one way).
// The caller's depth is resolved to its nearest sample and turned into the method's
// direction (with a copy, to see later which pixels the method changed); after the
// method, its single-sampled picture is written into every sample of the caller's
// colour and its depth, turned back, into the caller's depth where the method changed it.

// The caller's depth direction: reversed (near 1, far 0) or standard (near 0, far 1).
override REVERSE_Z: bool = false;
// The method's direction is the other one: its depth is 1 - the caller's.
override FLIP: bool = false;

// A triangle covering the screen (vertices 0, 1, 2).
@vertex
fn vs_full(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

// A depth turned from one direction into the other when FLIP (an involution).
fn turned(depth: f32) -> f32 {
    return select(depth, 1.0 - depth, FLIP);
}

// The caller's multisampled depth (the resolve pass; one sample when only flipping).
@group(0) @binding(0) var caller_depth_ms: texture_depth_multisampled_2d;
@group(0) @binding(4) var caller_depth: texture_depth_2d;

struct Resolved {
    @builtin(frag_depth) depth: f32,
    // The same depth, kept to compare with what the method leaves.
    @location(0) copy: f32,
}

// The nearest of the pixel's samples, in the method's direction: hair behind any sample
// of an opaque surface is hidden in that pixel.
@fragment
fn fs_resolve_depth_ms(@builtin(position) position: vec4<f32>) -> Resolved {
    let pixel = vec2<i32>(position.xy);
    var nearest = textureLoad(caller_depth_ms, pixel, 0);
    for (var s = 1; s < i32(textureNumSamples(caller_depth_ms)); s++) {
        let d = textureLoad(caller_depth_ms, pixel, s);
        nearest = select(min(nearest, d), max(nearest, d), REVERSE_Z);
    }
    let depth = turned(nearest);
    return Resolved(depth, depth);
}

// The caller's single-sampled depth in the method's direction.
@fragment
fn fs_resolve_depth(@builtin(position) position: vec4<f32>) -> Resolved {
    let depth = turned(textureLoad(caller_depth, vec2<i32>(position.xy), 0));
    return Resolved(depth, depth);
}

// The method's single-sampled targets and the resolved depth (the write-back pass).
@group(0) @binding(1) var single_color: texture_2d<f32>;
@group(0) @binding(2) var single_depth: texture_depth_2d;
@group(0) @binding(3) var resolved_depth: texture_2d<f32>;

// The method's colour, into every sample of the pixel.
@fragment
fn fs_write_color(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    return textureLoad(single_color, vec2<i32>(position.xy), 0);
}

// The method's depth where it differs from the resolved depth (its mesh or opaque hair),
// in the caller's direction, into every sample; elsewhere the caller's samples stay.
@fragment
fn fs_write_depth(@builtin(position) position: vec4<f32>) -> @builtin(frag_depth) f32 {
    let pixel = vec2<i32>(position.xy);
    let depth = textureLoad(single_depth, pixel, 0);
    if depth == textureLoad(resolved_depth, pixel, 0).x {
        discard;
    }
    return turned(depth);
}
