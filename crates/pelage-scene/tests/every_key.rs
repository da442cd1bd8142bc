//! Every table of a scene file refuses a key it does not use, naming the key and its
//! line; a tagged table may leave its tag out (it takes the default variant); and every
//! scene written by `SceneFile::to_toml` reads back as it was.

use glam::Vec3;
use pelage_scene::{
    AdsmParams, ChiangParams, DeepOpacityParams, DirectionalLight, GroomSource, GuideParams,
    HairType, KajiyaKayParams, LayerSpacing, Light, MarschnerParams, MeshSource,
    MultipleScattering, PointLight, SadeghiParams, SceneFile, SceneFileError, ShadingModel,
    ShadowMapParams, ShadowParams, Transparency, VoxelParams, WboitWeight,
};

/// Parses `text`, which must fail with a TOML error naming `key` at `line`.
fn refused(text: &str, key: &str, line: usize) -> String {
    let e = match SceneFile::parse(text) {
        Ok(file) => panic!("accepted:\n{text}\nas {file:#?}"),
        Err(e) => e,
    };
    let m = e.to_string();
    assert!(
        matches!(e, SceneFileError::Toml { .. }),
        "not a TOML error for\n{text}\n{m}"
    );
    assert!(
        m.contains(&format!("`{key}`")),
        "{text}\ndoes not name `{key}`:\n{m}"
    );
    assert!(
        m.contains(&format!("at line {line},")),
        "{text}\ndoes not point at line {line}:\n{m}"
    );
    m
}

