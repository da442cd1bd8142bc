//! Level of detail for stage 1: how many strands (stochastic simplification) and how
//! many segments per strand (segment reduction) the hair's size on screen needs.
//!
//! Roots are sampled independently per strand index (`sample_roots`), so the strand
//! order is already random and independent of position: the strands kept at level `λ`
//! are a prefix of the buffer, and every later pass simply draws fewer of them.

use glam::{Vec3, Vec4Swizzles};
use pelage_contract::StrandLayout;
use pelage_scene::{CameraMatrices, GrowthParams, HairParams, HairType, Transition, WindParams};

/// One frame's level of detail.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodLevel {
    /// Screen pixels covered by the hair's bounding box (`B`; infinite when not measured).
    pub pixels: f32,
    /// The larger side of that box on screen, pixels (infinite when not measured).
    pub extent_pixels: f32,
    /// The width scale over the priority order.
    pub zone: Transition,
    /// Strands grown and drawn (those with a width).
    pub strands: u32,
    /// Segments per strand (a divisor of the groom's segment count).
    pub segments: u32,
    /// The largest distance, in pixels, between a strand and its reduced polyline
    /// predicted by the curvature bound (0 at full segments).
    pub segment_error_pixels: f32,
}

impl LodLevel {
    /// Every strand and segment at full width.
    pub fn full(hair: &HairParams) -> Self {
        Self {
            pixels: f32::INFINITY,
            extent_pixels: f32::INFINITY,
            zone: Transition::full(),
            strands: hair.roots.count,
            segments: hair.growth.segments,
            segment_error_pixels: 0.0,
        }
    }

    /// The level `hair.lod` asks for when the hair, inside the world box `bounds`, is seen
    /// through `camera`'s view and projection (any handedness, either depth direction)
    /// on a `width` x `height` target. Full detail when LOD is disabled, when the box
    /// reaches nearer than the near plane, or when anything is not finite (the box's size
    /// on screen is measured either way, unless it reaches nearer than the near plane).
    pub fn for_view(
        hair: &HairParams,
        bounds: (Vec3, Vec3),
        camera: &CameraMatrices,
        width: u32,
        height: u32,
    ) -> Self {
        Self::for_view_with(hair, bounds, camera, width, height, |pixels_per_unit| {
            reduced_segments(
                &hair.growth,
                &hair.wind,
                hair.lod.segment_error_pixels,
                pixels_per_unit,
                max_length_scale(hair),
            )
        })
    }

    /// [`LodLevel::for_view`] with the segment count chosen by `segments`, which is given
    /// the pixels per world unit at the hair's nearest point and returns the count (a
    /// divisor of `hair.growth.segments`) and its predicted error in pixels: how a stage
    /// 1 method whose strands have a shape of their own (a groom file, say) bounds it.
    pub fn for_view_with(
        hair: &HairParams,
        bounds: (Vec3, Vec3),
        camera: &CameraMatrices,
        width: u32,
        height: u32,
        segments: impl FnOnce(f32) -> (u32, f32),
    ) -> Self {
        let full = Self::full(hair);
        if width == 0 || height == 0 {
            return full;
        }
        let Some(view) = ScreenBox::new(bounds, camera, width, height) else {
            return full;
        };
        if !hair.lod.enabled {
            return Self {
                pixels: view.pixels,
                extent_pixels: view.extent,
                ..full
            };
        }
        let lambda = hair.lod.lambda(view.pixels);
        let zone = Transition::new(lambda, hair.lod.transition);
        let (segments, error) = segments(view.pixels_per_unit);
        Self {
            pixels: view.pixels,
            extent_pixels: view.extent,
            zone,
            strands: zone.drawn(hair.roots.count),
            segments,
            segment_error_pixels: error,
        }
    }

    /// The layout this level grows.
    pub fn layout(&self) -> StrandLayout {
        StrandLayout {
            strands: self.strands,
            segments: self.segments,
        }
    }
}

/// The largest value of the length map (1 without one).
fn max_length_scale(hair: &HairParams) -> f32 {
    hair.roots
        .length_scale
        .as_ref()
        .map_or(1.0, |m| m.iter().copied().fold(0.0f32, f32::max))
}

/// A world box as seen on screen.
struct ScreenBox {
    /// Pixels its screen rectangle covers, clipped to the target.
    pixels: f32,
    /// The larger side of its screen rectangle, pixels.
    extent: f32,
    /// Pixels per world unit at its nearest corner.
    pixels_per_unit: f32,
}

