//! Stochastic simplification's formulas (seed 002 eqs. 4.1 to 4.7).

use pelage_scene::{LodParams, Transition};

/// ∫₀¹ s(x) dx by the midpoint rule on `n` cells.
fn integral(zone: &Transition, n: u32) -> f64 {
    (0..n)
        .map(|i| f64::from(zone.scale((i as f32 + 0.5) / n as f32)))
        .sum::<f64>()
        / f64::from(n)
}

#[test]
fn width_scale_integrates_to_one_for_every_lambda_and_t() {
    let mut worst: (f64, f32, f32) = (0.0, 0.0, 0.0);
    for li in 1..=200 {
        let lambda = li as f32 / 200.0;
        for ti in 1..=50 {
            let t = ti as f32 / 100.0;
            let zone = Transition::new(lambda, t);
            let err = (integral(&zone, 200_000) - 1.0).abs();
            if err > worst.0 {
                worst = (err, lambda, t);
            }
        }
    }
    println!(
        "largest |∫s - 1| = {:.2e} at lambda {} t {}",
        worst.0, worst.1, worst.2
    );
    assert!(worst.0 < 2e-4, "{worst:?}");
}

#[test]
fn width_scale_is_continuous_monotone_and_one_at_full_detail() {
    for li in 1..=100 {
        let lambda = li as f32 / 100.0;
        for t in [0.01, 0.1, 0.25, 0.5] {
            let zone = Transition::new(lambda, t);
            let mut last = f32::INFINITY;
            for i in 0..=10_000 {
                let s = zone.scale(i as f32 / 10_000.0);
                assert!(s.is_finite() && s >= 0.0, "lambda {lambda} t {t}: s = {s}");
                // Non-increasing, with no jump bigger than the zone's slope allows.
                assert!(s <= last + 1e-4, "lambda {lambda} t {t}: rises at {i}");
                if last.is_finite() {
                    let slope = if zone.t_e > 0.0 {
                        (zone.s_max - zone.s_min) / (2.0 * zone.t_e)
                    } else {
                        0.0
                    };
                    assert!(
                        last - s <= slope / 10_000.0 * 1.01 + 1e-4,
                        "lambda {lambda} t {t}: jump {} at {i}, slope {slope}",
                        last - s
                    );
                }
                last = s;
            }
        }
    }
    let full = Transition::new(1.0, 0.1);
    for i in 0..=100 {
        assert!((full.scale(i as f32 / 100.0) - 1.0).abs() < 1e-6);
    }
}

#[test]
fn the_formulas_meet_at_lambda_plus_t_equal_one() {
    // Eqs. 4.4 and 4.5 switch form at λ + t = 1; s must not jump there.
    let t = 0.2;
    let below = Transition::new(0.8 - 1e-4, t);
    let above = Transition::new(0.8 + 1e-4, t);
    for x in [0.0, 0.5, 0.7, 0.85, 0.95, 1.0] {
        assert!(
            (below.scale(x) - above.scale(x)).abs() < 2e-3,
            "x {x}: {} vs {}",
            below.scale(x),
            above.scale(x)
        );
    }
}

#[test]
fn drawn_strands_are_exactly_those_with_a_width() {
    for lambda in [0.05, 0.1, 0.3, 0.5, 0.85, 0.95, 1.0] {
        for t in [0.05, 0.1, 0.3] {
            let zone = Transition::new(lambda, t);
            for count in [1, 7, 100, 1013] {
                let drawn = zone.drawn(count);
                for i in 0..count {
                    let s = zone.scale((i as f32 + 0.5) / count as f32);
                    if i >= drawn {
                        assert_eq!(s, 0.0, "lambda {lambda} t {t} count {count} strand {i}");
                    }
                }
                // Nothing with a width is left out (but the first strand is always kept).
                if drawn > 1 {
                    assert!(zone.scale((drawn as f32 - 0.5) / count as f32) > 0.0);
                }
            }
        }
    }
}

