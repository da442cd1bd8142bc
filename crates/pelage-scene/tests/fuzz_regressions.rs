//! Regression tests for crashes found while fuzzing the file readers (see
//! `fuzz/README.md`). Each input must give an error, never a panic.

use pelage_scene::{ObjError, parse_obj};

/// Parses `bytes` (UTF-8) and returns the `FaceIndexOutOfRange` fields
/// `(line, kind, index)` of the error, panicking on any other outcome.
fn out_of_range(bytes: &[u8]) -> (usize, &'static str, i64) {
    let text = std::str::from_utf8(bytes).unwrap();
    match parse_obj(text) {
        Err(ObjError::FaceIndexOutOfRange {
            line, kind, index, ..
        }) => (line, kind, index),
        other => panic!("{text:?}: expected FaceIndexOutOfRange, got {other:?}"),
    }
}

// `tobj` parses an `l` (polyline) statement like `f` and exports one with
// three or more vertices as triangles even with `ignore_lines`, so its
// indices reach tobj's `index * 3 + 2` / `index * 2 + 1` arithmetic.
// `parse_obj` used to check only the indices of `f` lines: these inputs made
// that arithmetic overflow (a panic with overflow checks, as in debug builds
// and `cargo test`; a silently wrapped index in release builds).

/// Huge normal index on an `l` line: `vn * 3` overflowed.
#[test]
fn polyline_with_huge_normal_index_is_an_error() {
    let bytes = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nl 1//9223372036854775807 2 3\n";
    assert_eq!(out_of_range(bytes), (5, "normal", 9223372036854775807));
}

/// Normal index whose `* 3` wraps to 2 in release builds, which passed
/// tobj's bounds check and read the wrong normal.
#[test]
fn polyline_with_wrapping_normal_index_is_an_error() {
    let bytes =
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nl 1//6148914691236517207 2//1 3//1\n";
    assert_eq!(out_of_range(bytes), (6, "normal", 6148914691236517207));
}

/// Negative texture index on an `l` line, before any texture coordinate is
/// defined (tobj resolved it to `usize::MAX - 4`): `vt * 2` overflowed.
#[test]
fn polyline_with_negative_texture_index_is_an_error() {
    let bytes = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1/-5 2 3\nvt 0 0\n";
    assert_eq!(out_of_range(bytes), (4, "texture coordinate", -5));
}

/// In-range polylines are still accepted and do not disturb the faces.
#[test]
fn polyline_with_valid_indices_still_parses() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nl 1 2\nl -3 -2 -1\n";
    let mesh = parse_obj(text).unwrap();
    assert!(mesh.validate().is_ok());
}
