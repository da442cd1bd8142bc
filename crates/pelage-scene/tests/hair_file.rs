//! Tests of the `.hair` reader and writer.

use glam::Vec3;
use pelage_scene::{HairFile, HairFileError};

/// Three strands of 3, 2 and 4 points (odd hair count: the u16 segment array
/// leaves the points unaligned), all arrays present.
fn full() -> HairFile {
    let strands = vec![
        vec![Vec3::ZERO, Vec3::Y, Vec3::new(0.1, 2.0, 0.0)],
        vec![Vec3::X, Vec3::new(1.0, 1.0, 0.5)],
        vec![
            Vec3::Z,
            Vec3::new(0.0, 0.5, 1.0),
            Vec3::new(0.0, 1.0, 1.2),
            Vec3::new(0.0, 1.5, 1.5),
        ],
    ];
    let mut hair = HairFile::from_strands(&strands).unwrap();
    let n = hair.points.len();
    hair.has_thickness = true;
    hair.has_transparency = true;
    hair.has_colors = true;
    hair.thickness = (0..n).map(|i| 0.1 + i as f32 * 0.01).collect();
    hair.transparency = (0..n).map(|i| i as f32 / n as f32).collect();
    hair.colors = (0..n)
        .map(|i| Vec3::new(i as f32 * 0.1, 0.5, 1.0 - i as f32 * 0.1))
        .collect();
    hair.info = "test hair: all arrays".to_owned();
    hair.default_segments = 7;
    hair.default_thickness = 0.25;
    hair.default_transparency = 0.5;
    hair.default_color = Vec3::new(0.3, 0.2, 0.1);
    hair
}

/// Two strands, only points: every optional value from the defaults.
fn minimal() -> HairFile {
    let strands = vec![
        vec![Vec3::ZERO, Vec3::Y, Vec3::Y * 2.0],
        vec![Vec3::X, Vec3::new(1.0, 1.0, 0.0)],
    ];
    let mut hair = HairFile::from_strands(&strands).unwrap();
    hair.info = "minimal".to_owned();
    hair
}

/// Four strands of 5 points each, no segments array (default segments 4).
fn default_segments() -> HairFile {
    let strands: Vec<Vec<Vec3>> = (0..4)
        .map(|s| {
            (0..5)
                .map(|k| Vec3::new(s as f32, k as f32 * 0.2, 0.0))
                .collect()
        })
        .collect();
    let mut hair = HairFile::from_strands(&strands).unwrap();
    hair.has_segments = false;
    hair.default_segments = 4;
    hair.has_colors = true;
    hair.colors = (0..20).map(|i| Vec3::splat(i as f32 / 20.0)).collect();
    hair
}

fn cases() -> Vec<(&'static str, HairFile)> {
    vec![
        ("full", full()),
        ("minimal", minimal()),
        ("default segments", default_segments()),
        ("odd hair count, points only", {
            let mut h = minimal();
            h.segments.push(1);
            h.points.extend([Vec3::NEG_X, Vec3::NEG_X + Vec3::Y]);
            h.thickness.extend([1.0; 2]);
            h.transparency.extend([0.0; 2]);
            h.colors.extend([Vec3::ONE; 2]);
            h
        }),
    ]
}

fn set_u32(bytes: &mut [u8], offset: usize, value: u32) {
    bytes[offset..offset + 4].copy_from_slice(&value.to_le_bytes());
}

#[test]
fn write_then_read_is_identical() {
    for (name, hair) in cases() {
        let bytes = hair.write().unwrap();
        let back = HairFile::read(&bytes).unwrap();
        assert_eq!(back, hair, "{name}");
        // ... and read-then-write gives the same bytes.
        assert_eq!(back.write().unwrap(), bytes, "{name}");
    }
}

