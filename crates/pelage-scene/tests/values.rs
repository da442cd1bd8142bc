//! Values checked where they are combined, ranges that match the arithmetic, and errors
//! that name what the user wrote (issue 34): lights' colour x intensity, the camera's
//! keys and its top and bottom views, the substep's floor, the pools' floors, maps at
//! every PNG bit depth, and keys that would have no effect.

use std::path::Path;

use glam::{Vec2, Vec3, Vec4};
use pelage_scene::{
    Camera, DirectionalLight, DynamicsParams, GuideParams, Light, MapImage, PointLight, SceneFile,
    SceneFileError, Transparency, WindParams,
};

/// The key of a scene's parameter error, or a panic naming what came instead.
fn key_of(text: &str) -> String {
    match SceneFile::parse(text) {
        Err(SceneFileError::Param { source, .. }) => source.name,
        other => panic!("{text}\nexpected a parameter error, got {other:?}"),
    }
}

fn message_of(text: &str) -> String {
    SceneFile::parse(text).unwrap_err().to_string()
}

#[test]
fn a_light_whose_colour_times_intensity_overflows_is_refused_for_every_kind() {
    for kind in ["directional", "point"] {
        // Each factor is finite; the product is 1e40, past f32.
        let text =
            format!("[[lights]]\nkind = \"{kind}\"\ncolor = [1e20, 1.0, 1.0]\nintensity = 1e20\n");
        assert_eq!(key_of(&text), "lights[0].intensity", "{kind}");
        assert!(message_of(&text).contains("color x intensity"), "{kind}");
        // Below the bound, each channel's product, is fine.
        let fine = format!(
            "[[lights]]\nkind = \"{kind}\"\ncolor = [1000.0, 1.0, 1.0]\nintensity = 1000.0\n"
        );
        SceneFile::parse(&fine).unwrap();
        let over = format!(
            "[[lights]]\nkind = \"{kind}\"\ncolor = [1000.0, 1.0, 1.0]\nintensity = 1000.1\n"
        );
        assert_eq!(key_of(&over), "lights[0].intensity", "{kind}");
    }
}

#[test]
fn a_negative_light_colour_is_refused_for_every_kind() {
    for kind in ["directional", "point"] {
        let text = format!("[[lights]]\nkind = \"{kind}\"\ncolor = [1.0, -0.5, 1.0]\n");
        assert_eq!(key_of(&text), "lights[0].color", "{kind}");
        let text = format!("[[lights]]\nkind = \"{kind}\"\nintensity = -1.0\n");
        assert_eq!(key_of(&text), "lights[0].intensity", "{kind}");
    }
    // The second light is named as the second.
    let text = "[[lights]]\nkind = \"point\"\n[[lights]]\ncolor = [-1.0, 0.0, 0.0]\n";
    assert_eq!(key_of(text), "lights[1].color");
}

#[test]
fn a_point_light_at_the_hairs_centre_names_its_position() {
    let centre = Vec3::new(0.0, 0.5, 0.0);
    let light = Light::Point(PointLight {
        position: centre,
        ..PointLight::default()
    });
    let e = light.shadow_light(1, centre).unwrap_err();
    assert_eq!(e.name, "lights[1].position");
    assert!(e.reason.contains("centre"), "{e}");
    // Anywhere else it gives a direction from the light to the centre.
    let light = Light::Point(PointLight {
        position: centre + Vec3::X,
        ..PointLight::default()
    });
    let d = light.shadow_light(1, centre).unwrap();
    assert_eq!(d.direction, -Vec3::X);
    // A directional light is itself.
    let sun = Light::Directional(DirectionalLight::default());
    assert_eq!(
        sun.shadow_light(0, centre).unwrap(),
        DirectionalLight::default()
    );
}

