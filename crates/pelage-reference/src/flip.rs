//! LDR-FLIP image difference metric, on the CPU.
//!
//! Andersson, Nilsson, Akenine-Möller, Oskarsson, Åström, Fairchild,
//! "FLIP: A Difference Evaluator for Alternating Images", HPG 2020
//! (<https://research.nvidia.com/publication/2020-07_FLIP>).
//!
//! This mirrors NVIDIA's reference implementation (`NVlabs/flip`, the
//! single-header C++ `FLIP.h`, function by function: `LDR_FLIP`,
//! `setSpatialFilters`, `computeColorDifference`, `setFeatureFilter`,
//! `computeFeatureDifferenceAndFinalError`, and the `color3` colour
//! transforms), in `f32` like the reference. The C++ code applies the
//! contrast sensitivity filters and the feature detectors as *separable*
//! convolutions; the Python reference (`python/flip_api.py`:
//! `compute_ldrflip`, `generate_spatial_filter`, `spatial_filter`,
//! `feature_detection`) applies the same kernels as full 2D convolutions.
//! Both give the same kernels (the 2D kernels are outer products of the
//! 1D ones; the blue-yellow kernel is a sum of two such products), so the
//! results agree to float rounding. Borders are clamp-to-edge
//! (OpenCV's `BORDER_REPLICATE` in Python, `Min(Max(0, x), w - 1)` in C++).
//!
//! Pipeline (paper Section 4, Figure 3), per pixel:
//!
//! 1. Clamp linear RGB to `[0, 1]` (LDR), convert to XYZ and to the
//!    opponent space YCxCz (Section 4.1).
//! 2. Colour pipeline (Section 4.1): filter Y, Cx, Cz with the achromatic,
//!    red-green and blue-yellow contrast sensitivity functions; back to
//!    linear RGB and clamp; to CIELAB; Hunt adjustment; HyAB distance
//!    (Section 4.1.2); raised to `q_c = 0.7` and remapped with
//!    `p_c = 0.4`, `p_t = 0.95` against `c_max`, the compressed HyAB
//!    distance between Hunt-adjusted green and blue.
//! 3. Feature pipeline (Section 4.2): on the normalised luminance, edge
//!    (first Gaussian derivative) and point (second derivative) detectors
//!    with `σ = 0.5 · w · ppd`, `w = 0.082°`; the feature difference is
//!    `(max(|Δedge|, |Δpoint|) / √2)^q_f` with `q_f = 0.5`.
//! 4. Combination (Section 4.3): `ΔE = ΔE_c^(1 − ΔE_f)`.

use std::f32::consts::PI;

/// Pixels per degree of visual angle for the reference's default observer:
/// a 0.7 m wide, 3840 pixel wide monitor seen from 0.7 m
/// (`0.7 · (3840 / 0.7) · π / 180 ≈ 67.02`, `FLIP::calculatePPD` in `FLIP.h`).
pub const DEFAULT_PIXELS_PER_DEGREE: f32 = 0.7 * (3840.0 / 0.7) * (PI / 180.0);

/// Smallest pixels-per-degree [`flip`] accepts (a pixel 100° wide). Far
/// below it the reference's filter construction degenerates in `f32`
/// (`1 / ppd` overflows, `σ²` underflows, and the weights become NaN).
pub const MIN_PIXELS_PER_DEGREE: f32 = 0.01;

/// Largest pixels-per-degree [`flip`] accepts. The filter widths grow
/// linearly with it (a 2703-tap spatial filter at this bound); anything
/// larger is almost certainly a unit mistake (pixels instead of degrees).
pub const MAX_PIXELS_PER_DEGREE: f32 = 10_000.0;

/// `q_c`: exponent compressing the HyAB colour distance (paper Section 4.1.3).
const QC: f32 = 0.7;
/// `p_c`: fraction of `c_max` below which errors map to `[0, p_t]`.
const PC: f32 = 0.4;
/// `p_t`: the error that `p_c · c_max` maps to.
const PT: f32 = 0.95;
/// `w`: peak-to-trough width of the edge detector in degrees (Section 4.2).
const FEATURE_WIDTH_DEGREES: f32 = 0.082;
/// `q_f`: exponent of the feature difference (Section 4.2).
const QF: f32 = 0.5;

