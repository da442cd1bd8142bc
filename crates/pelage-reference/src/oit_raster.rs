//! A CPU rasteriser of hair ribbons: the input of the exact composite
//! ([`crate::oit::composite_sorted`]) that does not come from the GPU's own fragments.
//!
//! The OIT labs and tests used to judge every transparency method against fragments the
//! GPU A-buffer captured, which cannot see a bug the A-buffer shares with the method
//! (a fragment never generated, a wrong alpha, a wrong depth). This module builds the
//! fragments from the geometry alone, on the CPU:
//!
//! 1. **Ribbon expansion**, as `shade/hair.wgsl` documents it: every strand vertex `p_k`
//!    has a tangent along the chord of its neighbours `p_{k+1} - p_{k-1}` (one-sided at
//!    the root and the tip), and the ribbon's edges sit at `p_k ± h_k s_k`, where `s_k`
//!    is the unit vector perpendicular to the tangent and to the direction to the eye
//!    (so the ribbon faces the camera) and `h_k` is half the strand's width there (the
//!    root width scaled linearly towards `tip_width` along the strand parameter
//!    `v_k = k / segments`), widened to half of `min_pixels` pixels at the vertex's
//!    distance from the eye. The fraction of the drawn ribbon the strand really covers,
//!    `true / drawn` half-width, scales alpha (`opacity × coverage`).
//! 2. **Rasterisation**: each segment is the quad between the edges of its two vertices,
//!    split into the triangles (near−, near+, far−) and (far−, near+, far+). Corners are
//!    projected with the camera's view-projection, snapped to a fixed-point grid of
//!    1/256 pixel ([`SUBPIXEL_BITS`], as Mesa's llvmpipe/lavapipe snap), and a sample is
//!    covered when every edge function is positive, or zero on a top or left edge (the
//!    top-left rule), evaluated exactly in integers: a sample on an edge two triangles
//!    share is covered once. Samples sit at pixel centres ([`SamplePattern::CENTRE`]) or
//!    on a regular grid inside the pixel ([`SamplePattern::grid`]).
//! 3. **Attributes**, interpolated perspective-correctly with the barycentrics of the
//!    snapped triangle: the view depth (clip `w`, the sort key) and the coverage.
//!    Colour is the strand's own, flat: the test renders with flat, unlit shading so
//!    that the comparison isolates visibility and compositing.
//!
//! Nothing here clips: a strand whose ribbon leaves the depth range (or comes behind
//! the eye) is refused with an error, while corners beyond the sides of the screen are
//! fine (samples outside it are not generated). Written from the geometry above, not
//! from the shader's code.

use glam::{Mat4, Vec3, Vec4};
use pelage_scene::CameraMatrices;

use crate::oit::{Fragment, composite_sorted};

/// Sub-pixel precision of the snapped vertex positions: 8 bits, 1/256 pixel.
pub const SUBPIXEL_BITS: u32 = 8;
const SUBPIXEL: f64 = (1u32 << SUBPIXEL_BITS) as f64;

/// One strand: a polyline with a root width and a flat colour.
#[derive(Clone, Debug, PartialEq)]
pub struct RibbonStrand {
    /// Vertices from root to tip, world units; at least two.
    pub points: Vec<Vec3>,
    /// Width at the root, world units (>= 0).
    pub width: f32,
    /// Linear RGB, not premultiplied: every fragment of the strand has it.
    pub color: [f32; 3],
}

/// How strands become ribbons (the fields of `RibbonStyle` in `pelage-shade` that
/// shape and blend them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RibbonStyle {
    /// Width at the tip as a fraction of the root width.
    pub tip_width: f32,
    /// Ribbons are drawn at least this many pixels wide (the transparency methods use
    /// `max(min_pixels, 1)`).
    pub min_pixels: f32,
    /// Alpha of a fragment whose ribbon is the strand's true width.
    pub opacity: f32,
}

/// The camera and the target the ribbons are rasterised for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterView {
    /// World to clip (standard depth: near 0, far 1; or reverse-Z).
    pub view_projection: Mat4,
    /// The eye, world units.
    pub eye: Vec3,
    /// World units per pixel at view distance 1.
    pub pixel_scale: f32,
    /// Target width in pixels.
    pub width: u32,
    /// Target height in pixels.
    pub height: u32,
}

