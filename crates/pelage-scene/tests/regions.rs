//! Per-region hair: mesh UVs (OBJ `vt`, the creature), texture maps and the region keys
//! of scene files, and every way they can be wrong.

use std::path::PathBuf;

use glam::{Vec2, Vec3};
use pelage_scene::obj::parse_obj;
use pelage_scene::{
    GrowthParams, HairParams, HairType, MAX_REGIONS, MapImage, Mesh, MeshError, ObjError,
    RegionParams, RootParams, SceneFile, SceneFileError, TextureMap,
};

/// A square of two triangles whose left and right halves have their own UVs along the
/// middle edge (a seam: positions 2 and 3 each carry two UVs).
const SEAM: &str = "\
v 0 0 0
v 2 0 0
v 1 0 1
v 1 0 0
v 0 0 1
v 2 0 1
vt 0 0
vt 0.5 0
vt 0.5 1
vt 0 1
vt 0.6 0
vt 1 0
vt 1 1
vt 0.6 1
f 1/1 5/4 3/3 4/2
f 4/5 3/8 6/7 2/6
";

#[test]
fn obj_uvs_are_kept_and_a_seam_splits_its_vertices() {
    let mesh = parse_obj(SEAM).unwrap();
    assert!(mesh.has_uvs());
    assert_eq!(mesh.uvs.len(), mesh.positions.len());
    // 8 distinct (position, uv) corners: the two seam positions are split.
    assert_eq!(mesh.positions.len(), 8);
    for (p, uv) in mesh.positions.iter().zip(&mesh.uvs) {
        let expected_u = if p.x < 1.0 || (p.x == 1.0 && uv.x <= 0.5) {
            p.x / 2.0
        } else {
            0.6 + 0.4 * (p.x - 1.0)
        };
        assert!((uv.x - expected_u).abs() < 1e-6, "{p} {uv}");
        assert_eq!(uv.y, p.z);
    }
}

