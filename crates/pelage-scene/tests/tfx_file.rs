//! Tests of the TressFX `.tfx` reader and writer.

use glam::{Vec2, Vec3, Vec4};
use pelage_scene::tfx_file::{HEADER_SIZE, MAX_VERTICES_PER_STRAND};
use pelage_scene::{TfxFile, TfxFileError};

/// `count` strands of `vertices` points each, gently curved, root at x = strand.
fn strands(count: usize, vertices: usize) -> Vec<Vec<Vec3>> {
    (0..count)
        .map(|s| {
            (0..vertices)
                .map(|k| {
                    let t = k as f32 / (vertices - 1) as f32;
                    Vec3::new(s as f32 + 0.1 * t * t, t, -0.5 * t)
                })
                .collect()
        })
        .collect()
}

/// Three strands of four vertices, positions only (what AMD's exporter writes
/// without a base mesh).
fn simple() -> TfxFile {
    TfxFile::from_strands(&strands(3, 4)).unwrap()
}

/// Five strands (odd: the thickness array needs padding) of 8 vertices,
/// every optional array present, reserved words set.
fn full() -> TfxFile {
    let mut tfx = TfxFile::from_strands(&strands(5, 8)).unwrap();
    let n = tfx.positions.len();
    tfx.version = 4.1;
    tfx.strand_uv = Some((0..5).map(|s| Vec2::new(s as f32 * 0.2, 0.5)).collect());
    tfx.vertex_uv = Some((0..n).map(|i| Vec2::new(i as f32, -(i as f32))).collect());
    tfx.thickness = Some(vec![0.1, 0.2, 0.3, 0.4, 0.5]);
    tfx.vertex_color = Some(
        (0..n)
            .map(|i| Vec4::new(i as f32 / n as f32, 0.5, 0.25, 1.0))
            .collect(),
    );
    tfx.reserved[0] = 0xdead_beef;
    tfx.reserved[31] = 7;
    tfx
}

fn cases() -> Vec<(&'static str, TfxFile)> {
    let mut thickness_last = simple();
    thickness_last.thickness = Some(vec![1.0, 2.0, 3.0]);
    let mut uv_only = simple();
    uv_only.strand_uv = Some(vec![Vec2::ZERO, Vec2::X, Vec2::Y]);
    vec![
        ("simple", simple()),
        ("full", full()),
        ("thickness last, padded", thickness_last),
        ("strand uv", uv_only),
        (
            "one strand of two vertices",
            TfxFile::from_strands(&strands(1, 2)).unwrap(),
        ),
    ]
}

fn u32_at(bytes: &[u8], offset: usize) -> u32 {
    u32::from_le_bytes(bytes[offset..offset + 4].try_into().unwrap())
}

fn set_u32(bytes: &mut [u8], offset: usize, value: u32) {
    bytes[offset..offset + 4].copy_from_slice(&value.to_le_bytes());
}

fn set_f32(bytes: &mut [u8], offset: usize, value: f32) {
    bytes[offset..offset + 4].copy_from_slice(&value.to_le_bytes());
}

/// Header byte offsets of the fields.
const VERSION: usize = 0;
const STRANDS: usize = 4;
const VERTICES: usize = 8;
const OFFSET_POSITION: usize = 12;
const OFFSET_STRAND_UV: usize = 16;
const OFFSET_THICKNESS: usize = 24;
const OFFSET_COLOR: usize = 28;

#[test]
fn write_then_read_is_identical() {
    for (name, tfx) in cases() {
        let bytes = tfx.write().unwrap();
        let back = TfxFile::read(&bytes).unwrap();
        assert_eq!(back, tfx, "{name}");
        // ... and read-then-write gives the same bytes.
        assert_eq!(back.write().unwrap(), bytes, "{name}");
    }
}

