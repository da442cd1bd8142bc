//! Parameters of stage 3's order-independent transparency methods.
//!
//! Each variant of [`Transparency`] is one method in `pelage-shade` (a type of the
//! same name) with one WGSL file under `wgsl/shade/oit/`. Hair alpha is the strand's
//! opacity ([`GrowthParams::opacity`](crate::GrowthParams::opacity)) times its
//! coverage of the drawn ribbon, so sub-pixel strands fade instead of looking dense.

use serde::{Deserialize, Serialize};

use crate::names::Named;
use crate::params::{ParamError, positive};

/// The largest k of the bounded methods (k-buffer, random subsets) and of the
/// linked-list resolves: the resolve sorts k fragments in registers.
pub const MAX_OIT_K: u32 = 64;

/// The smallest strand-rasterizer pool a scene may ask for, references per segment
/// ([`Transparency::StrandRaster`]'s `pool`): every segment on screen takes at least one
/// reference (one per tile it crosses; long hair needs about 1.2 at tiles of 16), so a
/// smaller pool drops hair in every frame that shows all of it.
pub const MIN_POOL: f32 = 1.0;

/// The smallest linked-list pool a scene may ask for, nodes per pixel (the A-buffer's
/// and the DBK-buffer's `nodes_per_pixel`): fewer cannot hold one layer of hair over the
/// whole screen.
pub const MIN_NODES_PER_PIXEL: f32 = 1.0;

/// The weight function of weighted blended OIT (McGuire and Bavoil 2013, eq. 7 to 10).
/// `z` is the fragment's view depth in scene units and `d` its window depth in [0, 1].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WboitWeight {
    /// Eq. 7: `a * clamp(10 / (1e-5 + (z/5)^2 + (z/200)^6), 1e-2, 3e3)`.
    #[default]
    Eq7,
    /// Eq. 8: `a * clamp(10 / (1e-5 + (z/10)^3 + (z/200)^6), 1e-2, 3e3)`.
    Eq8,
    /// Eq. 9: `a * clamp(0.03 / (1e-5 + (z/200)^4), 1e-2, 3e3)`.
    Eq9,
    /// Eq. 10: `a * max(1e-2, 3e3 * (1 - d)^3)`.
    Eq10,
    /// No depth weighting (`w = a`): plain weighted average, for comparison.
    Constant,
}

