//! Skinned meshes in the Bevy plugin, headless on the test machine's adapter (lavapipe
//! in CI), on the character example's trotting creature (eight joints under a parent of
//! their own, the mesh entity placed with another transform):
//! - the joint matrices the plugin hands pelage put every vertex where Bevy's own
//!   skinning convention puts it (`world_from_joint · inverse_bindpose`, computed here
//!   in `f64` from Bevy's propagated transforms) and equal the example's pose computed
//!   from the pivots alone;
//! - the plugin's frame of a trotting pose equals pelage's own frame of the same
//!   skinned pose (`Frame::with_skin` with the example's matrices) by mean FLIP, and
//!   differs from the bind pose's (the fur moved with the joints);
//! - a skinned mesh held in its bind pose equals pelage's frame of the unskinned mesh;
//! - bad skins are errors naming what is wrong.

// The example's app and scene, compiled into this test; its `main` goes unused here.
#[allow(dead_code)]
#[path = "../examples/character.rs"]
mod character;

use bevy::mesh::skinning::{SkinnedMesh, SkinnedMeshInverseBindposes};
use bevy::prelude::*;
use bevy_pelage::{Fur, FurError, pelage_skin, skin_joint_matrices};
use glam::{DMat4, DVec3};
use pelage::gpu::{Gpu, wgpu};
use pelage::scene::Skin;
use pelage::shade::{TargetFormat, Targets};
use pelage::strands::MeshBuffers;
use pelage::{Frame, FrameTarget};
use pelage_reference::flip::{DEFAULT_PIXELS_PER_DEGREE, LinearImage, flip};
use pelage_reference::skin::{mesh_size, skin_mesh};

/// Pixels that differ between two pictures.
fn differing(a: &image::RgbaImage, b: &image::RgbaImage) -> usize {
    a.pixels().zip(b.pixels()).filter(|(p, q)| p != q).count()
}

/// Mean FLIP between two sRGB pictures.
fn mean_flip(a: &image::RgbaImage, b: &image::RgbaImage) -> f64 {
    let linear = |i: &image::RgbaImage| {
        LinearImage::from_srgb8_rgba(i.width(), i.height(), i.as_raw()).unwrap()
    };
    flip(&linear(a), &linear(b), DEFAULT_PIXELS_PER_DEGREE)
        .unwrap()
        .mean()
}

const PIXELS: usize = (character::WIDTH * character::HEIGHT) as usize;

/// The example's app after `frames` updates (frame 1 builds pelage on Bevy's device):
/// its last frame and Bevy's time.
fn bevy_frame(walking: bool, frames: usize) -> (App, image::RgbaImage, f32) {
    let (mut app, target) = character::app(walking).unwrap_or_else(|e| {
        panic!("this test needs a GPU adapter (install mesa-vulkan-drivers for lavapipe): {e}")
    });
    for _ in 0..frames {
        app.update();
    }
    let picture = character::read(&mut app, &target).unwrap();
    let t = character::time(&app);
    (app, picture, t)
}

/// pelage's own frame of the example's scene at `t` (on its own device, into an sRGB
/// target like Bevy's, reverse-Z as Bevy's), its mesh skinned by `matrices` or, with
/// `None`, unskinned; either way sized by the example's reach (as the plugin's is).
fn pelages_own(t: f32, matrices: Option<&[glam::Mat4]>) -> image::RgbaImage {
    let gpu = Gpu::headless().unwrap();
    let scene = character::scene().unwrap();
    let (mesh, skin) = character::character().unwrap();
    let reach = character::reach(&mesh);
    let format = TargetFormat {
        color: wgpu::TextureFormat::Rgba8UnormSrgb,
        depth: wgpu::TextureFormat::Depth32Float,
        samples: 1,
        reverse_z: true,
    };
    let (w, h) = (character::WIDTH, character::HEIGHT);
    let target = FrameTarget::new(format, w, h);
    let mut frame = match matrices {
        Some(matrices) => {
            let frame = Frame::with_skin(&gpu, &scene, &skin, reach, &target).unwrap();
            frame.set_joint_matrices(&gpu.queue, matrices).unwrap();
            frame
        }
        None => {
            // The same reach as a skinned frame's: the voxel shadow spans the same box.
            let mut buffers = MeshBuffers::upload(&gpu, &scene.mesh).unwrap();
            buffers.bounds = (reach.0.min(buffers.bounds.0), reach.1.max(buffers.bounds.1));
            Frame::with_mesh_buffers(&gpu, &scene, buffers, &target).unwrap()
        }
    };
    let targets = Targets::with_format(&gpu, w, h, &format).unwrap();
    let camera = scene.camera.matrices_reverse_z(w, h);
    frame.prepare(&gpu.queue, t, &camera).unwrap();
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    let views = targets.view_set();
    frame.record(&mut encoder, &views.views(), None).unwrap();
    gpu.queue.submit([encoder.finish()]);
    let data = targets.read_color(&gpu).unwrap();
    image::RgbaImage::from_raw(w, h, data.data).unwrap()
}

