//! Hair materials as artists' tools define them: a scene file that copies a Blender
//! Principled Hair BSDF's inputs means what Blender means (`melanin`, `melanin_redness`,
//! `tint`, Offset as `-alpha_deg`), and the keys that cannot go together are refused with
//! their line.

use std::path::Path;

use glam::Vec3;
use pelage_scene::{Absorption, SceneFile, ShadingModel};

fn chiang(text: &str) -> pelage_scene::ChiangParams {
    let file = SceneFile::parse(text).unwrap_or_else(|e| panic!("{text}\n{e}"));
    let ShadingModel::Chiang(p) = file.shade.model else {
        panic!("not chiang: {text}");
    };
    p
}

#[test]
fn the_principled_hair_scene_is_blenders_default_material() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/principled_hair.toml");
    let file = SceneFile::load(&path).unwrap();
    let ShadingModel::Chiang(p) = &file.shade.model else {
        panic!("principled_hair.toml does not use the Chiang model");
    };
    assert_eq!(
        (p.melanin, p.melanin_redness, p.tint),
        (Some(0.8), Some(1.0), Some(Vec3::ONE))
    );
    assert_eq!(
        (p.beta_m, p.beta_n, p.eta, p.alpha_deg),
        (0.3, 0.3, 1.55, -2.0)
    );
    // Blender's defaults give σ_a = -ln(0.2) · (0.343, 0.733, 1.924) (pure pheomelanin),
    // computed here from the definition, not from pelage's function.
    let q = -(0.2f64.ln());
    let want = [q * 0.343, q * 0.733, q * 1.924];
    let Absorption::Fixed(s) = p.absorption() else {
        panic!("melanin does not fix the absorption");
    };
    for (g, w) in s.to_array().iter().zip(want) {
        assert!((*g as f64 - w).abs() < 1e-5, "{s} against {want:?}");
    }
}

#[test]
fn artist_keys_read_and_write_back() {
    let text = "[shade.model]\nmodel = \"chiang\"\nmelanin = 0.35\nmelanin_redness = 0.2\n\
                tint = [0.9, 0.8, 0.7]\n";
    let p = chiang(text);
    assert_eq!(
        (p.melanin, p.melanin_redness, p.tint),
        (Some(0.35), Some(0.2), Some(Vec3::new(0.9, 0.8, 0.7)))
    );
    let file = SceneFile::parse(text).unwrap();
    let again = SceneFile::parse(&file.to_toml().unwrap()).unwrap();
    assert_eq!(again, file);
}

#[test]
fn artist_keys_out_of_range_or_mixed_are_refused_with_their_line() {
    let cases = [
        ("melanin = 1.5", "shading.chiang.melanin"),
        ("melanin = -0.5", "shading.chiang.melanin"),
        (
            "melanin = 0.5\nmelanin_redness = 2.0",
            "shading.chiang.melanin_redness",
        ),
        (
            "melanin = 0.5\ntint = [0.5, 2.0, 0.5]",
            "shading.chiang.tint",
        ),
        ("melanin_redness = 0.5", "shading.chiang.melanin_redness"),
        ("tint = [0.5, 0.5, 0.5]", "shading.chiang.tint"),
        ("melanin = 0.5\neumelanin = 1.0", "shading.chiang.melanin"),
        (
            "melanin = 0.5\nsigma_a = [0.1, 0.2, 0.3]",
            "shading.chiang.sigma_a",
        ),
    ];
    for (body, key) in cases {
        let text = format!("[shade.model]\nmodel = \"chiang\"\n{body}\n");
        let m = match SceneFile::parse(&text) {
            Ok(f) => panic!("accepted:\n{text}\nas {:?}", f.shade.model),
            Err(e) => e.to_string(),
        };
        assert!(m.contains(key), "{text}\ndoes not name {key}:\n{m}");
    }
}
