//! Render targets: the formats a method is built for ([`TargetFormat`], the caller's
//! choice), and offscreen targets of those formats ([`Targets`]).

use pelage_gpu::{Gpu, TextureData, read_texture, wgpu};
use pelage_scene::ParamError;

/// Default colour format of offscreen targets: 8-bit sRGB, so shaders write linear light.
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// Default depth format.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The targets a method draws into, chosen by the caller: an engine passes its own
/// (an HDR `Rgba16Float` colour, a `Depth24PlusStencil8` depth, reverse-Z, its sample
/// count). Shaders write linear light; an sRGB colour format encodes it, a float one
/// keeps it for the engine's tone mapping.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TargetFormat {
    /// Colour format: renderable and blendable on the adapter.
    pub color: wgpu::TextureFormat,
    /// Depth format (a depth or depth-stencil format; the stencil is left alone).
    pub depth: wgpu::TextureFormat,
    /// Samples per pixel of colour and depth (1, 2, 4, 8 as the adapter allows). The
    /// transparency methods draw single-sampled and refuse more.
    pub samples: u32,
    /// Depth reversed: near is 1, far is 0, the depth test is `Greater` and depth is
    /// cleared to 0. Must agree with the projection matrix (checked every frame).
    pub reverse_z: bool,
}

impl Default for TargetFormat {
    /// [`COLOR_FORMAT`], [`DEPTH_FORMAT`], one sample, standard depth.
    fn default() -> Self {
        Self {
            color: COLOR_FORMAT,
            depth: DEPTH_FORMAT,
            samples: 1,
            reverse_z: false,
        }
    }
}

impl TargetFormat {
    /// The default formats with the sample count `params` asks for
    /// ([`ShadeParams::samples`](pelage_scene::ShadeParams::samples)).
    pub fn for_params(params: &pelage_scene::ShadeParams) -> Self {
        Self {
            samples: params.samples(),
            ..Self::default()
        }
    }

    /// The depth test: `Less` with standard depth, `Greater` reversed.
    pub fn depth_compare(&self) -> wgpu::CompareFunction {
        if self.reverse_z {
            wgpu::CompareFunction::Greater
        } else {
            wgpu::CompareFunction::Less
        }
    }

    /// The depth a cleared target holds: the far plane.
    pub fn far_depth(&self) -> f32 {
        if self.reverse_z { 0.0 } else { 1.0 }
    }

    /// Whether the depth format has a stencil aspect (its view must then be given
    /// depth-only where a method samples it).
    pub fn has_stencil(&self) -> bool {
        self.depth.has_stencil_aspect()
    }