// Float literals below keep the reference's digits (they round to the same
// `f32`s as the shorter forms clippy suggests).
/// D65 reference illuminant (`DEFAULT_ILLUMINANT` in `FLIP.h`).
#[allow(clippy::excessive_precision)]
const ILLUMINANT: [f32; 3] = [0.950428545, 1.0, 1.088900371];
/// Its reciprocal, as the reference spells it (`INV_DEFAULT_ILLUMINANT`).
#[allow(clippy::excessive_precision)]
const INV_ILLUMINANT: [f32; 3] = [1.052156925, 1.0, 0.918357670];

// Contrast sensitivity constants `a1, b1, a2, b2` for the achromatic (A),
// red-green (RG) and blue-yellow (BY) channels (paper Section 4.1,
// `GaussianConstants` in `FLIP.h`). A and RG have `a2 = 0`.
const CSF_A1: [f32; 3] = [1.0, 1.0, 34.1];
const CSF_B1: [f32; 3] = [0.0047, 0.0053, 0.04];
const CSF_A2: [f32; 3] = [0.0, 0.0, 13.5];
const CSF_B2: [f32; 3] = [1.0e-5, 1.0e-5, 0.025];

/// Why an image could not be built or compared.
#[derive(Debug, thiserror::Error)]
pub enum FlipError {
    /// One of the dimensions is zero.
    #[error("image is {width}x{height}: FLIP needs at least one pixel; pass the real render size")]
    ZeroSize {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
    },
    /// `width * height` does not fit in memory addressing.
    #[error("image size {width}x{height} overflows usize; use a smaller image")]
    TooLarge {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
    },
    /// The pixel vector does not hold `width * height` pixels.
    #[error(
        "image is {width}x{height} = {expected} pixels but {actual} were given; \
         pass exactly width*height RGB pixels, row-major"
    )]
    PixelCountMismatch {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
        /// `width * height`.
        expected: usize,
        /// Length of the pixel vector.
        actual: usize,
    },
    /// The byte slice does not hold `width * height * 4` bytes.
    #[error(
        "{width}x{height} RGBA8 image needs {expected} bytes but {actual} were given; \
         strip any row padding (wgpu's 256-byte bytes_per_row alignment) before converting"
    )]
    ByteCountMismatch {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
        /// `width * height * 4`.
        expected: usize,
        /// Length of the byte slice.
        actual: usize,
    },
    /// A pixel holds a NaN or an infinity.
    #[error(
        "pixel ({x}, {y}) is {value:?}, not finite; fix the producer (NaN usually means a 0/0 \
         in a shader) or replace non-finite values before comparing"
    )]
    NonFinitePixel {
        /// Column of the offending pixel.
        x: u32,
        /// Row of the offending pixel.
        y: u32,
        /// Its RGB value.
        value: [f32; 3],
    },
    /// Reference and test differ in size.
    #[error(
        "reference is {reference_width}x{reference_height} but test is \
         {test_width}x{test_height}; render both at the same resolution"
    )]
    SizeMismatch {
        /// Reference width.
        reference_width: u32,
        /// Reference height.
        reference_height: u32,
        /// Test width.
        test_width: u32,
        /// Test height.
        test_height: u32,
    },
    /// Pixels per degree is not finite, or outside
    /// [`MIN_PIXELS_PER_DEGREE`, `MAX_PIXELS_PER_DEGREE`].
    #[error(
        "pixels per degree is {0}; it must be finite and within \
         [{MIN_PIXELS_PER_DEGREE}, {MAX_PIXELS_PER_DEGREE}] (use DEFAULT_PIXELS_PER_DEGREE = 67.02 \
         for a 0.7 m wide 4K monitor seen from 0.7 m)"
    )]
    InvalidPixelsPerDegree(f32),
}

/// An RGB image in linear light, row-major, `width * height` pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear RGB, row-major, top row first.
    pub pixels: Vec<[f32; 3]>,
}