#[test]
fn camera_keys_are_checked_as_keys_with_their_ranges() {
    for (text, key) in [
        ("[camera]\nnear = 1e-30\n", "camera.near"),
        ("[camera]\nnear = 0.0\n", "camera.near"),
        ("[camera]\nnear = 1.0\nfar = 0.5\n", "camera.far"),
        // A depth range past 32-bit depth.
        ("[camera]\nnear = 1e-5\nfar = 1e3\n", "camera.far"),
        ("[camera]\nfov_y = 1e-30\n", "camera.fov_y"),
        ("[camera]\nfov_y = 3.1415926\n", "camera.fov_y"),
        ("[camera]\neye = [1e30, 0.0, 0.0]\n", "camera.eye"),
        ("[camera]\ntarget = [0.0, 1e30, 0.0]\n", "camera.target"),
        (
            "[camera]\neye = [1.0, 2.0, 3.0]\ntarget = [1.0, 2.0, 3.0]\n",
            "camera.target",
        ),
    ] {
        assert_eq!(key_of(text), key, "{text}");
        let message = message_of(text);
        assert!(!message.contains("projection"), "{text}: {message}");
        assert!(!message.contains("(matrix)"), "{text}: {message}");
    }
    assert!(
        message_of("[camera]\neye = [1.0, 2.0, 3.0]\ntarget = [1.0, 2.0, 3.0]\n")
            .contains("camera.eye")
    );
    // The bounds themselves are accepted and give usable matrices.
    for text in [
        "[camera]\nnear = 1e-6\nfar = 1.0\n",
        "[camera]\nnear = 1e-3\nfar = 1e3\n",
        "[camera]\nfov_y = 1e-4\n",
        "[camera]\nfov_y = 3.1414\n",
    ] {
        let camera = SceneFile::parse(text).unwrap().camera;
        camera.matrices(640, 480).validate().unwrap();
        camera.matrices_reverse_z(640, 480).validate().unwrap();
    }
}

#[test]
fn a_camera_straight_above_or_below_its_target_gives_a_usable_view() {
    let target = Vec3::new(0.0, 0.2, 0.0);
    for (eye, up) in [
        (Vec3::new(0.0, 4.0, 0.0), Vec3::NEG_Z),
        (Vec3::new(0.0, -4.0, 0.0), Vec3::Z),
    ] {
        let camera = Camera {
            eye,
            target,
            ..Camera::default()
        };
        camera.validate().unwrap();
        assert_eq!(camera.up(), up);
        let m = camera.matrices(320, 240);
        m.validate().unwrap();
        assert!(camera.view().is_finite());
        // The target is straight ahead, `up` points up the picture.
        let ahead = m.view.transform_point3(target);
        assert!(
            ahead.x.abs() < 1e-5 && ahead.y.abs() < 1e-5 && ahead.z < 0.0,
            "{ahead}"
        );
        let above = m.view.transform_point3(target + up);
        assert!(above.y > 0.99 && above.x.abs() < 1e-5, "{eye}: {above}");
        // Every point near the target lands on the picture, in front of the eye.
        let clip = m.view_projection() * Vec4::new(0.1, 0.2, -0.1, 1.0);
        assert!(clip.is_finite() && clip.w > 0.0);
        // The same through a scene file.
        let text = format!(
            "[camera]\neye = [{}, {}, {}]\ntarget = [0.0, 0.2, 0.0]\n",
            eye.x, eye.y, eye.z
        );
        SceneFile::parse(&text).unwrap();
    }
    // Looking down from the +z side tends to the same picture as the top view.
    let tilted = Camera {
        eye: Vec3::new(0.0, 4.0, 1e-2),
        target,
        ..Camera::default()
    };
    let top = Camera {
        eye: Vec3::new(0.0, 4.0, 0.0),
        target,
        ..Camera::default()
    };
    let p = Vec3::new(0.3, 0.0, -0.4);
    let (a, b) = (
        tilted.view().transform_point3(p),
        top.view().transform_point3(p),
    );
    assert!((a - b).length() < 0.02, "{a} {b}");
}

