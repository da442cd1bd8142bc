//! The names of the methods: one table per method enum, read by the scene files (through
//! serde's tags and aliases, which a test checks against the table), the command line, the
//! viewer, the web demo and `pelage info`. A method is added or renamed here, once.

use crate::params::ShadowParams;
use crate::shading::{MultipleScattering, ShadingModel};
use crate::transparency::Transparency;

/// What a method is called: the name scene files and the command line write, the other
/// names they also accept, and one line saying what it does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MethodName {
    /// The method's name: a scene file's `method = "..."` / `model = "..."` and the
    /// command line's value, the labs' and the bench's series name.
    pub name: &'static str,
    /// Other names accepted for it (older or shorter spellings).
    pub aliases: &'static [&'static str],
    /// What it does, in one line (the command line's help).
    pub summary: &'static str,
}

impl MethodName {
    /// Whether `name` is this method's name or one of its aliases.
    pub fn is_called(&self, name: &str) -> bool {
        self.name == name || self.aliases.contains(&name)
    }
}

/// A method enum with a name table: every value is one row of [`Named::NAMES`], and every
/// row has a value at its defaults.
pub trait Named: Sized {
    /// One row per method, in the order lists show them.
    const NAMES: &'static [MethodName];

    /// The row of `self`.
    fn row(&self) -> usize;

    /// The method of row `row` at its defaults (`None` past the table's end).
    fn default_of(row: usize) -> Option<Self>;

    /// The method's name: [`Named::NAMES`]`[self.row()].name`.
    fn method_name(&self) -> &'static str {
        Self::NAMES[self.row()].name
    }

    /// The method called `name` (or one of its aliases) at its defaults; `None` for any
    /// other name.
    fn named(name: &str) -> Option<Self> {
        Self::NAMES
            .iter()
            .position(|m| m.is_called(name))
            .and_then(Self::default_of)
    }

    /// The names of every method, for error messages: `a, b, c`.
    fn name_list() -> String {
        Self::NAMES
            .iter()
            .map(|m| m.name)
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl Named for Transparency {
    const NAMES: &'static [MethodName] = &[
        MethodName {
            name: "opaque",
            aliases: &[],
            summary: "depth-tested ribbons, no blending (MSAA at the shade sample count)",
        },
        MethodName {
            name: "wboit",
            aliases: &[],
            summary: "weighted blended OIT: one pass, approximate, 10 bytes per pixel",
        },
        MethodName {
            name: "k_buffer",
            aliases: &[],
            summary: "the 8 nearest fragments per pixel kept exactly, the rest blended \
                      (64-bit atomics)",
        },
        MethodName {
            name: "a_buffer",
            aliases: &[],
            summary: "per-pixel linked lists in a bounded pool, the nearest resolved exactly",
        },
        MethodName {
            name: "dbk",
            aliases: &[],
            summary: "DBK-buffer: the fragments near the nearest hair blended, opaque behind",
        },
        MethodName {
            name: "random_subsets",
            aliases: &[],
            summary: "the nearest fragment of each of 8 random strand subsets (64-bit atomics)",
        },
        MethodName {
            name: "strand_raster",
            aliases: &[],
            summary: "the strand rasterizer: hair drawn in compute in screen tiles, analytic \
                      coverage, no 64-bit atomics",
        },
    ];

    fn row(&self) -> usize {
        match self {
            Self::Opaque => 0,
            Self::Wboit { .. } => 1,
            Self::KBuffer { .. } => 2,
            Self::ABuffer { .. } => 3,
            Self::Dbk { .. } => 4,
            Self::RandomSubsets { .. } => 5,
            Self::StrandRaster { .. } => 6,
        }
    }

    fn default_of(row: usize) -> Option<Self> {
        Some(match row {
            0 => Self::Opaque,
            1 => Self::wboit(),
            2 => Self::k_buffer(8),
            3 => Self::a_buffer(),
            4 => Self::dbk(0.05),
            5 => Self::random_subsets(8),
            6 => Self::strand_raster(),
            _ => return None,
        })
    }
}

impl Named for ShadowParams {
    const NAMES: &'static [MethodName] = &[
        MethodName {
            name: "none",
            aliases: &[],
            summary: "no hair shadows",
        },
        MethodName {
            name: "voxel",
            aliases: &[],
            summary: "voxel density splatted into a light-space grid, summed along the light \
                      (128³)",
        },
        MethodName {
            name: "deep_opacity",
            aliases: &["dom"],
            summary: "deep opacity maps: 3 layers of accumulated opacity (1024²)",
        },
        MethodName {
            name: "shadow_map",
            aliases: &["map"],
            summary: "hair shadow map with 3x3 PCF (1024²)",
        },
        MethodName {
            name: "adsm",
            aliases: &[],
            summary: "approximated deep shadow maps (TressFX): fibres in front from a depth \
                      map (1024²)",
        },
    ];

    fn row(&self) -> usize {
        match self {
            Self::None => 0,
            Self::Voxel(_) => 1,
            Self::DeepOpacity(_) => 2,
            Self::ShadowMap(_) => 3,
            Self::Adsm(_) => 4,
        }
    }

    fn default_of(row: usize) -> Option<Self> {
        Some(match row {
            0 => Self::None,
            1 => Self::Voxel(Default::default()),
            2 => Self::DeepOpacity(Default::default()),
            3 => Self::ShadowMap(Default::default()),
            4 => Self::Adsm(Default::default()),
            _ => return None,
        })
    }
}