impl RasterView {
    /// The view of `camera` on a `width` x `height` target.
    pub fn new(camera: &CameraMatrices, width: u32, height: u32) -> Self {
        Self {
            view_projection: camera.view_projection(),
            eye: camera.eye(),
            pixel_scale: camera.pixel_scale(height),
            width,
            height,
        }
    }
}

/// Where the samples of a pixel sit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamplePattern {
    /// `grid x grid` samples on a regular grid inside each pixel (1: one sample).
    pub grid: u32,
    /// A shift of every sample, in pixels (`[0, 0]`: the grid is centred in the pixel).
    pub offset: [f32; 2],
}

impl SamplePattern {
    /// One sample at the pixel centre: what a single-sample GPU target rasterises.
    pub const CENTRE: Self = Self {
        grid: 1,
        offset: [0.0, 0.0],
    };

    /// `n x n` samples evenly spread over the pixel (their mean approximates the pixel's
    /// area average).
    pub fn grid(n: u32) -> Self {
        Self {
            grid: n,
            offset: [0.0, 0.0],
        }
    }

    /// One sample, shifted from the centre by `offset` pixels.
    pub fn shifted(offset: [f32; 2]) -> Self {
        Self { grid: 1, offset }
    }

    fn samples(&self) -> usize {
        (self.grid as usize) * (self.grid as usize)
    }
}

/// What the rasteriser refuses.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum RasterError {
    /// The target has no pixels.
    #[error("target size {width}x{height}: both sides must be at least 1 pixel")]
    ZeroSize {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
    },
    /// A sample pattern with no samples, more than 16 x 16, or a non-finite offset.
    #[error("sample pattern {0:?}: grid must be in 1..=16 and the offset finite")]
    BadPattern(SamplePattern),
    /// The style or the view holds a non-finite or negative value.
    #[error("{name} = {value}: must be finite and >= 0")]
    BadParameter {
        /// Which parameter.
        name: &'static str,
        /// Its value.
        value: f32,
    },
    /// A strand has fewer than two points, a non-finite point, width or colour.
    #[error("strand {strand}: {reason}")]
    BadStrand {
        /// Index of the strand.
        strand: usize,
        /// What is wrong with it.
        reason: String,
    },
    /// A ribbon corner is behind the eye or outside the depth range; the reference does
    /// not clip.
    #[error(
        "strand {strand}, vertex {vertex}: the ribbon leaves the depth range (clip {clip:?}); \
         keep the strands between the near and far planes"
    )]
    OutsideDepthRange {
        /// Index of the strand.
        strand: usize,
        /// Index of the vertex.
        vertex: usize,
        /// The corner in clip space.
        clip: [f32; 4],
    },
    /// The tangent at a vertex points at the eye (or is zero), so no direction faces the
    /// camera.
    #[error(
        "strand {strand}, vertex {vertex}: the tangent is zero or points at the eye; \
         the ribbon has no side"
    )]
    NoSide {
        /// Index of the strand.
        strand: usize,
        /// Index of the vertex.
        vertex: usize,
    },
    /// A screen position does not fit the fixed-point grid.
    #[error("strand {strand}: a ribbon corner projects too far off screen ({x}, {y} pixels)")]
    TooFar {
        /// Index of the strand.
        strand: usize,
        /// Screen x in pixels.
        x: f64,
        /// Screen y in pixels.
        y: f64,
    },
}

/// Every fragment of every sample: `lists[(pixel * samples_per_pixel) + sample]`, pixels
/// row-major from the top-left, unsorted (in the order strands and segments were given).
#[derive(Clone, Debug, PartialEq)]
pub struct FragmentLists {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Samples per pixel.
    pub samples_per_pixel: usize,
    /// Fragments per sample.
    pub lists: Vec<Vec<Fragment>>,
}

impl FragmentLists {
    /// The fragments of each sample of pixel `(x, y)`.
    pub fn pixel(&self, x: u32, y: u32) -> &[Vec<Fragment>] {
        let first = (y as usize * self.width as usize + x as usize) * self.samples_per_pixel;
        &self.lists[first..first + self.samples_per_pixel]
    }

