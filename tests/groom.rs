//! Groom files through the whole frame: `scenes/long_hair.toml` draws the strands of
//! `scenes/long_hair.hair`, the same groom as a `.tfx` file draws the same picture, and
//! a scene file whose groom is missing or malformed names the file or the key.
//!
//! `scenes/long_hair.hair` is what `long_hair()` below writes; re-bless it after an
//! intended change with `PELAGE_BLESS=1 cargo test --test groom`.

use std::path::{Path, PathBuf};

use glam::Vec3;
use pelage::scene::{HairFile, SceneFile, SceneFileError, TfxFile, WindParams};
use pelage::strands::{hash_to_unit, pcg_hash};
use pelage::{Renderer, gpu::Gpu, scene::Scene};

const SIZE: (u32, u32) = (160, 120);

fn gpu() -> Gpu {
    Gpu::headless().unwrap_or_else(|e| panic!("these tests need a GPU adapter: {e}"))
}

fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// The groom of `scenes/long_hair.hair`: 3 000 strands of 20 to 47 points on the scalp of
/// a head (a sphere of radius 0.5 at the origin). Each strand lies along the head from
/// its root down its meridian, leaves it where the meridian turns vertical and hangs,
/// waving and flaring a little: a shape that grown fur cannot take, which is what groom
/// files are for.
fn long_hair() -> Vec<Vec<Vec3>> {
    const STRANDS: u32 = 3000;
    let mut out = Vec::with_capacity(STRANDS as usize);
    let mut state = pcg_hash(0x5eed);
    let mut next = || {
        state = pcg_hash(state);
        hash_to_unit(state)
    };
    while out.len() < STRANDS as usize {
        // A direction uniform on the sphere, kept where the scalp is.
        let y = 2.0 * next() - 1.0;
        let a = std::f32::consts::TAU * next();
        let r = (1.0 - y * y).sqrt();
        let n = Vec3::new(r * a.cos(), y, r * a.sin());
        let scalp = n.y > 0.55 || (n.y > 0.1 && n.z < 0.35) || (n.y > -0.45 && n.z < -0.1);
        if !scalp {
            continue;
        }
        let radius = 0.505 + 0.02 * next();
        // Where the strand leaves the head: on the equator, beside its root, combed back
        // and to the sides in front so that the face stays clear.
        let leave = Vec3::new(n.x, 0.0, n.z.min(0.3) - 0.15 * n.z.max(0.0))
            .normalize_or(Vec3::new(a.cos(), 0.0, a.sin()));
        let leave = if n.y > 0.0 { leave } else { n };
        // Along the head on the great circle from n to `leave`, then straight down.
        let arc = n.dot(leave).clamp(-1.0, 1.0).acos();
        let length = 1.0 + 0.25 * next();
        let points = 20 + (next() * 28.0) as usize;
        let wave = (
            0.01 + 0.02 * next(),
            2.5 + 2.0 * next(),
            std::f32::consts::TAU * next(),
        );
        let outward = Vec3::new(leave.x, 0.0, leave.z).normalize_or(Vec3::X);
        let side = outward.cross(Vec3::Y);
        let strand = (0..points)
            .map(|k| {
                let s = length * k as f32 / (points - 1) as f32;
                let u = if arc > 1e-4 {
                    (s / radius / arc).min(1.0)
                } else {
                    1.0
                };
                let on_head = radius * slerp(n, leave, arc, u);
                let hanging = (s - radius * arc).max(0.0);
                let waving = (std::f32::consts::TAU * wave.1 * hanging + wave.2).sin() * wave.0;
                on_head - Vec3::Y * hanging
                    + outward * (0.12 * hanging * hanging + waving)
                    + side * (0.3 * waving)
            })
            .collect();
        out.push(strand);
    }
    out
}

/// The unit vector a fraction `u` of the way from unit `a` to unit `b`, `arc` apart.
fn slerp(a: Vec3, b: Vec3, arc: f32, u: f32) -> Vec3 {
    if arc < 1e-4 {
        return b;
    }
    (a * ((1.0 - u) * arc).sin() + b * (u * arc).sin()) / arc.sin()
}