#[test]
fn views_that_are_not_vertical_are_unchanged() {
    for eye in [
        Vec3::new(2.2, 0.9, 2.9),
        Vec3::new(0.0, 5.0, 0.01),
        Vec3::new(-3.0, -1.0, 0.2),
    ] {
        let camera = Camera {
            eye,
            ..Camera::default()
        };
        assert_eq!(camera.up(), Vec3::Y);
        assert_eq!(
            camera.view(),
            glam::camera::rh::view::look_at_mat4(eye, camera.target, Vec3::Y)
        );
    }
}

#[test]
fn the_substep_floor_follows_the_scenes_size_and_acceleration() {
    let calm = WindParams::calm();
    let d = DynamicsParams {
        max_substep: 1e-4,
        ..DynamicsParams::default()
    };
    // Gravity 9.8 at 1 unit from the origin: sqrt(4 * 1.19e-7 / 9.8) = 2.2e-4 s.
    let min = d.min_substep(1.0, &calm);
    assert!((min - 2.2e-4).abs() < 0.1e-4, "{min}");
    let e = d.validate_at_scale(1.0, &calm).unwrap_err();
    assert_eq!(e.name, "dynamics.max_substep");
    assert!(e.reason.contains("freeze"), "{e}");
    // At the floor, and for the default substep, it is accepted.
    DynamicsParams {
        max_substep: min,
        ..d.clone()
    }
    .validate_at_scale(1.0, &calm)
    .unwrap();
    DynamicsParams::default()
        .validate_at_scale(1000.0, &calm)
        .unwrap();
    // Four times the size, twice the floor; the wind's mean force counts.
    assert!((d.min_substep(4.0, &calm) / min - 2.0).abs() < 1e-3);
    assert!(d.min_substep(1.0, &WindParams::default()) < min);
    // Nothing pulls: no floor.
    let still = DynamicsParams {
        gravity: Vec3::ZERO,
        ..d
    };
    assert_eq!(still.min_substep(1.0, &calm), 0.0);
    still.validate_at_scale(1.0, &calm).unwrap();
}

#[test]
fn pools_below_their_floor_are_refused_naming_the_key() {
    for (text, key) in [
        (
            "[shade.transparency]\nmethod = \"strand_raster\"\npool = 0.1\n",
            "transparency.pool",
        ),
        (
            "[shade.transparency]\nmethod = \"a_buffer\"\nnodes_per_pixel = 0.05\n",
            "transparency.nodes_per_pixel",
        ),
        (
            "[shade.transparency]\nmethod = \"dbk\"\nnodes_per_pixel = 0.5\n",
            "transparency.nodes_per_pixel",
        ),
    ] {
        assert_eq!(key_of(text), key, "{text}");
        assert!(message_of(text).contains("must be in [1, "), "{text}");
    }
    for method in Transparency::defaults() {
        method.validate_pools().unwrap();
    }
    SceneFile::parse("[shade.transparency]\nmethod = \"strand_raster\"\npool = 1.0\n").unwrap();
}

/// A 2 x 1 PNG of `color` at `depth` whose texels' red channels are `reds` (native
/// values; for a palette image, palette entries of those reds).
fn png_bytes(color: png::ColorType, depth: png::BitDepth, reds: [u16; 2]) -> Vec<u8> {
    use png::ColorType::*;
    let bits = depth as u8 as usize;
    let max = ((1u32 << bits) - 1) as u16;
    let (samples, palette): (Vec<u16>, Option<Vec<u8>>) = match color {
        Grayscale => (reds.to_vec(), None),
        GrayscaleAlpha => (reds.iter().flat_map(|&r| [r, max]).collect(), None),
        Rgb => (reds.iter().flat_map(|&r| [r, 0, 0]).collect(), None),
        Rgba => (reds.iter().flat_map(|&r| [r, 0, 0, max]).collect(), None),
        Indexed => (
            vec![0, 1],
            Some(vec![reds[0] as u8, 0, 0, reds[1] as u8, 0, 0]),
        ),
    };
    let mut row = Vec::new();
    match bits {
        16 => row.extend(samples.iter().flat_map(|s| s.to_be_bytes())),
        8 => row.extend(samples.iter().map(|&s| s as u8)),
        _ => {
            let mut byte = 0u8;
            let mut used = 0;
            for &s in &samples {
                byte |= (s as u8) << (8 - bits - used);
                used += bits;
                if used == 8 {
                    row.push(byte);
                    (byte, used) = (0, 0);
                }
            }
            if used > 0 {
                row.push(byte);
            }
        }
    }
    let mut out = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut out, 2, 1);
        encoder.set_color(color);
        encoder.set_depth(depth);
        if let Some(palette) = palette {
            encoder.set_palette(palette);
        }
        let mut writer = encoder.write_header().unwrap();
        writer.write_image_data(&row).unwrap();
    }
    out
}