impl Named for ShadingModel {
    const NAMES: &'static [MethodName] = &[
        MethodName {
            name: "kajiya_kay",
            aliases: &[],
            summary: "Kajiya-Kay diffuse and specular cone",
        },
        MethodName {
            name: "marschner",
            aliases: &[],
            summary: "Marschner R, TT and TRT lobes, evaluated analytically",
        },
        MethodName {
            name: "marschner_lut",
            aliases: &[],
            summary: "Marschner read from lookup tables built once on the GPU (8.7 MB); a \
                      scene file writes model = \"marschner\" with lut = true",
        },
        MethodName {
            name: "sadeghi",
            aliases: &[],
            summary: "Sadeghi's artist-friendly model",
        },
        MethodName {
            name: "chiang",
            aliases: &[],
            summary: "Chiang et al. 2016's fibres (pbrt-v3's hair) with melanin and dual \
                      scattering",
        },
    ];

    fn row(&self) -> usize {
        match self {
            Self::KajiyaKay(_) => 0,
            Self::Marschner { lut: false, .. } => 1,
            Self::Marschner { lut: true, .. } => 2,
            Self::Sadeghi(_) => 3,
            Self::Chiang(_) => 4,
        }
    }

    fn default_of(row: usize) -> Option<Self> {
        Some(match row {
            0 => Self::KajiyaKay(Default::default()),
            1 => Self::Marschner {
                params: Default::default(),
                lut: false,
            },
            2 => Self::Marschner {
                params: Default::default(),
                lut: true,
            },
            3 => Self::Sadeghi(Default::default()),
            4 => Self::Chiang(Default::default()),
            _ => return None,
        })
    }
}

impl Named for MultipleScattering {
    const NAMES: &'static [MethodName] = &[
        MethodName {
            name: "none",
            aliases: &["single"],
            summary: "single scattering only, shadowed by stage 2",
        },
        MethodName {
            name: "dual",
            aliases: &[],
            summary: "dual scattering (Zinke 2008) from stage 2's visibility",
        },
        MethodName {
            name: "volume",
            aliases: &[],
            summary: "a radiance grid over the hair (Moon 2008): orders >= 2 propagated cell to \
                      cell with Chiang's fibre energies and the body's bounce (16³ by default, 0.98 MB)",
        },
        MethodName {
            name: "dual_volume",
            aliases: &[],
            summary: "dual scattering for the lights, the radiance grid for the sky and the \
                      body's bounce",
        },
    ];

    fn row(&self) -> usize {
        match self {
            Self::None => 0,
            Self::Dual => 1,
            Self::Volume => 2,
            Self::DualVolume => 3,
        }
    }

    fn default_of(row: usize) -> Option<Self> {
        Some(match row {
            0 => Self::None,
            1 => Self::Dual,
            2 => Self::Volume,
            3 => Self::DualVolume,
            _ => return None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every row's default is of that row, and nothing past the end.
    fn rows_round_trip<T: Named>() {
        for (row, m) in T::NAMES.iter().enumerate() {
            let value = T::default_of(row).unwrap_or_else(|| panic!("no value for {}", m.name));
            assert_eq!(value.row(), row, "{}", m.name);
            assert_eq!(value.method_name(), m.name);
            assert_eq!(T::named(m.name).map(|v| v.row()), Some(row), "{}", m.name);
            for alias in m.aliases {
                assert_eq!(T::named(alias).map(|v| v.row()), Some(row), "{alias}");
            }
        }
        assert!(T::default_of(T::NAMES.len()).is_none());
        assert!(T::named("no_such_method").is_none());
        let mut all: Vec<&str> = T::NAMES
            .iter()
            .flat_map(|m| std::iter::once(m.name).chain(m.aliases.iter().copied()))
            .collect();
        let n = all.len();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), n, "a name or alias is used twice");
    }

    #[test]
    fn every_table_round_trips() {
        rows_round_trip::<Transparency>();
        rows_round_trip::<ShadowParams>();
        rows_round_trip::<ShadingModel>();
        rows_round_trip::<MultipleScattering>();
    }

    /// The scene files' serde tags are the table's names, and the aliases parse as the same
    /// method (a scene file and the command line accept the same words).
    #[test]
    fn scene_file_tags_are_the_table() {
        #[derive(serde::Deserialize, serde::Serialize)]
        struct Wrap<T> {
            x: T,
        }
        fn tag_of<T: serde::Serialize>(value: T, key: &str) -> String {
            let text = toml::to_string(&Wrap { x: value }).expect("serialises");
            let table: toml::Table = toml::from_str(&text).expect("parses");
            table["x"][key].as_str().expect("a tag").to_string()
        }
        for (row, m) in Transparency::NAMES.iter().enumerate() {
            let value = Transparency::default_of(row).expect("a value");
            assert_eq!(tag_of(value, "method"), m.name);
            for alias in m.aliases {
                let parsed: Wrap<Transparency> =
                    toml::from_str(&format!("[x]\nmethod = \"{alias}\"")).expect(alias);
                assert_eq!(parsed.x.row(), row, "{alias}");
            }
        }
        for (row, m) in ShadowParams::NAMES.iter().enumerate() {
            let value = ShadowParams::default_of(row).expect("a value");
            assert_eq!(tag_of(value, "method"), m.name);
            for alias in m.aliases {
                let parsed: Wrap<ShadowParams> =
                    toml::from_str(&format!("[x]\nmethod = \"{alias}\"")).expect(alias);
                assert_eq!(parsed.x.row(), row, "{alias}");
            }
        }
        for (row, m) in ShadingModel::NAMES.iter().enumerate() {
            let value = ShadingModel::default_of(row).expect("a value");
            // marschner_lut is Marschner with `lut = true` in a file.
            let tag = tag_of(value, "model");
            assert!(
                m.name.starts_with(&tag),
                "{} is written model = {tag}",
                m.name
            );
        }
    }
}
