//! Tests of OBJ loading.

use std::path::PathBuf;

use glam::Vec3;
use pelage_scene::obj::parse_obj;
use pelage_scene::{MeshError, ObjError, load_obj};

const CUBE: &str = "\
# unit cube, quads, no normals
o cube
v -0.5 -0.5 -0.5
v  0.5 -0.5 -0.5
v  0.5  0.5 -0.5
v -0.5  0.5 -0.5
v -0.5 -0.5  0.5
v  0.5 -0.5  0.5
v  0.5  0.5  0.5
v -0.5  0.5  0.5
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 4 8 7 3
f 1 5 8 4
f 2 3 7 6
";

/// A directory under the system temp dir, unique to this test run and name.
fn temp_dir(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("pelage-scene-obj-{}-{}", std::process::id(), name));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn cube_file_loads_with_computed_normals() {
    let dir = temp_dir("cube");
    let path = dir.join("cube.obj");
    std::fs::write(&path, CUBE).unwrap();
    let mesh = load_obj(&path).unwrap();
    std::fs::remove_dir_all(&dir).ok();

    assert_eq!(mesh.indices.len() / 3, 12);
    assert_eq!(mesh.positions.len(), 8);
    assert_eq!(mesh.normals.len(), 8);
    let report = mesh.validate().unwrap();
    assert!((report.total_area - 6.0).abs() < 1e-5);
    // Corner normals computed from the faces point away from the centre.
    for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
        assert!((n.length() - 1.0).abs() < 1e-5);
        assert!(n.dot(p.normalize()) > 0.9, "normal {n} at {p}");
    }
    // Every face winds CCW seen from outside.
    for tri in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[tri[k] as usize]);
        assert!((b - a).cross(c - a).dot(a + b + c) > 0.0);
    }
}

#[test]
fn file_normals_are_used_and_normalised() {
    let text = "\
v 0 0 0
v 1 0 0
v 0 1 0
vn 0 0 2
f 1//1 2//1 3//1
";
    let mesh = parse_obj(text).unwrap();
    assert_eq!(mesh.normals, vec![Vec3::Z; 3]);
}

#[test]
fn partial_normals_are_recomputed() {
    let text = "\
v 0 0 0
v 1 0 0
v 0 1 0
v 1 1 0
vn 1 0 0
f 1//1 2//1 3//1
f 2 4 3
";
    let mesh = parse_obj(text).unwrap();
    assert_eq!(mesh.normals.len(), mesh.positions.len());
    for n in &mesh.normals {
        assert!((*n - Vec3::Z).length() < 1e-6, "{n}");
    }
}

#[test]
fn several_objects_are_merged() {
    let text = format!("{CUBE}o second\nv 5 0 0\nv 6 0 0\nv 5 1 0\nf 9 10 11\n");
    let mesh = parse_obj(&text).unwrap();
    assert_eq!(mesh.indices.len() / 3, 13);
    assert_eq!(mesh.positions.len(), 11);
    mesh.validate().unwrap();
}

#[test]
fn missing_file_names_the_path() {
    let path = std::env::temp_dir().join("pelage-definitely-missing-file-1234.obj");
    let err = load_obj(&path).unwrap_err();
    assert!(matches!(err, ObjError::Io { .. }));
    assert!(
        err.to_string()
            .contains("pelage-definitely-missing-file-1234.obj"),
        "{err}"
    );
}

#[test]
fn garbage_is_an_error() {
    for text in [
        "this is not an obj file\n\0\u{1}",
        "v 1 2\nf 1 2 3\n",
        "v a b c\n",
        "f x y z\n",
        "v 0 0 0 0\n",
        "vn 1\n",
    ] {
        assert!(parse_obj(text).is_err(), "{text:?} parsed");
    }
    // Not UTF-8.
    let dir = temp_dir("binary");
    let path = dir.join("binary.obj");
    std::fs::write(&path, [0xff, 0xfe, 0x00, 0x80, b'v']).unwrap();
    let err = load_obj(&path).unwrap_err();
    std::fs::remove_dir_all(&dir).ok();
    assert!(matches!(err, ObjError::NotText { offset: 0, .. }), "{err}");
}

#[test]
fn no_faces_is_an_error() {
    for text in [
        "",
        "# nothing\n",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\n",
        "v 0 0 0\nv 1 0 0\nl 1 2\n",
    ] {
        let err = parse_obj(text).unwrap_err();
        assert!(matches!(err, ObjError::NoFaces { .. }), "{text:?}: {err}");
    }
}

#[test]
fn face_index_out_of_range_is_an_error() {
    let cases = [
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", 4, "vertex"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", 0, "vertex"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", -4, "vertex"),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999\n",
            99999999999999999,
            "vertex",
        ),
        // Indices that would overflow tobj's arithmetic.
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//0\n",
            0,
            "normal",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//-9223372036854775807\n",
            -9223372036854775807,
            "normal",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/5\n",
            5,
            "texture coordinate",
        ),
    ];
    for (text, index, kind) in cases {
        let err = parse_obj(text).unwrap_err();
        match &err {
            ObjError::FaceIndexOutOfRange {
                line,
                index: i,
                kind: k,
                ..
            } => {
                assert_eq!(
                    (*line, *i, *k),
                    (text.lines().count(), index, kind),
                    "{err}"
                );
            }
            other => panic!("{text:?}: unexpected {other}"),
        }
    }
}

#[test]
fn invalid_mesh_is_reported() {
    // All faces collinear: parses, but there is no surface.
    let text = "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n";
    let err = parse_obj(text).unwrap_err();
    assert!(
        matches!(
            err,
            ObjError::Invalid {
                source: MeshError::AllTrianglesDegenerate { .. },
                ..
            }
        ),
        "{err}"
    );
    // Huge coordinates overflow to infinity.
    let text = "v 0 0 1e39\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    assert!(parse_obj(text).is_err());
}

#[test]
fn face_index_errors_count_in_plain_english() {
    let err = parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").unwrap_err();
    assert!(
        err.to_string().contains("(3 vertices are defined;"),
        "{err}"
    );
    let err = parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//2\n").unwrap_err();
    assert!(err.to_string().contains("(1 normal is defined;"), "{err}");
}