#[test]
fn layout_matches_tressfx_header() {
    let bytes = simple().write().unwrap();
    assert_eq!(bytes.len(), 160 + 12 * 16);
    assert_eq!(f32::from_le_bytes(bytes[0..4].try_into().unwrap()), 4.0);
    assert_eq!(u32_at(&bytes, STRANDS), 3);
    assert_eq!(u32_at(&bytes, VERTICES), 4);
    assert_eq!(u32_at(&bytes, OFFSET_POSITION), 160);
    for field in (16..32).step_by(4) {
        assert_eq!(
            u32_at(&bytes, field),
            0,
            "absent array at header byte {field}"
        );
    }
    assert!(bytes[32..160].iter().all(|&b| b == 0), "reserved words");
    // Strand 1, vertex 3: x = 1.1, y = 1, z = -0.5, w = 1 (movable).
    let v = 160 + (4 + 3) * 16;
    let floats: Vec<f32> = bytes[v..v + 16]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(floats, vec![1.1, 1.0, -0.5, 1.0]);

    // Full: arrays in header order, each 8-byte aligned; 5 thicknesses are
    // 20 bytes, padded to 24.
    let bytes = full().write().unwrap();
    let offsets: Vec<u32> = (12..32).step_by(4).map(|o| u32_at(&bytes, o)).collect();
    let n = 40;
    let pos = 160;
    let strand_uv = pos + n * 16;
    let vertex_uv = strand_uv + 5 * 8;
    let thickness = vertex_uv + n * 8;
    let color = thickness + 24;
    assert_eq!(
        offsets,
        [pos, strand_uv, vertex_uv, thickness, color].map(|o| o as u32)
    );
    assert!(offsets.iter().all(|o| o % 8 == 0));
    assert_eq!(bytes.len(), color + n * 16);
    assert_eq!(u32_at(&bytes, 32), 0xdead_beef);
    assert_eq!(u32_at(&bytes, 156), 7);
}

#[test]
fn inverse_mass_follows_the_exporter() {
    let tfx = simple();
    for strand in tfx.strands() {
        let w: Vec<f32> = strand.iter().map(|p| p.w).collect();
        assert_eq!(w, vec![0.0, 0.0, 1.0, 1.0]);
    }
    assert_eq!(tfx.strand_count(), 3);
    assert_eq!(
        tfx.strands().nth(2).unwrap()[0].truncate(),
        Vec3::new(2.0, 0.0, 0.0)
    );
}

#[test]
fn every_truncation_is_an_error() {
    for (name, tfx) in cases() {
        let bytes = tfx.write().unwrap();
        // Only the padding after a trailing thickness array may go.
        let padding = if name.starts_with("thickness last") {
            4
        } else {
            0
        };
        for len in 0..bytes.len() {
            let result = TfxFile::read(&bytes[..len]);
            if len + padding >= bytes.len() {
                assert_eq!(result.unwrap(), tfx, "{name} cut at {len}");
            } else {
                assert!(result.is_err(), "{name} cut at byte {len} was accepted");
            }
        }
    }
    let err = TfxFile::read(&[0; 100]).unwrap_err();
    assert!(
        matches!(
            err,
            TfxFileError::Truncated {
                needed: 160,
                got: 100,
                ..
            }
        ),
        "{err:?}"
    );
    let message = err.to_string();
    assert!(message.contains("truncated at byte 100"), "{message}");
    assert!(message.contains("header"), "{message}");
}

#[test]
fn unaligned_input_reads_the_same() {
    let tfx = full();
    let bytes = tfx.write().unwrap();
    let mut shifted = vec![0u8; 1];
    shifted.extend_from_slice(&bytes);
    assert_eq!(TfxFile::read(&shifted[1..]).unwrap(), tfx);
}

