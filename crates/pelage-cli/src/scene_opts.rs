//! The scene options `render` and `animate` share: a scene file and what the command
//! line overrides in it.

use std::path::PathBuf;
use std::str::FromStr;

use clap::ValueEnum;
use pelage::Scene;
use pelage::scene::{Light, ShadingModel, ShadowParams, Transparency};

use crate::error::CliError;

/// An image size, `WxH` on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Size {
    /// Pixels across.
    pub width: u32,
    /// Pixels down.
    pub height: u32,
}

impl FromStr for Size {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let (w, h) = text
            .split_once(['x', 'X'])
            .ok_or_else(|| format!("expected WxH in pixels, e.g. 480x360, not `{text}`"))?;
        let side = |v: &str| {
            v.trim()
                .parse::<u32>()
                .map_err(|e| format!("`{v}` in `{text}`: {e}"))
                .and_then(|n| match n {
                    0 => Err(format!("`{text}`: width and height must be at least 1")),
                    n => Ok(n),
                })
        };
        Ok(Self {
            width: side(w)?,
            height: side(h)?,
        })
    }
}

impl std::fmt::Display for Size {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}", self.width, self.height)
    }
}

/// Stage 2 methods by command-line name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
#[value(rename_all = "snake_case")]
pub enum ShadowArg {
    /// No hair shadows.
    None,
    /// Voxel density splatted into a light-space grid, summed along the light (128³).
    Voxel,
    /// Deep opacity maps: 3 layers of accumulated opacity (1024²).
    Dom,
    /// Hair shadow map with 3x3 PCF (1024²).
    Map,
    /// Approximated deep shadow maps (TressFX): fibres in front from a depth map (1024²).
    Adsm,
}

impl ShadowArg {
    fn params(self) -> ShadowParams {
        match self {
            Self::None => ShadowParams::None,
            Self::Voxel => ShadowParams::Voxel(Default::default()),
            Self::Dom => ShadowParams::DeepOpacity(Default::default()),
            Self::Map => ShadowParams::ShadowMap(Default::default()),
            Self::Adsm => ShadowParams::Adsm(Default::default()),
        }
    }
}

/// Stage 3 compositing methods by command-line name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
#[value(rename_all = "snake_case")]
pub enum OitArg {
    /// Depth-tested ribbons, 4x MSAA.
    Opaque,
    /// Weighted blended OIT: 10 bytes per pixel.
    Wboit,
    /// The 8 nearest fragments per pixel, the rest blended: 84 bytes per pixel.
    KBuffer,
    /// Per-pixel linked lists in a bounded pool, 8 nearest resolved.
    ABuffer,
    /// DBK-buffer: the fragments within 0.05 of the nearest hair, opaque behind.
    Dbk,
    /// Nearest fragment of each of 8 random strand subsets.
    RandomSubsets,
}

impl OitArg {
    fn params(self) -> Transparency {
        match self {
            Self::Opaque => Transparency::Opaque,
            Self::Wboit => Transparency::wboit(),
            Self::KBuffer => Transparency::k_buffer(8),
            Self::ABuffer => Transparency::a_buffer(),
            Self::Dbk => Transparency::dbk(0.05),
            Self::RandomSubsets => Transparency::random_subsets(8),
        }
    }
}

/// Hair shading models by command-line name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
#[value(rename_all = "snake_case")]
pub enum ModelArg {
    /// Kajiya-Kay diffuse and specular cone.
    KajiyaKay,
    /// Marschner R, TT and TRT lobes, evaluated analytically.
    Marschner,
    /// Marschner read from lookup tables built once on the GPU (8.7 MB).
    MarschnerLut,
    /// Sadeghi's artist-friendly model.
    Sadeghi,
}

impl ModelArg {
    fn params(self) -> ShadingModel {
        match self {
            Self::KajiyaKay => ShadingModel::default(),
            Self::Marschner => ShadingModel::Marschner {
                params: Default::default(),
                lut: false,
            },
            Self::MarschnerLut => ShadingModel::Marschner {
                params: Default::default(),
                lut: true,
            },
            Self::Sadeghi => ShadingModel::Sadeghi(Default::default()),
        }
    }
}

