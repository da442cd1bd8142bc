//! Guide strands: how a groom's strands, taken as guides, are interpolated into render
//! strands on the mesh (`pelage_strands::GuideStrands`; the `guides` key of a scene's
//! `[groom]` table).

use serde::{Deserialize, Serialize};

use crate::ParamError;
use crate::params::{finite, non_negative, positive};

/// The most guides one render strand blends.
pub const MAX_GUIDE_NEIGHBOURS: u32 = 4;

/// The most guides a groom may have when it is interpolated (guide indices are stored
/// in 16 bits per render strand).
pub const MAX_GUIDES: u32 = 1 << 16;

/// How render strands are interpolated from guides: how many, how many guides each
/// blends, how much they clump toward their nearest guide and how much per-strand noise
/// they get. Roots are placed on the mesh by `hair.roots` (its seed and density map;
/// `strands` replaces its count).
///
/// In a scene file: `[groom]` `guides = { strands = 20000, clump = 0.3, noise = 0.1 }`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GuideParams {
    /// Render strands rooted on the mesh (at least 1).
    pub strands: u32,
    /// Guides each render strand blends: the `k` whose roots are nearest its root,
    /// weighted by inverse distance (1 to [`MAX_GUIDE_NEIGHBOURS`]; the default 4).
    pub k: u32,
    /// Clumping toward the nearest guide, in [0, 1]: at parameter `s` along the strand
    /// the blended strand moves a fraction `clump · s` of the way to that guide (0: a
    /// pure blend; 1: the tips meet the guide's tip).
    pub clump: f32,
    /// Per-strand noise, >= 0 (at most 1): each strand drifts from the blend along a
    /// direction drawn from its seed by `noise · length · s²` (0 at the root, `noise`
    /// times the strand's length at the tip, per axis).
    pub noise: f32,
    /// The farthest a guide's root may be from the mesh, as a fraction of the mesh's
    /// bounding box diagonal (> 0; the default 0.05): a guide beyond it is an error,
    /// since render strands are rooted on the mesh.
    pub max_root_distance: f32,
}

impl Default for GuideParams {
    fn default() -> Self {
        Self {
            strands: 20_000,
            k: MAX_GUIDE_NEIGHBOURS,
            clump: 0.0,
            noise: 0.0,
            max_root_distance: 0.05,
        }
    }
}

impl GuideParams {
    /// Checks every field; the error names the first bad one (`guides.<field>`).
    pub fn validate(&self) -> Result<(), ParamError> {
        if self.strands == 0 {
            return Err(ParamError::new(
                "guides.strands",
                self.strands,
                "must be at least 1",
            ));
        }
        if self.k == 0 || self.k > MAX_GUIDE_NEIGHBOURS {
            return Err(ParamError::new(
                "guides.k",
                self.k,
                &format!("must be in 1..={MAX_GUIDE_NEIGHBOURS}"),
            ));
        }
        finite("guides.clump", self.clump)?;
        if !(0.0..=1.0).contains(&self.clump) {
            return Err(ParamError::new(
                "guides.clump",
                self.clump,
                "must be in [0, 1]",
            ));
        }
        non_negative("guides.noise", self.noise)?;
        if self.noise > 1.0 {
            return Err(ParamError::new(
                "guides.noise",
                self.noise,
                "must be in [0, 1] (a fraction of the strand's length)",
            ));
        }
        positive("guides.max_root_distance", self.max_root_distance)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_bad_values_name_the_key() {
        GuideParams::default().validate().unwrap();
        let bad = |p: GuideParams| p.validate().unwrap_err().name;
        let d = GuideParams::default;
        assert_eq!(bad(GuideParams { strands: 0, ..d() }), "guides.strands");
        assert_eq!(bad(GuideParams { k: 0, ..d() }), "guides.k");
        assert_eq!(bad(GuideParams { k: 5, ..d() }), "guides.k");
        assert_eq!(
            bad(GuideParams {
                clump: f32::NAN,
                ..d()
            }),
            "guides.clump"
        );
        assert_eq!(bad(GuideParams { clump: 1.5, ..d() }), "guides.clump");
        assert_eq!(bad(GuideParams { noise: -0.1, ..d() }), "guides.noise");
        assert_eq!(
            bad(GuideParams {
                max_root_distance: 0.0,
                ..d()
            }),
            "guides.max_root_distance"
        );
    }

    #[test]
    fn unknown_keys_are_refused_and_left_out_ones_default() {
        let p: GuideParams = toml::from_str("strands = 300\nclump = 0.5").unwrap();
        assert_eq!((p.strands, p.k, p.clump), (300, 4, 0.5));
        assert!(toml::from_str::<GuideParams>("strand = 3").is_err());
    }
}