#[test]
fn arrays_anywhere_in_the_file_are_found() {
    // Positions after the strand UVs, a gap, trailing bytes: not the
    // writer's layout, but a valid file.
    let tfx = simple();
    let mut bytes = vec![0u8; HEADER_SIZE];
    set_f32(&mut bytes, VERSION, 4.0);
    set_u32(&mut bytes, STRANDS, 3);
    set_u32(&mut bytes, VERTICES, 4);
    let uv_at = HEADER_SIZE + 8;
    set_u32(&mut bytes, OFFSET_STRAND_UV, uv_at as u32);
    bytes.resize(uv_at, 0xaa);
    for v in [1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    let pos_at = bytes.len() + 3; // unaligned
    set_u32(&mut bytes, OFFSET_POSITION, pos_at as u32);
    bytes.resize(pos_at, 0xbb);
    for p in &tfx.positions {
        for v in p.to_array() {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    bytes.extend_from_slice(b"trailing");
    let back = TfxFile::read(&bytes).unwrap();
    assert_eq!(back.positions, tfx.positions);
    assert_eq!(
        back.strand_uv,
        Some(vec![
            Vec2::new(1.0, 2.0),
            Vec2::new(3.0, 4.0),
            Vec2::new(5.0, 6.0)
        ])
    );
    assert_eq!(back.thickness, None);
}

#[test]
fn bad_counts_are_errors() {
    let good = simple().write().unwrap();
    let with = |field: usize, value: u32| {
        let mut bytes = good.clone();
        set_u32(&mut bytes, field, value);
        TfxFile::read(&bytes).unwrap_err()
    };

    let err = with(STRANDS, u32::MAX);
    match &err {
        TfxFileError::ArrayExceedsFile {
            array,
            strands,
            vertices_per_strand,
            count,
            end,
            got,
            ..
        } => {
            assert_eq!(*array, "vertex position");
            assert_eq!((*strands, *vertices_per_strand), (u32::MAX, 4));
            assert_eq!(*count, u64::from(u32::MAX) * 4);
            assert_eq!(*end, Some(160 + u64::from(u32::MAX) * 64));
            assert_eq!(*got, good.len() as u64);
        }
        other => panic!("{other:?}"),
    }
    let message = err.to_string();
    assert!(
        message.contains("4294967295 strands × 4 vertices"),
        "{message}"
    );
    assert!(message.contains("truncated"), "{message}");

    assert!(matches!(with(STRANDS, 0), TfxFileError::NoStrands));
    assert!(matches!(
        with(STRANDS, 4),
        TfxFileError::ArrayExceedsFile { .. }
    ));
    for count in [0, 1] {
        let err = with(VERTICES, count);
        assert!(
            matches!(err, TfxFileError::TooFewVerticesPerStrand { count: c } if c == count),
            "{err:?}"
        );
        assert!(err.to_string().contains("at least 2"), "{err}");
    }
    for count in [MAX_VERTICES_PER_STRAND + 1, u32::MAX] {
        assert!(matches!(
            with(VERTICES, count),
            TfxFileError::TooManyVerticesPerStrand { .. }
        ));
    }
    // Both counts huge: still a clean error.
    let mut bytes = good.clone();
    set_u32(&mut bytes, STRANDS, u32::MAX);
    set_u32(&mut bytes, VERTICES, MAX_VERTICES_PER_STRAND);
    assert!(matches!(
        TfxFile::read(&bytes).unwrap_err(),
        TfxFileError::ArrayExceedsFile { .. }
    ));
}

#[test]
fn bad_versions_are_errors() {
    let good = simple().write().unwrap();
    for version in [3.0, 0.0, -4.0, f32::NAN, f32::INFINITY] {
        let mut bytes = good.clone();
        set_f32(&mut bytes, VERSION, version);
        let err = TfxFile::read(&bytes).unwrap_err();
        assert!(
            matches!(err, TfxFileError::UnsupportedVersion { .. }),
            "{version}: {err:?}"
        );
        assert!(err.to_string().contains("TressFX 4"), "{err}");
    }
    let mut bytes = good.clone();
    set_f32(&mut bytes, VERSION, 4.5);
    assert_eq!(TfxFile::read(&bytes).unwrap().version, 4.5);
}

#[test]
fn bad_offsets_are_errors() {
    let good = simple().write().unwrap();
    let len = good.len() as u32;
    let with = |field: usize, value: u32| {
        let mut bytes = good.clone();
        set_u32(&mut bytes, field, value);
        TfxFile::read(&bytes)
    };
    for (field, offset) in [
        (OFFSET_POSITION, len + 1),
        (OFFSET_POSITION, u32::MAX),
        (OFFSET_STRAND_UV, len + 8),
        (OFFSET_COLOR, u32::MAX),
    ] {
        let err = with(field, offset).unwrap_err();
        assert!(
            matches!(err, TfxFileError::OffsetBeyondEnd { offset: o, got, .. } if o == offset && got == u64::from(len)),
            "{err:?}"
        );
        assert!(err.to_string().contains("beyond the end"), "{err}");
    }
    // At the very end (or close to it): the array does not fit.
    for (field, offset) in [
        (OFFSET_POSITION, len),
        (OFFSET_POSITION, 168),
        (OFFSET_STRAND_UV, len),
        (OFFSET_THICKNESS, len - 8),
    ] {
        let err = with(field, offset).unwrap_err();
        assert!(
            matches!(err, TfxFileError::ArrayExceedsFile { .. }),
            "{err:?}"
        );
    }
    // Inside the header: the position offset 0 is not "absent".
    for (field, offset, mandatory) in [
        (OFFSET_POSITION, 0, true),
        (OFFSET_POSITION, 159, true),
        (OFFSET_STRAND_UV, 4, false),
    ] {
        let err = with(field, offset).unwrap_err();
        assert!(
            matches!(err, TfxFileError::OffsetInHeader { mandatory: m, .. } if m == mandatory),
            "{err:?}"
        );
    }
    // An optional array overlapping the positions is read as it is.
    let tfx = with(OFFSET_THICKNESS, 160).unwrap();
    assert_eq!(tfx.thickness.as_ref().map(Vec::len), Some(3));
}

#[test]
fn non_finite_values_are_errors() {
    let good = full().write().unwrap();
    let vps = 8;
    for (strand, vertex, component, value) in [
        (0, 0, 0, f32::NAN),
        (2, 5, 1, f32::INFINITY),
        (4, 7, 3, f32::NEG_INFINITY), // w
    ] {
        let mut bytes = good.clone();
        let at = 160 + ((strand * vps + vertex) * 4 + component) * 4;
        set_f32(&mut bytes, at, value);
        let err = TfxFile::read(&bytes).unwrap_err();
        match &err {
            TfxFileError::NonFinitePosition {
                strand: s,
                vertex: v,
                ..
            } => assert_eq!((*s, *v), (strand, vertex)),
            other => panic!("{other:?}"),
        }
        let message = err.to_string();
        assert!(
            message.contains(&format!("vertex {vertex} of strand {strand}")),
            "{message}"
        );
    }
    // NaN thickness of strand 3.
    let mut bytes = good.clone();
    let thickness_at = u32_at(&bytes, OFFSET_THICKNESS) as usize;
    set_f32(&mut bytes, thickness_at + 3 * 4, f32::NAN);
    assert!(matches!(
        TfxFile::read(&bytes).unwrap_err(),
        TfxFileError::NonFiniteThickness { strand: 3, .. }
    ));
    // NaN colours and UVs are carried, not checked.
    let mut bytes = good.clone();
    let color_at = u32_at(&bytes, OFFSET_COLOR) as usize;
    set_f32(&mut bytes, color_at, f32::NAN);
    assert!(
        TfxFile::read(&bytes).unwrap().vertex_color.unwrap()[0]
            .x
            .is_nan()
    );
}

#[test]
fn inconsistent_structs_are_not_written() {
    let mut tfx = simple();
    tfx.positions.pop();
    assert!(matches!(
        tfx.write().unwrap_err(),
        TfxFileError::PositionCount { positions: 11, .. }
    ));
    let mut tfx = simple();
    tfx.positions.clear();
    assert!(matches!(
        tfx.write().unwrap_err(),
        TfxFileError::PositionCount { .. }
    ));
    let mut tfx = simple();
    tfx.thickness = Some(vec![1.0; 4]);
    let err = tfx.write().unwrap_err();
    assert!(matches!(
        err,
        TfxFileError::LengthMismatch {
            array: "thickness",
            len: 4,
            expected: 3,
            per: "strand"
        }
    ));
    let mut tfx = simple();
    tfx.vertex_color = Some(vec![Vec4::ONE; 3]);
    assert!(matches!(
        tfx.write().unwrap_err(),
        TfxFileError::LengthMismatch { expected: 12, .. }
    ));
    let mut tfx = simple();
    tfx.vertices_per_strand = 1;
    assert!(matches!(
        tfx.write().unwrap_err(),
        TfxFileError::TooFewVerticesPerStrand { count: 1 }
    ));
    let mut tfx = simple();
    tfx.version = 3.0;
    assert!(matches!(
        tfx.write().unwrap_err(),
        TfxFileError::UnsupportedVersion { .. }
    ));
    let mut tfx = simple();
    tfx.positions[5].y = f32::NAN;
    assert!(matches!(
        tfx.write().unwrap_err(),
        TfxFileError::NonFinitePosition {
            strand: 1,
            vertex: 1,
            ..
        }
    ));
}

#[test]
fn from_strands_checks_its_input() {
    assert!(matches!(
        TfxFile::from_strands(&[]).unwrap_err(),
        TfxFileError::NoStrands
    ));
    let mut uneven = strands(3, 4);
    uneven[2].pop();
    let err = TfxFile::from_strands(&uneven).unwrap_err();
    assert!(matches!(
        err,
        TfxFileError::UnequalStrands {
            strand: 2,
            len: 3,
            expected: 4
        }
    ));
    assert!(err.to_string().contains("resample"), "{err}");
    assert!(matches!(
        TfxFile::from_strands(&strands(2, 1)).unwrap_err(),
        TfxFileError::TooFewVerticesPerStrand { count: 1 }
    ));
    let mut nan = strands(2, 3);
    nan[1][2].z = f32::NAN;
    assert!(matches!(
        TfxFile::from_strands(&nan).unwrap_err(),
        TfxFileError::NonFinitePosition {
            strand: 1,
            vertex: 2,
            ..
        }
    ));
}

#[test]
fn load_reads_a_file_and_names_a_missing_one() {
    let dir = std::env::temp_dir().join(format!("pelage-scene-tfx-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("full.tfx");
    let tfx = full();
    std::fs::write(&path, tfx.write().unwrap()).unwrap();
    assert_eq!(TfxFile::load(&path).unwrap(), tfx);
    let missing = dir.join("missing.tfx");
    let err = TfxFile::load(&missing).unwrap_err();
    assert!(matches!(err, TfxFileError::Io { .. }));
    assert!(err.to_string().contains("missing.tfx"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// xorshift64*: a small deterministic generator for the mutation loop.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// Whatever `read` accepts passes its own checks and survives write → read
/// (floats compared bit for bit: NaN colours are allowed).
fn check_accepted(tfx: &TfxFile) {
    tfx.check().unwrap();
    let bytes = tfx.write().unwrap();
    let back = TfxFile::read(&bytes).unwrap();
    assert_eq!(format!("{back:?}"), format!("{tfx:?}"));
    assert_eq!(back.write().unwrap(), bytes);
}

#[test]
fn mutated_files_never_panic() {
    let seeds: Vec<Vec<u8>> = cases().iter().map(|(_, t)| t.write().unwrap()).collect();
    let edges = [
        0u32,
        1,
        2,
        3,
        4,
        64,
        159,
        160,
        161,
        65536,
        65537,
        0x7fff_ffff,
        0x8000_0000,
        u32::MAX - 1,
        u32::MAX,
    ];
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut accepted = 0;
    for _ in 0..20_000 {
        let mut bytes = seeds[rng.below(seeds.len())].clone();
        for _ in 0..1 + rng.below(4) {
            match rng.below(6) {
                // Flip one bit anywhere.
                0 => {
                    let i = rng.below(bytes.len());
                    bytes[i] ^= 1 << rng.below(8);
                }
                // Replace one byte.
                1 => {
                    let i = rng.below(bytes.len());
                    bytes[i] = rng.next() as u8;
                }
                // An edge value into a header field.
                2 => {
                    let field = rng.below(8) * 4;
                    let value = edges[rng.below(edges.len())];
                    if bytes.len() >= field + 4 {
                        set_u32(&mut bytes, field, value);
                    }
                }
                // A value near the file length into an offset.
                3 => {
                    let field = 12 + rng.below(5) * 4;
                    let value = (bytes.len() as u32)
                        .wrapping_add(rng.below(33) as u32)
                        .wrapping_sub(16);
                    if bytes.len() >= field + 4 {
                        set_u32(&mut bytes, field, value);
                    }
                }
                // Truncate.
                4 => {
                    let len = rng.below(bytes.len() + 1);
                    bytes.truncate(len);
                }
                // Append garbage.
                _ => {
                    for _ in 0..rng.below(64) {
                        bytes.push(rng.next() as u8);
                    }
                }
            }
            if bytes.is_empty() {
                break;
            }
        }
        if let Ok(tfx) = TfxFile::read(&bytes) {
            accepted += 1;
            check_accepted(&tfx);
        }
    }
    // The loop must exercise the accepting path too, not only errors.
    assert!(
        accepted > 1000,
        "only {accepted} mutated files were accepted"
    );
}
