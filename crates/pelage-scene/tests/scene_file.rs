//! Scene files: defaults written out, errors that name the key or the path.

use std::path::Path;

use pelage_scene::{MeshSource, MultipleScattering, SceneFile, SceneFileError, Transparency};

const DEFAULT: &str = "../../scenes/default.toml";

#[test]
fn the_committed_default_scene_lists_every_default() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(DEFAULT);
    let generated = SceneFile::default().to_toml().unwrap();
    let header = "# Every key of a pelage scene file with its default value (SceneFile::default()).\n\
                  # Every key is optional. Regenerate with PELAGE_BLESS=1 cargo test -p pelage-scene --test scene_file.\n\n";
    let expected = format!("{header}{generated}");
    if std::env::var_os("PELAGE_BLESS").is_some() {
        std::fs::write(&path, &expected).unwrap();
        return;
    }
    let committed = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e}; bless it with PELAGE_BLESS=1", path.display()));
    assert_eq!(
        committed, expected,
        "scenes/default.toml is stale: bless it with PELAGE_BLESS=1"
    );
    assert_eq!(SceneFile::parse(&committed).unwrap(), SceneFile::default());
}

#[test]
fn an_empty_file_is_the_default_scene_and_keys_override_it() {
    assert_eq!(SceneFile::parse("").unwrap(), SceneFile::default());
    let file = SceneFile::parse(
        "[hair.roots]\ncount = 1234\n[shade.transparency]\nmethod = \"k_buffer\"\nk = 4\n[mesh]\nkind = \"icosphere\"\nradius = 0.5\nsubdivisions = 2\n",
    )
    .unwrap();
    assert_eq!(file.hair.roots.count, 1234);
    assert_eq!(file.shade.transparency, Transparency::k_buffer(4));
    assert_eq!(
        file.mesh,
        MeshSource::Icosphere {
            radius: 0.5,
            subdivisions: 2
        }
    );
    assert!(file.mesh(Path::new("x")).is_ok());
}

#[test]
fn an_unknown_key_is_named_with_its_line() {
    let e = SceneFile::parse("[shade]\nambient = 0.2\nshinyness = 3.0\n").unwrap_err();
    let m = e.to_string();
    println!("{m}");
    assert!(matches!(e, SceneFileError::Toml { .. }));
    assert!(m.contains("shinyness"), "{m}");
    assert!(m.contains("line 3"), "{m}");
}

#[test]
fn a_wrong_type_is_named_with_its_line() {
    let e = SceneFile::parse("[hair.roots]\ncount = \"many\"\n").unwrap_err();
    let m = e.to_string();
    println!("{m}");
    assert!(m.contains("count"), "{m}");
    assert!(m.contains("line 2"), "{m}");
}

#[test]
fn a_bad_value_is_named() {
    let e = SceneFile::parse("[shade]\nambient = -1.0\n").unwrap_err();
    let m = e.to_string();
    println!("{m}");
    assert!(m.contains("shade.ambient"), "{m}");
}