#[test]
fn an_unknown_key_of_every_table_is_refused_at_its_line() {
    let cases: &[(&str, &str, usize)] = &[
        // Plain tables (serde refused these before, with the key's line).
        ("bogus = 1\n", "bogus", 1),
        ("[hair]\nbogus = 1\n", "bogus", 2),
        ("[hair.roots]\ncount = 10\nbogus = 1\n", "bogus", 3),
        ("[hair.growth]\nbogus = 1\n", "bogus", 2),
        ("[hair.wind]\nbogus = 1\n", "bogus", 2),
        ("[hair.lod]\nbogus = 1\n", "bogus", 2),
        ("[shade]\nbogus = 1\n", "bogus", 2),
        ("[camera]\nbogus = 1\n", "bogus", 2),
        ("[groom]\npath = \"x.hair\"\nbogus = 1\n", "bogus", 3),
        // [mesh], every kind (a unit variant used to drop the key).
        ("[mesh]\nkind = \"creature\"\nbogus = 1\n", "bogus", 3),
        (
            "[mesh]\nkind = \"icosphere\"\nradius = 1.0\nsubdivisions = 2\nbogus = 1\n",
            "bogus",
            5,
        ),
        (
            "[mesh]\nkind = \"torus\"\nmajor_radius = 1.0\nminor_radius = 0.3\nmajor_segments = 8\nminor_segments = 6\nbogus = 1\n",
            "bogus",
            7,
        ),
        (
            "[mesh]\nkind = \"plane\"\nsize_x = 1.0\nsize_z = 1.0\nsubdivisions_x = 2\nsubdivisions_z = 2\nbogus = 1\n",
            "bogus",
            7,
        ),
        (
            "[mesh]\nkind = \"obj\"\npath = \"a.obj\"\nbogus = 1\n",
            "bogus",
            4,
        ),
        // [hair.growth.hair_type], every kind (all used to drop it).
        (
            "[hair.growth.hair_type]\nkind = \"straight\"\nbogus = 1\n",
            "bogus",
            3,
        ),
        (
            "[hair.growth.hair_type]\nkind = \"wavy\"\namplitude = 0.1\nfrequency = 1.0\nbogus = 1\n",
            "bogus",
            5,
        ),
        (
            "[hair.growth.hair_type]\nkind = \"curly\"\nradius = 0.1\npitch = 0.1\nbogus = 1\n",
            "bogus",
            5,
        ),
        // [shadow], every method, and the deep opacity maps' own tables.
        ("[shadow]\nmethod = \"none\"\nbogus = 1\n", "bogus", 3),
        ("[shadow]\nmethod = \"voxel\"\nbogus = 1\n", "bogus", 3),
        (
            "[shadow]\nmethod = \"deep_opacity\"\nbogus = 1\n",
            "bogus",
            3,
        ),
        ("[shadow]\nmethod = \"shadow_map\"\nbogus = 1\n", "bogus", 3),
        ("[shadow]\nmethod = \"adsm\"\nbogus = 1\n", "bogus", 3),
        (
            "[shadow]\nmethod = \"deep_opacity\"\n[shadow.map]\nbogus = 1\n",
            "bogus",
            4,
        ),
        (
            "[shadow]\nmethod = \"deep_opacity\"\n[shadow.spacing]\nkind = \"linear\"\ndepth = 0.1\nbogus = 1\n",
            "bogus",
            6,
        ),
        (
            "[shadow]\nmethod = \"deep_opacity\"\nlayers = 3\n[shadow.spacing]\nkind = \"fractions\"\nends = [0.1, 0.2]\nbogus = 1\n",
            "bogus",
            7,
        ),
        (
            "[shadow]\nmethod = \"adsm\"\n[shadow.map]\nbogus = 1\n",
            "bogus",
            4,
        ),
        // [shade.model], every model; Marschner's own level used to drop it.
        (
            "[shade.model]\nmodel = \"kajiya_kay\"\nbogus_key = 1\n",
            "bogus_key",
            3,
        ),
        (
            "[shade.model]\nmodel = \"marschner\"\nbogus_key = 1\n",
            "bogus_key",
            3,
        ),
        (
            "[shade.model]\nmodel = \"marschner\"\nlut = true\n[shade.model.params]\neta = 1.6\nbogus_key = 1\n",
            "bogus_key",
            6,
        ),
        (
            "[shade.model]\nmodel = \"sadeghi\"\nbogus_key = 1\n",
            "bogus_key",
            3,
        ),
        (
            "[shade.model]\nmodel = \"chiang\"\nbogus_key = 1\n",
            "bogus_key",
            3,
        ),
        // A table under a model that has none.
        (
            "[shade.model]\nmodel = \"chiang\"\n[shade.model.params]\neta = 1.6\n",
            "params",
            3,
        ),
        // [shade.transparency], every method (opaque used to drop it).
        (
            "[shade.transparency]\nmethod = \"opaque\"\nbogus = 1\n",
            "bogus",
            3,
        ),
        (
            "[shade.transparency]\nmethod = \"wboit\"\nbogus = 1\n",
            "bogus",
            3,
        ),
        (
            "[shade.transparency]\nmethod = \"k_buffer\"\nbogus = 1\n",
            "bogus",
            3,
        ),
        (
            "[shade.transparency]\nmethod = \"a_buffer\"\nbogus = 1\n",
            "bogus",
            3,
        ),
        (
            "[shade.transparency]\nmethod = \"dbk\"\nbogus = 1\n",
            "bogus",
            3,
        ),
        (
            "[shade.transparency]\nmethod = \"random_subsets\"\nbogus = 1\n",
            "bogus",
            3,
        ),
        // [[lights]], both kinds, and in a later light.
        (
            "[[lights]]\nkind = \"directional\"\nbogus = 1\n",
            "bogus",
            3,
        ),
        ("[[lights]]\nkind = \"point\"\nbogus = 1\n", "bogus", 3),
        (
            "[[lights]]\nkind = \"directional\"\n[[lights]]\nkind = \"point\"\nintensity = 2.0\nbogus = 1\n",
            "bogus",
            6,
        ),
        // Inline tables and dotted keys.
        (
            "shade = { model = { model = \"sadeghi\", bogus = 2 } }\n",
            "bogus",
            1,
        ),
        (
            "[shade]\nmodel.model = \"marschner\"\nmodel.bogus = 2\n",
            "bogus",
            3,
        ),
        // A variant that does not exist is named where it is written.
        ("[shade.model]\nmodel = \"phong\"\n", "phong", 2),
        (
            "[shadow]\nbias_voxels = 1.0\nmethod = \"rays\"\n",
            "rays",
            3,
        ),
    ];
    for (text, key, line) in cases {
        refused(text, key, *line);
    }
}

