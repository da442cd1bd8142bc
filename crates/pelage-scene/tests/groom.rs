//! Tests of the groom type: building from `.hair` and `.tfx`, loading by
//! extension, arc-length resampling, normalisation.

use glam::{Vec2, Vec3};
use pelage_scene::params::MAX_SEGMENTS;
use pelage_scene::{Groom, GroomError, HairFile, TfxFile};

fn polyline_length(points: &[Vec3]) -> f64 {
    points
        .windows(2)
        .map(|w| w[0].as_dvec3().distance(w[1].as_dvec3()))
        .sum()
}

fn assert_close(a: Vec3, b: Vec3, tolerance: f32, what: &str) {
    assert!(
        (a - b).abs().max_element() <= tolerance,
        "{what}: {a} vs {b}"
    );
}

#[test]
fn straight_strand_resamples_evenly() {
    // A straight strand with very uneven point spacing.
    let strand = vec![
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 0.1, 0.0),
        Vec3::new(1.0, 0.15, 0.0),
        Vec3::new(1.0, 2.0, 0.0),
        Vec3::new(1.0, 3.0, 0.0),
    ];
    let groom = Groom::from_strands(&[strand]).unwrap();
    for segments in [1, 2, 3, 6, 16, MAX_SEGMENTS] {
        let r = groom.resample(segments).unwrap();
        assert_eq!(r.points.len(), segments as usize + 1);
        assert_eq!((r.strands, r.skipped), (1, 0));
        assert_eq!(r.segments, segments);
        for (k, p) in r.points.iter().enumerate() {
            let expected = Vec3::new(1.0, 3.0 * k as f32 / segments as f32, 0.0);
            assert_close(
                *p,
                expected,
                1e-6,
                &format!("{segments} segments, point {k}"),
            );
        }
        let gaps: Vec<f32> = r.points.windows(2).map(|w| w[0].distance(w[1])).collect();
        let step = 3.0 / segments as f32;
        assert!(gaps.iter().all(|g| (g - step).abs() < 1e-5), "{gaps:?}");
    }
}

#[test]
fn uneven_polyline_keeps_length_and_endpoints() {
    // Segment lengths 1 and 3 at a right angle: with 4 segments the corner
    // is a sample point, so the resampled polyline has the same length.
    let l_shape = vec![
        Vec3::new(0.5, -1.0, 2.0),
        Vec3::new(1.5, -1.0, 2.0),
        Vec3::new(1.5, 2.0, 2.0),
    ];
    // A zigzag whose corners sit at multiples of 1/8 of its length (lengths
    // 0.25, 0.5, 0.125, 0.125 in different directions, plus a repeated
    // point, a zero-length segment).
    let zigzag = vec![
        Vec3::ZERO,
        Vec3::new(0.25, 0.0, 0.0),
        Vec3::new(0.25, 0.5, 0.0),
        Vec3::new(0.25, 0.5, 0.0),
        Vec3::new(0.25, 0.5, 0.125),
        Vec3::new(0.25 - 0.125 * 0.6, 0.5 + 0.125 * 0.8, 0.125),
    ];
    let groom = Groom::from_strands(&[l_shape.clone(), zigzag.clone()]).unwrap();
    for segments in [8, 16, 64] {
        let r = groom.resample(segments).unwrap();
        let n = segments as usize + 1;
        assert_eq!(r.points.len(), 2 * n);
        for (strand, original) in [&l_shape, &zigzag].into_iter().enumerate() {
            let points = &r.points[strand * n..(strand + 1) * n];
            assert_eq!(points[0], original[0], "root of strand {strand}");
            assert_eq!(
                points[n - 1],
                *original.last().unwrap(),
                "tip of strand {strand}"
            );
            let (before, after) = (polyline_length(original), polyline_length(points));
            assert!(
                ((after - before) / before).abs() < 1e-5,
                "strand {strand}, {segments} segments: length {before} → {after}"
            );
            // Evenly spaced along the arc: every gap is length / segments.
            let step = before / f64::from(segments);
            for w in points.windows(2) {
                let gap = w[0].as_dvec3().distance(w[1].as_dvec3());
                assert!((gap - step).abs() < 1e-5 * before, "gap {gap} vs {step}");
            }
        }
    }
}