#[test]
fn file_sizes_and_layout() {
    // Full: header + 3 u16 segments (odd, no padding) + 9 points × (12 + 4 + 4 + 12).
    let bytes = full().write().unwrap();
    assert_eq!(bytes.len(), 128 + 3 * 2 + 9 * 32);
    assert_eq!(&bytes[..4], b"HAIR");
    assert_eq!(u32::from_le_bytes(bytes[4..8].try_into().unwrap()), 3);
    assert_eq!(u32::from_le_bytes(bytes[8..12].try_into().unwrap()), 9);
    assert_eq!(u32::from_le_bytes(bytes[12..16].try_into().unwrap()), 0x1f);
    assert_eq!(&bytes[128..134], &[2, 0, 1, 0, 3, 0]);
    // First point right after the odd-length segment array.
    assert_eq!(
        &bytes[134 + 12..134 + 24],
        &[0, 0, 0, 0, 0, 0, 128, 63, 0, 0, 0, 0]
    );
    // Minimal: header + segments + points only.
    let bytes = minimal().write().unwrap();
    assert_eq!(bytes.len(), 128 + 2 * 2 + 5 * 12);
    assert_eq!(u32::from_le_bytes(bytes[12..16].try_into().unwrap()), 0x3);
    // Default segments: no segments array.
    let bytes = default_segments().write().unwrap();
    assert_eq!(bytes.len(), 128 + 20 * 24);
    assert_eq!(u32::from_le_bytes(bytes[12..16].try_into().unwrap()), 0x12);
}

#[test]
fn defaults_fill_absent_arrays() {
    let mut hair = minimal();
    hair.default_thickness = 0.75;
    hair.thickness = vec![0.75; hair.points.len()];
    let back = HairFile::read(&hair.write().unwrap()).unwrap();
    assert!(back.thickness.iter().all(|&t| t == 0.75));
    assert!(back.transparency.iter().all(|&t| t == 0.0));
    assert!(back.colors.iter().all(|&c| c == Vec3::ONE));
    assert!(!back.has_thickness && !back.has_transparency && !back.has_colors);
    let back = HairFile::read(&default_segments().write().unwrap()).unwrap();
    assert_eq!(back.segments, vec![4; 4]);
    assert!(!back.has_segments);
}

#[test]
fn strands_iterate_in_order() {
    let hair = full();
    let lengths: Vec<usize> = hair.strands().map(<[Vec3]>::len).collect();
    assert_eq!(lengths, vec![3, 2, 4]);
    let ranges: Vec<_> = hair.strand_ranges().collect();
    assert_eq!(ranges, vec![0..3, 3..5, 5..9]);
    assert_eq!(hair.strands().nth(1).unwrap()[0], Vec3::X);
}

