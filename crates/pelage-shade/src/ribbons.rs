//! The uniforms every stage 3 pass shares (`shade/frame.wgsl`, `shade/hair.wgsl`, `shade/mesh.wgsl`).

use encase::ShaderType;
use glam::{Mat4, Vec3, Vec4};
use pelage_scene::{CameraMatrices, Light, MAX_LIGHTS, ShadeParams};

/// One light as the shaders see it (`FrameLight` in `wgsl/shade/frame.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, ShaderType)]
pub struct FrameLight {
    /// w = 0: directional, xyz the unit vector towards the light; w = 1: a point light at xyz.
    pub position: Vec4,
    /// Colour times intensity; w unused.
    pub color: Vec4,
}

/// Camera and lights for one frame (`Frame` in `wgsl/shade/frame.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct FrameUniforms {
    /// World to clip.
    pub view_proj: Mat4,
    /// Eye position.
    pub eye: Vec3,
    /// World units per pixel at distance 1: `2 tan(fov_y / 2) / height`.
    pub pixel_scale: f32,
    /// Ambient fraction.
    pub ambient: f32,
    /// Lights in use, 1 to [`MAX_LIGHTS`].
    pub light_count: u32,
    /// Floats per light in the hair's visibility buffer (0: none, every vertex lit).
    pub visibility_stride: u32,
    /// Padding.
    pub _pad: u32,
    /// The lights; entries past `light_count` are ignored.
    pub lights: [FrameLight; MAX_LIGHTS],
}

/// Style of the hair ribbons (`RibbonStyle` in `shade/hair.wgsl`).
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
    /// Opacity of a strand covering its whole ribbon (the transparency methods' alpha).
    pub opacity: f32,
}

/// Style of one draw of the opaque mesh (`MeshStyle` in `mesh.wgsl`). The mesh is drawn
/// once per light with a shadow: the first draw the body's sky, light 0 through its
/// shadow and the lights without a shadow of their own; each later draw adds one light
/// through its own shadow.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct MeshStyle {
    /// Albedo, linear RGB.
    pub color: Vec3,
    /// 1 in the first draw: the body's sky and the lights from `unshadowed_from` on,
    /// unshadowed; 0 in the others.
    pub base: u32,
    /// The light this draw adds through the shadow bound with it (`u32::MAX`: none).
    pub shadowed: u32,
    /// In the first draw, the first light without a shadow of its own.
    pub unshadowed_from: u32,
}

impl FrameUniforms {
    /// Frame uniforms for `camera` and `lights` on a target `height` pixels tall, with the
    /// hair's visibility buffer holding `visibility_stride` floats per light (0: none).
    pub fn new(
        camera: &CameraMatrices,
        lights: &[Light],
        params: &ShadeParams,
        height: u32,
        visibility_stride: u32,
    ) -> crate::Result<Self> {
        camera.validate()?;
        Light::validate_all(lights)?;
        let mut uniforms = [FrameLight::default(); MAX_LIGHTS];
        for (u, light) in uniforms.iter_mut().zip(lights) {
            *u = match light {
                Light::Directional(d) => FrameLight {
                    position: d.to_light()?.extend(0.0),
                    color: (d.color * d.intensity).extend(0.0),
                },
                Light::Point(p) => FrameLight {
                    position: p.position.extend(1.0),
                    color: (p.color * p.intensity).extend(0.0),
                },
            };
        }
        Ok(Self {
            view_proj: camera.view_projection(),
            eye: camera.eye(),
            pixel_scale: camera.pixel_scale(height),
            ambient: params.ambient,
            light_count: lights.len().min(MAX_LIGHTS) as u32,
            visibility_stride,
            _pad: 0,
            lights: uniforms,
        })
    }
}