impl LinearImage {
    /// Wraps `pixels`, checking that there are exactly `width * height` of
    /// them, that the image is not empty, and that every value is finite.
    pub fn new(width: u32, height: u32, pixels: Vec<[f32; 3]>) -> Result<Self, FlipError> {
        let image = Self {
            width,
            height,
            pixels,
        };
        image.validate()?;
        Ok(image)
    }

    /// From 8-bit sRGB-encoded RGBA bytes (alpha ignored), as read back from
    /// an `Rgba8UnormSrgb` texture: `width * height * 4` bytes, row-major,
    /// no row padding. Decodes with the sRGB transfer function exactly as
    /// the reference does (`color3::sRGBToLinearRGB` on `byte / 255`).
    pub fn from_srgb8_rgba(width: u32, height: u32, bytes: &[u8]) -> Result<Self, FlipError> {
        let count = pixel_count(width, height)?;
        let expected = count
            .checked_mul(4)
            .ok_or(FlipError::TooLarge { width, height })?;
        if bytes.len() != expected {
            return Err(FlipError::ByteCountMismatch {
                width,
                height,
                expected,
                actual: bytes.len(),
            });
        }
        let lut: [f32; 256] = std::array::from_fn(|i| srgb_to_linear(i as f32 / 255.0));
        let pixels = bytes
            .chunks_exact(4)
            .map(|p| {
                [
                    lut[usize::from(p[0])],
                    lut[usize::from(p[1])],
                    lut[usize::from(p[2])],
                ]
            })
            .collect();
        Ok(Self {
            width,
            height,
            pixels,
        })
    }

    /// Checks the invariants [`LinearImage::new`] promises (the fields are
    /// public, so an image may have been built by hand).
    fn validate(&self) -> Result<(), FlipError> {
        let (width, height) = (self.width, self.height);
        let expected = pixel_count(width, height)?;
        if self.pixels.len() != expected {
            return Err(FlipError::PixelCountMismatch {
                width,
                height,
                expected,
                actual: self.pixels.len(),
            });
        }
        if let Some(i) = self
            .pixels
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
        {
            let w = width as usize;
            return Err(FlipError::NonFinitePixel {
                x: (i % w) as u32,
                y: (i / w) as u32,
                value: self.pixels[i],
            });
        }
        Ok(())
    }
}

/// `width * height`, refusing empty and overflowing sizes.
fn pixel_count(width: u32, height: u32) -> Result<usize, FlipError> {
    if width == 0 || height == 0 {
        return Err(FlipError::ZeroSize { width, height });
    }
    (width as usize)
        .checked_mul(height as usize)
        .ok_or(FlipError::TooLarge { width, height })
}

/// Validates both images and that they have the same size.
fn validate_pair(reference: &LinearImage, test: &LinearImage) -> Result<(), FlipError> {
    reference.validate()?;
    test.validate()?;
    if reference.width != test.width || reference.height != test.height {
        return Err(FlipError::SizeMismatch {
            reference_width: reference.width,
            reference_height: reference.height,
            test_width: test.width,
            test_height: test.height,
        });
    }
    Ok(())
}

/// A per-pixel FLIP error map, values in `[0, 1]`, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct FlipMap {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// FLIP error per pixel, row-major, top row first.
    pub values: Vec<f32>,
}

impl FlipMap {
    /// Mean FLIP error (the number the paper and the tool report), summed in
    /// `f64`. NaN for an empty map.
    pub fn mean(&self) -> f64 {
        if self.values.is_empty() {
            return f64::NAN;
        }
        self.values.iter().map(|&v| f64::from(v)).sum::<f64>() / self.values.len() as f64
    }

    /// The `p`-th percentile (`p` in `[0, 100]`, clamped), nearest-rank:
    /// the smallest value such that at least `p`% of the values are `<=` it
    /// (`p = 0` gives the minimum, `p = 100` the maximum). NaN for an empty
    /// map or a NaN `p`.
    pub fn percentile(&self, p: f64) -> f32 {
        percentile_nearest_rank(&self.values, p)
    }
}