#[test]
fn path_round_trip() {
    let dir = std::env::temp_dir().join(format!("pelage-scene-hair-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("full.hair");
    let hair = full();
    std::fs::write(&path, hair.write().unwrap()).unwrap();
    assert_eq!(HairFile::read_path(&path).unwrap(), hair);
    // An inconsistent struct is not encoded.
    let mut bad = hair.clone();
    bad.thickness.pop();
    assert!(bad.write().is_err());
    std::fs::remove_dir_all(&dir).ok();
    // Missing file names its path.
    let err = HairFile::read_path(&dir.join("missing.hair")).unwrap_err();
    assert!(err.to_string().contains("missing.hair"), "{err}");
}

#[test]
fn truncated_file_is_an_error() {
    for (name, hair) in cases() {
        let bytes = hair.write().unwrap();
        // Every cut: inside the header, inside each array, just short of the end.
        for len in 0..bytes.len() {
            let err = HairFile::read(&bytes[..len]).unwrap_err();
            if len < 128 {
                assert!(
                    matches!(err, HairFileError::Truncated { needed: 128, got } if got == len as u64),
                    "{name} cut at {len}: {err}"
                );
            } else {
                assert!(
                    matches!(err, HairFileError::ArraysExceedFile { got, .. } if got == len as u64),
                    "{name} cut at {len}: {err}"
                );
            }
        }
    }
}

#[test]
fn trailing_bytes_are_ignored() {
    let hair = full();
    let mut bytes = hair.write().unwrap();
    bytes.extend_from_slice(&[0xAB; 7]);
    assert_eq!(HairFile::read(&bytes).unwrap(), hair);
}

#[test]
fn wrong_signature_is_an_error() {
    let mut bytes = full().write().unwrap();
    bytes[..4].copy_from_slice(b"HIAR");
    let err = HairFile::read(&bytes).unwrap_err();
    assert!(matches!(err, HairFileError::BadSignature { found } if &found == b"HIAR"));
    assert!(err.to_string().contains("HIAR"), "{err}");
}

#[test]
fn counts_beyond_the_file_are_an_error() {
    let mut bytes = full().write().unwrap();
    set_u32(&mut bytes, 4, u32::MAX);
    set_u32(&mut bytes, 8, u32::MAX);
    let err = HairFile::read(&bytes).unwrap_err();
    match err {
        HairFileError::ArraysExceedFile {
            hair_count,
            point_count,
            needed,
            got,
            ..
        } => {
            assert_eq!((hair_count, point_count), (u32::MAX, u32::MAX));
            assert_eq!(needed, 128 + 34 * u64::from(u32::MAX));
            assert_eq!(got, bytes.len() as u64);
        }
        other => panic!("unexpected {other}"),
    }
    // Huge hair count without a segments array: refused by the point check,
    // nothing of that size is allocated.
    let mut bytes = default_segments().write().unwrap();
    set_u32(&mut bytes, 4, u32::MAX);
    assert!(matches!(
        HairFile::read(&bytes),
        Err(HairFileError::SegmentPointMismatch {
            from_default: true,
            ..
        })
    ));
}

#[test]
fn segment_counts_disagreeing_with_points_are_an_error() {
    // Segments array: change strand 0 from 2 to 3 segments.
    let mut bytes = full().write().unwrap();
    bytes[128] = 3;
    let err = HairFile::read(&bytes).unwrap_err();
    assert!(
        matches!(
            err,
            HairFileError::SegmentPointMismatch {
                hair_count: 3,
                point_count: 9,
                expected_points: 10,
                from_default: false
            }
        ),
        "{err}"
    );
    // Default segments: 4 strands of 5 points but the default says 3 segments.
    let mut bytes = default_segments().write().unwrap();
    set_u32(&mut bytes, 16, 3);
    let err = HairFile::read(&bytes).unwrap_err();
    assert!(
        matches!(
            err,
            HairFileError::SegmentPointMismatch {
                expected_points: 16,
                from_default: true,
                ..
            }
        ),
        "{err}"
    );
}

#[test]
fn default_segments_too_large_is_an_error() {
    // One strand of 70001 points without a segments array.
    let strand: Vec<Vec3> = (0..70_001).map(|i| Vec3::Y * i as f32).collect();
    let mut bytes = Vec::new();
    bytes.extend_from_slice(b"HAIR");
    for v in [1u32, 70_001, 2, 70_000] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    bytes.extend_from_slice(&[0u8; 128 - 20]);
    for p in &strand {
        for x in p.to_array() {
            bytes.extend_from_slice(&x.to_le_bytes());
        }
    }
    assert!(matches!(
        HairFile::read(&bytes),
        Err(HairFileError::DefaultSegmentsTooLarge {
            default_segments: 70_000
        })
    ));
}

#[test]
fn missing_points_array_is_an_error() {
    let mut bytes = minimal().write().unwrap();
    set_u32(&mut bytes, 12, 0x1);
    assert!(matches!(
        HairFile::read(&bytes),
        Err(HairFileError::MissingPoints { arrays: 1 })
    ));
}

#[test]
fn unknown_flag_bits_are_ignored() {
    let hair = full();
    let mut bytes = hair.write().unwrap();
    set_u32(&mut bytes, 12, 0x1f | 1 << 10);
    assert_eq!(HairFile::read(&bytes).unwrap(), hair);
}

#[test]
fn unaligned_read() {
    let hair = full();
    let bytes = hair.write().unwrap();
    for shift in 1..4 {
        let mut buf = vec![0u8; shift];
        buf.extend_from_slice(&bytes);
        assert_eq!(HairFile::read(&buf[shift..]).unwrap(), hair);
    }
}

#[test]
fn nan_point_is_rejected() {
    let mut bytes = full().write().unwrap();
    // Point 4 (second strand, second point), y coordinate.
    let offset = 128 + 3 * 2 + 4 * 12 + 4;
    bytes[offset..offset + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let err = HairFile::read(&bytes).unwrap_err();
    assert!(
        matches!(err, HairFileError::NonFinitePoint { index: 4, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("point 4"), "{err}");
    let mut bytes = full().write().unwrap();
    bytes[offset..offset + 4].copy_from_slice(&f32::INFINITY.to_le_bytes());
    assert!(HairFile::read(&bytes).is_err());
}

#[test]
fn info_is_nul_trimmed_and_lossy() {
    let mut bytes = minimal().write().unwrap();
    bytes[40..40 + 88].fill(b'a');
    bytes[40 + 3] = 0xff;
    let hair = HairFile::read(&bytes).unwrap();
    assert_eq!(hair.info.chars().count(), 88);
    assert!(hair.info.starts_with("aaa\u{fffd}a"));
}

#[test]
fn inconsistent_struct_is_not_written() {
    let mut h = full();
    h.thickness.pop();
    assert!(matches!(
        h.write(),
        Err(HairFileError::LengthMismatch {
            array: "thickness",
            ..
        })
    ));
    let mut h = full();
    h.segments[1] = 5;
    assert!(matches!(
        h.write(),
        Err(HairFileError::SegmentPointMismatch { .. })
    ));
    let mut h = full();
    h.info = "x".repeat(89);
    assert!(matches!(
        h.write(),
        Err(HairFileError::BadInfo { len: 89, .. })
    ));
    let mut h = full();
    h.info = "x".repeat(88);
    assert_eq!(HairFile::read(&h.write().unwrap()).unwrap(), h);
    h.info = "a\0b".to_owned();
    assert!(matches!(
        h.write(),
        Err(HairFileError::BadInfo { has_nul: true, .. })
    ));
    let mut h = minimal();
    h.thickness[0] = 3.0;
    assert!(matches!(
        h.write(),
        Err(HairFileError::NotDefault {
            flag: "has_thickness",
            index: 0,
            ..
        })
    ));
    let mut h = default_segments();
    h.segments[0] = 3;
    h.points.pop();
    h.thickness.pop();
    h.transparency.pop();
    h.colors.pop();
    assert!(matches!(
        h.write(),
        Err(HairFileError::NotDefault {
            flag: "has_segments",
            ..
        })
    ));
    let mut h = full();
    h.points[2].x = f32::NAN;
    assert!(matches!(
        h.write(),
        Err(HairFileError::NonFinitePoint { index: 2, .. })
    ));
}

#[test]
fn from_strands_rejects_bad_strands() {
    let ok = vec![Vec3::ZERO, Vec3::Y];
    assert!(matches!(
        HairFile::from_strands(&[ok.clone(), vec![Vec3::ZERO]]),
        Err(HairFileError::BadStrandLength {
            strand: 1,
            points: 1
        })
    ));
    assert!(HairFile::from_strands(&[vec![]]).is_err());
    let long = vec![Vec3::ZERO; 65_537];
    assert!(matches!(
        HairFile::from_strands(&[ok.clone(), long]),
        Err(HairFileError::BadStrandLength {
            strand: 1,
            points: 65_537
        })
    ));
    let longest = vec![Vec3::ZERO; 65_536];
    let hair = HairFile::from_strands(&[ok, longest]).unwrap();
    assert_eq!(hair.segments, vec![1, 65_535]);
    assert_eq!(HairFile::read(&hair.write().unwrap()).unwrap(), hair);
    // Empty is fine.
    let empty = HairFile::from_strands(&[]).unwrap();
    assert_eq!(HairFile::read(&empty.write().unwrap()).unwrap(), empty);
}

/// Flips every byte of small valid files to a few values and reads the
/// result: it must never panic (errors are fine), and whatever reads must
/// write back and read again equal.
#[test]
fn corrupted_bytes_never_panic() {
    let mut small = full();
    small.info = "fz".to_owned();
    for hair in [small, minimal(), default_segments()] {
        let bytes = hair.write().unwrap();
        for i in 0..bytes.len() {
            for value in [0x00, 0x01, 0x7f, 0x80, 0xff, bytes[i] ^ 0x10] {
                let mut corrupt = bytes.clone();
                corrupt[i] = value;
                if let Ok(read) = HairFile::read(&corrupt) {
                    let _ = read.strands().count();
                    // Non-finite colours/thickness etc. are allowed and would
                    // not compare equal; only check the write succeeds or
                    // fails cleanly.
                    let _ = read.write();
                }
            }
        }
    }
}

/// A tiny file whose header claims 4 billion strands is named by its header's counts
/// and its real size (it was "larger than 2 GiB (is it a device or a stream?)").
#[test]
fn a_header_claiming_more_than_the_file_holds_names_its_counts_and_the_size() {
    let mut bytes = minimal().write().unwrap();
    set_u32(&mut bytes, 4, u32::MAX);
    set_u32(&mut bytes, 8, u32::MAX);
    let path = std::env::temp_dir().join(format!("pelage-liar-{}.hair", std::process::id()));
    std::fs::write(&path, &bytes).unwrap();
    let e = HairFile::read_path(&path).unwrap_err();
    std::fs::remove_file(&path).unwrap();
    assert!(
        matches!(
            e,
            HairFileError::ArraysExceedFile {
                hair_count: u32::MAX,
                ..
            }
        ),
        "{e}"
    );
    let message = e.to_string();
    assert!(
        message.contains("hair_count 4294967295")
            && message.contains(&format!("the file has {}", bytes.len()))
            && !message.contains("device"),
        "{message}"
    );
}
