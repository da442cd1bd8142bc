//! USD grooms through the whole frame (feature `usd`): the same strands saved as
//! `.hair` and as `.usda` draw the same picture, a groom-only scene (`[mesh] kind =
//! "none"`) draws its hair and no mesh, a groom without wind keeps its file shape
//! exactly at t = 0, and a file's `displayColor` colours its strands.

use std::path::{Path, PathBuf};

use glam::Vec3;
use pelage::scene::{Groom, GroomSource, HairFile, HairParams, SceneFile, WindParams, usd_file};
use pelage::strands::{GroomStrands, StrandStage};
use pelage::{Renderer, gpu::Gpu, scene::Scene};

const SIZE: (u32, u32) = (96, 72);

fn gpu() -> Gpu {
    Gpu::headless().unwrap_or_else(|e| panic!("these tests need a GPU adapter: {e}"))
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pelage-usd-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes `groom` to `path` as USD (the format by the extension).
fn write_usd(groom: &Groom, path: &Path) {
    std::fs::write(path, usd_file::encode(groom, path).unwrap()).unwrap();
}

/// 300 wavy strands of 12 points hanging from a 1 x 0.4 patch at y = 0.5 down to
/// about y = -0.5.
fn strands() -> Vec<Vec<Vec3>> {
    (0..300)
        .map(|s| {
            let root = Vec3::new(
                (s % 20) as f32 / 19.0 - 0.5,
                0.5,
                (s / 20) as f32 / 14.0 * 0.4 - 0.2,
            );
            (0..12)
                .map(|k| {
                    let y = k as f32 / 11.0;
                    root + Vec3::new(0.04 * (6.0 * y + s as f32).sin(), -y, 0.02 * y)
                })
                .collect()
        })
        .collect()
}

/// A scene file around the groom at `groom` (relative to the scene file), with `mesh`
/// as its `[mesh]` table and no `[hair.wind]`.
fn scene_text(groom: &str, mesh: &str) -> String {
    format!(
        r#"{mesh}

[groom]
path = "{groom}"
segments = 8

[hair.growth]
width = 0.01
color = [0.5, 0.3, 0.15]
color_jitter = 0.0

[shadow]
method = "voxel"
resolution = [24, 24, 24]

[shade]
mesh_color = [0.0, 1.0, 0.0]

[camera]
eye = [0.0, 0.0, 2.6]
target = [0.0, 0.0, 0.0]
fov_y = 0.8
near = 0.05
far = 10.0
"#
    )
}

fn render(gpu: &Gpu, scene: &Scene) -> image::RgbaImage {
    let mut renderer = Renderer::new(gpu, scene, SIZE.0, SIZE.1).unwrap();
    renderer.render(gpu, 0.0, &scene.camera).unwrap();
    renderer.image(gpu).unwrap()
}

fn load_scene(dir: &Path, text: &str) -> Scene {
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    Scene::from_file(&path).unwrap()
}

#[test]
fn the_same_strands_as_hair_and_as_usda_draw_the_same_picture() {
    let gpu = gpu();
    let dir = temp("same");
    let strands = strands();
    std::fs::write(
        dir.join("groom.hair"),
        HairFile::from_strands(&strands).unwrap().write().unwrap(),
    )
    .unwrap();
    write_usd(
        &Groom::from_strands(&strands).unwrap(),
        &dir.join("groom.usda"),
    );
    let mesh = "[mesh]\nkind = \"icosphere\"\nradius = 0.3\nsubdivisions = 2";
    let hair = load_scene(&dir, &scene_text("groom.hair", mesh));
    let usd = load_scene(&dir, &scene_text("groom.usda", mesh));
    assert_eq!(hair.groom, usd.groom, "the two files resample differently");
    let (a, b) = (render(&gpu, &hair), render(&gpu, &usd));
    let differing = a.pixels().zip(b.pixels()).filter(|(p, q)| p != q).count();
    assert_eq!(differing, 0, "{differing} pixels differ");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Pixels whose green stands well above red and blue: the green mesh.
fn green(image: &image::RgbaImage) -> usize {
    image
        .pixels()
        .filter(|p| {
            let [r, g, b, _] = p.0;
            i32::from(g) > i32::from(r) + 40 && i32::from(g) > i32::from(b) + 40
        })
        .count()
}

#[test]
fn a_groom_only_scene_draws_the_hair_and_no_mesh() {
    let gpu = gpu();
    let dir = temp("only");
    write_usd(
        &Groom::from_strands(&strands()).unwrap(),
        &dir.join("groom.usda"),
    );
    let with_mesh = load_scene(
        &dir,
        &scene_text(
            "groom.usda",
            "[mesh]\nkind = \"icosphere\"\nradius = 0.8\nsubdivisions = 2",
        ),
    );
    let only = load_scene(&dir, &scene_text("groom.usda", "[mesh]\nkind = \"none\""));
    assert!(only.mesh.indices.is_empty());
    let (a, b) = (render(&gpu, &only), render(&gpu, &with_mesh));
    let corner = *a.get_pixel(0, 0);
    let hair = a.pixels().filter(|p| **p != corner).count();
    println!(
        "groom only: {hair} hair pixels, {} green; with the mesh: {} green",
        green(&a),
        green(&b)
    );
    assert!(green(&b) > 500, "the mesh scene shows too little mesh");
    assert_eq!(green(&a), 0, "a groom-only scene drew mesh pixels");
    assert!(hair > 300, "only {hair} hair pixels");
    // Stage 2 shadowed the hair alone: its reach is the groom's.
    let renderer = Renderer::new(&gpu, &only, SIZE.0, SIZE.1).unwrap();
    assert_eq!(renderer.frame().mesh_buffers().triangle_count, 0);
    // Dynamics and motion need a mesh: refused, naming the key, not drawn wrong.
    for (key, scene) in [
        (
            "dynamics",
            Scene {
                dynamics: Some(pelage::scene::DynamicsParams::default()),
                ..only.clone()
            },
        ),
        (
            "motion",
            Scene {
                motion: Some(pelage::scene::MeshMotion::default()),
                ..only.clone()
            },
        ),
        (
            "skin",
            Scene {
                skin: Some(pelage::scene::SkinBend::default()),
                ..only.clone()
            },
        ),
    ] {
        let e = Renderer::new(&gpu, &scene, SIZE.0, SIZE.1).unwrap_err();
        assert!(
            matches!(&e, pelage::Error::Param(p) if p.name == key),
            "{key}: {e}"
        );
    }
    // No mesh and no groom is refused, naming the key.
    let e = SceneFile::parse("[mesh]\nkind = \"none\"\n").unwrap_err();
    assert!(e.to_string().contains("mesh.kind"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_groom_keeps_its_file_shape_at_t_0_unless_the_scene_asks_for_wind() {
    let gpu = gpu();
    let dir = temp("still");
    write_usd(
        &Groom::from_strands(&strands()).unwrap(),
        &dir.join("groom.usda"),
    );
    let calm = load_scene(&dir, &scene_text("groom.usda", "[mesh]\nkind = \"none\""));
    assert_eq!(
        calm.hair.wind,
        WindParams::calm(),
        "no [hair.wind]: no wind"
    );
    let windy_text = format!(
        "{}\n[hair.wind]\nstrength = 0.8\n",
        scene_text("groom.usda", "[mesh]\nkind = \"none\"")
    );
    let windy = load_scene(&dir, &windy_text);
    assert!(windy.hair.wind.strength > 0.0);

    let vertices = |scene: &Scene| {
        let groom = scene.groom.as_ref().unwrap();
        let mut strands = GroomStrands::new(&gpu, groom, &scene.hair).unwrap();
        let frame = strands.prepare(&gpu.queue, 0.0).unwrap();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        strands.encode(&mut encoder, &frame, None).unwrap();
        gpu.queue.submit([encoder.finish()]);
        let bytes = pelage::gpu::read_buffer(&gpu, &strands.buffers().vertices).unwrap();
        let floats: Vec<f32> = bytemuck::cast_slice(&bytes).to_vec();
        let points: Vec<Vec3> = floats
            .chunks_exact(4)
            .take(strands.rest_points().len())
            .map(|v| Vec3::new(v[0], v[1], v[2]))
            .collect();
        (points, strands.rest_points().to_vec())
    };
    let (drawn, rest) = vertices(&calm);
    assert_eq!(drawn, rest, "a groom without wind moved at t = 0");
    let (drawn, rest) = vertices(&windy);
    let moved = drawn
        .iter()
        .zip(&rest)
        .filter(|(a, b)| a.distance(**b) > 1e-4)
        .count();
    assert!(
        moved > rest.len() / 2,
        "the wind moved only {moved} vertices"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn display_colors_colour_the_strands() {
    let gpu = gpu();
    let dir = temp("colour");
    let n = strands().len();
    let red = Groom::from_strands(&strands())
        .unwrap()
        .with_colors(Some(vec![Vec3::new(0.9, 0.05, 0.05); n]))
        .unwrap();
    write_usd(&red, &dir.join("groom.usda"));
    let groom = GroomSource::new(dir.join("groom.usda")).load().unwrap();
    assert_eq!(groom.colors.as_ref().map(Vec::len), Some(n));
    let strands = GroomStrands::new(&gpu, &groom, &HairParams::default()).unwrap();
    // color_jitter scales each strand's colour, so the hue stays red.
    assert!(
        strands
            .roots()
            .iter()
            .all(|r| r.color.x > 5.0 * r.color.y && r.color.y == r.color.z),
        "the file's colour was not used"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
