//! The uniforms every stage 3 pass shares (`shade/frame.wgsl`, `shade/hair.wgsl`, `shade/mesh.wgsl`).

use encase::ShaderType;
use glam::{Mat4, Vec3};
use pelage_scene::{Camera, DirectionalLight, ShadeParams};

/// Camera and light for one frame (`Frame` in `wgsl/shade/frame.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct FrameUniforms {
    /// World to clip.
    pub view_proj: Mat4,
    /// Eye position.
    pub eye: Vec3,
    /// World units per pixel at distance 1: `2 tan(fov_y / 2) / height`.
    pub pixel_scale: f32,
    /// Unit vector towards the light.
    pub to_light: Vec3,
    /// Ambient fraction.
    pub ambient: f32,
    /// Light colour times intensity.
    pub light_color: Vec3,
    /// Padding.
    pub _pad: f32,
}

/// Style of the hair ribbons (`RibbonStyle` in `ribbons.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct RibbonStyle {
    /// Segments per strand.
    pub segments: u32,
    /// Tip width as a fraction of the root width.
    pub tip_width: f32,
    /// Minimum ribbon width in pixels.
    pub min_pixels: f32,
    /// Root darkening.
    pub root_occlusion: f32,
    /// Kajiya-Kay diffuse weight.
    pub diffuse: f32,
    /// Kajiya-Kay specular weight.
    pub specular: f32,
    /// Kajiya-Kay exponent.
    pub shininess: f32,
    /// Padding.
    pub _pad: f32,
    /// Specular colour.
    pub specular_color: Vec3,
    /// Opacity of a strand covering its whole ribbon (the transparency methods' alpha).
    pub opacity: f32,
}

/// Style of the opaque mesh (`MeshStyle` in `mesh.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct MeshStyle {
    /// Albedo, linear RGB.
    pub color: Vec3,
    /// Padding.
    pub _pad: f32,
}

impl FrameUniforms {
    /// Frame uniforms for `camera` and `light` on a `width` x `height` target.
    pub fn new(
        camera: &Camera,
        light: &DirectionalLight,
        params: &ShadeParams,
        width: u32,
        height: u32,
    ) -> crate::Result<Self> {
        camera.validate()?;
        let to_light = light.to_light()?;
        let height = height.max(1) as f32;
        Ok(Self {
            view_proj: camera.view_projection(width.max(1) as f32 / height),
            eye: camera.eye,
            pixel_scale: 2.0 * (camera.fov_y * 0.5).tan() / height,
            to_light,
            ambient: params.ambient,
            light_color: light.color * light.intensity,
            _pad: 0.0,
        })
    }
}