#[test]
fn maps_of_every_png_bit_depth_and_colour_type_read_native_regions_and_unit_values() {
    use png::BitDepth::*;
    use png::ColorType::*;
    let cases = [
        (Grayscale, One),
        (Grayscale, Two),
        (Grayscale, Four),
        (Grayscale, Eight),
        (Grayscale, Sixteen),
        (GrayscaleAlpha, Eight),
        (GrayscaleAlpha, Sixteen),
        (Rgb, Eight),
        (Rgb, Sixteen),
        (Rgba, Eight),
        (Rgba, Sixteen),
        (Indexed, One),
        (Indexed, Two),
        (Indexed, Four),
        (Indexed, Eight),
    ];
    for (color, depth) in cases {
        let name = format!("{color:?} {depth:?}");
        // A palette's entries are 8-bit colours whatever the index depth.
        let max = if color == Indexed {
            255
        } else {
            ((1u32 << depth as u8) - 1) as u16
        };
        // Regions: native integers, so region 1 is 1 at every depth.
        let image = MapImage::decode(&png_bytes(color, depth, [0, 1]), Path::new("r.png")).unwrap();
        assert_eq!(image.reds().collect::<Vec<_>>(), [0, 1], "{name}");
        assert_eq!(image.region(Vec2::new(0.75, 0.5)), 1, "{name}");
        assert_eq!(image.max_value(), max, "{name}");
        // Scalars: white is 1 and black 0 at every depth; the middle is the middle.
        let image =
            MapImage::decode(&png_bytes(color, depth, [0, max]), Path::new("s.png")).unwrap();
        assert_eq!(image.scalar(Vec2::new(0.25, 0.5)), 0.0, "{name}");
        assert_eq!(image.scalar(Vec2::new(0.75, 0.5)), 1.0, "{name}");
        assert_eq!(image.color(Vec2::new(0.75, 0.5)).x, 1.0, "{name}");
        if max > 1 {
            let image =
                MapImage::decode(&png_bytes(color, depth, [0, max / 3]), Path::new("m.png"))
                    .unwrap();
            let v = image.scalar(Vec2::new(0.75, 0.5));
            let want = f32::from(max / 3) / f32::from(max);
            assert!((v - want).abs() < 1e-6, "{name}: {v} against {want}");
        }
    }
}

