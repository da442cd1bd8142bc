//! Tests of the LDR-FLIP metric (`pelage_reference::flip`).
//!
//! Besides the behavioural checks, two independent `f64` re-derivations
//! live here: the closed form for two constant images (the CSF filters
//! preserve a constant field and the feature detectors see nothing, so
//! FLIP is the redistributed, compressed HyAB distance of the two colours),
//! and a brute-force mirror of the Python reference (`python/flip_api.py`,
//! full 2D kernels from `generate_spatial_filter` and `feature_detection`,
//! `cv.filter2D` with `BORDER_REPLICATE`) that the separable implementation
//! must match.

use std::time::Instant;

use pelage_reference::flip::{
    DEFAULT_PIXELS_PER_DEGREE, FlipError, FlipMap, LinearImage, MAX_PIXELS_PER_DEGREE,
    MIN_PIXELS_PER_DEGREE, flip, rmse_linear,
};

/// Tiny deterministic xorshift32.
struct XorShift(u32);

impl XorShift {
    fn next_u32(&mut self) -> u32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        x
    }
    /// Uniform in `[0, 1)`.
    fn unit(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 / (1u32 << 24) as f32
    }
}

fn constant(width: u32, height: u32, c: [f32; 3]) -> LinearImage {
    LinearImage::new(width, height, vec![c; (width * height) as usize]).unwrap()
}

/// A smooth colour gradient in `[0.3, 0.7]`.
fn gradient(width: u32, height: u32) -> LinearImage {
    let mut pixels = Vec::new();
    for y in 0..height {
        for x in 0..width {
            let u = x as f32 / (width - 1) as f32;
            let v = y as f32 / (height - 1) as f32;
            pixels.push([0.3 + 0.4 * u, 0.3 + 0.4 * v, 0.5 - 0.2 * (u - v)]);
        }
    }
    LinearImage::new(width, height, pixels).unwrap()
}

/// Random image with some structure: noise plus a few hard-edged blocks.
fn structured_random(width: u32, height: u32, seed: u32) -> LinearImage {
    let mut rng = XorShift(seed);
    let mut pixels = Vec::new();
    for y in 0..height {
        for x in 0..width {
            let block = ((x / 5) + (y / 4)) % 3;
            let base = [0.2 + 0.3 * block as f32, 0.5, 0.8 - 0.3 * block as f32];
            pixels.push(base.map(|c| (c + 0.3 * (rng.unit() - 0.5)).clamp(0.0, 1.0)));
        }
    }
    LinearImage::new(width, height, pixels).unwrap()
}

// ---------------------------------------------------------------------------
// Independent f64 re-derivation of the reference formulas.
// ---------------------------------------------------------------------------

mod reference64 {
    use std::f64::consts::PI;

    pub const QC: f64 = 0.7;
    pub const PC: f64 = 0.4;
    pub const PT: f64 = 0.95;
    const INV_ILLUMINANT: [f64; 3] = [1.052156925, 1.0, 0.918357670];
    const ILLUMINANT: [f64; 3] = [0.950428545, 1.0, 1.088900371];