/// Nearest-rank percentile of `values` (copied and sorted).
fn percentile_nearest_rank(values: &[f32], p: f64) -> f32 {
    if values.is_empty() || p.is_nan() {
        return f32::NAN;
    }
    let mut sorted = values.to_vec();
    sorted.sort_unstable_by(f32::total_cmp);
    let n = sorted.len();
    let rank = (p.clamp(0.0, 100.0) / 100.0 * n as f64).ceil() as usize;
    let index = rank.clamp(1, n) - 1;
    sorted.get(index).copied().unwrap_or(f32::NAN)
}

/// RMSE over all channels in linear light, and the 99th percentile
/// (nearest-rank) of the per-pixel RMS error over the three channels.
/// No clamping: HDR values count as they are. Both in `f64`.
pub fn rmse_linear(reference: &LinearImage, test: &LinearImage) -> Result<(f64, f64), FlipError> {
    validate_pair(reference, test)?;
    let mut total = 0.0f64;
    let per_pixel: Vec<f64> = reference
        .pixels
        .iter()
        .zip(&test.pixels)
        .map(|(r, t)| {
            let sq: f64 = r
                .iter()
                .zip(t)
                .map(|(&a, &b)| {
                    let d = f64::from(a) - f64::from(b);
                    d * d
                })
                .sum();
            total += sq;
            (sq / 3.0).sqrt()
        })
        .collect();
    let rmse = (total / (3.0 * per_pixel.len() as f64)).sqrt();
    let mut sorted = per_pixel;
    sorted.sort_unstable_by(f64::total_cmp);
    let n = sorted.len();
    let rank = (0.99 * n as f64).ceil() as usize;
    let p99 = sorted
        .get(rank.clamp(1, n) - 1)
        .copied()
        .unwrap_or(f64::NAN);
    Ok((rmse, p99))
}

/// LDR-FLIP of `test` against `reference` (reference: `FLIP::evaluate` with
/// `useHDR = false`, i.e. `image<float>::LDR_FLIP`). Both images are linear
/// RGB; values are clamped to `[0, 1]` first, as the reference does.
/// `pixels_per_degree` sets the observer ([`DEFAULT_PIXELS_PER_DEGREE`] for
/// the reference's default).
pub fn flip(
    reference: &LinearImage,
    test: &LinearImage,
    pixels_per_degree: f32,
) -> Result<FlipMap, FlipError> {
    validate_pair(reference, test)?;
    if !(MIN_PIXELS_PER_DEGREE..=MAX_PIXELS_PER_DEGREE).contains(&pixels_per_degree) {
        return Err(FlipError::InvalidPixelsPerDegree(pixels_per_degree));
    }
    let width = reference.width as usize;
    let height = reference.height as usize;

    // `evaluate`: clamp to [0, 1]; `LDR_FLIP`: linear RGB -> YCxCz.
    let to_opponent = |img: &LinearImage| -> Vec<[f32; 3]> {
        img.pixels
            .iter()
            .map(|p| xyz_to_ycxcz(linear_rgb_to_xyz(p.map(|c| c.clamp(0.0, 1.0)))))
            .collect()
    };
    let reference_opponent = to_opponent(reference);
    let test_opponent = to_opponent(test);

    let spatial = SpatialFilters::new(pixels_per_degree);
    let mut values = color_difference(&reference_opponent, &test_opponent, width, height, &spatial);
    let feature = feature_filter(pixels_per_degree);
    feature_difference_and_final_error(
        &reference_opponent,
        &test_opponent,
        width,
        height,
        &feature,
        &mut values,
    );
    Ok(FlipMap {
        width: reference.width,
        height: reference.height,
        values,
    })
}

// ---------------------------------------------------------------------------
// Colour transforms (`color3` in FLIP.h; `color_space_transform` in Python).
// ---------------------------------------------------------------------------

