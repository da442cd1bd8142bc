//! Parameters as scene-file data: TOML round trips, unknown keys and wrong types named.

use pelage_scene::{Camera, GrowthParams, HairParams, HairType, ShadeParams};

#[test]
fn hair_params_round_trip_through_toml() {
    let mut p = HairParams::default();
    p.growth.hair_type = HairType::Curly {
        radius: 0.01,
        pitch: 0.05,
    };
    p.roots.count = 1234;
    let text = toml::to_string(&p).unwrap();
    let back: HairParams = toml::from_str(&text).unwrap();
    assert_eq!(p, back);
}

#[test]
fn missing_fields_take_their_defaults() {
    let p: HairParams = toml::from_str("[growth]\nsegments = 12\n").unwrap();
    assert_eq!(p.growth.segments, 12);
    assert_eq!(p.growth.length, GrowthParams::default().length);
    let c: Camera = toml::from_str("fov_y = 0.5").unwrap();
    assert_eq!(c.near, Camera::default().near);
    let s: ShadeParams = toml::from_str("").unwrap();
    assert_eq!(s, ShadeParams::default());
}

#[test]
fn unknown_key_and_wrong_type_are_named() {
    let err = toml::from_str::<HairParams>("[growth]\nsegmets = 12\n")
        .unwrap_err()
        .to_string();
    assert!(err.contains("segmets"), "{err}");
    let err = toml::from_str::<HairParams>("[growth]\nlength = \"long\"\n")
        .unwrap_err()
        .to_string();
    assert!(err.contains("length"), "{err}");
    let err = toml::from_str::<HairParams>("[growth.hair_type]\nkind = \"frizzy\"\n")
        .unwrap_err()
        .to_string();
    assert!(err.contains("frizzy"), "{err}");
}

#[test]
fn lengths_and_widths_whose_squares_overflow_are_refused_by_name() {
    // width = 1e38 drew no hair and length = 1e30 a black mesh, both with exit code 0.
    for (key, value) in [
        ("growth.width", 1e38f32),
        ("growth.width", 1e19),
        ("growth.length", 1e30),
        ("growth.length", 2e9),
    ] {
        let mut g = pelage_scene::GrowthParams::default();
        match key {
            "growth.width" => g.width = value,
            _ => g.length = value,
        }
        let err = g.validate().unwrap_err();
        assert_eq!(err.name, key, "{err}");
        assert!(err.to_string().contains("overflow"), "{err}");
    }
    let at_limit = pelage_scene::GrowthParams {
        length: pelage_scene::MAX_EXTENT,
        ..Default::default()
    };
    assert!(at_limit.validate().is_ok());
}
