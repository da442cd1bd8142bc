// Per-frame camera and lights, shared by every raster pass of stage 3.
// Declares structs and pure functions only; each pass binds the Frame as
// `@group(0) @binding(0) var<uniform> frame: Frame`.

const MAX_LIGHTS: u32 = 4u;

struct FrameLight {
    // w = 0: a directional light, xyz the unit vector towards it.
    // w = 1: a point light at xyz.
    position: vec4<f32>,
    // Linear RGB times intensity (irradiance at distance 1 for a point light); w unused.
    color: vec4<f32>,
}

struct Frame {
    view_proj: mat4x4<f32>,
    eye: vec3<f32>,
    // World units per pixel at distance 1 from the eye (2 tan(fov_y / 2) / height).
    pixel_scale: f32,
    ambient: f32,
    light_count: u32,
    // Floats per light in the hair's per-vertex visibility buffer (0: no buffer, all lit).
    visibility_stride: u32,
    _pad: u32,
    lights: array<FrameLight, MAX_LIGHTS>,
}

// Unit vector from `p` towards light `l`.
fn frame_to_light(l: FrameLight, p: vec3<f32>) -> vec3<f32> {
    if (l.position.w == 0.0) {
        return l.position.xyz;
    }
    let d = l.position.xyz - p;
    let len = length(d);
    if (len < 1e-6) {
        return vec3<f32>(0.0, 1.0, 0.0);
    }
    return d / len;
}

// Irradiance light `l` delivers at `p` on a surface facing it.
fn frame_irradiance(l: FrameLight, p: vec3<f32>) -> vec3<f32> {
    if (l.position.w == 0.0) {
        return l.color.rgb;
    }
    let d = l.position.xyz - p;
    return l.color.rgb / max(dot(d, d), 1e-4);
}
