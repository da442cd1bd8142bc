//! OBJ reader: `parse_obj` must never panic on any text, and a mesh it
//! returns must be valid (`Mesh::validate`) with unit-length normals.
//!
//! The input bytes are parsed as they are when they are UTF-8, and always
//! also after lossy UTF-8 decoding (so non-UTF-8 inputs still reach the
//! parser, with U+FFFD in place of the invalid bytes).

#![no_main]

use libfuzzer_sys::fuzz_target;
use pelage_scene::parse_obj;

fn check(text: &str) {
    let Ok(mesh) = parse_obj(text) else {
        return;
    };
    let report = mesh
        .validate()
        .expect("parse_obj returned a mesh that fails validate");
    assert!(report.triangles >= 1);
    assert_eq!(mesh.positions.len(), mesh.normals.len());
    for n in &mesh.normals {
        assert!(
            (n.length() - 1.0).abs() < 1e-3,
            "parse_obj returned a normal that is not unit length: {n}"
        );
    }
}

fuzz_target!(|data: &[u8]| {
    match std::str::from_utf8(data) {
        Ok(text) => check(text),
        Err(_) => check(&String::from_utf8_lossy(data)),
    }
});
