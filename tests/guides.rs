//! Guide strands through the whole frame: `scenes/guides.toml` interpolates 6 000 render
//! strands from the 300 guides of `scenes/long_hair_guides.hair` and draws them.
//!
//! `scenes/long_hair_guides.hair` is every 10th strand of `scenes/long_hair.hair`;
//! re-bless it after an intended change with
//! `PELAGE_BLESS=1 cargo test --features png --test guides`.

use std::path::{Path, PathBuf};

use glam::Vec4;
use pelage::scene::{HairFile, KajiyaKayParams, SceneFile, ShadingModel, WindParams};
use pelage::strands::GuideStrands;
use pelage::{Renderer, gpu::Gpu, scene::Scene};

const SIZE: (u32, u32) = (160, 120);

fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

#[test]
fn the_committed_guides_are_every_tenth_strand_of_long_hair() {
    let all = HairFile::read_path(&scenes().join("long_hair.hair")).unwrap();
    let every_tenth: Vec<Vec<glam::Vec3>> = all
        .strands()
        .step_by(10)
        .map(<[glam::Vec3]>::to_vec)
        .collect();
    let path = scenes().join("long_hair_guides.hair");
    if std::env::var_os("PELAGE_BLESS").is_some() {
        std::fs::write(
            &path,
            HairFile::from_strands(&every_tenth)
                .unwrap()
                .write()
                .unwrap(),
        )
        .unwrap();
    }
    let file =
        HairFile::read_path(&path).unwrap_or_else(|e| panic!("{e}; bless it with PELAGE_BLESS=1"));
    let strands: Vec<&[glam::Vec3]> = file.strands().collect();
    assert_eq!(strands.len(), 300);
    for (a, b) in strands.iter().zip(&every_tenth) {
        assert_eq!(*a, &b[..]);
    }
}

#[test]
fn the_guides_scene_draws_its_interpolated_strands() {
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
    let path = scenes().join("guides.toml");
    let mut file = SceneFile::load(&path).unwrap();
    file.hair.wind = WindParams::calm();
    let mut scene = Scene::from_scene_file(&file, &path).unwrap();
    // The test asks whether the strands are drawn, not how they are lit: Kajiya-Kay's
    // colour does not depend on the multiple scattering (with Chiang and the volume grid,
    // the sparse tips' light moved with the grid's transport: 93% of the tips drew 6
    // levels off the background after the six-direction transport, 95% or more before).
    scene.shade.model = ShadingModel::KajiyaKay(KajiyaKayParams::default());
    let guides = scene
        .guides
        .as_ref()
        .expect("the scene interpolates guides");
    assert_eq!(guides.strands, 6000);
    assert_eq!(scene.groom.as_ref().map(|g| g.strands), Some(300));
    let mut renderer = Renderer::new(&gpu, &scene, SIZE.0, SIZE.1).unwrap();
    renderer.render(&gpu, 0.0, &scene.camera).unwrap();
    let image = renderer.image(&gpu).unwrap();
    let strands = renderer.frame().strands();
    assert_eq!(strands.buffers().strand_count, 6000);
    assert_eq!(
        strands.passes().len(),
        2,
        "the guides are bent, then interpolated"
    );
    let plan = renderer.frame().plan([]).unwrap();
    let plan = plan.labels();
    assert!(
        plan.contains(&"strands: guides bend") && plan.contains(&"strands: guides"),
        "{plan:?}"
    );

    // Where the interpolated strands' tips hang below the head, the picture is hair.
    let bytes = pelage::gpu::read_buffer(&gpu, &strands.buffers().vertices).unwrap();
    let vertices: Vec<Vec4> = bytemuck::cast_slice::<u8, [f32; 4]>(&bytes)
        .iter()
        .map(|v| Vec4::from_array(*v))
        .collect();
    let background = scene.shade.background;
    let to_srgb = |c: f32| (c.clamp(0.0, 1.0).powf(1.0 / 2.4) * 1.055 - 0.055) * 255.0;
    let bg = [
        to_srgb(background.x),
        to_srgb(background.y),
        to_srgb(background.z),
    ];
    let view_projection = scene.camera.view_projection(SIZE.0 as f32 / SIZE.1 as f32);
    let (mut tips, mut covered) = (0, 0);
    for strand in vertices.chunks(17) {
        let tip = strand[16].truncate();
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
        let near = (x.saturating_sub(1)..=(x + 1).min(SIZE.0 - 1)).any(|px| {
            (y.saturating_sub(1)..=(y + 1).min(SIZE.1 - 1)).any(|py| {
                let p = image.get_pixel(px, py).0;
                (0..3).any(|c| (f32::from(p[c]) - bg[c]).abs() > 6.0)
            })
        });
        covered += usize::from(near);
    }
    println!("{covered} of {tips} hanging tips of interpolated strands drawn");
    assert!(tips > 1000, "too few tips in view ({tips})");
    assert!(covered as f64 >= 0.95 * tips as f64, "{covered} of {tips}");

    // The reach of the interpolated strands holds every vertex.
    let groom = scene.groom.as_ref().unwrap();
    let (lo, hi) = GuideStrands::reach_of(groom, scene.mesh.bounds(), &scene.hair, guides).unwrap();
    for v in &vertices {
        let p = v.truncate();
        assert!(
            p.cmpge(lo).all() && p.cmple(hi).all(),
            "{p} outside {lo} {hi}"
        );
    }
}