/// Bevy's `Mat4` as `f64` glam.
fn dmat(m: Mat4) -> DMat4 {
    glam::Mat4::from_cols_array(&m.to_cols_array()).as_dmat4()
}

#[test]
fn a_trotting_characters_fur_is_pelages_own_frame_of_the_same_pose() {
    let (mut app, bevy_frame, t) = bevy_frame(true, 4);
    let (mesh, skin) = character::character().unwrap();
    let size = mesh_size(&mesh);

    // The matrices the plugin computes from Bevy's world, against Bevy's convention.
    let world = app.world_mut();
    let (world_from_mesh, skinned) = world
        .query_filtered::<(&GlobalTransform, &SkinnedMesh), With<Fur>>()
        .single(world)
        .map(|(g, s)| (*g, s.clone()))
        .unwrap();
    let joints: Vec<GlobalTransform> = (skinned.joints.iter())
        .map(|&j| *world.get::<GlobalTransform>(j).unwrap())
        .collect();
    let bindposes: Vec<Mat4> = world
        .resource::<Assets<SkinnedMeshInverseBindposes>>()
        .get(&skinned.inverse_bindposes)
        .unwrap()
        .to_vec();
    let plugins = skin_joint_matrices(&world_from_mesh, &joints, &bindposes).unwrap();
    // Bevy's skinning, in f64: a vertex goes to Σ w_k world_from_joint_k · ibp_k · p.
    let skinned_mesh = skin_mesh(&mesh, &skin, &plugins);
    let to_world = dmat(world_from_mesh.to_matrix());
    let mut worst_bevy = 0.0f64;
    for (v, p) in mesh.positions.iter().enumerate() {
        let mut bevy = DVec3::ZERO;
        for k in 0..4 {
            let w = f64::from(skin.weights[v][k]);
            let j = skin.joints[v][k] as usize;
            let m = dmat(joints[j].to_matrix()) * dmat(bindposes[j]);
            bevy += w * m.transform_point3(p.as_dvec3());
        }
        let ours = to_world.transform_point3(skinned_mesh.positions[v].as_dvec3());
        worst_bevy = worst_bevy.max(ours.distance(bevy));
    }
    // The example's pose from its pivots alone (no Bevy hierarchy, no mesh transform).
    let pose = character::pose(t, true);
    let worst_pose = (plugins.iter().zip(&pose))
        .map(|(a, b)| {
            (*a - *b)
                .abs()
                .to_cols_array()
                .into_iter()
                .fold(0.0f32, f32::max)
        })
        .fold(0.0f32, f32::max);
    // How far the pose moved the mesh from its bind pose (what the fur must follow).
    let posed = skin_mesh(&mesh, &skin, &pose);
    let moved = (mesh.positions.iter().zip(&posed.positions))
        .map(|(a, b)| a.distance(*b))
        .fold(0.0f32, f32::max);
    println!(
        "t = {t:.3} s: plugin's skin vs Bevy's convention {:.2e} of the mesh size, its joint \
         matrices vs the example's pose {worst_pose:.2e}; the pose moves a vertex {moved:.3} \
         ({:.1}% of the mesh size {size:.3})",
        worst_bevy / f64::from(size),
        100.0 * moved / size
    );
    // Measured 1e-7 .. 1e-6 (f32 transforms through three levels of parents): 1e-5 is
    // the library's skinning tolerance.
    assert!(worst_bevy <= 1e-5 * f64::from(size), "{worst_bevy}");
    assert!(worst_pose <= 1e-5, "{worst_pose}");
    assert!(
        moved > 0.05 * size,
        "the pose at {t} hardly moves the mesh ({moved})"
    );
    // Every vertex of this pose is inside the reach box the example gives the plugin.
    let (lo, hi) = character::reach(&mesh);
    assert!(
        posed
            .positions
            .iter()
            .all(|p| p.cmpge(lo).all() && p.cmple(hi).all())
    );

    // The plugin's frame against pelage's own frame of the same skinned pose.
    let own = pelages_own(t, Some(&pose));
    let (flip_same, differ_same) = (mean_flip(&own, &bevy_frame), differing(&own, &bevy_frame));
    // And against pelage's frame of the bind pose: the fur moved with the joints.
    let bind = pelages_own(t, None);
    let (flip_bind, differ_bind) = (mean_flip(&bind, &bevy_frame), differing(&bind, &bevy_frame));
    println!(
        "Bevy's frame vs pelage's of the same pose: mean FLIP {flip_same:.5}, {differ_same} of \
         {PIXELS} pixels differ; vs pelage's bind pose: mean FLIP {flip_bind:.5}, {differ_bind} \
         pixels differ"
    );
    // PELAGE_BEVY_OUT=DIR keeps the pictures (docs/src/images/bevy_character.png is
    // Bevy's frame).
    if let Some(dir) = std::env::var_os("PELAGE_BEVY_OUT").map(std::path::PathBuf::from) {
        std::fs::create_dir_all(&dir).unwrap();
        bevy_frame.save(dir.join("bevy_character.png")).unwrap();
        own.save(dir.join("pelage_character.png")).unwrap();
        bind.save(dir.join("pelage_character_bind.png")).unwrap();
    }
    // Issue 37's target: mean FLIP <= 0.005; as tests/fur.rs, at most 1% of the pixels
    // differing (a mean alone lets a near miss through).
    assert!(flip_same <= 0.005, "mean FLIP {flip_same} > 0.005");
    assert!(
        differ_same * 100 <= PIXELS,
        "{differ_same} of {PIXELS} pixels differ"
    );
    // The bind pose is another picture (measured on lavapipe: mean FLIP 0.042, 17 618
    // pixels differ, against 0.00006 and 42 for the same pose): at least half that
    // FLIP and a tenth of the pixels.
    assert!(
        flip_bind > 0.02,
        "the fur did not move: mean FLIP {flip_bind} to the bind pose"
    );
    assert!(differ_bind * 10 > PIXELS, "only {differ_bind} pixels moved");
}