#[test]
fn curved_strand_converges_to_its_length() {
    // A quarter circle polyline of 200 points: the resampled length
    // approaches the original from below as segments grow.
    let strand: Vec<Vec3> = (0..200)
        .map(|i| {
            let a = std::f32::consts::FRAC_PI_2 * i as f32 / 199.0;
            Vec3::new(a.cos(), a.sin(), 0.0)
        })
        .collect();
    let length = polyline_length(&strand);
    let groom = Groom::from_strands(std::slice::from_ref(&strand)).unwrap();
    let mut previous = 0.0;
    for segments in [4, 16, 64, 256] {
        let r = groom.resample(segments).unwrap();
        let l = polyline_length(&r.points);
        assert!(
            l <= length + 1e-9 && l >= previous - 1e-9,
            "{segments}: {l}"
        );
        assert_eq!(r.points[0], strand[0]);
        assert_eq!(*r.points.last().unwrap(), *strand.last().unwrap());
        previous = l;
    }
    assert!((length - previous) / length < 1e-4);
}

#[test]
fn degenerate_strands_are_skipped_and_counted() {
    let good = vec![Vec3::ZERO, Vec3::Y];
    let groom = Groom::from_strands(&[
        vec![Vec3::ONE],                        // a single point
        good.clone(),                           // kept
        vec![Vec3::X, Vec3::X, Vec3::X],        // all points equal
        vec![Vec3::Z, Vec3::Z + Vec3::Y * 2.0], // kept
    ])
    .unwrap();
    let r = groom.resample(4).unwrap();
    assert_eq!((r.strands, r.skipped), (2, 2));
    assert_eq!(r.source_strands, vec![1, 3]);
    assert_eq!(r.points.len(), 2 * 5);
    assert_eq!(r.points[0], Vec3::ZERO);
    assert_eq!(r.points[5], Vec3::Z);
    assert_eq!(r.points[9], Vec3::Z + Vec3::Y * 2.0);

    // From a .hair file: a strand with 0 segments is a single point.
    let mut hair = HairFile::from_strands(std::slice::from_ref(&good)).unwrap();
    hair.segments.push(0);
    hair.points.push(Vec3::NEG_ONE);
    hair.thickness.push(1.0);
    hair.transparency.push(0.0);
    hair.colors.push(Vec3::ONE);
    let hair = HairFile::read(&hair.write().unwrap()).unwrap();
    let groom = Groom::from_hair(&hair).unwrap();
    assert_eq!(groom.strand_count(), 2);
    let r = groom.resample(3).unwrap();
    assert_eq!((r.strands, r.skipped), (1, 1));

    // Every strand degenerate: an error, not an empty result.
    let groom = Groom::from_strands(&[vec![Vec3::ONE], vec![Vec3::X; 5]]).unwrap();
    let err = groom.resample(8).unwrap_err();
    assert!(
        matches!(err, GroomError::AllDegenerate { strands: 2 }),
        "{err:?}"
    );
    assert!(err.to_string().contains("degenerate"), "{err}");
}

#[test]
fn resample_refuses_bad_segment_counts() {
    let groom = Groom::from_strands(&[vec![Vec3::ZERO, Vec3::X]]).unwrap();
    for segments in [0, MAX_SEGMENTS + 1, u32::MAX] {
        let err = groom.resample(segments).unwrap_err();
        assert!(
            matches!(err, GroomError::BadSegments { segments: s, .. } if s == segments),
            "{err:?}"
        );
    }
}

#[test]
fn huge_coordinates_do_not_overflow() {
    // Finite f32 points whose distance overflows f32: lengths are f64.
    let groom = Groom::from_strands(&[vec![Vec3::new(-3e38, 0.0, 0.0), Vec3::new(3e38, 0.0, 0.0)]])
        .unwrap();
    let r = groom.resample(2).unwrap();
    assert_eq!(r.points[1], Vec3::ZERO);
    assert!(r.points.iter().all(|p| p.is_finite()));
    let n = groom.normalized(2.0).unwrap();
    assert_close(
        n.points()[0],
        Vec3::new(-1.0, 0.0, 0.0),
        1e-6,
        "normalised root",
    );
}

/// The same strands (4 strands of 6 points) as a .hair file and as a .tfx
/// file, each with a thickness per strand.
fn same_hair_both_ways() -> (HairFile, TfxFile) {
    let strands: Vec<Vec<Vec3>> = (0..4)
        .map(|s| {
            (0..6)
                .map(|k| {
                    let t = k as f32 * 0.2;
                    Vec3::new(s as f32 * 0.5 + 0.1 * t * t, 2.0 - t, 0.3 * t.sin())
                })
                .collect()
        })
        .collect();
    let thickness = [0.01, 0.02, 0.03, 0.04];
    let mut hair = HairFile::from_strands(&strands).unwrap();
    hair.has_thickness = true;
    hair.thickness = thickness
        .iter()
        .flat_map(|&t| std::iter::repeat_n(t, 6))
        .collect();
    let mut tfx = TfxFile::from_strands(&strands).unwrap();
    tfx.thickness = Some(thickness.to_vec());
    tfx.strand_uv = Some(vec![Vec2::ZERO; 4]);
    // Through the bytes, as a loader would see them.
    (
        HairFile::read(&hair.write().unwrap()).unwrap(),
        TfxFile::read(&tfx.write().unwrap()).unwrap(),
    )
}