#[test]
fn lambda_follows_the_coverage_curve() {
    let mut lod = LodParams {
        enabled: true,
        start_pixels: 10_000.0,
        half_at: 0.5,
        min_fraction: 0.01,
        ..LodParams::default()
    };
    // h = 0.5 is linear in the covered area.
    assert!((lod.lambda(2_500.0) - 0.25).abs() < 1e-6);
    assert_eq!(lod.lambda(10_000.0), 1.0);
    assert_eq!(lod.lambda(1e9), 1.0);
    // At h · B0 half the strands are drawn, for any h.
    for h in [0.1, 0.2, 0.3, 0.5] {
        lod.half_at = h;
        assert!((lod.lambda(h * 10_000.0) - 0.5).abs() < 1e-5, "h {h}");
    }
    // The cap, and off means full detail.
    lod.min_fraction = 0.1;
    assert_eq!(lod.lambda(0.0), 0.1);
    lod.enabled = false;
    assert_eq!(lod.lambda(1.0), 1.0);
}

#[test]
fn bad_lod_parameters_are_named() {
    for (lod, name) in [
        (
            LodParams {
                start_pixels: -1.0,
                ..Default::default()
            },
            "lod.start_pixels",
        ),
        (
            LodParams {
                half_at: 0.7,
                ..Default::default()
            },
            "lod.half_at",
        ),
        (
            LodParams {
                transition: 0.0,
                ..Default::default()
            },
            "lod.transition",
        ),
        (
            LodParams {
                min_fraction: f32::NAN,
                ..Default::default()
            },
            "lod.min_fraction",
        ),
        (
            LodParams {
                segment_error_pixels: -0.5,
                ..Default::default()
            },
            "lod.segment_error_pixels",
        ),
    ] {
        let err = lod.validate().unwrap_err();
        assert_eq!(err.name, name, "{err}");
    }
    LodParams::default().validate().unwrap();
}

#[test]
fn shadows_and_transparency_are_sized_down_to_the_picture() {
    use pelage_scene::{ShadowParams, Transparency, VoxelParams};
    let voxel = ShadowParams::default().sized_for(200.0);
    let ShadowParams::Voxel(v) = &voxel else {
        panic!("{voxel:?}")
    };
    // A voxel per 4 pixels, the mesh map 2 texels per pixel (powers of two).
    assert_eq!((v.resolution, v.mesh_map_size), ([64; 3], 512));
    voxel.validate().unwrap();
    // Never more than configured; never less than the floor.
    assert_eq!(
        ShadowParams::default().sized_for(5000.0),
        ShadowParams::default()
    );
    assert_eq!(
        ShadowParams::default().sized_for(f32::NAN),
        ShadowParams::default()
    );
    let ShadowParams::Voxel(v) = ShadowParams::default().sized_for(1.0) else {
        unreachable!()
    };
    assert_eq!((v.resolution[0], v.mesh_map_size), (16, 256));
    // An explicit voxel size is the user's choice.
    let fixed = ShadowParams::Voxel(VoxelParams {
        voxel_size: Some(0.01),
        ..Default::default()
    });
    let ShadowParams::Voxel(v) = fixed.sized_for(10.0) else {
        unreachable!()
    };
    assert_eq!(v.resolution, VoxelParams::default().resolution);
    let dom = ShadowParams::DeepOpacity(Default::default()).sized_for(300.0);
    let ShadowParams::DeepOpacity(d) = &dom else {
        unreachable!()
    };
    assert_eq!(d.map.size, 512);
    dom.validate().unwrap();
    assert_eq!(ShadowParams::None.sized_for(10.0), ShadowParams::None);

    let k = |mean: f64| match Transparency::k_buffer(16).sized_for_depth(mean) {
        Transparency::KBuffer { k } => k,
        other => panic!("{other:?}"),
    };
    assert_eq!(
        (k(0.3), k(1.0), k(3.2), k(6.9), k(500.0), k(f64::NAN)),
        (1, 1, 4, 8, 16, 16)
    );
    assert_eq!(
        Transparency::wboit().sized_for_depth(9.0),
        Transparency::wboit()
    );
}