    /// The exact composite of every sample over `background` (linear RGB), averaged per
    /// pixel (a box filter): linear RGB, row-major.
    pub fn composite(&self, background: [f32; 3]) -> Vec<[f32; 3]> {
        let n = self.samples_per_pixel.max(1);
        self.lists
            .chunks(n)
            .map(|samples| {
                let mut sum = [0.0f64; 3];
                for list in samples {
                    let c = composite_sorted(&mut list.clone(), background);
                    for (s, v) in sum.iter_mut().zip(c) {
                        *s += f64::from(v);
                    }
                }
                sum.map(|s| (s / n as f64) as f32)
            })
            .collect()
    }

    /// Fragments per pixel (the most of any of its samples).
    pub fn depth_complexity(&self) -> Vec<usize> {
        self.lists
            .chunks(self.samples_per_pixel.max(1))
            .map(|s| s.iter().map(Vec::len).max().unwrap_or(0))
            .collect()
    }
}

/// A ribbon corner after projection: fixed-point screen position, clip w, coverage.
#[derive(Clone, Copy, Debug)]
struct Corner {
    x: i64,
    y: i64,
    w: f64,
    coverage: f64,
}

/// Rasterises `strands` as camera-facing ribbons (see the module documentation) with
/// the samples of `pattern`, keeping every fragment of every sample.
pub fn rasterize(
    strands: &[RibbonStrand],
    style: &RibbonStyle,
    view: &RasterView,
    pattern: SamplePattern,
) -> Result<FragmentLists, RasterError> {
    let (width, height) = (view.width, view.height);
    if width == 0 || height == 0 {
        return Err(RasterError::ZeroSize { width, height });
    }
    if pattern.grid == 0 || pattern.grid > 16 || !pattern.offset.iter().all(|o| o.is_finite()) {
        return Err(RasterError::BadPattern(pattern));
    }
    for (name, value) in [
        ("style.tip_width", style.tip_width),
        ("style.min_pixels", style.min_pixels),
        ("style.opacity", style.opacity),
        ("view.pixel_scale", view.pixel_scale),
    ] {
        if !value.is_finite() || value < 0.0 {
            return Err(RasterError::BadParameter { name, value });
        }
    }
    let spp = pattern.samples();
    let mut lists = vec![Vec::new(); width as usize * height as usize * spp];
    // Sample positions inside a pixel, in fixed point relative to its top-left corner.
    let n = f64::from(pattern.grid);
    let mut offsets = Vec::with_capacity(spp);
    for j in 0..pattern.grid {
        for i in 0..pattern.grid {
            let sx = (f64::from(i) + 0.5) / n + f64::from(pattern.offset[0]);
            let sy = (f64::from(j) + 0.5) / n + f64::from(pattern.offset[1]);
            offsets.push((
                (sx * SUBPIXEL).round() as i64,
                (sy * SUBPIXEL).round() as i64,
            ));
        }
    }
    let raster = Raster {
        width: i64::from(width),
        height: i64::from(height),
        offsets,
    };
    for (index, strand) in strands.iter().enumerate() {
        check_strand(index, strand)?;
        let corners = ribbon_corners(index, strand, style, view)?;
        let alpha = f64::from(style.opacity);
        for pair in corners.windows(2) {
            let ([a_minus, a_plus], [b_minus, b_plus]) = (pair[0], pair[1]);
            for tri in [[a_minus, a_plus, b_minus], [b_minus, a_plus, b_plus]] {
                raster.triangle(tri, |sample, depth, coverage| {
                    lists[sample].push(Fragment {
                        depth: depth as f32,
                        color: strand.color,
                        alpha: (alpha * coverage) as f32,
                    });
                });
            }
        }
    }
    Ok(FragmentLists {
        width,
        height,
        samples_per_pixel: spp,
        lists,
    })
}