#[test]
fn a_skinned_character_in_its_bind_pose_is_the_unskinned_mesh() {
    let (_app, bevy_frame, t) = bevy_frame(false, 3);
    let own = pelages_own(t, None);
    let (flip_bind, differ) = (mean_flip(&own, &bevy_frame), differing(&own, &bevy_frame));
    println!(
        "a still skinned character vs pelage's unskinned mesh at t = {t:.3} s: mean FLIP \
         {flip_bind:.5}, {differ} of {PIXELS} pixels differ"
    );
    assert!(flip_bind <= 0.005, "mean FLIP {flip_bind} > 0.005");
    assert!(differ * 100 <= PIXELS, "{differ} of {PIXELS} pixels differ");
}

/// One triangle with a skin of `joints` and `weights` per corner.
fn triangle(joints: [[u16; 4]; 3], weights: [[f32; 4]; 3]) -> Mesh {
    let mut mesh = bevy_pelage::bevy_mesh(&pelage::scene::Mesh {
        positions: vec![glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y],
        normals: vec![glam::Vec3::Z; 3],
        indices: vec![0, 1, 2],
        uvs: Vec::new(),
    });
    mesh.insert_attribute(
        Mesh::ATTRIBUTE_JOINT_INDEX,
        bevy::mesh::VertexAttributeValues::Uint16x4(joints.to_vec()),
    );
    mesh.insert_attribute(Mesh::ATTRIBUTE_JOINT_WEIGHT, weights.to_vec());
    mesh
}

