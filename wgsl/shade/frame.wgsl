// Per-frame camera and light, shared by every raster pass of stage 3.
// Declares a struct only; each pass binds it as `@group(0) @binding(0) var<uniform>`.

struct Frame {
    view_proj: mat4x4<f32>,
    eye: vec3<f32>,
    // World units per pixel at distance 1 from the eye (2 tan(fov_y / 2) / height).
    pixel_scale: f32,
    // Unit vector from the scene towards the light.
    to_light: vec3<f32>,
    ambient: f32,
    light_color: vec3<f32>,
    _pad: f32,
}