#[test]
fn the_committed_groom_file_is_what_its_generator_writes() {
    let path = scenes().join("long_hair.hair");
    let strands = long_hair();
    if std::env::var_os("PELAGE_BLESS").is_some() {
        std::fs::write(
            &path,
            HairFile::from_strands(&strands).unwrap().write().unwrap(),
        )
        .unwrap();
    }
    let file =
        HairFile::read_path(&path).unwrap_or_else(|e| panic!("{e}; bless it with PELAGE_BLESS=1"));
    assert_eq!(file.strands().count(), strands.len());
    let worst = file
        .strands()
        .zip(&strands)
        .flat_map(|(a, b)| a.iter().zip(b).map(|(p, q)| p.distance(*q)))
        .fold(0.0f32, f32::max);
    assert!(
        worst < 1e-5,
        "the file differs from its generator by {worst}"
    );
}

/// The scene of `scenes/long_hair.toml` with its wind calmed (when `calm`) and its groom
/// read from `path` instead.
fn long_hair_scene(groom: Option<&Path>, calm: bool) -> Scene {
    let mut file = SceneFile::load(&scenes().join("long_hair.toml")).unwrap();
    if let (Some(path), Some(source)) = (groom, file.groom.as_mut()) {
        source.path = path.to_path_buf();
    }
    if calm {
        file.hair.wind = WindParams::calm();
    }
    let mut scene = Scene::from_scene_file(&file, &scenes().join("long_hair.toml")).unwrap();
    // The tips are found by their brightness against the background (more than 6 of 255
    // in a 3x3): judged with dual scattering, as measured. Volume scattering (the default)
    // lights isolated tips less (2 288 of 2 507 tips over the threshold, against 95% or
    // more with dual), as the path tracer does sparse hair.
    if let pelage::scene::ShadingModel::Chiang(p) = &mut scene.shade.model {
        p.multiple_scattering = pelage::scene::MultipleScattering::Dual;
    }
    scene
}