#[test]
fn a_missing_file_and_a_missing_obj_are_named() {
    let dir = std::env::temp_dir().join(format!("pelage-scene-file-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let missing = dir.join("nope.toml");
    let m = SceneFile::load(&missing).unwrap_err().to_string();
    assert!(m.contains("nope.toml"), "{m}");

    let scene = dir.join("scene.toml");
    std::fs::write(&scene, "[mesh]\nkind = \"obj\"\npath = \"head.obj\"\n").unwrap();
    let file = SceneFile::load(&scene).unwrap();
    let m = file.mesh(&scene).unwrap_err().to_string();
    println!("{m}");
    assert!(m.contains("head.obj") && m.contains("scene.toml"), "{m}");

    // Relative to the scene file, not to the current folder.
    std::fs::write(
        dir.join("head.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n",
    )
    .unwrap();
    let mesh = file.mesh(&scene).unwrap();
    assert_eq!(mesh.indices.len(), 3);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn garbage_never_panics() {
    let mut state = 0x9e3779b9u32;
    let base = SceneFile::default().to_toml().unwrap().into_bytes();
    for _ in 0..2000 {
        let mut bytes = base.clone();
        for _ in 0..4 {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            let i = state as usize % bytes.len();
            bytes[i] = (state >> 24) as u8;
        }
        let text = String::from_utf8_lossy(&bytes);
        let _ = SceneFile::parse(&text);
    }
}

#[test]
fn a_groom_table_round_trips_and_its_path_is_relative_to_the_scene() {
    let text = "[groom]\npath = \"hair/long.tfx\"\nsegments = 24\nfit = 1.5\n";
    let file = SceneFile::parse(text).unwrap();
    let groom = file.groom.as_ref().expect("a groom");
    assert_eq!(
        (groom.segments, groom.fit, groom.scale),
        (24, Some(1.5), 1.0),
        "the defaults fill what is left out"
    );
    let again = SceneFile::parse(&file.to_toml().unwrap()).unwrap();
    assert_eq!(again, file);
    // Without a groom the table is not written (the default scene has none).
    assert!(!SceneFile::default().to_toml().unwrap().contains("groom"));

    let dir = std::env::temp_dir().join(format!("pelage-groom-scene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    let loaded = SceneFile::load(&path).unwrap();
    assert_eq!(
        loaded.groom.unwrap().path,
        dir.join("hair/long.tfx"),
        "relative to the scene file's folder"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_groom_scene_without_a_wind_table_has_no_wind_and_mesh_none_needs_a_groom() {
    use pelage_scene::WindParams;
    let calm = SceneFile::parse("[groom]\npath = \"hair.usda\"\n").unwrap();
    assert_eq!(calm.hair.wind, WindParams::calm());
    let windy =
        SceneFile::parse("[groom]\npath = \"hair.usda\"\n[hair.wind]\nstrength = 0.5\n").unwrap();
    assert_eq!(windy.hair.wind.strength, 0.5);
    assert_eq!(windy.hair.wind.turbulence, WindParams::default().turbulence);
    // Without a groom the default breeze stays.
    assert_eq!(
        SceneFile::parse("").unwrap().hair.wind,
        WindParams::default()
    );
    let only =
        SceneFile::parse("[mesh]\nkind = \"none\"\n[groom]\npath = \"hair.usda\"\n").unwrap();
    assert_eq!(only.mesh, MeshSource::None);
    assert!(only.mesh(Path::new("x.toml")).unwrap().indices.is_empty());
    let e = SceneFile::parse("[mesh]\nkind = \"none\"\n").unwrap_err();
    assert!(e.to_string().contains("mesh.kind"), "{e}");
}

#[test]
fn bad_chiang_values_in_a_scene_file_are_named() {
    let chiang = |body: &str| format!("[shade.model]\nmodel = \"chiang\"\n{body}\n");
    for (body, key) in [
        ("eumelanin = -0.5", "shading.chiang.eumelanin"),
        ("pheomelanin = -1.0", "shading.chiang.pheomelanin"),
        ("eumelanin = nan", "shading.chiang.eumelanin"),
        ("beta_m = 0.0", "shading.chiang.beta_m"),
        ("beta_m = 1.5", "shading.chiang.beta_m"),
        ("beta_m = nan", "shading.chiang.beta_m"),
        ("beta_n = -0.2", "shading.chiang.beta_n"),
        ("beta_n = inf", "shading.chiang.beta_n"),
        ("alpha_deg = nan", "shading.chiang.alpha_deg"),
        ("eta = 1.0", "shading.chiang.eta"),
        ("eta = nan", "shading.chiang.eta"),
        ("sigma_a = [0.1, nan, 0.1]", "shading.chiang.sigma_a"),
        (
            "sigma_a = [0.1, 0.1, 0.1]\neumelanin = 1.0",
            "shading.chiang.sigma_a",
        ),
    ] {
        let text = chiang(body);
        let e = SceneFile::parse(&text).unwrap_err();
        let m = e.to_string();
        assert!(
            matches!(&e, SceneFileError::Param { source, .. } if source.name == key),
            "{text}\n{m}"
        );
        assert!(m.contains(key), "{m}");
    }
    let file = SceneFile::parse(&chiang("eumelanin = 0.3\ndual_scattering = false")).unwrap();
    let pelage_scene::ShadingModel::Chiang(p) = file.shade.model else {
        panic!("not chiang");
    };
    assert_eq!(
        (p.eumelanin, p.multiple_scattering),
        (Some(0.3), MultipleScattering::None)
    );
}

#[test]
fn every_scene_in_the_repository_parses_and_blond_chiang_is_blond() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            SceneFile::load(&path).unwrap_or_else(|e| panic!("{e}"));
            count += 1;
        }
    }
    assert!(count >= 3, "{count} scenes");
    let file = SceneFile::load(&dir.join("blond_chiang.toml")).unwrap();
    assert_eq!(file.mesh, MeshSource::Creature);
    let pelage_scene::ShadingModel::Chiang(p) = &file.shade.model else {
        panic!("blond_chiang.toml does not use the Chiang model");
    };
    assert_eq!(p.eumelanin, Some(0.3));
    assert_eq!(
        p.absorption(),
        pelage_scene::Absorption::Fixed(pelage_scene::sigma_a_from_melanin(0.3, 0.0))
    );
}

#[test]
fn dynamics_and_motion_tables_parse_and_name_their_bad_keys() {
    let file = SceneFile::parse(
        "[dynamics]\ndamping = 3.0\ncolliders = [{ center = [0.0, 1.0, 0.0], radius = 0.5 }, \
         { center = [0.0, 0.0, 0.0], end = [0.0, -1.0, 0.0], radius = 0.2 }]\n\
         [motion]\nturn = 0.5\n",
    )
    .unwrap();
    let dynamics = file.dynamics.unwrap();
    assert_eq!(dynamics.damping, 3.0);
    assert_eq!(dynamics.colliders.len(), 2);
    assert_eq!(
        dynamics.colliders[1].end,
        Some(glam::Vec3::new(0.0, -1.0, 0.0))
    );
    assert_eq!(file.motion.unwrap().turn, 0.5);
    assert!(SceneFile::default().dynamics.is_none());
    for (text, key) in [
        ("[dynamics]\ndamping = -1.0\n", "dynamics.damping"),
        ("[dynamics]\nsdf_standoff = -0.1\n", "dynamics.sdf_standoff"),
        ("[dynamics]\nsdf_standoff = 2.5\n", "dynamics.sdf_standoff"),
        ("[dynamics]\nsdf_standoff = nan\n", "dynamics.sdf_standoff"),
        ("[dynamics]\nstiffness = 1.0\n", "stiffness"),
        (
            "[dynamics]\ncolliders = [{ center = [0.0, 0.0, 0.0], radius = 0.0 }]\n",
            "dynamics.colliders[0].radius",
        ),
        ("[motion]\nnod = -1.0\n", "motion.nod"),
    ] {
        let message = SceneFile::parse(text).unwrap_err().to_string();
        assert!(message.contains(key), "{text}: {message}");
    }
}