#[test]
fn obj_uv_errors_are_typed_and_name_the_line() {
    let mixed = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nf 1/1 2/1 3/1\nf 2 4 3\n";
    match parse_obj(mixed) {
        Err(ObjError::MixedUvs {
            line: 7,
            has_uv: false,
            first_line: 6,
            ..
        }) => {}
        other => panic!("{other:?}"),
    }
    let bad = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n";
    match parse_obj(bad) {
        Err(e @ ObjError::FaceIndexOutOfRange { line: 5, .. }) => {
            assert!(e.to_string().contains("texture coordinate"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    // No `vt` at all: no UVs, no error.
    let plain = parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    assert!(plain.uvs.is_empty() && !plain.has_uvs());
}

#[test]
fn mesh_uvs_are_validated() {
    let mut mesh = Mesh::plane(1.0, 1.0, 2, 2).unwrap();
    assert!(mesh.has_uvs());
    mesh.uvs.pop();
    assert!(matches!(
        mesh.validate(),
        Err(MeshError::UvCountMismatch { .. })
    ));
    let mut mesh = Mesh::plane(1.0, 1.0, 2, 2).unwrap();
    mesh.uvs[3] = Vec2::new(f32::NAN, 0.0);
    assert!(matches!(
        mesh.validate(),
        Err(MeshError::NonFiniteUv { vertex: 3, .. })
    ));
    // Appending a part without UVs leaves none.
    let mut mesh = Mesh::plane(1.0, 1.0, 1, 1).unwrap();
    mesh.append(&Mesh::icosphere(1.0, 0).unwrap()).unwrap();
    assert!(mesh.uvs.is_empty());
    mesh.validate().unwrap();
}

#[test]
fn creature_uvs_are_its_side_view() {
    let mesh = Mesh::creature();
    assert!(mesh.has_uvs());
    mesh.validate().unwrap();
    let (lo, hi) = mesh.bounds();
    for (p, uv) in mesh.positions.iter().zip(&mesh.uvs) {
        let expected = Vec2::new((p.z - lo.z) / (hi.z - lo.z), (p.y - lo.y) / (hi.y - lo.y));
        assert!((*uv - expected).abs().max_element() < 1e-5, "{p} {uv}");
    }
    // The nose is at u = 1, the tail at u = 0, the ear tips at v = 1.
    let top = mesh
        .positions
        .iter()
        .zip(&mesh.uvs)
        .max_by(|a, b| a.0.y.total_cmp(&b.0.y));
    assert_eq!(top.map(|(_, uv)| uv.y), Some(1.0));
    println!("creature bounds (centred): {lo} .. {hi}");
}

/// A 2 x 1 region map: region 0 on the left half of the UV square, `right` on the right.
fn halves(right: u8) -> TextureMap {
    TextureMap::from_image(
        "halves.png",
        MapImage::new(2, 1, vec![[0, 0, 0, 255], [right, 0, 0, 255]]).unwrap(),
    )
}

fn one_region() -> GrowthParams {
    GrowthParams {
        regions: vec![RegionParams {
            length: Some(0.5),
            ..Default::default()
        }],
        ..Default::default()
    }
}

#[test]
fn region_maps_are_checked_against_the_regions_and_the_mesh() {
    let plane = Mesh::plane(1.0, 1.0, 2, 2).unwrap();
    let regions = one_region().regions.len() + 1;
    let roots = RootParams {
        textures: pelage_scene::RootTextures {
            region: Some(halves(1)),
            ..Default::default()
        },
        ..Default::default()
    };
    roots.validate_maps(regions, Some(&plane)).unwrap();

    // A texel naming region 2 of 2.
    let mut bad = roots.clone();
    bad.textures.region = Some(halves(2));
    let e = bad.validate_maps(regions, Some(&plane)).unwrap_err();
    assert_eq!(e.name, "roots.textures.region");
    assert!(e.value.contains("texel (1, 0)"), "{e}");

    // A texture map on a mesh without UVs.
    let sphere = Mesh::icosphere(1.0, 1).unwrap();
    let e = roots.validate_maps(regions, Some(&sphere)).unwrap_err();
    assert_eq!(e.name, "roots.textures.region");
    assert!(e.reason.contains("no texture coordinates"), "{e}");

    // A map named but never loaded.
    let mut unloaded = roots.clone();
    unloaded.textures.density = Some(TextureMap::from(PathBuf::from("d.png")));
    let e = unloaded.validate_maps(regions, Some(&plane)).unwrap_err();
    assert_eq!(e.name, "roots.textures.density");

    // Per vertex: one value per vertex, each an existing region, not with a texture.
    let vertex = RootParams {
        region: Some(vec![0, 1, 0, 1, 0, 1, 0, 1, 0]),
        ..Default::default()
    };
    vertex.validate(plane.positions.len()).unwrap();
    vertex.validate_maps(regions, Some(&plane)).unwrap();
    let e = vertex.validate(4).unwrap_err();
    assert_eq!(e.name, "roots.region");
    let mut out_of_range = vertex.clone();
    out_of_range.region.as_mut().unwrap()[5] = 7;
    let e = out_of_range.validate_maps(regions, None).unwrap_err();
    assert_eq!(e.name, "roots.region[5]");
    let mut both = vertex.clone();
    both.textures.region = Some(halves(1));
    assert_eq!(
        both.validate(plane.positions.len()).unwrap_err().name,
        "roots.textures.region"
    );
    // HairParams::validate checks the per-vertex regions too.
    let hair = HairParams {
        roots: out_of_range,
        growth: one_region(),
        ..Default::default()
    };
    assert_eq!(hair.validate(9).unwrap_err().name, "roots.region[5]");
}

#[test]
fn region_values_are_validated_and_named() {
    let cases: Vec<(RegionParams, &str)> = vec![
        (
            RegionParams {
                length: Some(f32::NAN),
                ..Default::default()
            },
            "growth.regions[1].length",
        ),
        (
            RegionParams {
                width: Some(-1.0),
                ..Default::default()
            },
            "growth.regions[1].width",
        ),
        (
            RegionParams {
                color: Some(Vec3::new(0.1, -0.2, 0.0)),
                ..Default::default()
            },
            "growth.regions[1].color",
        ),
        (
            RegionParams {
                length_jitter: Some(1.5),
                ..Default::default()
            },
            "growth.regions[1].length_jitter",
        ),
        (
            RegionParams {
                hair_type: Some(HairType::Curly {
                    radius: 0.1,
                    pitch: 0.0,
                }),
                ..Default::default()
            },
            "growth.regions[1].hair_type.pitch",
        ),
    ];
    for (region, name) in cases {
        let growth = GrowthParams {
            regions: vec![RegionParams::default(), region],
            ..Default::default()
        };
        assert_eq!(growth.validate().unwrap_err().name, name);
    }
    let many = GrowthParams {
        regions: vec![RegionParams::default(); MAX_REGIONS + 1],
        ..Default::default()
    };
    assert_eq!(many.validate().unwrap_err().name, "growth.regions");
    // Left-out keys keep the base values.
    let resolved = one_region().resolved_regions();
    assert_eq!(resolved.len(), 2);
    assert_eq!(resolved[1].length, 0.5);
    assert_eq!(resolved[1].width, GrowthParams::default().width);
    assert!(resolved.iter().all(|g| g.regions.is_empty()));
}

#[test]
fn scene_files_declare_regions_and_load_their_maps() {
    let text = "\
[hair.roots.textures]
region = \"halves.png\"

[[hair.growth.regions]]
length = 0.4
color = [0.5, 0.3, 0.1]
[hair.growth.regions.hair_type]
amplitude = 0.02
frequency = 6.0
kind = \"wavy\"

[[hair.growth.regions]]
width = 0.006
[hair.growth.regions.hair_type]
";
    let scene = SceneFile::parse(text).unwrap();
    let regions = &scene.hair.growth.regions;
    assert_eq!(regions.len(), 2);
    assert!(matches!(regions[0].hair_type, Some(HairType::Wavy { .. })));
    // A left-out tag is the default variant, as in [hair.growth.hair_type].
    assert_eq!(regions[1].hair_type, Some(HairType::Straight));
    // It round-trips (the map as its path).
    let back = SceneFile::parse(&scene.to_toml().unwrap()).unwrap();
    assert_eq!(back, scene);

    // An unknown key in a region is named with its line.
    let e = SceneFile::parse("[[hair.growth.regions]]\nlenght = 0.4\n").unwrap_err();
    assert!(e.to_string().contains("line 2"), "{e}");
    // A bad value is named.
    let e = SceneFile::parse("[[hair.growth.regions]]\nlength = -0.4\n").unwrap_err();
    assert!(e.to_string().contains("growth.regions[0].length"), "{e}");
    // Regions with dynamics are simulated fur grown per region; with a groom, refused.
    let simulated = SceneFile::parse(
        "[hair.roots.textures]\nregion = \"halves.png\"\n[[hair.growth.regions]]\nlength = 0.4\n\
         [dynamics]\n",
    );
    assert!(simulated.is_ok(), "{simulated:?}");
    let e = SceneFile::parse("[[hair.growth.regions]]\nlength = 0.4\n[groom]\npath = \"x.hair\"\n")
        .unwrap_err();
    assert!(e.to_string().contains("growth.regions"), "{e}");
    assert!(e.to_string().contains("[groom]"), "{e}");

    // Loading reads the maps relative to the scene file; a missing one is named.
    let dir = std::env::temp_dir().join(format!("pelage-regions-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    match SceneFile::load(&path) {
        Err(e @ SceneFileError::Map { key, .. }) => {
            assert_eq!(key, "roots.textures.region");
            assert!(e.to_string().contains("halves.png"), "{e}");
        }
        other => panic!("{other:?}"),
    }
    // A map naming region 3 of 3.
    let mut png = Vec::new();
    image::GrayImage::from_raw(2, 1, vec![0, 3])
        .unwrap()
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    std::fs::write(dir.join("halves.png"), &png).unwrap();
    match SceneFile::load(&path) {
        Err(SceneFileError::Param { source, .. }) => {
            assert_eq!(source.name, "roots.textures.region")
        }
        other => panic!("{other:?}"),
    }
    png.clear();
    image::GrayImage::from_raw(2, 1, vec![0, 2])
        .unwrap()
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    std::fs::write(dir.join("halves.png"), &png).unwrap();
    let loaded = SceneFile::load(&path).unwrap();
    let image = loaded.hair.roots.textures.region.unwrap().image.unwrap();
    assert_eq!(image.nearest(Vec2::new(0.9, 0.5))[0], 2);
    // Garbage in place of the PNG.
    std::fs::write(dir.join("halves.png"), b"garbage").unwrap();
    assert!(matches!(
        SceneFile::load(&path),
        Err(SceneFileError::Map { .. })
    ));
    std::fs::remove_dir_all(&dir).unwrap();
}