/// `color3::sRGBToLinearRGB`.
fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// `color3::LinearRGBToXYZ` (D65; constants from image-engineering.de, as
/// the reference spells them).
fn linear_rgb_to_xyz(c: [f32; 3]) -> [f32; 3] {
    const A11: f32 = 10_135_552.0 / 24_577_794.0;
    const A12: f32 = 8_788_810.0 / 24_577_794.0;
    const A13: f32 = 4_435_075.0 / 24_577_794.0;
    const A21: f32 = 2_613_072.0 / 12_288_897.0;
    const A22: f32 = 8_788_810.0 / 12_288_897.0;
    const A23: f32 = 887_015.0 / 12_288_897.0;
    const A31: f32 = 1_425_312.0 / 73_733_382.0;
    const A32: f32 = 8_788_810.0 / 73_733_382.0;
    const A33: f32 = 70_074_185.0 / 73_733_382.0;
    [
        A11 * c[0] + A12 * c[1] + A13 * c[2],
        A21 * c[0] + A22 * c[1] + A23 * c[2],
        A31 * c[0] + A32 * c[1] + A33 * c[2],
    ]
}

/// `color3::XYZToLinearRGB` (the inverse matrix, as the reference spells it).
#[allow(clippy::excessive_precision)]
fn xyz_to_linear_rgb(c: [f32; 3]) -> [f32; 3] {
    const A11: f32 = 3.241003275;
    const A12: f32 = -1.537398934;
    const A13: f32 = -0.498615861;
    const A21: f32 = -0.969224334;
    const A22: f32 = 1.875930071;
    const A23: f32 = 0.041554224;
    const A31: f32 = 0.055639423;
    const A32: f32 = -0.204011202;
    const A33: f32 = 1.057148933;
    [
        A11 * c[0] + A12 * c[1] + A13 * c[2],
        A21 * c[0] + A22 * c[1] + A23 * c[2],
        A31 * c[0] + A32 * c[1] + A33 * c[2],
    ]
}

