//! Offscreen render targets.

use pelage_gpu::{Gpu, TextureData, read_texture, wgpu};

/// Colour format of offscreen targets: 8-bit sRGB, so shaders write linear light.
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// Depth format of every pass.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Offscreen colour (multisampled, plus a single-sample resolve target) and depth.
#[derive(Debug)]
pub struct Targets {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Samples per pixel (1 or 4).
    pub sample_count: u32,
    /// Multisampled colour; `None` when `sample_count` is 1.
    pub msaa: Option<wgpu::Texture>,
    /// The final single-sample colour, readable back.
    pub color: wgpu::Texture,
    /// Depth, with `sample_count` samples.
    pub depth: wgpu::Texture,
}

impl Targets {
    /// Creates targets of `width` x `height` with `sample_count` samples (1 or 4).
    pub fn new(gpu: &Gpu, width: u32, height: u32, sample_count: u32) -> crate::Result<Self> {
        let max = gpu.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(pelage_scene::ParamError {
                name: "image size".into(),
                value: format!("{width}x{height}"),
                reason: format!("each side must be in 1..={max} on this adapter"),
            }
            .into());
        }
        if sample_count != 1 && sample_count != 4 {
            return Err(pelage_scene::ParamError {
                name: "sample_count".into(),
                value: sample_count.to_string(),
                reason: "must be 1 or 4".into(),
            }
            .into());
        }
        let texture = |label: &str, format, samples, usage| {
            gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let attach = wgpu::TextureUsages::RENDER_ATTACHMENT;
        gpu.scoped(|_| Self {
            width,
            height,
            sample_count,
            msaa: (sample_count > 1)
                .then(|| texture("pelage msaa colour", COLOR_FORMAT, sample_count, attach)),
            color: texture(
                "pelage colour",
                COLOR_FORMAT,
                1,
                attach | wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::TEXTURE_BINDING,
            ),
            depth: texture(
                "pelage depth",
                DEPTH_FORMAT,
                sample_count,
                attach | wgpu::TextureUsages::TEXTURE_BINDING,
            ),
        })
        .map_err(Into::into)
    }

    /// The view to render colour into, and the resolve view if multisampled.
    pub fn color_views(&self) -> (wgpu::TextureView, Option<wgpu::TextureView>) {
        let color = self.color.create_view(&Default::default());
        match &self.msaa {
            Some(msaa) => (msaa.create_view(&Default::default()), Some(color)),
            None => (color, None),
        }
    }

    /// The views to pass to a method's `encode`, with their size.
    pub fn views<'a>(
        &self,
        color: &'a wgpu::TextureView,
        resolve: Option<&'a wgpu::TextureView>,
        depth: &'a wgpu::TextureView,
    ) -> crate::TargetViews<'a> {
        crate::TargetViews {
            color,
            resolve,
            depth,
            width: self.width,
            height: self.height,
            load: false,
        }
    }

    /// The depth view.
    pub fn depth_view(&self) -> wgpu::TextureView {
        self.depth.create_view(&Default::default())
    }

    /// Reads the final colour back (RGBA8, sRGB encoded, rows tightly packed).
    pub fn read_color(&self, gpu: &Gpu) -> crate::Result<TextureData> {
        Ok(read_texture(gpu, &self.color)?)
    }
}