#[test]
fn from_hair_and_from_tfx_agree() {
    let (hair, tfx) = same_hair_both_ways();
    let a = Groom::from_hair(&hair).unwrap();
    let b = Groom::from_tfx(&tfx).unwrap();
    assert_eq!(a, b);
    assert_eq!(a.strand_count(), 4);
    assert_eq!(a.point_count(), 24);
    assert_eq!(a.offsets(), &[0, 6, 12, 18, 24]);
    assert_eq!(a.strand(2).unwrap(), hair.strands().nth(2).unwrap());
    assert_eq!(a.strand(4), None);
    assert_eq!(a.widths().unwrap()[13], 0.03);
    assert_eq!(a.bounds(), b.bounds());
    assert_eq!(a.resample(7).unwrap(), b.resample(7).unwrap());

    // Without thickness arrays there are no widths.
    let mut hair = hair.clone();
    hair.has_thickness = false;
    hair.thickness = vec![hair.default_thickness; 24];
    let mut tfx = tfx.clone();
    tfx.thickness = None;
    let (a, b) = (
        Groom::from_hair(&hair).unwrap(),
        Groom::from_tfx(&tfx).unwrap(),
    );
    assert_eq!(a, b);
    assert_eq!(a.widths(), None);
    assert_eq!(a.resample(3).unwrap().widths, None);
}

#[test]
fn widths_are_interpolated() {
    let hair = {
        let mut h = HairFile::from_strands(&[vec![Vec3::ZERO, Vec3::Y, Vec3::Y * 3.0]]).unwrap();
        h.has_thickness = true;
        h.thickness = vec![1.0, 0.5, 0.0];
        h
    };
    let r = Groom::from_hair(&hair).unwrap().resample(6).unwrap();
    // Arc length 3 in 6 steps: s = 0, 0.5, 1, 1.5, ... 3.
    let expected = [1.0, 0.75, 0.5, 0.375, 0.25, 0.125, 0.0];
    let widths = r.widths.unwrap();
    for (w, e) in widths.iter().zip(expected) {
        assert!((w - e).abs() < 1e-6, "{widths:?}");
    }
}

#[test]
fn bad_inputs_are_errors() {
    assert!(matches!(
        Groom::from_strands(&[]).unwrap_err(),
        GroomError::NoStrands
    ));
    assert!(matches!(
        Groom::from_strands(&[vec![Vec3::X], vec![]]).unwrap_err(),
        GroomError::EmptyStrand { strand: 1 }
    ));
    let err = Groom::from_strands(&[vec![Vec3::X], vec![Vec3::Y, Vec3::new(0.0, f32::NAN, 0.0)]])
        .unwrap_err();
    assert!(
        matches!(
            err,
            GroomError::NonFinitePoint {
                strand: 1,
                point: 1,
                ..
            }
        ),
        "{err:?}"
    );

    // A .hair file with an empty point list: no strands.
    let empty = HairFile::from_strands(&[]).unwrap();
    assert!(matches!(
        Groom::from_hair(&empty).unwrap_err(),
        GroomError::NoStrands
    ));
    // A HairFile whose public fields disagree.
    let mut hair = HairFile::from_strands(&[vec![Vec3::ZERO, Vec3::X]]).unwrap();
    hair.points.push(Vec3::Y);
    assert!(matches!(
        Groom::from_hair(&hair).unwrap_err(),
        GroomError::InconsistentHair {
            array: "points",
            len: 3,
            expected: 2
        }
    ));
    // Negative and NaN thickness.
    for bad in [-1.0, f32::NAN] {
        let mut hair = HairFile::from_strands(&[vec![Vec3::ZERO, Vec3::X]]).unwrap();
        hair.has_thickness = true;
        hair.thickness = vec![0.5, bad];
        assert!(matches!(
            Groom::from_hair(&hair).unwrap_err(),
            GroomError::BadWidth {
                attribute: "thickness",
                strand: 0,
                point: 1,
                ..
            }
        ));
    }
    // An inconsistent TfxFile.
    let mut tfx = TfxFile::from_strands(&[vec![Vec3::ZERO, Vec3::X]]).unwrap();
    tfx.positions.pop();
    assert!(matches!(
        Groom::from_tfx(&tfx).unwrap_err(),
        GroomError::Tfx(_)
    ));
}

