//! The Chiang et al. 2016 fibre BSDF (pbrt-v3's definition): energy, sampling, symmetry,
//! far field and geometry. Every tolerance is stated with the figure it guards.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use glam::{DVec3, Vec3};
use pelage_reference::chiang::{
    ChiangFibre, FibreFrame, bessel_i0, deflection, log_bessel_i0, longitudinal_scattering,
};
use pelage_reference::path_tracer::Pcg32;
use pelage_reference::transmittance::{Segment, SegmentBvh};
use rayon::prelude::*;

fn fibre(sigma_a: f64, beta_m: f64, beta_n: f64, alpha_deg: f64) -> ChiangFibre {
    ChiangFibre {
        sigma_a: DVec3::splat(sigma_a),
        beta_m,
        beta_n,
        alpha: alpha_deg.to_radians(),
        eta: 1.55,
    }
}

fn dir(sin_theta: f64, phi: f64) -> DVec3 {
    let c = (1.0 - sin_theta * sin_theta).max(0.0).sqrt();
    DVec3::new(sin_theta, c * phi.cos(), c * phi.sin())
}

fn uniform_sphere(rng: &mut Pcg32) -> DVec3 {
    dir(2.0 * rng.next_f64() - 1.0, TAU * rng.next_f64())
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

/// Composite 8-point Gauss-Legendre of `f` over [a, b] with `panels` panels.
fn gl(a: f64, b: f64, panels: usize, f: impl Fn(f64) -> f64) -> f64 {
    const X: [f64; 4] = [
        0.183_434_642_495_649_8,
        0.525_532_409_916_329,
        0.796_666_477_413_626_7,
        0.960_289_856_497_536_3,
    ];
    const W: [f64; 4] = [
        0.362_683_783_378_362,
        0.313_706_645_877_887_3,
        0.222_381_034_453_374_5,
        0.101_228_536_290_376_3,
    ];
    let w = (b - a) / panels as f64;
    let mut s = 0.0;
    for k in 0..panels {
        let m = a + (k as f64 + 0.5) * w;
        for (x, wt) in X.iter().zip(W) {
            s += wt * (f(m - 0.5 * w * x) + f(m + 0.5 * w * x));
        }
    }
    0.5 * w * s
}

#[test]
fn bessel_i0_matches_mpmath_and_the_log_form_is_continuous() {
    // mpmath (30 digits): I0(1), I0(10), I0(12), I0(30) and ln I0 at 50 and 200.
    for (x, v) in [
        (1.0, 1.266_065_877_752_008_3),
        (10.0, 2_815.716_628_466_254_5),
        (12.0, 18_948.925_349_296_31),
        (30.0, 781_672_297_823.977_5),
    ] {
        assert!(rel(bessel_i0(x), v) < 1e-14, "I0({x}) = {}", bessel_i0(x));
        assert!((log_bessel_i0(x) - v.ln()).abs() < 1e-13);
    }
    assert!((log_bessel_i0(50.0) - 47.127_575_501_871_8).abs() < 1e-12);
    assert!((log_bessel_i0(200.0) - 196.432_529_354_223_47).abs() < 1e-11);
    // Either side of the switch from the series (<= 30) to the asymptotic expansion (> 30).
    assert!((log_bessel_i0(29.5) - 26.893_178_122_058_44).abs() < 1e-13);
    assert!((log_bessel_i0(30.5) - 27.876_366_092_542_707).abs() < 1e-13);
}

#[test]
fn mp_is_normalised_for_every_variance() {
    // ∫ M cos θ_i dθ_i = 1 over θ_i ∈ [-π/2, π/2]: v from β_m = 0.1's TT (0.0016) to
    // β_m = 1's TRT (110), across the log form's whole range.
    let mut worst = 0.0f64;
    for v in [0.0016, 0.0065, 0.05, 0.1, 0.1000001, 0.5, 3.0, 27.4, 110.0] {
        for theta_o in [-1.4, -0.7, 0.0, 0.3, 1.2, 1.5] {
            let (so, co) = f64::sin_cos(theta_o);
            let total = gl(-FRAC_PI_2, FRAC_PI_2, 2000, |t| {
                let (si, ci) = t.sin_cos();
                longitudinal_scattering(ci, co, si, so, v) * ci
            });
            worst = worst.max((total - 1.0).abs());
        }
    }
    println!("Mp normalisation: worst |∫M cos - 1| = {worst:.2e}");
    assert!(worst < 1e-9, "{worst}");
}

/// `(β_m, β_n)` pairs of the furnace tests: the extremes and the middle.
const BETAS: [(f64, f64); 6] = [
    (0.1, 0.1),
    (0.3, 0.3),
    (0.5, 0.8),
    (1.0, 1.0),
    (0.1, 1.0),
    (1.0, 0.1),
];

/// Stratified samples per fixed-h furnace estimate (`ChiangFibre::furnace_at`): 512 x 512
/// strata in (θ_i, φ_i), cells of 0.006 x 0.012 rad, finer than the narrowest lobe here (TT at
/// β_m = 0.1 has a standard deviation of 0.04 rad, the logistic at β_n = 0.1 s = 0.024), and
/// 1024 x 1024 when β_m or β_n is 0.1 (at 512² those still show 0.3-0.6% noise; at 2048² all
/// cases are within 3e-4 of 1).
fn furnace_samples(beta_m: f64, beta_n: f64) -> usize {
    if beta_m.min(beta_n) <= 0.1 {
        1024 * 1024
    } else {
        512 * 512
    }
}

/// Offsets cycled through the θ_o of each (β_m, β_n), so every θ_o and every offset is covered.
const OFFSETS: [f64; 7] = [0.0, -0.95, 0.6, -0.3, 0.999, 0.15, -0.75];

fn furnace_table(betas: &[(f64, f64)], alpha_deg: f64) -> Vec<(f64, f64, i32, f64, f64)> {
    let configs: Vec<(f64, f64, i32, f64)> = betas
        .iter()
        .enumerate()
        .flat_map(|(i, &(bm, bn))| {
            (-85..=85)
                .step_by(10)
                .enumerate()
                .map(move |(j, d)| (bm, bn, d, OFFSETS[(i + j) % OFFSETS.len()]))
        })
        .collect();
    configs
        .par_iter()
        .map(|&(bm, bn, deg, h)| {
            let f = fibre(0.0, bm, bn, alpha_deg);
            let r = f.furnace_at(
                f64::from(deg).to_radians(),
                h,
                furnace_samples(bm, bn),
                (deg + 1000) as u64,
            );
            // σ_a = 0: every channel is the same.
            assert!((r.x - r.y).abs() < 1e-12 && (r.y - r.z).abs() < 1e-12);
            (bm, bn, deg, h, r.y)
        })
        .collect()
}

#[test]
fn white_furnace_integrates_to_one() {
    // σ_a = 0, α = 0, six (β_m, β_n) pairs from 0.1 to 1, θ_o = -85°..85° in 10° steps (108
    // cases, h cycling through 7 offsets), 2^18 or 2^20 stratified samples each
    // (see furnace_samples): ∫ f |cos θ_i| dω = 1 within 1%.
    let table = furnace_table(&BETAS, 0.0);
    let worst = table
        .iter()
        .map(|r| (r.4 - 1.0).abs())
        .fold(0.0f64, f64::max);
    for &(bm, bn, deg, h, v) in &table {
        assert!(
            (v - 1.0).abs() < 0.01,
            "beta_m {bm} beta_n {bn} theta_o {deg} h {h}: furnace {v}"
        );
    }
    println!(
        "white furnace (alpha 0): {} cases, worst |value - 1| = {worst:.2e}",
        table.len()
    );
}

#[test]
fn white_furnace_averaged_over_the_width_integrates_to_one() {
    // The same over h as well (ChiangFibre::furnace, 2^20 samples: 203 x 203 x 25 strata in
    // (θ_i, φ_i, h)), where its ridges in (h, φ) let it converge: β_n >= 0.3.
    let cases: Vec<(f64, f64, i32)> = [(0.3, 0.3), (1.0, 1.0), (0.1, 0.5)]
        .iter()
        .flat_map(|&(bm, bn)| [-85, -45, 5, 35, 75].map(move |d| (bm, bn, d)))
        .collect();
    let worst = cases
        .par_iter()
        .map(|&(bm, bn, deg)| {
            let v = fibre(0.0, bm, bn, 0.0)
                .furnace(f64::from(deg).to_radians(), 1 << 20, 77)
                .y;
            assert!(
                (v - 1.0).abs() < 0.01,
                "beta_m {bm} beta_n {bn} theta_o {deg}: {v}"
            );
            (v - 1.0).abs()
        })
        .reduce(|| 0.0, f64::max);
    println!("white furnace averaged over h: worst |value - 1| = {worst:.2e}");
}

#[test]
fn white_furnace_with_cuticle_tilt_stays_one() {
    // The tilt only moves each M_p, which stays normalised, so the albedo stays 1 (and
    // certainly <= 1.01). α = 5° here (pbrt's default is 2°), three (β_m, β_n) pairs.
    let table = furnace_table(&[BETAS[0], BETAS[1], BETAS[3]], 5.0);
    let most = table.iter().map(|r| r.4).fold(0.0f64, f64::max);
    let least = table.iter().map(|r| r.4).fold(2.0f64, f64::min);
    for &(bm, bn, deg, h, v) in &table {
        assert!(
            (0.99..=1.01).contains(&v),
            "beta_m {bm} beta_n {bn} theta_o {deg} h {h}: {v}"
        );
    }
    println!("white furnace (alpha 5 deg): values in [{least:.5}, {most:.5}]");
}

#[test]
fn absorbing_fibres_lose_energy() {
    // σ_a > 0 must give an albedo below 1, darker for larger σ_a (the furnace can fail low).
    let a = fibre(0.2, 0.3, 0.3, 2.0).furnace(0.3, 1 << 18, 1).y;
    let b = fibre(2.0, 0.3, 0.3, 2.0).furnace(0.3, 1 << 18, 1).y;
    let c = fibre(2.0, 0.3, 0.3, 2.0).furnace_at(0.3, 0.2, 1 << 18, 1).y;
    assert!(c < 0.2, "{c}");
    println!("albedo at sigma_a 0.2: {a:.4}, at 2.0: {b:.4}");
    assert!(a < 0.97 && b < a && b > 0.04, "{a} {b}");
}

#[test]
fn sampling_weights_are_one_for_white_fibres() {
    // pbrt's SamplingWeights: with σ_a = 0 the lobe probabilities equal A_p, so the sample
    // weight f |cos θ_i| / pdf is exactly 1. 10 000 samples for each of 25 (β_m, β_n).
    let mut rng = Pcg32::new(7, 1);
    let mut worst = 0.0f64;
    let mut none = 0;
    for bm in [0.1, 0.3, 0.5, 0.7, 0.9] {
        for bn in [0.1, 0.3, 0.5, 0.7, 0.9] {
            for alpha in [0.0, 2.0] {
                let f = fibre(0.0, bm, bn, alpha);
                for _ in 0..5000 {
                    let h = 2.0 * rng.next_f64() - 1.0;
                    let wo = uniform_sphere(&mut rng);
                    let u = [
                        rng.next_f64(),
                        rng.next_f64(),
                        rng.next_f64(),
                        rng.next_f64(),
                    ];
                    match f.sample(wo, h, u) {
                        Some((wi, fv, pdf)) => {
                            let c = (1.0 - wi.x * wi.x).sqrt();
                            worst = worst.max((fv.y * c / pdf - 1.0).abs());
                            assert!(rel(pdf, f.pdf(wo, wi, h)) < 1e-9);
                        }
                        None => none += 1,
                    }
                }
            }
        }
    }
    println!("sample weights: worst |w - 1| = {worst:.2e}, {none} of 250000 rejected");
    assert!(worst < 1e-3, "{worst}");
    assert!(none < 10, "{none}");
}

#[test]
fn importance_sampling_agrees_with_uniform_integration() {
    // pbrt's SamplingConsistency with an absorbing fibre (σ_a = 0.25) and L_i(w) = w.z²:
    // ∫ f L_i |cos| by importance sampling (2^17 samples) vs by stratified uniform sampling
    // of (h, θ_i, φ_i) (2^20 samples), within 2%.
    for (bm, bn) in [(0.2, 0.4), (0.4, 0.6), (0.8, 0.8), (0.15, 0.15)] {
        let f = fibre(0.25, bm, bn, 2.0);
        let mut rng = Pcg32::new(11, 2);
        let wo = dir(0.35, 0.7);
        let n = 1 << 17;
        let mut imp = 0.0;
        for _ in 0..n {
            let h = 2.0 * rng.next_f64() - 1.0;
            let u = [
                rng.next_f64(),
                rng.next_f64(),
                rng.next_f64(),
                rng.next_f64(),
            ];
            if let Some((wi, fv, pdf)) = f.sample(wo, h, u) {
                let c = (1.0 - wi.x * wi.x).sqrt();
                imp += fv.y * c * wi.z * wi.z / pdf;
            }
        }
        imp /= n as f64;
        let m = 256;
        let k = 16;
        let mut uni = 0.0;
        for a in 0..k {
            for b in 0..m {
                for c in 0..m {
                    let h = -1.0 + 2.0 * (a as f64 + rng.next_f64()) / k as f64;
                    let th = -FRAC_PI_2 + PI * (b as f64 + rng.next_f64()) / m as f64;
                    let ph = -PI + TAU * (c as f64 + rng.next_f64()) / m as f64;
                    let wi = dir(th.sin(), ph);
                    uni += f.eval_projected(wo, wi, h).y * th.cos() * wi.z * wi.z;
                }
            }
        }
        uni *= PI * TAU / (k * m * m) as f64;
        println!("beta_m {bm} beta_n {bn}: importance {imp:.5} uniform {uni:.5}");
        assert!(rel(imp, uni) < 0.02, "{imp} vs {uni}");
    }
}

/// ∫ pdf dω over the sphere by a 512 x 512 stratified grid in (θ, φ).
fn pdf_integral(f: &ChiangFibre, wo: DVec3, h: f64, rng: &mut Pcg32) -> f64 {
    let m = 512;
    let mut s = 0.0;
    for b in 0..m {
        for c in 0..m {
            let th = -FRAC_PI_2 + PI * (b as f64 + rng.next_f64()) / m as f64;
            let ph = -PI + TAU * (c as f64 + rng.next_f64()) / m as f64;
            s += f.pdf(wo, dir(th.sin(), ph), h) * th.cos();
        }
    }
    s * PI * TAU / (m * m) as f64
}

#[test]
fn pdf_integrates_to_one() {
    let mut rng = Pcg32::new(3, 3);
    let mut worst = 0.0f64;
    for (bm, bn, sa) in [
        (0.3, 0.3, 0.5),
        (0.6, 0.9, 0.0),
        (1.0, 0.5, 3.0),
        (0.2, 0.2, 1.0),
    ] {
        let f = fibre(sa, bm, bn, 2.0);
        for (so, h) in [(0.0, 0.0), (0.5, 0.7), (-0.8, -0.3), (0.95, 0.99)] {
            let v = pdf_integral(&f, dir(so, 1.0), h, &mut rng);
            worst = worst.max((v - 1.0).abs());
            assert!((v - 1.0).abs() < 0.01, "bm {bm} bn {bn} so {so} h {h}: {v}");
        }
    }
    println!("pdf integral: worst |∫pdf - 1| = {worst:.2e}");
}

/// The χ² quantile at `dof` degrees of freedom for the standard normal quantile `z`.
fn chi2_quantile(dof: f64, z: f64) -> f64 {
    // Wilson-Hilferty: χ²_q ≈ k (1 - 2/(9k) + z sqrt(2/(9k)))³.
    let a = 2.0 / (9.0 * dof);
    dof * (1.0 - a + z * a.sqrt()).powi(3)
}

#[test]
fn sampled_directions_follow_the_pdf_chi_square() {
    // 400 000 sampled directions binned in 40 (θ) x 80 (φ) cells; expected counts from the
    // pdf integrated over each cell (8 x 8 Gauss-Legendre); cells expecting < 5 pooled. The
    // statistic must stay below the χ² quantile at z = 4.26 (p ≈ 1e-5): a correct sampler
    // fails this about once in 100 000 seeds; one whose density differs by a few percent in
    // any region fails always.
    let (nt, np) = (40usize, 80usize);
    for (bm, bn, sa, so, h) in [
        (0.3, 0.3, 0.3, 0.3, 0.4),
        (0.6, 0.5, 1.0, -0.6, -0.8),
        (0.2, 0.7, 0.0, 0.0, 0.1),
    ] {
        let f = fibre(sa, bm, bn, 2.0);
        let wo = dir(so, 0.4);
        let mut rng = Pcg32::new(19, 4);
        let n = 400_000usize;
        let mut counts = vec![0f64; nt * np];
        let mut accepted = 0usize;
        for _ in 0..n {
            let u = [
                rng.next_f64(),
                rng.next_f64(),
                rng.next_f64(),
                rng.next_f64(),
            ];
            if let Some((wi, _, _)) = f.sample(wo, h, u) {
                let th = wi.x.clamp(-1.0, 1.0).asin();
                let ph = wi.z.atan2(wi.y);
                let bt = (((th + FRAC_PI_2) / PI * nt as f64) as usize).min(nt - 1);
                let bp = (((ph + PI) / TAU * np as f64) as usize).min(np - 1);
                counts[bt * np + bp] += 1.0;
                accepted += 1;
            }
        }
        assert_eq!(accepted, n);
        let mut expected = vec![0f64; nt * np];
        let (dt, dp) = (PI / nt as f64, TAU / np as f64);
        for bt in 0..nt {
            for bp in 0..np {
                let t0 = -FRAC_PI_2 + bt as f64 * dt;
                let p0 = -PI + bp as f64 * dp;
                let v = gl(t0, t0 + dt, 1, |t| {
                    gl(p0, p0 + dp, 1, |p| f.pdf(wo, dir(t.sin(), p), h)) * t.cos()
                });
                expected[bt * np + bp] = v * n as f64;
            }
        }
        let total: f64 = expected.iter().sum();
        // Pool cells expecting fewer than 5 into one.
        let (mut chi2, mut cells, mut pool_e, mut pool_o) = (0.0, 0usize, 0.0, 0.0);
        for (e, o) in expected.iter().zip(&counts) {
            if *e < 5.0 {
                pool_e += e;
                pool_o += o;
            } else {
                chi2 += (o - e) * (o - e) / e;
                cells += 1;
            }
        }
        if pool_e > 0.0 {
            chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e.max(1.0);
            cells += 1;
        }
        let dof = (cells - 1) as f64;
        let limit = chi2_quantile(dof, 4.26);
        println!(
            "chi2 (bm {bm} bn {bn}): {chi2:.1} over {dof} dof (limit {limit:.1}), ∫pdf over cells {:.5}",
            total / n as f64
        );
        assert!(rel(total, n as f64) < 0.005, "{}", total / n as f64);
        assert!(chi2 < limit, "chi2 {chi2} dof {dof}");
    }
}

#[test]
fn reciprocal_with_mirrored_offset_when_longitudinal_angles_match() {
    // With α = 0 and |θ_i| = |θ_o|, f(wo, wi; h) = f(wi, wo; -h) exactly: M_p is symmetric,
    // A_p and η' depend on |sin θ_o| only, and N_p(-φ; h) = N_p(φ; -h). The far field
    // (the h-average) is then reciprocal too.
    let f = ChiangFibre {
        sigma_a: DVec3::new(0.4, 0.9, 1.7),
        beta_m: 0.35,
        beta_n: 0.45,
        alpha: 0.0,
        eta: 1.55,
    };
    let mut rng = Pcg32::new(5, 5);
    let mut worst = 0.0f64;
    for _ in 0..2000 {
        let so = 2.0 * rng.next_f64() - 1.0;
        let si = if rng.next_f64() < 0.5 { so } else { -so };
        let wo = dir(so, TAU * rng.next_f64());
        let wi = dir(si, TAU * rng.next_f64());
        let h = 2.0 * rng.next_f64() - 1.0;
        let a = f.eval(wo, wi, h);
        let b = f.eval(wi, wo, -h);
        let scale = a.max_element().max(1e-12);
        worst = worst.max((a - b).abs().max_element() / scale);
    }
    println!("near-field reciprocity with mirrored h: worst relative {worst:.2e}");
    assert!(worst < 1e-9, "{worst}");
    // In general (|θ_i| != |θ_o|) pbrt's model is reciprocal only approximately; measure it.
    let mut worst_far = 0.0f64;
    for k in 0..40 {
        let so = -0.9 + 1.8 * (k as f64 + 0.5) / 40.0;
        let si = (0.7 * so + 0.25).clamp(-0.95, 0.95);
        let phi = 0.3 + 0.07 * k as f64;
        let t = Vec3::X;
        let v = dir(so, 0.0).as_vec3();
        let l = dir(si, phi).as_vec3();
        // f = f_cos / cos θ_i, so f(v, l) = far(t, l, v) / cos θ_l.
        let fa = f.far_field_radiance(t, l, v).y / (1.0 - si * si).sqrt();
        let fb = f.far_field_radiance(t, v, l).y / (1.0 - so * so).sqrt();
        worst_far = worst_far.max(rel(fa, fb));
    }
    println!(
        "far-field reciprocity for |theta_i| != |theta_o|: worst relative asymmetry {worst_far:.3}"
    );
}

#[test]
fn far_field_np_quadrature_is_converged() {
    // Doubling the panels changes N̄_p by < 1e-6 relative (beta_n down to 0.1, s ≈ 0.024;
    // measured 5.4e-7, from the kink the wrapped logistic has at ±π, largest at β_n ≈ 0.7).
    let mut worst = 0.0f64;
    for bn in [0.1, 0.3, 0.7, 1.0] {
        let f = fibre(0.7, 0.3, bn, 2.0);
        let s = f.azimuthal_scale();
        let panels = 256usize.max((TAU / s).ceil() as usize);
        for p in 0..4 {
            for phi in [0.0, 0.3, 1.0, 2.0, 3.0, PI] {
                for so in [0.0, 0.6, -0.9] {
                    let a = f.far_field_np(p, phi, so);
                    let b = f.far_field_np_panels(p, phi, so, 2 * panels);
                    let d = (a - b).abs().max_element() / b.max_element().max(1e-6);
                    worst = worst.max(d);
                }
            }
        }
    }
    println!("far-field N_p: worst relative change on doubling panels {worst:.2e}");
    assert!(worst < 1e-6, "{worst}");
}

#[test]
fn far_field_np_is_even_and_white_lobes_carry_all_energy() {
    // N̄_p(-φ) = N̄_p(φ); for a white fibre Σ_p ∫ N̄_p dφ = ½ ∫ Σ A_p dh = 1.
    let f = fibre(0.0, 0.3, 0.3, 0.0);
    for so in [0.0, 0.5, -0.85] {
        let mut total = 0.0;
        for p in 0..4 {
            for phi in [0.1, 0.9, 2.5] {
                let a = f.far_field_np(p, phi, so);
                let b = f.far_field_np(p, -phi, so);
                assert!((a - b).abs().max_element() <= 1e-12 * a.max_element().max(1e-12));
            }
            total += gl(-PI, PI, 64, |phi| f.far_field_np(p, phi, so).y);
        }
        assert!((total - 1.0).abs() < 1e-6, "so {so}: {total}");
    }
}

#[test]
fn far_field_radiance_equals_brute_force_h_integral_of_eval() {
    // far_field_radiance(t, l, v) = ½ ∫ f(h) |cos θ_i| dh, here by the midpoint rule over
    // 200 000 offsets of eval in a frame built from t: within 2e-5 relative.
    let mut rng = Pcg32::new(9, 9);
    let mut worst = 0.0f64;
    for (bm, bn, sa, alpha) in [
        (0.3, 0.3, 0.5, 2.0),
        (0.15, 0.1, 0.2, 3.0),
        (0.8, 0.9, 1.5, -2.0),
    ] {
        let f = fibre(sa, bm, bn, alpha);
        for _ in 0..6 {
            let t = uniform_sphere(&mut rng);
            let l = uniform_sphere(&mut rng);
            let v = uniform_sphere(&mut rng);
            let frame = FibreFrame::from_tangent(t).unwrap();
            let (wo, wi) = (frame.to_local(v), frame.to_local(l));
            let n = 200_000;
            let mut sum = DVec3::ZERO;
            for i in 0..n {
                let h = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                sum += f.eval(wo, wi, h) * (1.0 - wi.x * wi.x).sqrt();
            }
            let brute = sum / n as f64;
            let far = f.far_field_radiance(t.as_vec3(), l.as_vec3(), v.as_vec3());
            let d = (far - brute).abs().max_element() / brute.max_element().max(1e-9);
            worst = worst.max(d);
            assert!(d < 2e-5, "bm {bm} bn {bn}: far {far} brute {brute}");
        }
    }
    println!("far field vs brute-force h integral: worst relative {worst:.2e}");
}

/// `(φ_i - φ_o)` wrapped to [-π, π).
fn wrap(x: f64) -> f64 {
    x - TAU * ((x + PI) / TAU).floor()
}

fn refract(d: DVec3, n: DVec3, eta_ratio: f64) -> DVec3 {
    // d incident (travel), n facing against d, eta_ratio = n1 / n2.
    let c = -n.dot(d);
    let k = 1.0 - eta_ratio * eta_ratio * (1.0 - c * c);
    eta_ratio * d + (eta_ratio * c - k.sqrt()) * n
}

#[test]
fn lobe_directions_match_the_cylinder_geometry_of_h() {
    // The h a real ray gets from SegmentBvh::closest_hit, and the lobe centres Φ(0, h) and
    // Φ(1, h) of chiang.rs, describe the same ray: the mirror reflection at the entry point has
    // φ_i - φ_o = Φ(0, h) and the ray refracted through the cylinder and out has
    // φ_i - φ_o = Φ(1, h) (with γ_t from pbrt's η'); both keep θ_i = -θ_o.
    let eta = 1.55;
    let radius = 0.5f32;
    let seg = Segment {
        a: Vec3::new(-50.0, 0.0, 0.0),
        b: Vec3::new(50.0, 0.0, 0.0),
        radius,
        opacity: 1.0,
        strand: 0,
    };
    let bvh = SegmentBvh::build(vec![seg]);
    let frame = FibreFrame::new(DVec3::X, DVec3::Y).unwrap();
    let mut rng = Pcg32::new(1, 1);
    let mut checked = 0;
    for _ in 0..500 {
        let d = DVec3::new(0.8 * (rng.next_f64() - 0.5), 1.0, 0.0).normalize();
        let (s, c) = (TAU * rng.next_f64()).sin_cos();
        // Rotate the ray about the axis by a random angle, offset it across.
        let rot = |v: DVec3| DVec3::new(v.x, c * v.y - s * v.z, s * v.y + c * v.z);
        let d = rot(d);
        let off = rot(DVec3::new(
            0.0,
            0.0,
            0.98 * (2.0 * rng.next_f64() - 1.0) * 0.5,
        ));
        let o = off - 3.0 * d;
        let Some(hit) = bvh.closest_hit(o, d, f64::INFINITY, None) else {
            continue;
        };
        let p = o + hit.t * d;
        let n = DVec3::new(0.0, p.y, p.z).normalize();
        let wo = frame.to_local(-d);
        let phi_o = wo.z.atan2(wo.y);
        let gamma_o = hit.h.asin();
        // R: mirror about n.
        let r = frame.to_local(d - 2.0 * d.dot(n) * n);
        let dphi_r = wrap(r.z.atan2(r.y) - phi_o);
        assert!((wrap(dphi_r - deflection(0, gamma_o, 0.0))).abs() < 1e-9);
        assert!((r.x + wo.x).abs() < 1e-12);
        // TT: refract in, cross, refract out.
        let inside = refract(d, n, 1.0 / eta);
        // Far intersection with the cylinder y² + z² = r² from p along `inside`.
        let (py, pz, dy, dz) = (p.y, p.z, inside.y, inside.z);
        let qa = dy * dy + dz * dz;
        let qb = py * dy + pz * dz;
        let qc = py * py + pz * pz - 0.25;
        let t = (-qb + (qb * qb - qa * qc).max(0.0).sqrt()) / qa;
        let q = p + t * inside;
        let n2 = DVec3::new(0.0, q.y, q.z).normalize();
        let out = refract(inside, -n2, eta);
        let tt = frame.to_local(out);
        let so = wo.x;
        let etap = (eta * eta - so * so).sqrt() / (1.0 - so * so).sqrt();
        let gamma_t = (hit.h / etap).asin();
        let dphi_t = wrap(tt.z.atan2(tt.y) - phi_o);
        assert!(
            wrap(dphi_t - deflection(1, gamma_o, gamma_t)).abs() < 1e-9,
            "h {} : {} vs {}",
            hit.h,
            dphi_t,
            deflection(1, gamma_o, gamma_t)
        );
        assert!((tt.x + wo.x).abs() < 1e-12);
        checked += 1;
    }
    assert!(checked > 450, "{checked}");
}

#[test]
fn invalid_parameters_are_rejected() {
    let ok = ChiangFibre::default();
    assert!(ok.validate().is_ok());
    let cases = [
        ("beta_m", ChiangFibre { beta_m: 0.0, ..ok }),
        ("beta_n", ChiangFibre { beta_n: 1.5, ..ok }),
        ("eta", ChiangFibre { eta: 1.0, ..ok }),
        (
            "alpha",
            ChiangFibre {
                alpha: f64::NAN,
                ..ok
            },
        ),
        (
            "sigma_a",
            ChiangFibre {
                sigma_a: DVec3::new(0.1, -1.0, 0.0),
                ..ok
            },
        ),
    ];
    for (name, f) in cases {
        assert_eq!(f.validate().unwrap_err().name, name);
    }
}