#[test]
fn a_16_bit_region_map_keeps_region_1_and_names_a_region_past_the_last() {
    let dir = std::env::temp_dir().join(format!("pelage-values-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = |map: &str| {
        format!(
            "[mesh]\nkind = \"plane\"\nsize_x = 1.0\nsize_z = 1.0\nsubdivisions_x = 1\n\
             subdivisions_z = 1\n[hair.roots.textures]\nregion = \"{map}\"\n\
             [[hair.growth.regions]]\nlength = 0.3\n"
        )
    };
    std::fs::write(
        dir.join("one.png"),
        png_bytes(png::ColorType::Grayscale, png::BitDepth::Sixteen, [1, 1]),
    )
    .unwrap();
    std::fs::write(dir.join("one.toml"), scene("one.png")).unwrap();
    let file = SceneFile::load(&dir.join("one.toml")).unwrap();
    let image = file.hair.roots.textures.region.as_ref().unwrap();
    let image = image.image.as_deref().unwrap();
    assert_eq!(image.region(Vec2::splat(0.5)), 1);
    // 256 is region 256 (8-bit scaling read it as 1): past the last, named.
    std::fs::write(
        dir.join("big.png"),
        png_bytes(png::ColorType::Grayscale, png::BitDepth::Sixteen, [0, 256]),
    )
    .unwrap();
    std::fs::write(dir.join("big.toml"), scene("big.png")).unwrap();
    let e = SceneFile::load(&dir.join("big.toml")).unwrap_err();
    let message = e.to_string();
    assert!(message.contains("roots.textures.region"), "{message}");
    assert!(message.contains("256 at texel (1, 0)"), "{message}");
    assert!(message.contains("16-bit"), "{message}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_all_zero_density_map_is_named_with_its_file() {
    let dir = std::env::temp_dir().join(format!("pelage-values-zero-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("zero.png"),
        png_bytes(png::ColorType::Grayscale, png::BitDepth::Eight, [0, 0]),
    )
    .unwrap();
    std::fs::write(
        dir.join("scene.toml"),
        "[mesh]\nkind = \"plane\"\nsize_x = 1.0\nsize_z = 1.0\nsubdivisions_x = 1\n\
         subdivisions_z = 1\n[hair.roots.textures]\ndensity = \"zero.png\"\n",
    )
    .unwrap();
    let message = SceneFile::load(&dir.join("scene.toml"))
        .unwrap_err()
        .to_string();
    assert!(message.contains("roots.textures.density"), "{message}");
    assert!(message.contains("zero.png"), "{message}");
    std::fs::remove_dir_all(&dir).unwrap();
    // A per-vertex map of zeros is named too.
    let mut hair = pelage_scene::HairParams::default();
    hair.roots.density = Some(vec![0.0; 4]);
    assert_eq!(hair.validate(4).unwrap_err().name, "roots.density");
}

#[test]
fn keys_without_effect_are_errors_naming_them() {
    let groom = "[groom]\npath = \"long_hair.hair\"\n";
    let guided = "[groom]\npath = \"long_hair.hair\"\nguides = { strands = 100 }\n";
    for (text, key) in [
        // Maps beside a groom.
        (
            format!("{groom}[hair.roots.textures]\ncolor = \"c.png\"\n"),
            "roots.textures.color",
        ),
        (
            format!("{groom}[hair.roots.textures]\ndensity = \"d.png\"\n"),
            "roots.textures.density",
        ),
        (
            format!("{groom}[hair.roots]\ndensity = [1.0]\n"),
            "roots.density",
        ),
        (
            format!("{guided}[hair.roots.textures]\nlength_scale = \"l.png\"\n"),
            "roots.textures.length_scale",
        ),
        (
            format!("{groom}[hair.roots.textures]\nregion = \"r.png\"\n"),
            "roots.textures.region",
        ),
        (format!("{guided}[hair.roots]\ncount = 5\n"), "roots.count"),
        // The shape of a groom's strands is its file's.
        (
            format!("{groom}[hair.growth]\nlength = 0.5\n"),
            "growth.length",
        ),
        (
            format!(
                "{guided}[hair.growth]\nhair_type = {{ kind = \"curly\", radius = 0.1, pitch = 0.1 }}\n"
            ),
            "growth.hair_type",
        ),
        (
            format!("{groom}[hair.growth]\nsegments = 4\n"),
            "growth.segments",
        ),
        // Regions with no map, a map with no regions.
        (
            "[[hair.growth.regions]]\nlength = 0.3\n".to_string(),
            "growth.regions",
        ),
        (
            "[hair.roots.textures]\nregion = \"r.png\"\n".to_string(),
            "roots.textures.region",
        ),
        (
            "[hair.roots]\nregion = [0, 0, 0]\n".to_string(),
            "roots.region",
        ),
        // The simulation's gravity moves simulated strands.
        (
            "[dynamics]\n[hair.growth]\ngravity = [0.0, -3.0, 0.0]\n".to_string(),
            "growth.gravity",
        ),
        (
            "[dynamics]\n[hair.growth]\nforce_weight = 0.5\n".to_string(),
            "growth.force_weight",
        ),
        // voxel_size sets the resolution.
        (
            "[shadow]\nvoxel_size = 0.01\nresolution = [64, 64, 64]\n".to_string(),
            "shadow.resolution",
        ),
    ] {
        assert_eq!(key_of(&text), key, "{text}");
        assert!(message_of(&text).contains(key), "{text}");
    }
    // What a guided groom does use is accepted: its density and colour maps, its seed.
    SceneFile::parse(&format!(
        "{guided}[hair.roots]\nseed = 3\n[hair.roots.textures]\ndensity = \"d.png\"\n\
         color = \"c.png\"\n"
    ))
    .unwrap();
    // And the keys a groom uses of growth.
    SceneFile::parse(&format!(
        "{groom}[hair.growth]\nwidth = 0.003\ntip_width = 0.4\ncolor = [0.5, 0.3, 0.2]\n\
         color_jitter = 0.2\nopacity = 0.5\nforce_weight = 0.04\n"
    ))
    .unwrap();
    let _ = GuideParams::default();
}

#[test]
fn colours_and_scaled_lengths_stay_within_what_32_bit_shading_holds() {
    for (text, key) in [
        ("[hair.growth]\ncolor = [1e30, 0.0, 0.0]\n", "growth.color"),
        (
            "[shade]\nmesh_color = [0.0, 1e30, 0.0]\n",
            "shade.mesh_color",
        ),
        (
            "[shade]\nbackground = [-1.0, 0.0, 0.0]\n",
            "shade.background",
        ),
        ("[shade]\nambient = 1e30\n", "shade.ambient"),
    ] {
        assert_eq!(key_of(text), key, "{text}");
    }
    // A length of 1e8 times a per-vertex length scale of 100 is 1e10, past MAX_EXTENT.
    let mut hair = pelage_scene::HairParams::default();
    hair.growth.length = 1e8;
    hair.roots.length_scale = Some(vec![100.0, 1.0, 1.0]);
    assert_eq!(hair.validate(3).unwrap_err().name, "roots.length_scale");
    hair.roots.length_scale = Some(vec![1.0, 1.0, 1.0]);
    hair.validate(3).unwrap();
}

#[test]
fn wave_and_curl_products_are_bounded() {
    for (text, key) in [
        (
            "[hair.growth]\nhair_type = { kind = \"wavy\", amplitude = 1e30, frequency = 1e30 }\n",
            "growth.hair_type.frequency",
        ),
        (
            "[hair.growth]\nlength = 1e3\nhair_type = { kind = \"wavy\", amplitude = 0.0, frequency = 1e4 }\n",
            "growth.hair_type.frequency",
        ),
        (
            "[hair.growth]\nhair_type = { kind = \"curly\", radius = 1e30, pitch = 0.1 }\n",
            "growth.hair_type.radius",
        ),
        (
            "[hair.growth]\nhair_type = { kind = \"curly\", radius = 0.01, pitch = 1e-30 }\n",
            "growth.hair_type.pitch",
        ),
    ] {
        assert_eq!(key_of(text), key, "{text}");
    }
    SceneFile::parse(
        "[hair.growth]\nhair_type = { kind = \"wavy\", amplitude = 0.02, frequency = 6.0 }\n",
    )
    .unwrap();
}

#[test]
fn strand_raster_tiles_bins_and_pools_out_of_range_are_refused_naming_the_key() {
    for (line, key, range) in [
        ("tile = 12", "transparency.tile", "must be 8 or 16"),
        ("tile = 0", "transparency.tile", "must be 8 or 16"),
        ("bins = 0", "transparency.bins", "1..=256"),
        ("bins = 257", "transparency.bins", "1..=256"),
        ("pool = 0.0", "transparency.pool", ""),
        ("pool = 1e9", "transparency.pool", "at most 1024"),
    ] {
        let text = format!("[shade.transparency]\nmethod = \"strand_raster\"\n{line}\n");
        assert_eq!(key_of(&text), key, "{text}");
        assert!(
            message_of(&text).contains(range),
            "{text}: {}",
            message_of(&text)
        );
    }
}