#[test]
fn normalized_centres_and_scales() {
    let groom = Groom::from_strands(&[
        vec![Vec3::new(10.0, 20.0, 30.0), Vec3::new(14.0, 20.0, 30.0)],
        vec![Vec3::new(12.0, 22.0, 31.0)],
    ])
    .unwrap();
    assert_eq!(
        groom.bounds(),
        (Vec3::new(10.0, 20.0, 30.0), Vec3::new(14.0, 22.0, 31.0))
    );
    let n = groom.normalized(2.0).unwrap();
    let (lo, hi) = n.bounds();
    assert_close(lo, Vec3::new(-1.0, -0.5, -0.25), 1e-6, "min");
    assert_close(hi, Vec3::new(1.0, 0.5, 0.25), 1e-6, "max");
    assert_eq!(n.offsets(), groom.offsets());

    // Widths scale with the groom.
    let mut hair = HairFile::from_strands(&[vec![Vec3::ZERO, Vec3::X * 100.0]]).unwrap();
    hair.has_thickness = true;
    hair.thickness = vec![2.0, 1.0];
    let n = Groom::from_hair(&hair).unwrap().normalized(1.0).unwrap();
    assert_eq!(n.widths().unwrap(), &[0.02, 0.01]);

    // A groom that is a single point is only centred.
    let dot = Groom::from_strands(&[vec![Vec3::ONE]]).unwrap();
    assert_eq!(dot.normalized(5.0).unwrap().points(), &[Vec3::ZERO]);

    for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        assert!(matches!(
            groom.normalized(bad).unwrap_err(),
            GroomError::BadTransform { .. }
        ));
    }
}

#[test]
fn transformed_scales_then_moves() {
    let groom = Groom::from_strands(&[vec![Vec3::ZERO, Vec3::ONE]]).unwrap();
    let t = groom.transformed(2.0, Vec3::new(0.0, -1.0, 0.0)).unwrap();
    assert_eq!(
        t.points(),
        &[Vec3::new(0.0, -1.0, 0.0), Vec3::new(2.0, 1.0, 2.0)]
    );
    assert!(matches!(
        groom.transformed(0.0, Vec3::ZERO).unwrap_err(),
        GroomError::BadTransform { .. }
    ));
    assert!(matches!(
        groom
            .transformed(1.0, Vec3::new(0.0, f32::NAN, 0.0))
            .unwrap_err(),
        GroomError::BadTransform { .. }
    ));
    // Overflowing f32 is an error, not an infinite point.
    assert!(matches!(
        groom
            .transformed(f32::MAX, Vec3::splat(f32::MAX))
            .unwrap_err(),
        GroomError::NonFinitePoint { point: 1, .. }
    ));
}