/// `color3::XYZToYCxCz`: the linearised CIELAB opponent space (paper
/// Section 4.1, after Kolpatzik and Bouman).
fn xyz_to_ycxcz(c: [f32; 3]) -> [f32; 3] {
    let x = c[0] * INV_ILLUMINANT[0];
    let y = c[1] * INV_ILLUMINANT[1];
    let z = c[2] * INV_ILLUMINANT[2];
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

/// `color3::YCxCzToXYZ`.
fn ycxcz_to_xyz(c: [f32; 3]) -> [f32; 3] {
    let y = (c[0] + 16.0) / 116.0;
    let cx = c[1] / 500.0;
    let cz = c[2] / 200.0;
    [
        (y + cx) * ILLUMINANT[0],
        y * ILLUMINANT[1],
        (y - cz) * ILLUMINANT[2],
    ]
}

/// `color3::XYZToCIELab` (D65).
fn xyz_to_cielab(c: [f32; 3]) -> [f32; 3] {
    const DELTA: f32 = 6.0 / 29.0;
    let delta_cube = DELTA * DELTA * DELTA;
    let factor = 1.0 / (3.0 * DELTA * DELTA);
    let term = 4.0 / 29.0;
    let f = |v: f32| {
        if v > delta_cube {
            v.powf(1.0 / 3.0)
        } else {
            factor * v + term
        }
    };
    let x = f(c[0] * INV_ILLUMINANT[0]);
    let y = f(c[1] * INV_ILLUMINANT[1]);
    let z = f(c[2] * INV_ILLUMINANT[2]);
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

/// Linear RGB -> CIELAB -> Hunt-adjusted L*A*B* (paper Section 4.1.1,
/// `hunt_adjustment` in Python, `color3::Hunt` in C++): chroma scaled by
/// `0.01 · L`.
fn hunt_lab(linear_rgb: [f32; 3]) -> [f32; 3] {
    let lab = xyz_to_cielab(linear_rgb_to_xyz(linear_rgb));
    [lab[0], 0.01 * lab[0] * lab[1], 0.01 * lab[0] * lab[2]]
}

/// `color3::HyAB` (paper Section 4.1.2, `hyab` in Python): city-block in
/// L, Euclidean in (a, b).
fn hyab(a: [f32; 3], b: [f32; 3]) -> f32 {
    let dl = (a[0] - b[0]).abs();
    let da = a[1] - b[1];
    let db = a[2] - b[2];
    dl + (da * da + db * db).sqrt()
}

/// `c_max`: the compressed HyAB distance between Hunt-adjusted pure green
/// and pure blue, the largest in the RGB cube (`color3::computeMaxDistance`).
fn max_color_distance() -> f32 {
    hyab(hunt_lab([0.0, 1.0, 0.0]), hunt_lab([0.0, 0.0, 1.0])).powf(QC)
}

/// `redistribute_errors` (paper Section 4.1.3): maps the compressed HyAB
/// distance to `[0, 1]`, `[0, p_c·c_max)` linearly onto `[0, p_t)` and the
/// rest onto `[p_t, 1]`.
fn redistribute(power_hyab: f32, cmax: f32) -> f32 {
    let pccmax = PC * cmax;
    if power_hyab < pccmax {
        power_hyab * (PT / pccmax)
    } else {
        PT + ((power_hyab - pccmax) / (cmax - pccmax)) * (1.0 - PT)
    }
}

// ---------------------------------------------------------------------------
// Filters.
// ---------------------------------------------------------------------------

/// `Gaussian(x2, a, b)`: the CSF's Gaussian in the paper's form
/// `a · sqrt(π / b) · exp(−π² x² / b)` (Section 4.1, Equation 2).
fn csf_gaussian(x2: f32, a: f32, b: f32) -> f32 {
    a * (PI / b).sqrt() * (-(PI * PI) * x2 / b).exp()
}

/// `GaussianSqrt`: one 1D factor of a 2D CSF Gaussian, used to separate the
/// blue-yellow sum of two Gaussians (`misc/separatedConvolutions.pdf`).
fn csf_gaussian_sqrt(x2: f32, a: f32, b: f32) -> f32 {
    (a * (PI / b).sqrt()).sqrt() * (-(PI * PI) * x2 / b).exp()
}

/// Separated contrast sensitivity filters (`setSpatialFilters`,
/// `calculateSpatialFilterRadius` in `FLIP.h`; the same kernels as
/// `generate_spatial_filter` in Python).
struct SpatialFilters {
    radius: usize,
    /// Per tap: weight for Y (achromatic) and for Cx (red-green); the 2D
    /// kernel of each is the outer product of its 1D weights.
    ycx: Vec<[f32; 2]>,
    /// Per tap: the two 1D factors of the blue-yellow kernel, which is
    /// `cz1 ⊗ cz1 + cz2 ⊗ cz2`.
    cz: Vec<[f32; 2]>,
}

impl SpatialFilters {
    fn new(ppd: f32) -> Self {
        let max_b = CSF_B1.iter().chain(&CSF_B2).fold(0.0f32, |m, &b| m.max(b));
        // Radius from the widest Gaussian: 3 standard deviations.
        let radius = (3.0 * (max_b / (2.0 * PI * PI)).sqrt() * ppd).ceil() as usize;
        let delta_x = 1.0 / ppd;
        let taps = 2 * radius + 1;
        let mut ycx = Vec::with_capacity(taps);
        let mut cz = Vec::with_capacity(taps);
        let mut sum_ycx = [0.0f32; 2];
        let mut sum_cz = [0.0f32; 2];
        for i in 0..taps {
            let ix = (i as f32 - radius as f32) * delta_x;
            let ix2 = ix * ix;
            let w_ycx = [
                csf_gaussian(ix2, CSF_A1[0], CSF_B1[0]),
                csf_gaussian(ix2, CSF_A1[1], CSF_B1[1]),
            ];
            let w_cz = [
                csf_gaussian_sqrt(ix2, CSF_A1[2], CSF_B1[2]),
                csf_gaussian_sqrt(ix2, CSF_A2[2], CSF_B2[2]),
            ];
            sum_ycx[0] += w_ycx[0];
            sum_ycx[1] += w_ycx[1];
            sum_cz[0] += w_cz[0];
            sum_cz[1] += w_cz[1];
            ycx.push(w_ycx);
            cz.push(w_cz);
        }
        // Normalise: Y and Cx kernels sum to 1; the blue-yellow 2D kernel
        // sums to (s1² + s2²)·n², so n = 1 / sqrt(s1² + s2²).
        let norm_ycx = [1.0 / sum_ycx[0], 1.0 / sum_ycx[1]];
        let norm_cz = 1.0 / (sum_cz[0] * sum_cz[0] + sum_cz[1] * sum_cz[1]).sqrt();
        for w in &mut ycx {
            *w = [w[0] * norm_ycx[0], w[1] * norm_ycx[1]];
        }
        for w in &mut cz {
            *w = [w[0] * norm_cz, w[1] * norm_cz];
        }
        Self { radius, ycx, cz }
    }
}

/// Separated edge/point detection filter (`setFeatureFilter` in `FLIP.h`;
/// the same kernels as `feature_detection` in Python). Per tap: Gaussian
/// `g`, first derivative `−x·g`, second derivative `(x²/σ² − 1)·g`, with
/// `σ = 0.5 · w · ppd`. `g` is normalised to sum 1; the positive and
/// negative weights of each derivative to sum 1 and −1.
fn feature_filter(ppd: f32) -> Vec<[f32; 3]> {
    let std_dev = 0.5 * FEATURE_WIDTH_DEGREES * ppd;
    let radius = (3.0 * std_dev).ceil() as usize;
    let taps = 2 * radius + 1;
    let mut g_sum = 0.0f32;
    let (mut dg_pos, mut dg_neg) = (0.0f32, 0.0f32);
    let (mut ddg_pos, mut ddg_neg) = (0.0f32, 0.0f32);
    let mut filter = Vec::with_capacity(taps);
    for i in 0..taps {
        let x = i as f32 - radius as f32;
        let g = (-(x * x) / (2.0 * std_dev * std_dev)).exp();
        g_sum += g;
        let dg = -x * g;
        if dg > 0.0 {
            dg_pos += dg;
        } else {
            dg_neg -= dg;
        }
        let ddg = (x * x / (std_dev * std_dev) - 1.0) * g;
        if ddg > 0.0 {
            ddg_pos += ddg;
        } else {
            ddg_neg -= ddg;
        }
        filter.push([g, dg, ddg]);
    }
    // The reference divides unconditionally; at tiny ppd a sum can be zero
    // (every tap but the centre underflows), where it would produce 0/0.
    let div = |v: f32, sum: f32| {
        if sum > 0.0 && sum.is_finite() {
            v / sum
        } else {
            0.0
        }
    };
    for w in &mut filter {
        *w = [
            div(w[0], g_sum),
            div(w[1], if w[1] > 0.0 { dg_pos } else { dg_neg }),
            div(w[2], if w[2] > 0.0 { ddg_pos } else { ddg_neg }),
        ];
    }
    filter
}

/// Clamp-to-edge source index for output `i` and tap `k` of a filter of
/// the given radius (`Min(Max(0, x + ix), w - 1)` in the reference).
#[inline]
fn clamp_tap(i: usize, k: usize, radius: usize, n: usize) -> usize {
    (i + k).saturating_sub(radius).min(n - 1)
}

/// `computeColorDifference`: separable CSF filtering of both images, back
/// to linear RGB with a clamp to the unit cube, Hunt-adjusted CIELAB,
/// HyAB, `^q_c`, redistribution. Returns `ΔE_c` per pixel.
fn color_difference(
    reference: &[[f32; 3]],
    test: &[[f32; 3]],
    width: usize,
    height: usize,
    filters: &SpatialFilters,
) -> Vec<f32> {
    let cmax = max_color_distance();
    let radius = filters.radius;

    // Horizontal pass: per pixel, [Y·wY, Cx·wCx, Cz·wCz1, Cz·wCz2].
    let horizontal = |img: &[[f32; 3]]| -> Vec<[f32; 4]> {
        let mut out = Vec::with_capacity(width * height);
        for row in img.chunks_exact(width) {
            for x in 0..width {
                let mut acc = [0.0f32; 4];
                for (k, (wycx, wcz)) in filters.ycx.iter().zip(&filters.cz).enumerate() {
                    let c = row[clamp_tap(x, k, radius, width)];
                    acc[0] += wycx[0] * c[0];
                    acc[1] += wycx[1] * c[1];
                    acc[2] += wcz[0] * c[2];
                    acc[3] += wcz[1] * c[2];
                }
                out.push(acc);
            }
        }
        out
    };
    let reference_h = horizontal(reference);
    let test_h = horizontal(test);

    // Vertical pass, then the colour metric.
    let vertical = |img: &[[f32; 4]], x: usize, y: usize| -> [f32; 3] {
        let mut acc = [0.0f32; 4];
        for (k, (wycx, wcz)) in filters.ycx.iter().zip(&filters.cz).enumerate() {
            let c = img[clamp_tap(y, k, radius, height) * width + x];
            acc[0] += wycx[0] * c[0];
            acc[1] += wycx[1] * c[1];
            acc[2] += wcz[0] * c[2];
            acc[3] += wcz[1] * c[3];
        }
        let ycxcz = [acc[0], acc[1], acc[2] + acc[3]];
        let rgb = xyz_to_linear_rgb(ycxcz_to_xyz(ycxcz)).map(|c| c.clamp(0.0, 1.0));
        hunt_lab(rgb)
    };
    let mut out = Vec::with_capacity(width * height);
    for y in 0..height {
        for x in 0..width {
            let r = vertical(&reference_h, x, y);
            let t = vertical(&test_h, x, y);
            out.push(redistribute(hyab(r, t).powf(QC), cmax));
        }
    }
    out
}

/// `computeFeatureDifferenceAndFinalError`: separable edge and point
/// detection on the normalised luminance `(Y + 16) / 116` of both images,
/// `ΔE_f = (max(|Δ‖edge‖|, |Δ‖point‖|) / √2)^q_f`, then the final
/// `ΔE = ΔE_c^(1 − ΔE_f)` written over `color` (paper Section 4.3).
fn feature_difference_and_final_error(
    reference: &[[f32; 3]],
    test: &[[f32; 3]],
    width: usize,
    height: usize,
    filter: &[[f32; 3]],
    color: &mut [f32],
) {
    let radius = filter.len() / 2;
    let one_over_116 = 1.0f32 / 116.0;
    let sixteen_over_116 = 16.0f32 / 116.0;

    // Horizontal pass: per pixel [dx, ddx, gaussian].
    let horizontal = |img: &[[f32; 3]]| -> Vec<[f32; 3]> {
        let mut out = Vec::with_capacity(width * height);
        for row in img.chunks_exact(width) {
            for x in 0..width {
                let mut acc = [0.0f32; 3];
                for (k, w) in filter.iter().enumerate() {
                    let v =
                        row[clamp_tap(x, k, radius, width)][0] * one_over_116 + sixteen_over_116;
                    acc[0] += w[1] * v;
                    acc[1] += w[2] * v;
                    acc[2] += w[0] * v;
                }
                out.push(acc);
            }
        }
        out
    };
    let reference_h = horizontal(reference);
    let test_h = horizontal(test);

    // Vertical pass: returns (‖edge‖, ‖point‖).
    let vertical = |img: &[[f32; 3]], x: usize, y: usize| -> (f32, f32) {
        let (mut dx, mut ddx, mut dy, mut ddy) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for (k, w) in filter.iter().enumerate() {
            let c = img[clamp_tap(y, k, radius, height) * width + x];
            dx += w[0] * c[0];
            ddx += w[0] * c[1];
            dy += w[1] * c[2];
            ddy += w[2] * c[2];
        }
        ((dx * dx + dy * dy).sqrt(), (ddx * ddx + ddy * ddy).sqrt())
    };
    let normalization = 1.0 / 2.0f32.sqrt();
    for (i, out) in color.iter_mut().enumerate() {
        let (x, y) = (i % width, i / width);
        let (edge_r, point_r) = vertical(&reference_h, x, y);
        let (edge_t, point_t) = vertical(&test_h, x, y);
        let edge_diff = (edge_r - edge_t).abs();
        let point_diff = (point_r - point_t).abs();
        let feature = (normalization * edge_diff.max(point_diff)).powf(QF);
        *out = out.powf(1.0 - feature);
    }
}