fn check_strand(index: usize, strand: &RibbonStrand) -> Result<(), RasterError> {
    let bad = |reason: String| {
        Err(RasterError::BadStrand {
            strand: index,
            reason,
        })
    };
    if strand.points.len() < 2 {
        return bad(format!(
            "{} points; a strand needs at least 2",
            strand.points.len()
        ));
    }
    if let Some(k) = strand.points.iter().position(|p| !p.is_finite()) {
        return bad(format!("point {k} is {:?}", strand.points[k]));
    }
    if !strand.width.is_finite() || strand.width < 0.0 {
        return bad(format!("width {} must be finite and >= 0", strand.width));
    }
    if !strand.color.iter().all(|c| c.is_finite()) {
        return bad(format!("colour {:?} must be finite", strand.color));
    }
    Ok(())
}

/// The two edge corners (−side, +side) of every vertex of `strand`, projected.
fn ribbon_corners(
    index: usize,
    strand: &RibbonStrand,
    style: &RibbonStyle,
    view: &RasterView,
) -> Result<Vec<[Corner; 2]>, RasterError> {
    let points = &strand.points;
    let last = points.len() - 1;
    let mut out = Vec::with_capacity(points.len());
    for (k, &p) in points.iter().enumerate() {
        // Work in f64: the reference's own rounding stays far below the GPU's.
        let p = p.as_dvec3();
        let chord = points[(k + 1).min(last)].as_dvec3() - points[k.saturating_sub(1)].as_dvec3();
        let to_eye = view.eye.as_dvec3() - p;
        let side = chord.cross(to_eye);
        let side_len = side.length();
        let scale = chord.length() * to_eye.length();
        if scale == 0.0 || side_len.is_nan() || side_len <= 1e-9 * scale {
            return Err(RasterError::NoSide {
                strand: index,
                vertex: k,
            });
        }
        let side = side / side_len;
        let v = k as f64 / last as f64;
        let true_half =
            0.5 * f64::from(strand.width) * (1.0 + (f64::from(style.tip_width) - 1.0) * v);
        let least_half =
            0.5 * f64::from(style.min_pixels) * f64::from(view.pixel_scale) * to_eye.length();
        let half = true_half.max(least_half);
        let coverage = if half > 0.0 {
            (true_half / half).clamp(0.0, 1.0)
        } else {
            1.0
        };
        let mut pair = [None, None];
        for (slot, sign) in pair.iter_mut().zip([-1.0, 1.0]) {
            let world = p + side * (half * sign);
            *slot = Some(project(index, k, world, coverage, view)?);
        }
        if let [Some(minus), Some(plus)] = pair {
            out.push([minus, plus]);
        }
    }
    Ok(out)
}

fn project(
    strand: usize,
    vertex: usize,
    world: glam::DVec3,
    coverage: f64,
    view: &RasterView,
) -> Result<Corner, RasterError> {
    let clip = view.view_projection.as_dmat4() * world.extend(1.0);
    let outside = || RasterError::OutsideDepthRange {
        strand,
        vertex,
        clip: Vec4::new(clip.x as f32, clip.y as f32, clip.z as f32, clip.w as f32).to_array(),
    };
    if clip.w.is_nan() || clip.w <= 0.0 || clip.z.is_nan() || clip.z < 0.0 || clip.z > clip.w {
        return Err(outside());
    }
    let sx = (clip.x / clip.w * 0.5 + 0.5) * f64::from(view.width);
    let sy = (0.5 - clip.y / clip.w * 0.5) * f64::from(view.height);
    // Keep the integer edge functions far from overflow: +-2^24 pixels.
    let limit = f64::from(1u32 << 24);
    if sx.is_nan() || sy.is_nan() || sx.abs() >= limit || sy.abs() >= limit {
        return Err(RasterError::TooFar {
            strand,
            x: sx,
            y: sy,
        });
    }
    Ok(Corner {
        x: (sx * SUBPIXEL).round() as i64,
        y: (sy * SUBPIXEL).round() as i64,
        w: clip.w,
        coverage,
    })
}

struct Raster {
    width: i64,
    height: i64,
    /// Sample positions in a pixel, fixed point from its top-left corner.
    offsets: Vec<(i64, i64)>,
}

/// Twice the signed area of (a, b, p), in fixed point squared (exact).
fn edge(a: (i64, i64), b: (i64, i64), p: (i64, i64)) -> i64 {
    (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0)
}

/// Whether the edge a -> b of a triangle wound with positive [`edge`] area (clockwise on
/// a y-down screen) is a top edge (horizontal, the triangle below it) or a left edge.
fn top_left(a: (i64, i64), b: (i64, i64)) -> bool {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    (dy == 0 && dx > 0) || dy < 0
}