impl ScreenBox {
    fn new(bounds: (Vec3, Vec3), camera: &CameraMatrices, width: u32, height: u32) -> Option<Self> {
        let (lo, hi) = bounds;
        if !lo.is_finite() || !hi.is_finite() {
            return None;
        }
        let clip = camera.view_projection();
        let reverse_z = camera.reverse_z();
        let (mut min, mut max) = (glam::Vec2::splat(f32::MAX), glam::Vec2::splat(f32::MIN));
        let mut nearest = f32::MAX;
        for corner in 0..8 {
            let p = Vec3::new(
                if corner & 1 == 0 { lo.x } else { hi.x },
                if corner & 2 == 0 { lo.y } else { hi.y },
                if corner & 4 == 0 { lo.z } else { hi.z },
            );
            // A perspective projection's clip w is the distance along the view axis;
            // a corner nearer than the near plane has clip depth outside [0, w] on the
            // near side (below 0, or above w with reverse-Z).
            let c = clip * p.extend(1.0);
            let before_near = if reverse_z { c.z >= c.w } else { c.z <= 0.0 };
            if c.w <= 0.0 || before_near {
                return None;
            }
            nearest = nearest.min(c.w);
            let ndc = c.xy() / c.w;
            min = min.min(ndc);
            max = max.max(ndc);
        }
        let min = min.clamp(glam::Vec2::splat(-1.0), glam::Vec2::splat(1.0));
        let max = max.clamp(glam::Vec2::splat(-1.0), glam::Vec2::splat(1.0));
        let size = (max - min) * 0.5 * glam::Vec2::new(width as f32, height as f32);
        // Pixels per world unit at distance 1: the projection's focal length in pixels.
        let focal = 1.0 / camera.pixel_scale(height);
        let out = Self {
            pixels: size.x * size.y,
            extent: size.max_element(),
            pixels_per_unit: focal / nearest,
        };
        (out.pixels.is_finite() && out.pixels_per_unit.is_finite()).then_some(out)
    }
}

/// The fewest segments (a divisor of `growth.segments`) whose polyline stays within
/// `max_error_pixels` of the full strand, by a curvature bound: a chord spanning arc
/// length `L` of a curve of curvature `κ` is at most `κL²/8` from it. The curvature is
/// that of the hair type plus the bend the force field puts in every segment, the
/// worst over every region of `growth` (its own length and hair type). Returns
/// the count and its predicted error in pixels.
pub fn reduced_segments(
    growth: &GrowthParams,
    wind: &WindParams,
    max_error_pixels: f32,
    pixels_per_unit: f32,
    length_scale: f32,
) -> (u32, f32) {
    let full = growth.segments;
    let turn = bend_per_segment(growth, wind);
    // Each region's longest segment and the curvature of its hair type.
    let regions: Vec<(f32, f32)> = growth
        .resolved_regions()
        .iter()
        .map(|g| {
            let seg = g.length * (1.0 + g.length_jitter) * length_scale.max(0.0) / full as f32;
            (seg, shape_curvature(g.hair_type))
        })
        .collect();
    fewest_segments(full, max_error_pixels, pixels_per_unit, |k| {
        regions
            .iter()
            .map(|&(seg, curvature)| {
                let span = k as f32 * seg;
                curvature * span * span / 8.0 + bend_error(k, seg, turn)
            })
            .fold(0.0f32, f32::max)
    })
}

/// The largest curvature of a strand of `hair_type`, per scene unit (0 when straight).
fn shape_curvature(hair_type: HairType) -> f32 {
    match hair_type {
        HairType::Straight => 0.0,
        HairType::Wavy {
            amplitude,
            frequency,
        } => {
            let k = std::f32::consts::TAU * frequency;
            k * k * amplitude.abs()
        }
        HairType::Curly { radius, pitch } => {
            let rise = pitch / std::f32::consts::TAU;
            radius.abs() / (radius * radius + rise * rise).max(1e-12)
        }
    }
}

/// The angle, radians, by which the force field can turn a strand from one segment to
/// the next (seed 001's bend: about `force_weight · |F|`, at most a right angle), for
/// the largest force `growth.gravity` and `wind` can make.
pub fn bend_per_segment(growth: &GrowthParams, wind: &WindParams) -> f32 {
    let force = growth.gravity.length()
        + wind.strength * (1.0 + wind.gust_strength.abs())
        + wind.turbulence * 3f32.sqrt();
    (growth.force_weight * force).min(std::f32::consts::FRAC_PI_2)
}

/// The largest distance, world units, between a strand that turns by `turn` radians per
/// segment of length `seg` and the chord that skips `step - 1` of its vertices.
pub fn bend_error(step: u32, seg: f32, turn: f32) -> f32 {
    (step * step) as f32 * seg * turn / 8.0
}

/// The fewest segments, a divisor of `full`, whose error stays within `max_error_pixels`
/// when keeping every `k`-th vertex costs `error_world(k)` world units, and that error in
/// pixels. Full detail when no error is allowed or the scale is not finite.
pub fn fewest_segments(
    full: u32,
    max_error_pixels: f32,
    pixels_per_unit: f32,
    error_world: impl Fn(u32) -> f32,
) -> (u32, f32) {
    if max_error_pixels <= 0.0 || !pixels_per_unit.is_finite() {
        return (full, 0.0);
    }
    let mut best = (full, 0.0);
    for segments in (1..full).rev() {
        if !full.is_multiple_of(segments) {
            continue;
        }
        let e = error_world(full / segments) * pixels_per_unit;
        if !e.is_finite() || e > max_error_pixels {
            break;
        }
        best = (segments, e);
    }
    best
}