/// How stage 3 composites the hair's fragments.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "snake_case", deny_unknown_fields)]
pub enum Transparency {
    /// Depth-tested opaque ribbons, no blending (the baseline; works with 4x MSAA).
    Opaque,
    /// Weighted blended OIT (McGuire and Bavoil 2013): one pass into an accumulation
    /// and a revealage target, then a resolve. No per-pixel lists; approximate.
    Wboit {
        /// The depth weight.
        #[serde(default)]
        weight: WboitWeight,
    },
    /// The k nearest fragments per pixel, kept by a 64-bit `atomicMax` insertion
    /// (depth in the high word, packed colour in the low word); fragments behind the
    /// k nearest are blended approximately (accumulated colour, summed optical depth),
    /// never dropped. Needs `SHADER_INT64_ATOMIC_ALL_OPS`.
    KBuffer {
        /// Fragments kept per pixel, 1..=64 (4 to 16 are useful).
        #[serde(default = "default_k")]
        k: u32,
    },
    /// A per-pixel linked list of every fragment (PPLL) in a node pool the caller sizes;
    /// the resolve sorts the `resolve_k` nearest and blends the rest approximately.
    /// Fragments beyond the pool are counted and dropped.
    ABuffer {
        /// Pool size as an average number of nodes per pixel (16 bytes each); the pool
        /// is capped by the device's storage binding size, and the screen is drawn in
        /// horizontal slices when it does not fit.
        #[serde(default = "default_nodes_per_pixel")]
        nodes_per_pixel: f32,
        /// Fragments sorted exactly per pixel at resolve, 1..=64.
        #[serde(default = "default_resolve_k")]
        resolve_k: u32,
    },
    /// Hunz 2016's DBK-buffer: a depth pre-pass finds the nearest hair per pixel; the
    /// fragments within `depth_shift` behind it go into a linked list, the others are
    /// drawn as opaque hair behind it (the opaque fallback).
    Dbk {
        /// Thickness of the blended layer, in scene units along the view ray (> 0).
        #[serde(default = "default_depth_shift")]
        depth_shift: f32,
        /// Pool size as an average number of nodes per pixel, as for the A-buffer.
        #[serde(default = "default_dbk_nodes")]
        nodes_per_pixel: f32,
        /// Fragments sorted exactly per pixel at resolve, 1..=64.
        #[serde(default = "default_resolve_k")]
        resolve_k: u32,
    },
    /// Hunz 2016's random subsets: strands are split into k random subsets and each
    /// pixel keeps the nearest fragment of each subset; the k are sorted and blended.
    /// Needs `SHADER_INT64_ATOMIC_MIN_MAX`.
    RandomSubsets {
        /// Number of subsets, 1..=64.
        #[serde(default = "default_k")]
        k: u32,
    },
    /// The strand rasterizer: hair drawn in compute, not by the raster pipeline. Strand
    /// vertices are shaded once each; segments are binned into screen tiles and depth
    /// bins (32-bit atomics and a prefix sum), sorted by depth per tile in workgroup
    /// memory, and composited front to back per pixel with analytic coverage (no MSAA,
    /// no 64-bit atomics). Runs on WebGPU's default limits.
    StrandRaster {
        /// Tile edge in pixels, 8 (the default) or 16: one workgroup of tile x tile threads
        /// per tile.
        #[serde(default = "default_tile")]
        tile: u32,
        /// Depth bins per tile, 1..=256: a tile's segments are sorted bin by bin in
        /// chunks of 1024, so more bins keep more of a deep tile exactly sorted.
        #[serde(default = "default_bins")]
        bins: u32,
        /// The pool of (tile, segment) references, as references per segment of the
        /// strands at full detail (> 0, at most 1024). A frame that needs more draws
        /// what fits, counts the rest (`HairPass::stats`) and the pool grows for the
        /// next frame, up to the device's storage binding limit.
        #[serde(default = "default_pool")]
        pool: f32,
    },
}

/// 8: on the main job (`pelage animate`, 20 000 strands at 480x360) the shade stage took
/// 346 ms at tile 8 against 760 ms at tile 16 (each pixel of a tile tests every segment
/// binned to it, and a 16-pixel tile holds more segments per pixel).
fn default_tile() -> u32 {
    8
}
fn default_bins() -> u32 {
    64
}
fn default_pool() -> f32 {
    4.0
}

fn default_k() -> u32 {
    8
}
fn default_nodes_per_pixel() -> f32 {
    16.0
}
fn default_resolve_k() -> u32 {
    32
}
fn default_depth_shift() -> f32 {
    0.05
}
fn default_dbk_nodes() -> f32 {
    8.0
}

impl Default for Transparency {
    /// The strand rasterizer ([`Transparency::strand_raster`]): `pelage bench` and
    /// `pelage lab oit` measure it the fastest hair pass and at least as accurate as the
    /// others.
    fn default() -> Self {
        Self::strand_raster()
    }
}

impl Transparency {
    /// This method sized down to a measured depth complexity, `mean_fragments` hair
    /// fragments per covered pixel: the k-buffer and random subsets get `k` = the mean
    /// rounded up to a power of two, at least 1 and at most their configured `k` (the
    /// k-buffer's tail blends what lies past k, so k near the mean keeps the nearest,
    /// most visible layers exact). The linked-list
    /// methods are returned as they are: their pools are averaged over the whole screen
    /// and report their own overflow ([`crate::Transparency::ABuffer`]).
    pub fn sized_for_depth(&self, mean_fragments: f64) -> Self {
        let wanted = |configured: u32| {
            if mean_fragments.is_finite() && mean_fragments > 1.0 {
                (mean_fragments.ceil().min(f64::from(MAX_OIT_K)) as u32)
                    .next_power_of_two()
                    .min(configured)
            } else if mean_fragments.is_finite() {
                1
            } else {
                configured
            }
        };
        match self {
            Self::KBuffer { k } => Self::KBuffer { k: wanted(*k) },
            Self::RandomSubsets { k } => Self::RandomSubsets { k: wanted(*k) },
            other => other.clone(),
        }
    }