#[test]
fn load_dispatches_on_the_extension() {
    let dir = std::env::temp_dir().join(format!("pelage-scene-groom-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (hair, tfx) = same_hair_both_ways();
    let hair_path = dir.join("a.hair");
    let tfx_path = dir.join("b.TFX");
    std::fs::write(&hair_path, hair.write().unwrap()).unwrap();
    std::fs::write(&tfx_path, tfx.write().unwrap()).unwrap();
    let a = Groom::load(&hair_path).unwrap();
    let b = Groom::load(&tfx_path).unwrap();
    assert_eq!(a, b);

    // The right reader's error comes through.
    let bad = dir.join("bad.tfx");
    std::fs::write(&bad, [0u8; 10]).unwrap();
    assert!(matches!(
        Groom::load(&bad).unwrap_err(),
        GroomError::Tfx(pelage_scene::TfxFileError::Truncated { .. })
    ));
    assert!(matches!(
        Groom::load(dir.join("missing.hair")).unwrap_err(),
        GroomError::Hair(pelage_scene::HairFileError::Io { .. })
    ));

    for (name, shown) in [("c.obj", "the extension .obj"), ("noext", "no extension")] {
        let err = Groom::load(dir.join(name)).unwrap_err();
        assert!(
            matches!(err, GroomError::UnknownExtension { .. }),
            "{err:?}"
        );
        let message = err.to_string();
        assert!(message.contains(shown), "{message}");
        assert!(
            message.contains(".hair") && message.contains(".tfx"),
            "{message}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A `.hair` file's colour array and a `.tfx` file's vertex colours become one colour per
/// strand, each strand's root colour; bad colours anywhere in the array are refused,
/// naming the point.
#[test]
fn per_point_colours_give_each_strand_its_root_colour() {
    let strands = vec![
        vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0],
        vec![Vec3::Y, Vec3::new(1.0, 1.0, 0.0)],
    ];
    let mut hair = HairFile::from_strands(&strands).unwrap();
    let groom = Groom::from_hair(&hair).unwrap();
    assert!(groom.colors().is_none(), "no colour array, no colours");
    hair.has_colors = true;
    hair.colors = vec![
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::ONE,
        Vec3::ONE,
        Vec3::new(0.0, 0.5, 0.0),
        Vec3::ONE,
    ];
    let groom = Groom::from_hair(&hair).unwrap();
    assert_eq!(
        groom.colors().unwrap(),
        &[Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.5, 0.0)]
    );
    // Through the file, and resampled.
    let read = Groom::from_hair(&HairFile::read(&hair.write().unwrap()).unwrap()).unwrap();
    assert_eq!(
        read.resample(4).unwrap().colors,
        groom.colors().map(<[Vec3]>::to_vec)
    );
    // A bad colour past the root is refused too, naming the point and strand.
    hair.colors[4] = Vec3::new(f32::NAN, 0.0, 0.0);
    let e = Groom::from_hair(&hair).unwrap_err();
    assert!(
        matches!(
            e,
            GroomError::BadPointColor {
                point: 4,
                strand: 1,
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("colour array"), "{e}");

    let mut tfx =
        TfxFile::from_strands(&[vec![Vec3::ZERO, Vec3::X], vec![Vec3::Y, Vec3::ONE]]).unwrap();
    tfx.vertex_color = Some(vec![
        glam::Vec4::new(0.2, 0.3, 0.4, 1.0),
        glam::Vec4::ONE,
        glam::Vec4::new(0.5, 0.0, 0.0, 0.5),
        glam::Vec4::ONE,
    ]);
    let groom = Groom::from_tfx(&TfxFile::read(&tfx.write().unwrap()).unwrap()).unwrap();
    assert_eq!(
        groom.colors().unwrap(),
        &[Vec3::new(0.2, 0.3, 0.4), Vec3::new(0.5, 0.0, 0.0)]
    );
}

/// Widths a file gives are named by the file's attribute, with the allowed range, at
/// the groom (they were reported as the scene key `growth.width`).
#[test]
fn widths_too_large_name_the_files_attribute() {
    let mut hair = HairFile::from_strands(&[vec![Vec3::ZERO, Vec3::X]]).unwrap();
    hair.has_thickness = true;
    hair.thickness = vec![0.5, 1e30];
    let e = Groom::from_hair(&hair).unwrap_err().to_string();
    assert!(
        e.contains("thickness of point 1 of strand 0 is 1000000000000000000000000000000")
            && e.contains("0..=1e9")
            && !e.contains("growth.width"),
        "{e}"
    );
    // Scaled past the limit by the scene's placement.
    hair.thickness = vec![0.5, 1e6];
    let e = Groom::from_hair(&hair)
        .unwrap()
        .transformed(1e4, Vec3::ZERO)
        .unwrap_err()
        .to_string();
    assert!(e.contains("width after groom.fit and groom.scale"), "{e}");
}

/// `Groom::read` (an engine's asset loader's bytes) gives what `Groom::load` gives for the
/// same file, chooses the format by the name's extension, and refuses an unknown one,
/// naming the file.
#[test]
fn read_from_bytes_is_load() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut files = vec!["long_hair.hair"];
    if cfg!(feature = "usd") {
        files.push("usd_groom.usda");
    }
    for file in files {
        let path = dir.join(file);
        let loaded = Groom::load(&path).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        // Only the name's extension counts: the bytes come from anywhere.
        let read = Groom::read(bytes, std::path::Path::new(file)).unwrap();
        assert_eq!(read, loaded, "{file}");
    }
    let (_, tfx) = same_hair_both_ways();
    let from_tfx = Groom::from_tfx(&tfx).unwrap();
    let read = Groom::read(tfx.write().unwrap(), std::path::Path::new("a.TFX")).unwrap();
    assert_eq!(read, from_tfx);
    let err = Groom::read(vec![0; 16], std::path::Path::new("hair.obj")).unwrap_err();
    assert!(
        matches!(err, GroomError::UnknownExtension { .. }) && err.to_string().contains("hair.obj"),
        "{err}"
    );
}
