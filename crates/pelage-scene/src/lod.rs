//! Level of detail: stochastic simplification (seed 002 after Cook et al. 2007) and
//! segment reduction, driven by the hair's size on screen.

use serde::{Deserialize, Serialize};

use crate::ParamError;
use crate::params::{finite, positive};

/// How much of the groom is grown and drawn for the hair's size on screen.
///
/// Stochastic simplification keeps a random subset of the strands (they are stored in
/// random order, so the subset is a prefix) and widens the kept ones so the covered
/// area, and with it the shadow density and the image's mean, stays the same. The
/// fraction kept is `λ = b^(log_h ½)` for `b = B / B0 < 1`, where `B` is the number of
/// screen pixels the hair's bounding box covers; strands near the cut shrink to zero
/// across a transition zone instead of popping. Shadows read the same strands, so the
/// shadow pass is simplified with the image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LodParams {
    /// Simplify at all. Off by default: every strand and segment is grown and drawn.
    pub enabled: bool,
    /// `B0`: screen pixels covered by the hair's bounding box below which simplification
    /// starts (> 0). At or above it every strand is drawn.
    pub start_pixels: f32,
    /// `h` in (0, 0.5]: at `h · B0` pixels half of the strands are drawn. 0.5 makes `λ`
    /// linear in the covered area; smaller values simplify slowly at first, then fast.
    pub half_at: f32,
    /// Transition zone `t` in (0, 0.5]: the fraction of the priority order over which a
    /// strand shrinks from full width to nothing on either side of the cut (seed 002
    /// uses 0.1).
    pub transition: f32,
    /// Smallest `λ` ever used, in (0, 1]: seed 002 finds area preservation fails and
    /// contrast rises when fewer than about 10% of the strands are drawn.
    pub min_fraction: f32,
    /// Largest distance in pixels between a strand and its simplified polyline when
    /// segments are merged (segment reduction), as predicted by a curvature bound that
    /// overestimates 2 to 3 times (`tests/lod.rs` in pelage-strands measures it); 0
    /// keeps every segment.
    pub segment_error_pixels: f32,
}

impl Default for LodParams {
    fn default() -> Self {
        Self {
            enabled: false,
            start_pixels: 60_000.0,
            half_at: 0.3,
            transition: 0.1,
            min_fraction: 0.1,
            segment_error_pixels: 0.5,
        }
    }
}

impl LodParams {
    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ParamError> {
        positive("lod.start_pixels", self.start_pixels)?;
        for (name, v, what) in [
            ("lod.half_at", self.half_at, "must be in (0, 0.5]"),
            ("lod.transition", self.transition, "must be in (0, 0.5]"),
        ] {
            finite(name, v)?;
            if !(v > 0.0 && v <= 0.5) {
                return Err(ParamError::new(name, v, what));
            }
        }
        finite("lod.min_fraction", self.min_fraction)?;
        if !(self.min_fraction > 0.0 && self.min_fraction <= 1.0) {
            return Err(ParamError::new(
                "lod.min_fraction",
                self.min_fraction,
                "must be in (0, 1]",
            ));
        }
        finite("lod.segment_error_pixels", self.segment_error_pixels)?;
        if self.segment_error_pixels < 0.0 {
            return Err(ParamError::new(
                "lod.segment_error_pixels",
                self.segment_error_pixels,
                "must be at least 0 (0 keeps every segment)",
            ));
        }
        Ok(())
    }

    /// `λ` in [`min_fraction`, 1] for a bounding box covering `pixels` screen pixels
    /// (1 when disabled). Seed 002 eq. 4.1, clamped.
    pub fn lambda(&self, pixels: f32) -> f32 {
        if !self.enabled || !pixels.is_finite() || pixels >= self.start_pixels {
            return 1.0;
        }
        let b = (pixels / self.start_pixels).max(0.0);
        // b^(log_h ½) = b^(ln ½ / ln h).
        let lambda = b.powf(0.5f32.ln() / self.half_at.ln());
        lambda.clamp(self.min_fraction, 1.0)
    }
}

/// Seed 002's transition zone for one `λ` and `t` (eqs. 4.3 to 4.7): the width scale
/// `s(x)` of the strand at position `x` in [0, 1] of the priority order.
///
/// `∫₀¹ s(x) dx = 1` for every `λ` in (0, 1] and `t` in (0, 0.5]: the widened strands
/// cover the area all strands covered.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transition {
    /// `λ`, the fraction of strands at full enlargement plus half the zone.
    pub lambda: f32,
    /// `t_e`, the effective half width of the zone.
    pub t_e: f32,
    /// `s_max`, the scale at `x = 0`.
    pub s_max: f32,
    /// `s_min`, the scale at `x = 1`.
    pub s_min: f32,
}

impl Transition {
    /// The zone for `lambda` in (0, 1] and `t` in (0, 0.5] (both clamped into range).
    pub fn new(lambda: f32, t: f32) -> Self {
        let lambda = if lambda.is_finite() {
            lambda.clamp(1e-6, 1.0)
        } else {
            1.0
        };
        let t = if t.is_finite() {
            t.clamp(1e-6, 0.5)
        } else {
            0.1
        };
        let t_e = if lambda - t < 0.0 {
            lambda
        } else if lambda + t > 1.0 {
            1.0 - lambda
        } else {
            t
        };
        let (s_max, s_min) = if lambda + t <= 1.0 {
            (1.0 / lambda, 0.0)
        } else {
            let s_max = 1.0 / (1.0 - t_e * t_e / t);
            (s_max, s_max * (1.0 - t_e / t))
        };
        Self {
            lambda,
            t_e,
            s_max,
            s_min,
        }
    }

    /// No simplification: `s ≡ 1`.
    pub fn full() -> Self {
        Self::new(1.0, 0.1)
    }

    /// `i(x)`: 1 before the zone, 0 after it, linear inside (eq. 4.7).
    pub fn enlargement(&self, x: f32) -> f32 {
        if x <= self.lambda - self.t_e {
            1.0
        } else if x >= self.lambda + self.t_e {
            0.0
        } else {
            (self.lambda + self.t_e - x) / (2.0 * self.t_e)
        }
    }

    /// `s(x) = s_min + (s_max - s_min) · i(x)` (eq. 4.6).
    pub fn scale(&self, x: f32) -> f32 {
        self.s_min + (self.s_max - self.s_min) * self.enlargement(x)
    }

    /// How many of `count` strands (at `x = (i + ½) / count`) have a scale above zero:
    /// the prefix that is grown and drawn.
    pub fn drawn(&self, count: u32) -> u32 {
        if self.s_min > 0.0 {
            return count;
        }
        // Strand i is drawn while (i + ½) / count < λ + t_e.
        let end = f64::from(self.lambda + self.t_e) * f64::from(count) - 0.5;
        let drawn = end.ceil().max(0.0) as u64;
        drawn.clamp(1, u64::from(count)) as u32
    }
}