    /// Every method at the defaults the command line, the viewer, the browser demo and
    /// the bench use (the k-buffer and random subsets with 8, the DBK-buffer with a depth
    /// shift of 0.05, the others at their constructors' defaults), in the enum's order.
    /// [`Transparency::by_name`] looks them up by name.
    pub fn defaults() -> [Self; 7] {
        std::array::from_fn(|row| Self::default_of(row).unwrap_or_default())
    }

    /// The method called `name` ([`Transparency::name`]: `opaque`, `wboit`, `k_buffer`,
    /// `a_buffer`, `dbk`, `random_subsets`, `strand_raster`, or an alias of the table
    /// [`Named::NAMES`]) at its defaults ([`Transparency::defaults`]); `None` for any
    /// other name.
    pub fn by_name(name: &str) -> Option<Self> {
        Self::named(name)
    }

    /// Weighted blended OIT with the paper's eq. 7.
    pub fn wboit() -> Self {
        Self::Wboit {
            weight: WboitWeight::default(),
        }
    }

    /// The k-buffer with `k` fragments per pixel.
    pub fn k_buffer(k: u32) -> Self {
        Self::KBuffer { k }
    }

    /// The A-buffer with its default pool (16 nodes per pixel) and resolve depth (32).
    pub fn a_buffer() -> Self {
        Self::ABuffer {
            nodes_per_pixel: default_nodes_per_pixel(),
            resolve_k: default_resolve_k(),
        }
    }

    /// The DBK-buffer with layer thickness `depth_shift`.
    pub fn dbk(depth_shift: f32) -> Self {
        Self::Dbk {
            depth_shift,
            nodes_per_pixel: default_dbk_nodes(),
            resolve_k: default_resolve_k(),
        }
    }

    /// Random subsets with `k` subsets.
    pub fn random_subsets(k: u32) -> Self {
        Self::RandomSubsets { k }
    }

    /// The strand rasterizer with its default tile (8 px), bins (64) and pool (4
    /// references per segment): the OIT lab's sweep (`pelage lab oit`) found 64 bins
    /// the most accurate everywhere; tiles of 8 halve the main job's shade stage against
    /// 16 (docs/src/strand-raster.md).
    pub fn strand_raster() -> Self {
        Self::StrandRaster {
            tile: default_tile(),
            bins: default_bins(),
            pool: default_pool(),
        }
    }

    /// Whether the method draws into reverse-Z targets itself. The k-buffer, A-buffer,
    /// DBK-buffer and random subsets test fragments against the opaque depth in the shader
    /// one way only: pelage-shade refuses reversed depth for them, and pelage's `Frame`
    /// draws them into standard-depth targets of its own between the caller's reversed
    /// ones (the facade's `tests/bridge.rs` checks this list against pelage-shade).
    pub fn draws_reverse_z(&self) -> bool {
        !matches!(
            self,
            Self::KBuffer { .. }
                | Self::ABuffer { .. }
                | Self::Dbk { .. }
                | Self::RandomSubsets { .. }
        )
    }

