//! The volume method's reading of its grid at a fibre (`FibreResponse`, the mirror of
//! `hair_scattered`) against its definition: an even light reads as `A(θ) φ / 4π` with
//! `A = a_f + a_b` integrated by `lobe_energies`, a flux longer than `φ / 3` reads as one
//! of `φ / 3`, and light travelling along `q` reads brighter than light against it.

use std::f64::consts::{FRAC_PI_2, PI};

use glam::{DVec3, DVec4};
use pelage_reference::chiang::ChiangFibre;
use pelage_reference::volume::FibreResponse;

fn fibre() -> ChiangFibre {
    ChiangFibre {
        sigma_a: DVec3::new(0.3, 0.6, 1.2),
        ..Default::default()
    }
}

#[test]
fn even_light_reads_as_the_fibres_energy() {
    let f = fibre();
    let reading = FibreResponse::new(&f);
    // θ on one of the table's 32 texels, so no interpolation is involved.
    let theta = 10.0 * FRAC_PI_2 / 31.0;
    let t = DVec3::X;
    let v = DVec3::new(theta.sin(), theta.cos(), 0.0);
    let phi = DVec3::new(1.0, 2.0, 3.0);
    let field = [0, 1, 2].map(|c| DVec4::new(phi[c], 0.0, 0.0, 0.0));
    let e = f.lobe_energies(theta);
    let want = (e.a_f() + e.a_b()) * phi / (4.0 * PI);
    let got = reading.radiance(t, v, &field);
    for c in 0..3 {
        assert!((got[c] - want[c]).abs() < 1e-9 * want[c], "{got} vs {want}");
    }
}

#[test]
fn a_long_flux_reads_shortened_and_its_direction_counts() {
    let reading = FibreResponse::new(&fibre());
    let t = DVec3::X;
    let v = DVec3::new(0.3, 0.9539392014169457, 0.0);
    let with_flux =
        |flux: DVec3| reading.radiance(t, v, &[DVec4::new(1.0, flux.x, flux.y, flux.z); 3]);
    // Beyond φ / 3 the flux is shortened to φ / 3: the same reading.
    let long = with_flux(DVec3::new(0.2, 0.6, 0.0));
    let third = with_flux(DVec3::new(0.2, 0.6, 0.0).normalize() / 3.0);
    assert!((long - third).length() < 1e-12, "{long} vs {third}");
    // Light travelling toward the camera (forward through the fibre, along q's across
    // part) reads brighter than the even light, and light travelling away from it darker.
    let even = with_flux(DVec3::ZERO);
    let toward = with_flux(v / 3.0);
    let away = with_flux(-v / 3.0);
    for c in 0..3 {
        assert!(
            toward[c] > even[c] && even[c] > away[c] && away[c] >= 0.0,
            "{toward} {even} {away}"
        );
    }
}