#[test]
fn a_scene_file_groom_is_drawn_and_a_tfx_copy_draws_the_same_picture() {
    let gpu = gpu();
    let scene = long_hair_scene(None, true);
    let groom = scene.groom.as_ref().expect("the scene has a groom");
    assert_eq!((groom.strands, groom.segments), (3000, 16));
    let mut renderer = Renderer::new(&gpu, &scene, SIZE.0, SIZE.1).unwrap();
    renderer.render(&gpu, 0.0, &scene.camera).unwrap();
    let hair_image = renderer.image(&gpu).unwrap();
    assert_eq!(renderer.frame().strands().buffers().strand_count, 3000);

    // Below the head there is only hair: where its tips project, the picture is not
    // the background.
    let background = scene.shade.background;
    let to_srgb = |c: f32| (c.clamp(0.0, 1.0).powf(1.0 / 2.4) * 1.055 - 0.055) * 255.0;
    let bg = [
        to_srgb(background.x),
        to_srgb(background.y),
        to_srgb(background.z),
    ];
    let view_projection = scene.camera.view_projection(SIZE.0 as f32 / SIZE.1 as f32);
    let (mut tips, mut covered) = (0, 0);
    for strand in groom.points.chunks(17) {
        let tip = strand[16];
        if tip.y > -0.6 {
            continue;
        }
        let clip = view_projection * tip.extend(1.0);
        let ndc = clip.truncate() / clip.w;
        let x = ((ndc.x * 0.5 + 0.5) * SIZE.0 as f32) as u32;
        let y = ((0.5 - ndc.y * 0.5) * SIZE.1 as f32) as u32;
        if x >= SIZE.0 || y >= SIZE.1 {
            continue;
        }
        tips += 1;
        // Any pixel of the 3x3 around the tip (the ribbon is under a pixel wide).
        let near = (x.saturating_sub(1)..=(x + 1).min(SIZE.0 - 1)).any(|px| {
            (y.saturating_sub(1)..=(y + 1).min(SIZE.1 - 1)).any(|py| {
                let p = hair_image.get_pixel(px, py).0;
                (0..3).any(|c| (f32::from(p[c]) - bg[c]).abs() > 6.0)
            })
        });
        covered += usize::from(near);
    }
    println!("{covered} of {tips} hanging tips drawn");
    assert!(
        tips > 500,
        "too few tips in view ({tips}): the camera misses the hair"
    );
    assert!(covered as f64 >= 0.95 * tips as f64, "{covered} of {tips}");

    // The same strands written as .hair and as TressFX (whose strands all have one
    // point count: the resampled groom's) give the same picture.
    let dir = std::env::temp_dir().join(format!("pelage-groom-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let strands: Vec<Vec<Vec3>> = groom.points.chunks(17).map(<[Vec3]>::to_vec).collect();
    let hair_path = dir.join("resampled.hair");
    std::fs::write(
        &hair_path,
        HairFile::from_strands(&strands).unwrap().write().unwrap(),
    )
    .unwrap();
    let tfx_path = dir.join("resampled.tfx");
    let bytes = TfxFile::from_strands(&strands).unwrap().write().unwrap();
    std::fs::write(&tfx_path, bytes).unwrap();
    let picture = |path: &Path| {
        let scene = long_hair_scene(Some(path), true);
        let mut renderer = Renderer::new(&gpu, &scene, SIZE.0, SIZE.1).unwrap();
        renderer.render(&gpu, 0.0, &scene.camera).unwrap();
        renderer.image(&gpu).unwrap()
    };
    let (from_hair, from_tfx) = (picture(&hair_path), picture(&tfx_path));
    let differ = from_hair
        .pixels()
        .zip(from_tfx.pixels())
        .filter(|(a, b)| a != b)
        .count();
    println!(".hair and .tfx pictures of the same strands: {differ} pixels differ");
    assert_eq!(differ, 0);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_wind_moves_a_groom_and_it_comes_back_for_the_same_time() {
    let gpu = gpu();
    let scene = long_hair_scene(None, false);
    let mut renderer = Renderer::new(&gpu, &scene, SIZE.0, SIZE.1).unwrap();
    let mut frame = |t: f32| {
        renderer.render(&gpu, t, &scene.camera).unwrap();
        renderer.image(&gpu).unwrap()
    };
    let (a, b, again) = (frame(0.0), frame(1.3), frame(0.0));
    let changed = |x: &image::RgbaImage, y: &image::RgbaImage| {
        x.pixels()
            .zip(y.pixels())
            .filter(|(p, q)| (0..3).any(|c| p.0[c].abs_diff(q.0[c]) > 8))
            .count()
    };
    println!(
        "wind: {} pixels change from t = 0 to 1.3 s",
        changed(&a, &b)
    );
    assert!(changed(&a, &b) > 200);
    assert_eq!(changed(&a, &again), 0, "a frame depends on its time alone");
}

#[test]
fn a_bad_groom_in_a_scene_file_names_the_file_or_the_key() {
    let dir = std::env::temp_dir().join(format!("pelage-bad-groom-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let load = |name: &str, text: &str| {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let file = SceneFile::load(&path)?;
        Scene::from_scene_file(&file, &path).map(|_| ())
    };
    let missing = load("missing.toml", "[groom]\npath = \"nowhere.hair\"\n").unwrap_err();
    assert!(matches!(missing, SceneFileError::Groom { .. }), "{missing}");
    assert!(missing.to_string().contains("nowhere.hair"), "{missing}");

    std::fs::write(dir.join("groom.obj"), "v 0 0 0\n").unwrap();
    let format = load("format.toml", "[groom]\npath = \"groom.obj\"\n").unwrap_err();
    assert!(format.to_string().contains(".hair"), "{format}");

    std::fs::write(dir.join("broken.tfx"), [1u8, 2, 3]).unwrap();
    let broken = load("broken.toml", "[groom]\npath = \"broken.tfx\"\n").unwrap_err();
    assert!(broken.to_string().contains("broken.tfx"), "{broken}");

    let key = load("key.toml", "[groom]\npath = \"a.hair\"\nsegmnets = 8\n").unwrap_err();
    assert!(key.to_string().contains("segmnets"), "{key}");

    let segments = load(
        "segments.toml",
        "[groom]\npath = \"a.hair\"\nsegments = 0\n",
    )
    .unwrap_err();
    assert!(
        segments.to_string().contains("groom.segments"),
        "{segments}"
    );

    let fit = load("fit.toml", "[groom]\npath = \"a.hair\"\nfit = -1.0\n").unwrap_err();
    assert!(fit.to_string().contains("groom.fit"), "{fit}");
    std::fs::remove_dir_all(&dir).ok();
}