/// Light set-ups by command-line name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
#[value(rename_all = "snake_case")]
pub enum LightsArg {
    /// The key light only (the scene's first light).
    Key,
    /// A white key light and a warm point light behind the hair, each with its own shadow.
    KeyBack,
}

/// A scene file and the command-line options that override it.
#[derive(Clone, Debug, clap::Args)]
pub struct SceneOpts {
    /// Scene file (TOML; scenes/default.toml lists every key with its default). The
    /// options below override it. Default: the built-in furred creature.
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// Image size in pixels, width x height.
    #[arg(long, value_name = "WxH", default_value = "480x360")]
    pub size: Size,
    /// Number of strands (the scene's own count by default: 20000 for the built-in scene).
    #[arg(long, value_name = "N")]
    pub strands: Option<u32>,
    /// Shadow method (the scene's by default: voxel).
    #[arg(long, value_name = "METHOD")]
    pub shadow: Option<ShadowArg>,
    /// Shadow resolution: voxels per axis for voxel shadows (default 128), texels per
    /// side for dom, map and adsm (default 1024). Applies to --shadow or the scene's method.
    #[arg(long, value_name = "N")]
    pub shadow_res: Option<u32>,
    /// Transparency (the scene's by default: opaque).
    #[arg(long, value_name = "METHOD")]
    pub oit: Option<OitArg>,
    /// Hair shading model (the scene's by default: kajiya_kay).
    #[arg(long, value_name = "MODEL")]
    pub model: Option<ModelArg>,
    /// Lights (the scene's by default: one key light).
    #[arg(long, value_name = "SET")]
    pub lights: Option<LightsArg>,
    /// Level of detail: grow and draw only as many strands and segments as the hair's
    /// size on screen needs (stochastic simplification with the scene's [hair.lod]
    /// parameters, seed 002), and size the shadow grid or maps down to it.
    #[arg(long)]
    pub lod: bool,
}

impl SceneOpts {
    /// The scene file (or the built-in scene) with the command line's overrides applied.
    pub fn scene(&self) -> Result<Scene, CliError> {
        let mut scene = match &self.scene {
            Some(path) => Scene::from_file(path)?,
            None => Scene::default(),
        };
        if let Some(shadow) = self.shadow {
            scene.shadow = shadow.params();
        }
        if let Some(n) = self.shadow_res {
            match &mut scene.shadow {
                ShadowParams::Voxel(v) => {
                    v.resolution = [n; 3];
                    v.voxel_size = None; // a voxel size would override the resolution
                }
                ShadowParams::DeepOpacity(d) => d.map.size = n,
                ShadowParams::ShadowMap(m) => m.map.size = n,
                ShadowParams::Adsm(a) => a.map.size = n,
                ShadowParams::None => {
                    return Err(CliError::Usage(
                        "--shadow-res: the scene has no shadow method; give --shadow too".into(),
                    ));
                }
            }
        }
        if let Some(oit) = self.oit {
            scene.shade.transparency = oit.params();
        }
        if let Some(model) = self.model {
            scene.shade.model = model.params();
        }
        match self.lights {
            Some(LightsArg::Key) => {
                scene.lights.truncate(1);
                if scene.lights.is_empty() {
                    scene.lights.push(Light::default());
                }
            }
            Some(LightsArg::KeyBack) => scene.lights = Light::key_and_back(&scene.camera),
            None => {}
        }
        if let Some(n) = self.strands {
            if scene.groom.is_some() {
                return Err(CliError::Usage(
                    "--strands: the scene draws a groom file, whose strands are its own; \
                     leave --strands out, or remove the scene's [groom] table to grow fur"
                        .into(),
                ));
            }
            scene.hair.roots.count = n;
        }
        if self.lod {
            scene.hair.lod.enabled = true;
            scene = scene.sized_for_view(&scene.camera, self.size.width, self.size.height);
        }
        Ok(scene)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes() {
        assert_eq!(
            "96x72".parse::<Size>(),
            Ok(Size {
                width: 96,
                height: 72
            })
        );
        assert!("96".parse::<Size>().is_err());
        assert!("0x72".parse::<Size>().is_err());
        assert!("ax72".parse::<Size>().is_err());
    }
}