#[test]
fn a_left_out_tag_is_the_default_variant() {
    // The case: resolution without method is the default method, voxel.
    let file = SceneFile::parse("[shadow]\nresolution = [64, 64, 64]\n").unwrap();
    assert_eq!(
        file.shadow,
        ShadowParams::Voxel(VoxelParams {
            resolution: [64; 3],
            ..Default::default()
        })
    );
    let file = SceneFile::parse("[shade.model]\nbeta_m = 0.4\n").unwrap();
    assert_eq!(
        file.shade.model,
        ShadingModel::Chiang(ChiangParams {
            beta_m: 0.4,
            ..Default::default()
        })
    );
    // A key of another model than the default names the default it was read against.
    let e = SceneFile::parse("[shade.model]\nshininess = 20.0\n").unwrap_err();
    assert!(e.to_string().contains("unknown field `shininess`"), "{e}");
    assert!(
        e.to_string().contains("so it is \"chiang\", the default"),
        "{e}"
    );
    let file = SceneFile::parse("[[lights]]\nintensity = 3.0\n").unwrap();
    assert_eq!(
        file.lights,
        vec![Light::Directional(DirectionalLight {
            intensity: 3.0,
            ..Default::default()
        })]
    );
    let file = SceneFile::parse("[mesh]\n[shade.transparency]\n[hair.growth.hair_type]\n").unwrap();
    assert_eq!(file, SceneFile::default());
    // A key of another variant under a left-out tag says what the tag became.
    let m = refused("[shade.transparency]\nk = 8\n", "k", 2);
    assert!(
        m.contains("`method` is left out") && m.contains("\"strand_raster\""),
        "{m}"
    );
    let m = refused("[shadow]\npcf_radius = 2\n", "pcf_radius", 2);
    assert!(m.contains("\"voxel\", the default"), "{m}");
    let m = refused("[mesh]\nradius = 2.0\n", "radius", 2);
    assert!(m.contains("\"creature\""), "{m}");
}

#[test]
fn marschner_parameters_may_sit_in_shade_model_or_in_its_params_table() {
    let marschner = |eta: f32, beta_r_deg: f32, lut: bool| ShadingModel::Marschner {
        params: MarschnerParams {
            eta,
            beta_r_deg,
            ..Default::default()
        },
        lut,
    };
    // The old form keeps working.
    let old = "[shade.model]\nmodel = \"marschner\"\nlut = true\n[shade.model.params]\neta = 1.6\nbeta_r_deg = 6.0\n";
    assert_eq!(
        SceneFile::parse(old).unwrap().shade.model,
        marschner(1.6, 6.0, true)
    );
    // The form of every other model.
    let flat = "[shade.model]\nmodel = \"marschner\"\neta = 1.6\nbeta_r_deg = 6.0\nlut = true\n";
    assert_eq!(
        SceneFile::parse(flat).unwrap().shade.model,
        marschner(1.6, 6.0, true)
    );
    // Both at once, for different parameters.
    let mixed =
        "[shade.model]\nmodel = \"marschner\"\neta = 1.6\n[shade.model.params]\nbeta_r_deg = 6.0\n";
    assert_eq!(
        SceneFile::parse(mixed).unwrap().shade.model,
        marschner(1.6, 6.0, false)
    );
    // One parameter in both places is refused at the flat one.
    let twice =
        "[shade.model]\nmodel = \"marschner\"\neta = 1.6\n[shade.model.params]\neta = 1.7\n";
    let m = refused(twice, "eta", 3);
    assert!(m.contains("twice"), "{m}");
    // A flat parameter out of range is named as always.
    let e = SceneFile::parse("[shade.model]\nmodel = \"marschner\"\neta = 0.5\n").unwrap_err();
    assert!(e.to_string().contains("shading.marschner.eta"), "{e}");
}