    /// Checks the formats against the device (the format features every adapter with its
    /// features guarantees): colour renderable and blendable, depth a
    /// depth format, the sample count supported by both.
    pub fn validate(&self, gpu: &Gpu) -> crate::Result<()> {
        let bad = |name: &str, value: String, reason: String| -> crate::ShadeError {
            ParamError {
                name: name.into(),
                value,
                reason,
            }
            .into()
        };
        let color = self.color.guaranteed_format_features(gpu.features());
        if !color
            .allowed_usages
            .contains(wgpu::TextureUsages::RENDER_ATTACHMENT)
            || self.color.is_depth_stencil_format()
        {
            return Err(bad(
                "target.color",
                format!("{:?}", self.color),
                format!(
                    "is not a colour format this device ({}) can render to; use Rgba8UnormSrgb, Bgra8UnormSrgb or Rgba16Float",
                    gpu.describe()
                ),
            ));
        }
        if !color
            .flags
            .contains(wgpu::TextureFormatFeatureFlags::BLENDABLE)
        {
            return Err(bad(
                "target.color",
                format!("{:?}", self.color),
                "cannot be blended on this device (the hair and the resolves blend); use Rgba8UnormSrgb or Rgba16Float".into(),
            ));
        }
        if !self.depth.is_depth_stencil_format() || !self.depth.has_depth_aspect() {
            return Err(bad(
                "target.depth",
                format!("{:?}", self.depth),
                "must be a depth format (Depth32Float, Depth24Plus, Depth24PlusStencil8, ...)"
                    .into(),
            ));
        }
        let depth = self.depth.guaranteed_format_features(gpu.features());
        for (features, format) in [(color, self.color), (depth, self.depth)] {
            if !features.flags.sample_count_supported(self.samples) {
                return Err(bad(
                    "target.samples",
                    self.samples.to_string(),
                    format!(
                        "{format:?} does not support {} samples on this device (supported: {:?})",
                        self.samples,
                        features.flags.supported_sample_counts()
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// Offscreen colour (multisampled, plus a single-sample resolve target) and depth.
#[derive(Debug)]
pub struct Targets {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Samples per pixel.
    pub sample_count: u32,
    /// The formats.
    pub format: TargetFormat,
    /// Multisampled colour; `None` when `sample_count` is 1.
    pub msaa: Option<wgpu::Texture>,
    /// The final single-sample colour, readable back.
    pub color: wgpu::Texture,
    /// Depth, with `sample_count` samples.
    pub depth: wgpu::Texture,
}

impl Targets {
    /// Creates targets of `width` x `height` with `sample_count` samples (1 or 4) in the
    /// default formats.
    pub fn new(gpu: &Gpu, width: u32, height: u32, sample_count: u32) -> crate::Result<Self> {
        if sample_count != 1 && sample_count != 4 {
            return Err(pelage_scene::ParamError {
                name: "sample_count".into(),
                value: sample_count.to_string(),
                reason: "must be 1 or 4".into(),
            }
            .into());
        }
        Self::with_format(
            gpu,
            width,
            height,
            &TargetFormat {
                samples: sample_count,
                ..TargetFormat::default()
            },
        )
    }

    /// Creates targets of `width` x `height` in `format` (checked against the adapter).
    pub fn with_format(
        gpu: &Gpu,
        width: u32,
        height: u32,
        format: &TargetFormat,
    ) -> crate::Result<Self> {
        format.validate(gpu)?;
        let sample_count = format.samples;
        check_image_size(gpu, width, height)?;
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
            format: *format,
            msaa: (sample_count > 1)
                .then(|| texture("pelage msaa colour", format.color, sample_count, attach)),
            color: texture(
                "pelage colour",
                format.color,
                1,
                attach | wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::TEXTURE_BINDING,
            ),
            // Only single-sampled depth is sampled (the transparency methods); a
            // multisampled one stays a render attachment, which wgpu's GL backend keeps
            // in a renderbuffer: it attaches a multisampled *texture* with
            // glFramebufferTexture2DMultisampleEXT, and on llvmpipe that pass then
            // clears, draws and resolves nothing.
            depth: texture(
                "pelage depth",
                format.depth,
                sample_count,
                if sample_count == 1 {
                    attach | wgpu::TextureUsages::TEXTURE_BINDING
                } else {
                    attach
                },
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
            depth_sampled: None,
            width: self.width,
            height: self.height,
            load: false,
        }
    }

    /// The depth view (every aspect: the one to render into).
    pub fn depth_view(&self) -> wgpu::TextureView {
        self.depth.create_view(&Default::default())
    }

    /// The depth aspect alone, to sample: what [`crate::TargetViews::depth_sampled`]
    /// needs for a depth-stencil format (`None` for a depth-only format, whose
    /// [`Targets::depth_view`] serves both).
    pub fn depth_sampled_view(&self) -> Option<wgpu::TextureView> {
        self.format.has_stencil().then(|| {
            self.depth.create_view(&wgpu::TextureViewDescriptor {
                aspect: wgpu::TextureAspect::DepthOnly,
                ..Default::default()
            })
        })
    }

    /// Every view of these targets, made once: record frames with
    /// [`TargetViewSet::views`] so the methods that sample the depth keep their bind
    /// groups (they rebuild them when handed a different view).
    pub fn view_set(&self) -> TargetViewSet {
        let (color, resolve) = self.color_views();
        TargetViewSet {
            color,
            resolve,
            depth: self.depth_view(),
            depth_sampled: self.depth_sampled_view(),
            width: self.width,
            height: self.height,
        }
    }

    /// Reads the final colour back (RGBA8, sRGB encoded, rows tightly packed).
    pub fn read_color(&self, gpu: &Gpu) -> crate::Result<TextureData> {
        Ok(read_texture(gpu, &self.color)?)
    }
}

/// The views of a [`Targets`] ([`Targets::view_set`]), kept from frame to frame.
#[derive(Debug)]
pub struct TargetViewSet {
    /// The view drawn into (the MSAA texture when multisampled).
    pub color: wgpu::TextureView,
    /// The single-sample view `color` resolves into, when multisampled.
    pub resolve: Option<wgpu::TextureView>,
    /// The depth view.
    pub depth: wgpu::TextureView,
    /// The depth aspect alone, when the depth format has a stencil.
    pub depth_sampled: Option<wgpu::TextureView>,
    /// Size in pixels.
    pub width: u32,
    /// Size in pixels.
    pub height: u32,
}

impl TargetViewSet {
    /// The views, cleared before drawing (`load: false`).
    pub fn views(&self) -> crate::TargetViews<'_> {
        crate::TargetViews {
            color: &self.color,
            resolve: self.resolve.as_ref(),
            depth: &self.depth,
            depth_sampled: self.depth_sampled.as_ref(),
            width: self.width,
            height: self.height,
            load: false,
        }
    }
}

/// Refuses targets of `width` x `height` unless each side is in 1..= the adapter's
/// `max_texture_dimension_2d`, naming `image size`: what [`Targets::with_format`] and a
/// frame built for the caller's targets both check first.
pub fn check_image_size(gpu: &Gpu, width: u32, height: u32) -> crate::Result<()> {
    let max = gpu.limits().max_texture_dimension_2d;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(pelage_scene::ParamError {
            name: "image size".into(),
            value: format!("{width}x{height}"),
            reason: format!("each side must be in 1..={max} on this adapter"),
        }
        .into());
    }
    Ok(())
}
