//! The CPU twin of dual scattering (`pelage_reference::dual`, Zinke et al. 2008 over
//! Chiang's far field): the energies it integrates in closed form against an independent
//! quadrature of the far-field azimuthal terms, energy conservation, and the limits of the
//! model.

use std::f64::consts::{FRAC_PI_2, PI};

use glam::{DVec3, Vec3};
use pelage_reference::chiang::{ChiangFibre, P_MAX, sigma_a_from_concentration};
use pelage_reference::dual::{back_scattering, crossings};

/// `∫` of `N̄_p` over `φ ∈ [lo, hi]` by composite Simpson on `n` (even) intervals.
fn np_integral(f: &ChiangFibre, p: usize, so: f64, lo: f64, hi: f64, n: usize) -> DVec3 {
    let h = (hi - lo) / n as f64;
    let mut sum = DVec3::ZERO;
    for k in 0..=n {
        let w = if k == 0 || k == n {
            1.0
        } else if k % 2 == 1 {
            4.0
        } else {
            2.0
        };
        sum += f.far_field_np(p, lo + k as f64 * h, so) * w;
    }
    sum * (h / 3.0)
}

/// With σ_a = 0 the lobes' forward and backward energies add up to 1 at every θ (pbrt's
/// `∫ f |cos θ| dω` over the sphere: the fibre's albedo, no factor of π), for smooth and
/// rough fibres.
#[test]
fn white_fibre_energies_add_up_to_one() {
    let mut worst: f64 = 0.0;
    for (beta_m, beta_n) in [(0.3, 0.3), (0.6, 0.8), (0.2, 0.15)] {
        let fibre = ChiangFibre {
            sigma_a: DVec3::ZERO,
            beta_m,
            beta_n,
            ..Default::default()
        };
        for k in 0..=16 {
            let theta = FRAC_PI_2 * 0.98 * k as f64 / 16.0;
            let e = fibre.lobe_energies(theta);
            let sum = e.a_f() + e.a_b();
            worst = worst.max((sum - DVec3::ONE).abs().max_element());
            assert!(e.a_b().min_element() > 0.0 && e.a_f().max_element() < 1.0);
        }
    }
    println!("largest |a_f + a_b - 1|: {worst:.2e}");
    assert!(worst < 1e-6, "white fibre a_f + a_b off 1 by {worst}");
}

/// The closed-form φ integral of the energies against Simpson's rule over the twin's own
/// far-field `N̄_p`, for an absorbing fibre: forward `∫_{|φ|>π/2} N̄_p dφ`, backward
/// `∫_{|φ|<π/2}` (`N̄_p` is even in φ).
#[test]
fn energies_match_far_field_quadrature() {
    let fibre = ChiangFibre {
        sigma_a: sigma_a_from_concentration(0.3, 0.1),
        beta_n: 0.5,
        ..Default::default()
    };
    for theta in [0.0f64, 0.5, 1.2] {
        let e = fibre.lobe_energies(theta);
        let so = theta.sin();
        for p in 0..=P_MAX {
            let back = 2.0 * np_integral(&fibre, p, so, 0.0, FRAC_PI_2, 64);
            let front = 2.0 * np_integral(&fibre, p, so, FRAC_PI_2, PI, 64);
            let err = (back - e.backward[p])
                .abs()
                .max((front - e.forward[p]).abs())
                .max_element();
            println!(
                "theta {theta} lobe {p}: forward {:.5} (quadrature {:.5}), backward {:.5} ({:.5})",
                e.forward[p].x, front.x, e.backward[p].x, back.x
            );
            assert!(err < 1e-4, "theta {theta} lobe {p}: {err}");
        }
    }
}

/// `n = τ / (1 - V)`: one fibre in the limit of no shadow, `τ` in deep shadow.
#[test]
fn crossings_limits() {
    assert!((crossings(1.0) - 1.0).abs() < 1e-12);
    assert!((crossings(1.0 - 1e-7) - 1.0).abs() < 1e-6);
    let tau: f64 = 9.0;
    assert!((crossings((-tau).exp()) - tau).abs() < 1e-2);
    let tau: f64 = 0.5;
    assert!((crossings((-tau).exp()) - tau / (1.0 - (-tau).exp())).abs() < 1e-12);
}

/// The dual radiance: unshadowed it is single scattering plus the local back scattering
/// (never less); in deep shadow a channel falls by `a_f` per fibre, so blond keeps its red
/// better than its blue, and it is finite and non-negative everywhere.
#[test]
fn dual_radiance_limits() {
    let fibre = ChiangFibre {
        sigma_a: sigma_a_from_concentration(0.3, 0.0),
        ..Default::default()
    };
    let t = Vec3::X;
    let l = Vec3::new(0.3, 0.8, 0.5).normalize();
    let v = Vec3::new(-0.2, 0.7, -0.68).normalize();
    let single = fibre.far_field_radiance(t, l, v);
    let lit = fibre.dual_radiance(t, l, v, 1.0);
    assert!(lit.cmpge(single).all(), "{lit} < {single}");
    let e = fibre.lobe_energies(f64::from(t.dot(l)).asin().abs());
    for c in 0..3 {
        let b = back_scattering(&fibre.dual_moments(&e, c));
        assert!(b.a_b.is_finite() && b.a_b > 0.0 && b.sigma_b > 0.0, "{b:?}");
    }
    let dark = fibre.dual_radiance(t, l, v, (-6.0f64).exp());
    let darker = fibre.dual_radiance(t, l, v, (-12.0f64).exp());
    assert!(dark.is_finite() && darker.min_element() > 0.0);
    assert!(darker.cmplt(dark).all());
    assert!(darker.x / darker.z > dark.x / dark.z);
}