#[test]
fn bad_skins_are_errors_that_name_what_is_wrong() {
    let good = [[1.0, 0.0, 0.0, 0.0]; 3];
    // Read as given: two joints.
    let skin: Skin = pelage_skin(
        &triangle([[0, 1, 0, 0], [1, 0, 0, 0], [0, 0, 0, 0]], good),
        2,
    )
    .unwrap();
    assert_eq!(skin.joints[1], [1, 0, 0, 0]);
    assert_eq!(skin.joint_count, 2);
    let message = |e: FurError| e.to_string();
    // A joint index past the SkinnedMesh's joints.
    let e =
        message(pelage_skin(&triangle([[0, 0, 0, 0], [0, 0, 2, 0], [0; 4]], good), 2).unwrap_err());
    assert!(e.contains("skin.joints[1][2]"), "{e}");
    // Weights that do not sum to 1.
    let half = [[0.5, 0.0, 0.0, 0.0]; 3];
    let e = message(pelage_skin(&triangle([[0; 4]; 3], half), 1).unwrap_err());
    assert!(e.contains("skin.weights[0]"), "{e}");
    // NaN weights.
    let nan = [[f32::NAN, 1.0, 0.0, 0.0]; 3];
    let e = message(pelage_skin(&triangle([[0; 4]; 3], nan), 1).unwrap_err());
    assert!(e.contains("skin.weights[0][0]"), "{e}");
    // No joints at all (a SkinnedMesh with an empty joint list), too many joints.
    let e = message(pelage_skin(&triangle([[0; 4]; 3], good), 0).unwrap_err());
    assert!(e.contains("skin.joint_count"), "{e}");
    let e = message(pelage_skin(&triangle([[0; 4]; 3], good), 100_000).unwrap_err());
    assert!(e.contains("skin.joint_count"), "{e}");
    // A mesh without joint attributes.
    let plain = bevy_pelage::bevy_mesh(&pelage::scene::Mesh::icosphere(1.0, 0).unwrap());
    assert!(matches!(pelage_skin(&plain, 1), Err(FurError::Skin(_))));
    // Fewer inverse bind matrices than joints.
    let joints = [GlobalTransform::IDENTITY; 2];
    let e =
        skin_joint_matrices(&GlobalTransform::IDENTITY, &joints, &[Mat4::IDENTITY]).unwrap_err();
    assert!(matches!(e, FurError::Skin(_)), "{e}");
    // The identity everywhere is the identity in the mesh's space; a mesh placed in the
    // world with joints placed with it is too.
    let placed = GlobalTransform::from(
        Transform::from_xyz(1.0, 2.0, 3.0).with_rotation(Quat::from_rotation_y(0.7)),
    );
    let m = skin_joint_matrices(&placed, &[placed], &[Mat4::IDENTITY]).unwrap();
    assert!(m[0].abs_diff_eq(glam::Mat4::IDENTITY, 1e-6), "{}", m[0]);
}

#[test]
fn an_entity_with_a_bad_skin_grows_no_fur_and_the_others_still_do() {
    let (mut app, _target) = character::app(true).unwrap();
    let world = app.world_mut();
    let joints = vec![
        world.spawn(Transform::default()).id(),
        world.spawn(Transform::from_xyz(0.0, 1.0, 0.0)).id(),
    ];
    let two = world
        .resource_mut::<Assets<SkinnedMeshInverseBindposes>>()
        .add(SkinnedMeshInverseBindposes::from(vec![Mat4::IDENTITY; 2]));
    let good = [[1.0, 0.0, 0.0, 0.0]; 3];
    let mut meshes = world.resource_mut::<Assets<Mesh>>();
    // A joint index (5) past the SkinnedMesh's two joints.
    let past = meshes.add(triangle([[0; 4], [0, 0, 5, 0], [1, 0, 0, 0]], good));
    let fine = meshes.add(triangle([[0; 4], [1, 0, 0, 0], [1, 0, 0, 0]], good));
    let past = world
        .spawn((
            Mesh3d(past),
            SkinnedMesh {
                inverse_bindposes: two.clone(),
                joints: joints.clone(),
            },
            Fur::default(),
        ))
        .id();
    // Three joints, two inverse bind matrices.
    let short = world
        .spawn((
            Mesh3d(fine.clone()),
            SkinnedMesh {
                inverse_bindposes: two.clone(),
                joints: vec![joints[0], joints[1], joints[1]],
            },
            Fur::default(),
        ))
        .id();
    // The same skin, well made: it gets fur.
    let ok = world
        .spawn((
            Mesh3d(fine),
            SkinnedMesh {
                inverse_bindposes: two,
                joints,
            },
            Fur::default(),
        ))
        .id();
    for _ in 0..3 {
        app.update();
    }
    let world = app.world();
    let has_fur = |e: Entity| world.get::<bevy_pelage::FurSource>(e).is_some();
    assert!(!has_fur(past), "a joint index past the joints grew fur");
    assert!(!has_fur(short), "too few inverse bind matrices grew fur");
    assert!(has_fur(ok), "a good skin grew no fur");
    let character = world
        .iter_entities()
        .find(|e| e.contains::<Fur>() && e.contains::<SkinnedMesh>() && e.id() != ok)
        .map(|e| e.id());
    assert!(character.is_some_and(has_fur));
}