    fn mul(m: [[f64; 3]; 3], c: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| m[i][0] * c[0] + m[i][1] * c[1] + m[i][2] * c[2])
    }

    pub fn linrgb2xyz(c: [f64; 3]) -> [f64; 3] {
        mul(
            [
                [
                    10135552.0 / 24577794.0,
                    8788810.0 / 24577794.0,
                    4435075.0 / 24577794.0,
                ],
                [
                    2613072.0 / 12288897.0,
                    8788810.0 / 12288897.0,
                    887015.0 / 12288897.0,
                ],
                [
                    1425312.0 / 73733382.0,
                    8788810.0 / 73733382.0,
                    70074185.0 / 73733382.0,
                ],
            ],
            c,
        )
    }

    pub fn xyz2linrgb(c: [f64; 3]) -> [f64; 3] {
        mul(
            [
                [3.241003275, -1.537398934, -0.498615861],
                [-0.969224334, 1.875930071, 0.041554224],
                [0.055639423, -0.204011202, 1.057148933],
            ],
            c,
        )
    }

    pub fn linrgb2ycxcz(c: [f64; 3]) -> [f64; 3] {
        let xyz = linrgb2xyz(c);
        let [x, y, z] = std::array::from_fn(|i| xyz[i] * INV_ILLUMINANT[i]);
        [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
    }

    pub fn ycxcz2linrgb(c: [f64; 3]) -> [f64; 3] {
        let y = (c[0] + 16.0) / 116.0;
        let xyz = [y + c[1] / 500.0, y, y - c[2] / 200.0];
        xyz2linrgb(std::array::from_fn(|i| xyz[i] * ILLUMINANT[i]))
    }

    /// linrgb2lab followed by hunt_adjustment.
    pub fn hunt_lab(c: [f64; 3]) -> [f64; 3] {
        let xyz = linrgb2xyz(c);
        let delta: f64 = 6.0 / 29.0;
        let f = |v: f64| {
            if v > delta.powi(3) {
                v.powf(1.0 / 3.0)
            } else {
                v / (3.0 * delta * delta) + 4.0 / 29.0
            }
        };
        let [x, y, z] = std::array::from_fn(|i| f(xyz[i] * INV_ILLUMINANT[i]));
        let l = 116.0 * y - 16.0;
        [l, 0.01 * l * 500.0 * (x - y), 0.01 * l * 200.0 * (y - z)]
    }

    pub fn hyab(a: [f64; 3], b: [f64; 3]) -> f64 {
        (a[0] - b[0]).abs() + ((a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    }

    pub fn cmax() -> f64 {
        hyab(hunt_lab([0.0, 1.0, 0.0]), hunt_lab([0.0, 0.0, 1.0])).powf(QC)
    }

    pub fn redistribute(power_hyab: f64) -> f64 {
        let cmax = cmax();
        let pccmax = PC * cmax;
        if power_hyab < pccmax {
            PT / pccmax * power_hyab
        } else {
            PT + (power_hyab - pccmax) / (cmax - pccmax) * (1.0 - PT)
        }
    }

    /// FLIP between two constant images of linear colours `a` and `b`.
    pub fn flip_constant(a: [f64; 3], b: [f64; 3]) -> f64 {
        redistribute(hyab(hunt_lab(a), hunt_lab(b)).powf(QC))
    }

    /// `generate_spatial_filter` (2D, normalised to sum 1) for channel 0, 1, 2.
    fn spatial_kernel(ppd: f64, channel: usize) -> (usize, Vec<f64>) {
        let (a1, b1, a2, b2) = [
            (1.0, 0.0047, 0.0, 1e-5),
            (1.0, 0.0053, 0.0, 1e-5),
            (34.1, 0.04, 13.5, 0.025),
        ][channel];
        let max_b: f64 = 0.04;
        let r = (3.0 * (max_b / (2.0 * PI * PI)).sqrt() * ppd).ceil() as usize;
        let n = 2 * r + 1;
        let dx = 1.0 / ppd;
        let mut k = Vec::with_capacity(n * n);
        for j in 0..n {
            for i in 0..n {
                let x = (i as f64 - r as f64) * dx;
                let y = (j as f64 - r as f64) * dx;
                let z = x * x + y * y;
                k.push(
                    a1 * (PI / b1).sqrt() * (-PI * PI * z / b1).exp()
                        + a2 * (PI / b2).sqrt() * (-PI * PI * z / b2).exp(),
                );
            }
        }
        let s: f64 = k.iter().sum();
        (r, k.into_iter().map(|v| v / s).collect())
    }

    /// `feature_detection`'s 2D kernel `Gx` (edge: first derivative, point:
    /// second), positive weights normalised to 1, negative to -1.
    fn feature_kernel(ppd: f64, point: bool) -> (usize, Vec<f64>) {
        let sd = 0.5 * 0.082 * ppd;
        let r = (3.0 * sd).ceil() as usize;
        let n = 2 * r + 1;
        let mut k = Vec::with_capacity(n * n);
        for j in 0..n {
            for i in 0..n {
                let x = i as f64 - r as f64;
                let y = j as f64 - r as f64;
                let g = (-(x * x + y * y) / (2.0 * sd * sd)).exp();
                k.push(if point {
                    (x * x / (sd * sd) - 1.0) * g
                } else {
                    -x * g
                });
            }
        }
        let neg: f64 = -k.iter().filter(|v| **v < 0.0).sum::<f64>();
        let pos: f64 = k.iter().filter(|v| **v > 0.0).sum();
        (
            r,
            k.into_iter()
                .map(|v| if v < 0.0 { v / neg } else { v / pos })
                .collect(),
        )
    }

    /// `cv.filter2D` (correlation) with `BORDER_REPLICATE`; `transpose`
    /// reads the kernel transposed.
    fn filter2d(img: &[f64], w: usize, h: usize, r: usize, k: &[f64], transpose: bool) -> Vec<f64> {
        let n = 2 * r + 1;
        let mut out = vec![0.0; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut acc = 0.0;
                for j in 0..n {
                    for i in 0..n {
                        let xx = (x as isize + i as isize - r as isize).clamp(0, w as isize - 1);
                        let yy = (y as isize + j as isize - r as isize).clamp(0, h as isize - 1);
                        let kv = if transpose {
                            k[i * n + j]
                        } else {
                            k[j * n + i]
                        };
                        acc += kv * img[yy as usize * w + xx as usize];
                    }
                }
                out[y * w + x] = acc;
            }
        }
        out
    }

    /// Python `compute_ldrflip`, with linear (not sRGB) inputs clamped to
    /// [0, 1] as `FLIP::evaluate` does.
    pub fn compute_ldrflip(
        reference: &[[f32; 3]],
        test: &[[f32; 3]],
        w: usize,
        h: usize,
        ppd: f64,
    ) -> Vec<f64> {
        let opponent = |img: &[[f32; 3]]| -> [Vec<f64>; 3] {
            let ycxcz: Vec<[f64; 3]> = img
                .iter()
                .map(|p| linrgb2ycxcz(p.map(|c| f64::from(c).clamp(0.0, 1.0))))
                .collect();
            std::array::from_fn(|c| ycxcz.iter().map(|p| p[c]).collect())
        };
        let r_opp = opponent(reference);
        let t_opp = opponent(test);
        let kernels: [(usize, Vec<f64>); 3] = std::array::from_fn(|c| spatial_kernel(ppd, c));
        let filtered = |opp: &[Vec<f64>; 3]| -> Vec<[f64; 3]> {
            let ch: [Vec<f64>; 3] = std::array::from_fn(|c| {
                filter2d(&opp[c], w, h, kernels[c].0, &kernels[c].1, false)
            });
            (0..w * h)
                .map(|i| {
                    let rgb =
                        ycxcz2linrgb([ch[0][i], ch[1][i], ch[2][i]]).map(|v| v.clamp(0.0, 1.0));
                    hunt_lab(rgb)
                })
                .collect()
        };
        let r_lab = filtered(&r_opp);
        let t_lab = filtered(&t_opp);

        let (er, edge) = feature_kernel(ppd, false);
        let (pr, point) = feature_kernel(ppd, true);
        let features = |opp: &[Vec<f64>; 3]| -> (Vec<f64>, Vec<f64>) {
            let y: Vec<f64> = opp[0].iter().map(|v| (v + 16.0) / 116.0).collect();
            let ex = filter2d(&y, w, h, er, &edge, false);
            let ey = filter2d(&y, w, h, er, &edge, true);
            let px = filter2d(&y, w, h, pr, &point, false);
            let py = filter2d(&y, w, h, pr, &point, true);
            (
                (0..w * h).map(|i| ex[i].hypot(ey[i])).collect(),
                (0..w * h).map(|i| px[i].hypot(py[i])).collect(),
            )
        };
        let (r_edge, r_point) = features(&r_opp);
        let (t_edge, t_point) = features(&t_opp);

        (0..w * h)
            .map(|i| {
                let dc = redistribute(hyab(r_lab[i], t_lab[i]).powf(QC));
                let df = (r_edge[i] - t_edge[i])
                    .abs()
                    .max((t_point[i] - r_point[i]).abs());
                let df = (df / 2f64.sqrt()).powf(0.5);
                dc.powf(1.0 - df)
            })
            .collect()
    }
}

// ---------------------------------------------------------------------------
// Tests.
// ---------------------------------------------------------------------------

#[test]
fn default_ppd_is_the_reference_observer() {
    // 0.7 m from a 0.7 m wide 3840 px monitor.
    let expected = 0.7 * (3840.0 / 0.7) * std::f64::consts::PI / 180.0;
    println!("DEFAULT_PIXELS_PER_DEGREE = {DEFAULT_PIXELS_PER_DEGREE}");
    assert!((f64::from(DEFAULT_PIXELS_PER_DEGREE) - expected).abs() < 1e-4);
    assert!((DEFAULT_PIXELS_PER_DEGREE - 67.02).abs() < 1e-3);
}

#[test]
fn identical_images_give_zero_everywhere() {
    for image in [
        gradient(40, 30),
        structured_random(37, 23, 9),
        constant(8, 8, [0.0; 3]),
        constant(5, 3, [1.0; 3]),
        constant(1, 1, [0.3, 0.6, 0.9]),
    ] {
        let map = flip(&image, &image, DEFAULT_PIXELS_PER_DEGREE).unwrap();
        assert_eq!(map.values.len(), (image.width * image.height) as usize);
        assert!(map.values.iter().all(|&v| v == 0.0), "{:?}", map.values);
        assert_eq!(map.mean(), 0.0);
    }
}

#[test]
fn black_versus_white_is_near_one() {
    let black = constant(32, 24, [0.0; 3]);
    let white = constant(32, 24, [1.0; 3]);
    let expected = reference64::flip_constant([0.0; 3], [1.0; 3]);
    let map = flip(&black, &white, DEFAULT_PIXELS_PER_DEGREE).unwrap();
    let mean = map.mean();
    let swapped = flip(&white, &black, DEFAULT_PIXELS_PER_DEGREE)
        .unwrap()
        .mean();
    println!(
        "black vs white: mean FLIP = {mean:.6}, reverse = {swapped:.6}, \
         closed form = {expected:.6}, c_max = {:.6}",
        reference64::cmax()
    );
    // HyAB(black, white) = 100.0 (+ a tiny chroma), 100^0.7 = 25.12 > p_c·c_max,
    // so it lands in the upper segment: 0.95 + (25.12 - 16.5)/(41.3 - 16.5)·0.05.
    assert!((0.966..0.969).contains(&expected), "{expected}");
    assert!((mean - expected).abs() < 1e-4);
    assert!((swapped - expected).abs() < 1e-4);
    let (lo, hi) = map
        .values
        .iter()
        .fold((f32::MAX, f32::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    assert!(
        hi - lo < 1e-4,
        "uniform images must give a uniform map: {lo}..{hi}"
    );
}

#[test]
fn uniform_colour_difference_matches_closed_form() {
    let pairs: [([f32; 3], [f32; 3]); 8] = [
        ([0.5, 0.5, 0.5], [0.55, 0.5, 0.5]),
        ([0.5, 0.5, 0.5], [0.5, 0.5, 0.52]),
        ([0.2, 0.3, 0.4], [0.25, 0.3, 0.35]),
        ([0.8, 0.2, 0.1], [0.8, 0.4, 0.1]),
        ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
        ([0.01, 0.01, 0.01], [0.02, 0.02, 0.02]),
        ([0.9, 0.9, 0.9], [0.1, 0.9, 0.9]),
        ([0.3, 0.3, 0.3], [0.3, 0.3, 0.3]),
    ];
    for (a, b) in pairs {
        let expected = reference64::flip_constant(a.map(f64::from), b.map(f64::from));
        let map = flip(
            &constant(24, 20, a),
            &constant(24, 20, b),
            DEFAULT_PIXELS_PER_DEGREE,
        )
        .unwrap();
        let worst = map
            .values
            .iter()
            .map(|&v| (f64::from(v) - expected).abs())
            .fold(0.0, f64::max);
        println!(
            "{a:?} vs {b:?}: closed form {expected:.6}, mean {:.6}, max |diff| {worst:.2e}",
            map.mean()
        );
        assert!(worst < 1e-4, "{a:?} vs {b:?}: {worst}");
    }
    // Green vs blue is c_max by construction, which maps to exactly 1.
    let gb = reference64::flip_constant([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
    assert!((gb - 1.0).abs() < 1e-12);
}

#[test]
fn separable_matches_python_2d_reference() {
    let (w, h) = (26u32, 19u32);
    let reference = structured_random(w, h, 1);
    let mut test = structured_random(w, h, 2);
    // Include out-of-range values: both sides clamp to [0, 1].
    test.pixels[5] = [1.7, -0.2, 0.5];
    for ppd in [DEFAULT_PIXELS_PER_DEGREE, 20.0, 5.0] {
        let ours = flip(&reference, &test, ppd).unwrap();
        let python = reference64::compute_ldrflip(
            &reference.pixels,
            &test.pixels,
            w as usize,
            h as usize,
            f64::from(ppd),
        );
        let worst = ours
            .values
            .iter()
            .zip(&python)
            .map(|(&a, &b)| (f64::from(a) - b).abs())
            .fold(0.0, f64::max);
        let python_mean = python.iter().sum::<f64>() / python.len() as f64;
        println!(
            "ppd {ppd}: mean ours {:.6}, 2D f64 reference {python_mean:.6}, max |diff| {worst:.2e}",
            ours.mean()
        );
        assert!(worst < 1e-4, "ppd {ppd}: {worst}");
        assert!((ours.mean() - python_mean).abs() < 1e-5);
    }
}

#[test]
fn more_noise_means_more_error() {
    let (w, h) = (64u32, 48u32);
    let reference = gradient(w, h);
    let mut rng = XorShift(0x1234_5678);
    let noise: Vec<[f32; 3]> = (0..w * h)
        .map(|_| [rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5])
        .collect();
    let mut previous = 0.0;
    for amplitude in [0.002f32, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.4] {
        let pixels = reference
            .pixels
            .iter()
            .zip(&noise)
            .map(|(p, n)| std::array::from_fn(|c| p[c] + amplitude * n[c]))
            .collect();
        let test = LinearImage::new(w, h, pixels).unwrap();
        let mean = flip(&reference, &test, DEFAULT_PIXELS_PER_DEGREE)
            .unwrap()
            .mean();
        println!("noise amplitude {amplitude}: mean FLIP {mean:.6}");
        assert!(mean > previous, "{amplitude}: {mean} <= {previous}");
        previous = mean;
    }
}

#[test]
fn single_pixel_difference_is_local() {
    let (w, h) = (64u32, 64u32);
    let reference = constant(w, h, [0.5; 3]);
    let mut test = reference.clone();
    let (cx, cy) = (30usize, 33usize);
    test.pixels[cy * w as usize + cx] = [1.0, 0.2, 0.2];
    let map = flip(&reference, &test, DEFAULT_PIXELS_PER_DEGREE).unwrap();
    let at = |x: usize, y: usize| map.values[y * w as usize + x];
    // Spatial filter radius is ceil(3·sqrt(0.04 / 2π²)·67.02) = 10 pixels,
    // feature filter radius ceil(3·0.5·0.082·67.02) = 9: every pixel more
    // than 10 away in x or y must be exactly 0.
    let mut far_max = 0.0f32;
    let mut near_nonzero = 0;
    for y in 0..h as usize {
        for x in 0..w as usize {
            let v = at(x, y);
            if x.abs_diff(cx) > 10 || y.abs_diff(cy) > 10 {
                far_max = far_max.max(v);
            } else if v > 0.0 {
                near_nonzero += 1;
            }
        }
    }
    let centre = at(cx, cy);
    println!(
        "single pixel: FLIP at pixel {centre:.6}, mean {:.6}, non-zero pixels within \
         radius 10: {near_nonzero}, max beyond: {far_max}",
        map.mean()
    );
    assert_eq!(far_max, 0.0);
    assert!(centre > 0.1, "{centre}");
    assert_eq!(
        map.values.iter().cloned().fold(0.0, f32::max),
        centre,
        "the changed pixel should carry the largest error"
    );
    assert!(near_nonzero > 1);
}

#[test]
fn image_edges_and_tiny_images_work() {
    // Images smaller than the filters: clamp-to-edge everywhere.
    for (w, h) in [(1u32, 1u32), (1, 7), (9, 1), (3, 2)] {
        let r = structured_random(w, h, 3);
        let t = structured_random(w, h, 4);
        let map = flip(&r, &t, DEFAULT_PIXELS_PER_DEGREE).unwrap();
        let python =
            reference64::compute_ldrflip(&r.pixels, &t.pixels, w as usize, h as usize, 67.0206);
        for (&a, &b) in map.values.iter().zip(&python) {
            assert!((0.0..=1.0).contains(&a));
            assert!((f64::from(a) - b).abs() < 1e-4, "{w}x{h}: {a} vs {b}");
        }
    }
    // Extreme but valid ppd values still give finite maps in [0, 1].
    let r = structured_random(16, 12, 5);
    let t = structured_random(16, 12, 6);
    for ppd in [MIN_PIXELS_PER_DEGREE, 1.0, 500.0, MAX_PIXELS_PER_DEGREE] {
        let map = flip(&r, &t, ppd).unwrap();
        assert!(
            map.values.iter().all(|v| (0.0..=1.0).contains(v)),
            "ppd {ppd}: {:?}",
            map.values
        );
    }
}

/// A QVGA map of two unrelated images: every value in [0, 1], clearly above 0, and the
/// same map from a second run, bit for bit. The time is printed, not asserted (speed belongs
/// to the bench).
#[test]
fn qvga_map_is_bounded_and_repeatable() {
    let reference = structured_random(320, 240, 11);
    let test = structured_random(320, 240, 12);
    let start = Instant::now();
    let map = flip(&reference, &test, DEFAULT_PIXELS_PER_DEGREE).unwrap();
    let elapsed = start.elapsed();
    println!(
        "320x240 FLIP: {:.1} ms, mean {:.4}, p50 {:.4}, p99 {:.4}",
        elapsed.as_secs_f64() * 1e3,
        map.mean(),
        map.percentile(50.0),
        map.percentile(99.0)
    );
    assert_eq!(map.values.len(), 320 * 240);
    assert!(
        map.values.iter().all(|v| (0.0..=1.0).contains(v)),
        "a value outside [0, 1]"
    );
    assert!(map.mean() > 0.05, "unrelated images score {}", map.mean());
    let again = flip(&reference, &test, DEFAULT_PIXELS_PER_DEGREE).unwrap();
    assert_eq!(again.values, map.values);
}

#[test]
fn errors_instead_of_panics() {
    let a = constant(4, 3, [0.5; 3]);
    let b = constant(3, 4, [0.5; 3]);
    let e = flip(&a, &b, DEFAULT_PIXELS_PER_DEGREE).unwrap_err();
    println!("{e}");
    assert!(matches!(e, FlipError::SizeMismatch { .. }));
    assert!(matches!(
        rmse_linear(&a, &b),
        Err(FlipError::SizeMismatch { .. })
    ));

    let e = LinearImage::from_srgb8_rgba(4, 3, &[0u8; 47]).unwrap_err();
    println!("{e}");
    assert!(matches!(
        e,
        FlipError::ByteCountMismatch {
            expected: 48,
            actual: 47,
            ..
        }
    ));
    assert!(matches!(
        LinearImage::from_srgb8_rgba(4, 3, &[0u8; 49]),
        Err(FlipError::ByteCountMismatch { .. })
    ));
    assert!(matches!(
        LinearImage::from_srgb8_rgba(0, 3, &[]),
        Err(FlipError::ZeroSize { .. })
    ));
    assert!(matches!(
        LinearImage::from_srgb8_rgba(u32::MAX, u32::MAX, &[]),
        Err(FlipError::TooLarge { .. }) | Err(FlipError::ByteCountMismatch { .. })
    ));

    let e = LinearImage::new(2, 2, vec![[0.0; 3]; 3]).unwrap_err();
    println!("{e}");
    assert!(matches!(
        e,
        FlipError::PixelCountMismatch {
            expected: 4,
            actual: 3,
            ..
        }
    ));
    assert!(matches!(
        LinearImage::new(0, 0, vec![]),
        Err(FlipError::ZeroSize { .. })
    ));
    let e = LinearImage::new(
        2,
        2,
        vec![[0.0; 3], [0.0; 3], [0.0; 3], [0.0, f32::NAN, 0.0]],
    )
    .unwrap_err();
    println!("{e}");
    assert!(matches!(e, FlipError::NonFinitePixel { x: 1, y: 1, .. }));

    // Hand-built images bypassing `new` are re-checked.
    let bad = LinearImage {
        width: 4,
        height: 3,
        pixels: vec![[0.0; 3]; 5],
    };
    assert!(matches!(
        flip(&bad, &bad, DEFAULT_PIXELS_PER_DEGREE),
        Err(FlipError::PixelCountMismatch { .. })
    ));
    let inf = LinearImage {
        width: 1,
        height: 1,
        pixels: vec![[f32::INFINITY, 0.0, 0.0]],
    };
    assert!(matches!(
        flip(&inf, &inf, DEFAULT_PIXELS_PER_DEGREE),
        Err(FlipError::NonFinitePixel { .. })
    ));
    let empty = LinearImage {
        width: 0,
        height: 5,
        pixels: vec![],
    };
    assert!(matches!(
        rmse_linear(&empty, &empty),
        Err(FlipError::ZeroSize { .. })
    ));

    for ppd in [
        0.0,
        -1.0,
        f32::NAN,
        f32::INFINITY,
        1e-30,
        MIN_PIXELS_PER_DEGREE * 0.5,
        MAX_PIXELS_PER_DEGREE * 2.0,
    ] {
        let e = flip(&a, &a, ppd).unwrap_err();
        assert!(matches!(e, FlipError::InvalidPixelsPerDegree(_)), "{ppd}");
    }
    println!("{}", flip(&a, &a, 0.0).unwrap_err());
}

#[test]
fn srgb8_decoding() {
    // Pixel 0: black, pixel 1: white, pixel 2: 128 (mid grey), alpha varies
    // and must be ignored.
    let bytes = [0, 0, 0, 255, 255, 255, 255, 0, 128, 10, 200, 77];
    let image = LinearImage::from_srgb8_rgba(3, 1, &bytes).unwrap();
    let decode = |b: u8| {
        let c = f64::from(b) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    println!("sRGB 128 -> {}", image.pixels[2][0]);
    assert_eq!(image.pixels[0], [0.0; 3]);
    for c in image.pixels[1] {
        assert!((c - 1.0).abs() < 1e-6);
    }
    for (c, b) in image.pixels[2].iter().zip([128u8, 10, 200]) {
        assert!((f64::from(*c) - decode(b)).abs() < 1e-6);
    }
    assert!((image.pixels[2][0] - 0.215_861).abs() < 1e-5);
    // The same image in different alpha compares equal.
    let mut other = bytes;
    other[3] = 0;
    other[7] = 255;
    let image2 = LinearImage::from_srgb8_rgba(3, 1, &other).unwrap();
    let map = flip(&image, &image2, DEFAULT_PIXELS_PER_DEGREE).unwrap();
    assert_eq!(map.mean(), 0.0);
}

#[test]
fn rmse_on_known_inputs() {
    let zero = constant(2, 1, [0.0; 3]);
    let one_channel = LinearImage::new(2, 1, vec![[1.0, 0.0, 0.0], [0.0; 3]]).unwrap();
    let (rmse, p99) = rmse_linear(&zero, &one_channel).unwrap();
    println!("2 px, one channel off by 1: rmse {rmse:.6}, p99 {p99:.6}");
    assert!((rmse - (1.0f64 / 6.0).sqrt()).abs() < 1e-12);
    assert!((p99 - (1.0f64 / 3.0).sqrt()).abs() < 1e-12);

    // 100 pixels, pixel i off by i/100 in every channel: per-pixel RMS i/100,
    // nearest-rank 99th percentile is the 99th smallest = 0.98, RMSE is
    // sqrt(Σi² / 100 / 10⁴) = sqrt(0.32835).
    let reference = constant(10, 10, [0.25; 3]);
    let test = LinearImage::new(
        10,
        10,
        (0..100).map(|i| [0.25 + i as f32 / 100.0; 3]).collect(),
    )
    .unwrap();
    let (rmse, p99) = rmse_linear(&reference, &test).unwrap();
    println!("ramp: rmse {rmse:.6}, p99 {p99:.6}");
    assert!((rmse - 0.32835f64.sqrt()).abs() < 1e-6);
    assert!((p99 - 0.98).abs() < 1e-6);

    let (rmse, p99) = rmse_linear(&test, &test).unwrap();
    assert_eq!((rmse, p99), (0.0, 0.0));
    // HDR values are not clamped.
    let hdr = constant(2, 1, [3.0; 3]);
    assert_eq!(rmse_linear(&zero, &hdr).unwrap(), (3.0, 3.0));
}

#[test]
fn flip_map_statistics() {
    let map = FlipMap {
        width: 5,
        height: 2,
        values: vec![0.9, 0.1, 0.5, 0.3, 0.7, 0.2, 0.4, 0.6, 0.8, 1.0],
    };
    assert!((map.mean() - 0.55).abs() < 1e-7);
    assert_eq!(map.percentile(0.0), 0.1);
    assert_eq!(map.percentile(10.0), 0.1);
    assert_eq!(map.percentile(11.0), 0.2);
    assert_eq!(map.percentile(50.0), 0.5);
    assert_eq!(map.percentile(99.0), 1.0);
    assert_eq!(map.percentile(100.0), 1.0);
    assert_eq!(map.percentile(250.0), 1.0);
    assert_eq!(map.percentile(-3.0), 0.1);
    assert!(map.percentile(f64::NAN).is_nan());
    let empty = FlipMap {
        width: 0,
        height: 0,
        values: vec![],
    };
    assert!(empty.mean().is_nan());
    assert!(empty.percentile(50.0).is_nan());
}