#[test]
fn guides_off_the_head_are_refused_naming_the_key_to_change() {
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
    let path = scenes().join("guides.toml");
    let mut file = SceneFile::load(&path).unwrap();
    if let Some(groom) = file.groom.as_mut() {
        groom.translation = glam::Vec3::new(0.0, 3.0, 0.0);
    }
    let scene = Scene::from_scene_file(&file, &path).unwrap();
    let e = Renderer::new(&gpu, &scene, SIZE.0, SIZE.1).unwrap_err();
    assert!(e.to_string().contains("guides.max_root_distance"), "{e}");
}

#[test]
fn guides_with_dynamics_simulate_the_guides_and_draw_the_interpolated_strands() {
    // The guides are simulated on the turning head; the render strands follow them.
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
    let path = scenes().join("guides.toml");
    let mut file = SceneFile::load(&path).unwrap();
    if let Some(guides) = file.groom.as_mut().and_then(|g| g.guides.as_mut()) {
        guides.strands = 1500;
    }
    let mut scene = Scene::from_scene_file(&file, &path).unwrap();
    scene.dynamics = Some(pelage::scene::DynamicsParams::default());
    scene.motion = Some(pelage::scene::MeshMotion::default());
    let mut renderer = Renderer::new(&gpu, &scene, SIZE.0, SIZE.1).unwrap();
    let plan = renderer.frame().plan([]).unwrap();
    let plan = plan.labels();
    assert!(
        plan.contains(&"strands: simulate") && plan.contains(&"strands: guides"),
        "{plan:?}"
    );
    assert!(!plan.contains(&"strands: guides bend"), "{plan:?}");
    let read = |renderer: &Renderer| {
        let bytes =
            pelage::gpu::read_buffer(&gpu, &renderer.frame().strands().buffers().vertices).unwrap();
        bytemuck::cast_slice::<u8, [f32; 4]>(&bytes)
            .iter()
            .map(|v| Vec4::from_array(*v))
            .collect::<Vec<_>>()
    };
    renderer.render(&gpu, 0.0, &scene.camera).unwrap();
    let first = read(&renderer);
    for frame in 1..=6 {
        renderer
            .render(&gpu, frame as f32 / 24.0, &scene.camera)
            .unwrap();
    }
    let last = read(&renderer);
    assert_eq!(renderer.frame().strands().buffers().strand_count, 1500);
    let moved = (first.iter().zip(&last))
        .map(|(a, b)| a.truncate().distance(b.truncate()))
        .fold(0.0f32, f32::max);
    let reach = renderer.frame().strands().buffers().reach;
    assert!(
        last.iter()
            .all(|v| v.truncate().cmpge(reach.0).all() && v.truncate().cmple(reach.1).all()),
        "a vertex leaves the reach"
    );
    println!("guides with dynamics: render strands moved up to {moved:.3} in 6 frames");
    assert!(moved > 0.01, "{moved}");
    let image = renderer.image(&gpu).unwrap();
    let background = image.get_pixel(0, 0).0;
    let drawn = image.pixels().filter(|p| p.0 != background).count();
    assert!(drawn > 1000, "{drawn} pixels differ from the background");
}