impl Raster {
    /// Calls `emit(sample index, view depth, coverage)` for every covered sample.
    fn triangle(&self, tri: [Corner; 3], mut emit: impl FnMut(usize, f64, f64)) {
        let [mut a, mut b, c] = tri;
        let pos = |k: &Corner| (k.x, k.y);
        let mut area = edge(pos(&a), pos(&b), pos(&c));
        if area == 0 {
            return;
        }
        if area < 0 {
            std::mem::swap(&mut a, &mut b);
            area = -area;
        }
        let (pa, pb, pc) = (pos(&a), pos(&b), pos(&c));
        // Bias: a sample exactly on an edge counts only for top and left edges.
        let bias = |from, to| i64::from(!top_left(from, to));
        let (bias_a, bias_b, bias_c) = (bias(pb, pc), bias(pc, pa), bias(pa, pb));
        let unit = 1i64 << SUBPIXEL_BITS;
        let min_x = pa.0.min(pb.0).min(pc.0).div_euclid(unit) - 1;
        let max_x = pa.0.max(pb.0).max(pc.0).div_euclid(unit) + 1;
        let min_y = pa.1.min(pb.1).min(pc.1).div_euclid(unit) - 1;
        let max_y = pa.1.max(pb.1).max(pc.1).div_euclid(unit) + 1;
        let spp = self.offsets.len();
        for py in min_y.max(0)..=max_y.min(self.height - 1) {
            for px in min_x.max(0)..=max_x.min(self.width - 1) {
                for (s, &(ox, oy)) in self.offsets.iter().enumerate() {
                    let p = (px * unit + ox, py * unit + oy);
                    // Weights of a, b, c: the areas of the sub-triangles opposite them.
                    let wa = edge(pb, pc, p);
                    let wb = edge(pc, pa, p);
                    let wc = edge(pa, pb, p);
                    if wa < bias_a || wb < bias_b || wc < bias_c {
                        continue;
                    }
                    // Perspective-correct interpolation: weights over clip w.
                    let (la, lb, lc) = (
                        wa as f64 / area as f64 / a.w,
                        wb as f64 / area as f64 / b.w,
                        wc as f64 / area as f64 / c.w,
                    );
                    let sum = la + lb + lc;
                    let depth = 1.0 / sum;
                    let coverage = (la * a.coverage + lb * b.coverage + lc * c.coverage) / sum;
                    let pixel = (py * self.width + px) as usize;
                    emit(pixel * spp + s, depth, coverage);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pelage_scene::Camera;

    fn view(w: u32, h: u32) -> RasterView {
        let camera = Camera {
            eye: Vec3::new(0.0, 0.0, 3.0),
            target: Vec3::ZERO,
            ..Default::default()
        };
        RasterView::new(&camera.matrices(w, h), w, h)
    }

    fn style() -> RibbonStyle {
        RibbonStyle {
            tip_width: 1.0,
            min_pixels: 1.0,
            opacity: 0.5,
        }
    }

    #[test]
    fn a_straight_strand_of_many_segments_covers_each_sample_once() {
        let v = view(64, 48);
        // A slanted strand in 16 segments: shared edges between the two triangles of a
        // segment and between segments must not cover a sample twice or leave a gap.
        let points = (0..=16)
            .map(|k| {
                let t = k as f32 / 16.0;
                Vec3::new(-0.8 + 1.6 * t, -0.5 + 0.9 * t, 0.1 * t)
            })
            .collect();
        let strands = [RibbonStrand {
            points,
            width: 0.12,
            color: [1.0, 0.0, 0.0],
        }];
        for pattern in [SamplePattern::CENTRE, SamplePattern::grid(4)] {
            let lists = rasterize(&strands, &style(), &v, pattern).unwrap();
            let counts: Vec<usize> = lists.lists.iter().map(Vec::len).collect();
            assert!(counts.iter().all(|&c| c <= 1), "a sample covered twice");
            let covered = counts.iter().filter(|&&c| c == 1).count();
            // About length x width in samples.
            let px_per_unit = 1.0 / (v.pixel_scale * 3.0);
            let expected =
                1.6f32.hypot(0.9) * 0.12 * px_per_unit * px_per_unit * pattern.samples() as f32;
            let ratio = covered as f32 / expected;
            assert!(
                (0.9..1.1).contains(&ratio),
                "{covered} samples, expected about {expected}"
            );
            for f in lists.lists.iter().flatten() {
                assert!((f.alpha - 0.5).abs() < 1e-6);
                assert!((2.8..3.2).contains(&f.depth), "depth {}", f.depth);
            }
        }
    }

    #[test]
    fn a_thin_strand_is_widened_and_fades() {
        let v = view(64, 48);
        let pixel = v.pixel_scale * 3.0;
        let strands = [RibbonStrand {
            points: vec![Vec3::new(-0.5, 0.0, 0.0), Vec3::new(0.5, 0.0, 0.0)],
            width: 0.25 * pixel,
            color: [0.0, 1.0, 0.0],
        }];
        let lists = rasterize(&strands, &style(), &v, SamplePattern::grid(4)).unwrap();
        let mut alpha_area = 0.0;
        for f in lists.lists.iter().flatten() {
            // A quarter of the 1-pixel-wide ribbon (the distance varies a little).
            assert!((f.alpha - 0.125).abs() < 0.005, "alpha {}", f.alpha);
            alpha_area += f64::from(f.alpha) / 16.0;
        }
        // Opacity x true width x length, in pixels.
        let expected = 0.5 * 0.25 * (1.0 / pixel);
        assert!((alpha_area / f64::from(expected) - 1.0).abs() < 0.05);
    }

    #[test]
    fn crossing_strands_sort_by_depth() {
        let v = view(32, 32);
        let near = RibbonStrand {
            points: vec![Vec3::new(-0.5, 0.0, 0.5), Vec3::new(0.5, 0.0, 0.5)],
            width: 0.2,
            color: [1.0, 0.0, 0.0],
        };
        let far = RibbonStrand {
            points: vec![Vec3::new(0.0, -0.5, -0.5), Vec3::new(0.0, 0.5, -0.5)],
            width: 0.2,
            color: [0.0, 0.0, 1.0],
        };
        let style = RibbonStyle {
            opacity: 1.0,
            ..style()
        };
        // Given far first, the near strand still wins where they cross.
        let lists = rasterize(&[far, near], &style, &v, SamplePattern::CENTRE).unwrap();
        let image = lists.composite([0.0; 3]);
        let centre = image[16 * 32 + 16];
        assert_eq!(centre, [1.0, 0.0, 0.0]);
        let depths = &lists.pixel(16, 16)[0];
        assert_eq!(depths.len(), 2);
        assert!((depths[0].depth - 3.5).abs() < 1e-3 && (depths[1].depth - 2.5).abs() < 1e-3);
    }

    #[test]
    fn bad_input_is_refused() {
        let v = view(16, 16);
        let strand = RibbonStrand {
            points: vec![Vec3::ZERO],
            width: 0.1,
            color: [1.0; 3],
        };
        let err = rasterize(&[strand], &style(), &v, SamplePattern::CENTRE).unwrap_err();
        assert!(
            matches!(err, RasterError::BadStrand { strand: 0, .. }),
            "{err}"
        );
        // Behind the eye.
        let behind = RibbonStrand {
            points: vec![Vec3::new(0.0, 0.0, 4.0), Vec3::new(0.1, 0.0, 4.0)],
            width: 0.1,
            color: [1.0; 3],
        };
        let err = rasterize(&[behind], &style(), &v, SamplePattern::CENTRE).unwrap_err();
        assert!(
            matches!(err, RasterError::OutsideDepthRange { .. }),
            "{err}"
        );
        // Pointing at the eye.
        let axial = RibbonStrand {
            points: vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0)],
            width: 0.1,
            color: [1.0; 3],
        };
        let err = rasterize(&[axial], &style(), &v, SamplePattern::CENTRE).unwrap_err();
        assert!(matches!(err, RasterError::NoSide { .. }), "{err}");
        let err = rasterize(&[], &style(), &v, SamplePattern::grid(0)).unwrap_err();
        assert!(matches!(err, RasterError::BadPattern(_)));
    }
}