/// One scene per variant of every tagged table (and the optional tables).
fn every_variant() -> Vec<SceneFile> {
    let mut files = Vec::new();
    let mut push = |f: &dyn Fn(&mut SceneFile)| {
        let mut file = SceneFile::default();
        f(&mut file);
        files.push(file);
    };
    for mesh in [
        MeshSource::Creature,
        MeshSource::Icosphere {
            radius: 1.0,
            subdivisions: 2,
        },
        MeshSource::Torus {
            major_radius: 1.0,
            minor_radius: 0.3,
            major_segments: 8,
            minor_segments: 6,
        },
        MeshSource::Plane {
            size_x: 1.0,
            size_z: 2.0,
            subdivisions_x: 2,
            subdivisions_z: 3,
        },
        MeshSource::Obj {
            path: "head.obj".into(),
        },
    ] {
        push(&|f| f.mesh = mesh.clone());
    }
    for hair_type in [
        HairType::Straight,
        HairType::Wavy {
            amplitude: 0.01,
            frequency: 3.0,
        },
        HairType::Curly {
            radius: 0.01,
            pitch: 0.02,
        },
    ] {
        push(&|f| f.hair.growth.hair_type = hair_type);
    }
    push(&|f| {
        f.hair.roots.density = Some(vec![1.0, 2.0]);
        f.hair.roots.length_scale = Some(vec![0.5]);
    });
    let linear = DeepOpacityParams {
        spacing: LayerSpacing::Linear { depth: 0.02 },
        ..Default::default()
    };
    for shadow in [
        ShadowParams::None,
        ShadowParams::Voxel(VoxelParams {
            voxel_size: Some(0.01),
            ..Default::default()
        }),
        ShadowParams::DeepOpacity(DeepOpacityParams::default()),
        ShadowParams::DeepOpacity(linear),
        ShadowParams::ShadowMap(ShadowMapParams::default()),
        ShadowParams::Adsm(AdsmParams::default()),
    ] {
        push(&|f| f.shadow = shadow.clone());
    }
    for model in [
        ShadingModel::KajiyaKay(KajiyaKayParams::default()),
        ShadingModel::Marschner {
            params: MarschnerParams::default(),
            lut: false,
        },
        ShadingModel::Marschner {
            params: MarschnerParams {
                eta: 1.6,
                ..Default::default()
            },
            lut: true,
        },
        ShadingModel::Sadeghi(SadeghiParams::default()),
        ShadingModel::Chiang(ChiangParams::default()),
        ShadingModel::Chiang(ChiangParams::melanin(0.3, 0.1)),
        ShadingModel::Chiang(ChiangParams {
            sigma_a: Some(Vec3::new(0.1, 0.2, 0.3)),
            multiple_scattering: MultipleScattering::None,
            ..Default::default()
        }),
        ShadingModel::Chiang(ChiangParams {
            multiple_scattering: MultipleScattering::Volume,
            volume_grid: 16,
            volume_iterations: 4,
            ..Default::default()
        }),
    ] {
        push(&|f| f.shade.model = model.clone());
    }
    for transparency in [
        Transparency::Opaque,
        Transparency::Wboit {
            weight: WboitWeight::Eq10,
        },
        Transparency::k_buffer(4),
        Transparency::a_buffer(),
        Transparency::dbk(0.1),
        Transparency::random_subsets(16),
    ] {
        push(&|f| f.shade.transparency = transparency.clone());
    }
    push(&|f| {
        f.lights = vec![
            Light::Point(PointLight::default()),
            Light::Directional(DirectionalLight::default()),
            Light::Point(PointLight {
                intensity: 2.0,
                ..Default::default()
            }),
        ]
    });
    push(&|f| {
        f.groom = Some(GroomSource {
            fit: Some(1.5),
            translation: Vec3::new(0.0, 1.0, 0.0),
            ..GroomSource::new("hair/long.tfx")
        })
    });
    // A groom-only scene.
    push(&|f| {
        f.mesh = MeshSource::None;
        f.groom = Some(GroomSource::new("hair/long.usda"));
    });
    push(&|f| {
        f.groom = Some(GroomSource {
            guides: Some(GuideParams {
                strands: 6000,
                clump: 0.3,
                noise: 0.1,
                ..GuideParams::default()
            }),
            ..GroomSource::new("long_hair.hair")
        })
    });
    files
}

#[test]
fn every_variant_written_out_reads_back_as_it_was() {
    // Also what keeps the check "every key is used" honest: it compares a document with
    // the scene written back, so a key that to_toml does not write would be refused.
    for file in every_variant() {
        let text = file.to_toml().unwrap();
        let back = SceneFile::parse(&text).unwrap_or_else(|e| panic!("{text}\n{e}"));
        assert_eq!(back, file, "{text}");
    }
}

#[test]
fn a_value_out_of_range_is_still_named_after_a_left_out_tag() {
    let e = SceneFile::parse("[shadow]\nresolution = [1, 64, 64]\n").unwrap_err();
    assert!(matches!(e, SceneFileError::Param { .. }), "{e}");
    assert!(e.to_string().contains("shadow.resolution"), "{e}");
}
