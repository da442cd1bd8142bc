//! A skinned scene through the facade: `scenes/creature_skinned.toml` builds a frame
//! whose plan records the skinning pass before stage 1, the fur's roots follow the skin
//! (against the CPU mirror), and a frame skinned with the caller's skin takes its joint
//! matrices and refuses bad ones, naming them.

use glam::{Mat4, Vec3};
use pelage::gpu::{Gpu, read_buffer};
use pelage::scene::{MeshMotion, SkinBend};
use pelage::shade::TargetFormat;
use pelage::strands::{SKIN_LABEL, StrandsError};
use pelage::{Error, Frame, FrameTarget, Renderer, scene::Scene};
use pelage_reference::skin::{mesh_size, skin_mesh};
use pelage_reference::strands::eval_surface;

fn gpu() -> Gpu {
    Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"))
}

/// `scenes/creature_skinned.toml` with 1 000 strands.
fn skinned_scene() -> Scene {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/creature_skinned.toml");
    let mut scene = Scene::from_file(&path).unwrap();
    scene.hair.roots.count = 1000;
    scene
}

#[test]
fn a_skinned_scene_skins_before_stage_1_and_its_roots_follow_the_skin() {
    let gpu = gpu();
    let scene = skinned_scene();
    let rig = scene.skin.clone().unwrap();
    let mut renderer = Renderer::new(&gpu, &scene, 64, 48).unwrap();
    let plan = renderer.frame().plan([]).unwrap();
    let labels: Vec<&str> = plan.passes().iter().map(|p| p.label.as_str()).collect();
    println!("{labels:?}");
    assert_eq!(labels[0], SKIN_LABEL);
    assert_eq!(labels[1], "strands: grow");
    // The rig's skin, computed here from the rig and the mesh, not taken from the frame.
    let skin = rig.skin(&scene.mesh);
    let size = mesh_size(&scene.mesh);
    let per = scene.hair.growth.segments as usize + 1;
    let pn = scene.hair.growth.surface == pelage::scene::SurfaceInterpolation::PnTriangle;
    let mut worst = 0.0f32;
    for t in [0.0, 0.6, 1.7] {
        renderer.render(&gpu, t, &scene.camera).unwrap();
        renderer.finish(&gpu).unwrap();
        let bytes = read_buffer(&gpu, &renderer.frame().strands().buffers().vertices).unwrap();
        let vertices: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
        let skinned = skin_mesh(&scene.mesh, &skin, &rig.joint_matrices(t));
        for (strand, root) in vertices.chunks(per).zip(renderer.frame().strands().roots()) {
            let on = eval_surface(&skinned, root.triangle, root.bary, pn).position;
            worst = worst.max(Vec3::from_slice(&strand[0][..3]).distance(on));
        }
    }
    println!(
        "roots at most {:.2e} of the mesh size from the mirror's skinned surface",
        worst / size
    );
    assert!(worst <= 1e-5 * size, "{worst}");
    // The rig's box holds the mesh in every pose: the scene's reach grew.
    let mut still = scene.clone();
    still.skin = None;
    let (lo, hi) = pelage::strands::scene_reach(&scene);
    let (slo, shi) = pelage::strands::scene_reach(&still);
    assert!(lo.cmple(slo).all() && hi.cmpge(shi).all());
}

#[test]
fn a_callers_skin_takes_its_matrices_and_bad_ones_are_refused_by_name() {
    let gpu = gpu();
    let mut scene = skinned_scene();
    let rig = scene.skin.take().unwrap();
    let skin = rig.skin(&scene.mesh);
    let target = FrameTarget::new(TargetFormat::default(), 32, 24);
    let reach = rig.reach(scene.mesh.bounds());
    let name = |e: Error| match e {
        Error::Param(p) => p.name,
        Error::Strands(StrandsError::Param(p)) => p.name,
        other => panic!("not a parameter error: {other}"),
    };
    let mut frame = Frame::with_skin(&gpu, &scene, &skin, reach, &target).unwrap();
    frame
        .set_joint_matrices(&gpu.queue, &rig.joint_matrices(0.5))
        .unwrap();
    let mut bad = rig.joint_matrices(0.5);
    bad[1].y_axis.z = f32::INFINITY;
    assert_eq!(
        name(frame.set_joint_matrices(&gpu.queue, &bad).unwrap_err()),
        "skin.joint_matrices[1]"
    );
    assert_eq!(
        name(
            frame
                .set_joint_matrices(&gpu.queue, &[Mat4::IDENTITY])
                .unwrap_err()
        ),
        "skin.joint_matrices"
    );
    frame
        .prepare(&gpu.queue, 0.5, &scene.camera.matrices(32, 24))
        .unwrap();
    // A rig's frame sets its own matrices; a frame without a skin has none to set.
    let rigged = Frame::new(&gpu, &skinned_scene(), &target).unwrap();
    assert_eq!(
        name(
            rigged
                .set_joint_matrices(&gpu.queue, &[Mat4::IDENTITY; 2])
                .unwrap_err()
        ),
        "skin"
    );
    let plain = Frame::new(&gpu, &scene, &target).unwrap();
    assert_eq!(
        name(
            plain
                .set_joint_matrices(&gpu.queue, &[Mat4::IDENTITY; 2])
                .unwrap_err()
        ),
        "skin"
    );
    // Refused: a skin and a motion, a rig and a caller's skin, a box that is not one.
    let moving = Scene {
        motion: Some(MeshMotion::default()),
        ..scene.clone()
    };
    assert_eq!(
        name(Frame::with_skin(&gpu, &moving, &skin, reach, &target).unwrap_err()),
        "skin"
    );
    let both = Scene {
        motion: Some(MeshMotion::default()),
        skin: Some(SkinBend::default()),
        ..scene.clone()
    };
    assert_eq!(name(Frame::new(&gpu, &both, &target).unwrap_err()), "skin");
    assert_eq!(
        name(Frame::with_skin(&gpu, &skinned_scene(), &skin, reach, &target).unwrap_err()),
        "skin"
    );
    assert_eq!(
        name(Frame::with_skin(&gpu, &scene, &skin, (Vec3::ONE, Vec3::ZERO), &target).unwrap_err()),
        "skin.reach"
    );
    let mut bad_skin = skin.clone();
    bad_skin.joints[3][0] = 7;
    assert_eq!(
        name(Frame::with_skin(&gpu, &scene, &bad_skin, reach, &target).unwrap_err()),
        "skin.joints[3][0]"
    );
}