    /// Short name, as in file names and the lab's tables (`opaque`, `wboit`, `k_buffer`,
    /// ...): its row of [`Named::NAMES`].
    pub fn name(&self) -> &'static str {
        self.method_name()
    }

    /// Name with its parameters, e.g. `k_buffer k=8`.
    pub fn label(&self) -> String {
        match self {
            Self::Opaque => "opaque".into(),
            Self::Wboit { weight } => format!("wboit {weight:?}").to_lowercase(),
            Self::KBuffer { k } => format!("k_buffer k={k}"),
            Self::ABuffer {
                nodes_per_pixel,
                resolve_k,
            } => format!("a_buffer pool={nodes_per_pixel}/px resolve={resolve_k}"),
            Self::Dbk {
                depth_shift,
                nodes_per_pixel,
                ..
            } => format!("dbk shift={depth_shift} pool={nodes_per_pixel}/px"),
            Self::RandomSubsets { k } => format!("random_subsets k={k}"),
            Self::StrandRaster { tile, bins, pool } => {
                format!("strand_raster tile={tile} bins={bins} pool={pool}/seg")
            }
        }
    }

    /// Checks the pools against their floors, [`MIN_POOL`] and
    /// [`MIN_NODES_PER_PIXEL`]: what a scene may ask for. ([`Transparency::validate`]
    /// accepts smaller pools, which a program may want to see overflow; a frame that
    /// overflows counts what it dropped.) The error names `transparency.pool` or
    /// `transparency.nodes_per_pixel` and the allowed range.
    pub fn validate_pools(&self) -> Result<(), ParamError> {
        self.validate()?;
        let (name, value, floor, unit) = match *self {
            Self::StrandRaster { pool, .. } => (
                "transparency.pool",
                pool,
                MIN_POOL,
                "1024] references per segment: every segment on screen takes at least one",
            ),
            Self::ABuffer {
                nodes_per_pixel, ..
            }
            | Self::Dbk {
                nodes_per_pixel, ..
            } => (
                "transparency.nodes_per_pixel",
                nodes_per_pixel,
                MIN_NODES_PER_PIXEL,
                "4096] nodes per pixel: fewer than one cannot hold one layer of hair over \
                 the screen",
            ),
            _ => return Ok(()),
        };
        if value < floor {
            return Err(ParamError::new(
                name,
                value,
                &format!("must be in [{floor}, {unit}; a smaller pool drops most of the hair"),
            ));
        }
        Ok(())
    }

    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ParamError> {
        let k_range = |name: &str, k: u32| {
            if (1..=MAX_OIT_K).contains(&k) {
                Ok(())
            } else {
                Err(ParamError::new(
                    name,
                    k,
                    &format!("must be in 1..={MAX_OIT_K}"),
                ))
            }
        };
        let pool = |name: &str, n: f32| {
            positive(name, n)?;
            if n > 4096.0 {
                return Err(ParamError::new(
                    name,
                    n,
                    "must be at most 4096 nodes per pixel",
                ));
            }
            Ok(())
        };
        match *self {
            Self::Opaque | Self::Wboit { .. } => Ok(()),
            Self::KBuffer { k } => k_range("transparency.k", k),
            Self::RandomSubsets { k } => k_range("transparency.k", k),
            Self::StrandRaster { tile, bins, pool } => {
                if tile != 8 && tile != 16 {
                    return Err(ParamError::new(
                        "transparency.tile",
                        tile,
                        "must be 8 or 16 pixels",
                    ));
                }
                if !(1..=256).contains(&bins) {
                    return Err(ParamError::new(
                        "transparency.bins",
                        bins,
                        "must be in 1..=256",
                    ));
                }
                positive("transparency.pool", pool)?;
                if pool > 1024.0 {
                    return Err(ParamError::new(
                        "transparency.pool",
                        pool,
                        "must be at most 1024 references per segment",
                    ));
                }
                Ok(())
            }
            Self::ABuffer {
                nodes_per_pixel,
                resolve_k,
            } => {
                pool("transparency.nodes_per_pixel", nodes_per_pixel)?;
                k_range("transparency.resolve_k", resolve_k)
            }
            Self::Dbk {
                depth_shift,
                nodes_per_pixel,
                resolve_k,
            } => {
                positive("transparency.depth_shift", depth_shift)?;
                pool("transparency.nodes_per_pixel", nodes_per_pixel)?;
                k_range("transparency.resolve_k", resolve_k)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_method_is_found_by_its_name_once_and_validates() {
        let defaults = Transparency::defaults();
        for method in &defaults {
            assert_eq!(Transparency::by_name(method.name()).as_ref(), Some(method));
            assert_eq!(
                defaults
                    .iter()
                    .filter(|m| m.name() == method.name())
                    .count(),
                1,
                "{} listed twice",
                method.name()
            );
            method.validate().unwrap();
        }
        assert_eq!(Transparency::by_name("k-buffer"), None);
        assert_eq!(Transparency::by_name(""), None);
    }
}
