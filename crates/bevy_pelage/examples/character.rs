//! A furred quadruped trotting in place, skinned in Bevy and furred by pelage: the
//! example builds the creature (ten ellipsoids), its eight-joint skeleton (hips, chest,
//! head, tail, four legs) with smooth spine weights, a Bevy `SkinnedMesh` of it, and a
//! system that turns the joints in a trot cycle every frame; `PelagePlugin` skins the
//! mesh on the GPU and the fur follows the joints. Rendered headless into an `Image`.
//!
//! ```text
//! cargo run -p bevy_pelage --example character -- [--frames N] [--out DIR] [--still]
//! ```
//!
//! Renders N frames (default 12, 1/12 s apart) of 320 x 240 and writes
//! `DIR/character_NNNN.png` (default `out/bevy`), then the median CPU time of the
//! plugin's systems after the first two frames; `--still` keeps the bind pose. No
//! window: runs on a machine without a display (lavapipe included).
//! `tests/skin.rs` renders the same app and compares it with pelage's own frame of
//! the same pose.
//!
//! The mesh entity, the skeleton's parent and the camera are each placed with their
//! own transform (as a glTF scene places them): the joints' world matrices times the
//! inverse bind matrices put the skin in the world, and the plugin brings them into
//! the mesh's own space.

use std::path::PathBuf;

use bevy::image::Image;
use bevy::mesh::VertexAttributeValues;
use bevy::mesh::skinning::{SkinnedMesh, SkinnedMeshInverseBindposes};
use bevy::prelude::*;
use bevy::render::view::Msaa;
use bevy::time::TimeUpdateStrategy;
use bevy_pelage::PelagePlugin;

#[path = "headless/mod.rs"]
mod headless;
use headless::Result;
pub use headless::{FRAME_STEP, HEIGHT, WIDTH, read, time};
/// Strands on the creature.
pub const STRANDS: u32 = 8_000;

/// The joints: hips (the root), chest, head, tail, front left, front right, hind left
/// and hind right leg.
pub const JOINTS: usize = 8;
/// Each joint's parent (`None`: the skeleton's root).
pub const PARENTS: [Option<usize>; JOINTS] = [
    None,
    Some(0),
    Some(1),
    Some(0),
    Some(1),
    Some(1),
    Some(0),
    Some(0),
];
/// Each joint's pivot in the mesh's bind pose, before the mesh is centred (see
/// [`CENTRE`]).
const PIVOTS: [[f32; 3]; JOINTS] = [
    [0.0, -0.1, -0.45],
    [0.0, -0.1, 0.15],
    [0.0, 0.15, 0.35],
    [0.0, 0.05, -0.75],
    [0.28, -0.4, 0.25],
    [-0.28, -0.4, 0.25],
    [0.28, -0.4, -0.5],
    [-0.28, -0.4, -0.5],
];
/// Subtracted from every part and pivot: the creature's box is about centred.
const CENTRE: [f32; 3] = [0.0, 0.08, -0.11];
/// Trot cycles per second.
pub const CYCLES_PER_SECOND: f32 = 1.2;

/// The mesh placement in the world, the skeleton's parent and the camera are rigid
/// transforms of their own (the plugin must undo the mesh's: see the module docs).
pub fn mesh_transform() -> Transform {
    Transform::from_xyz(0.4, -0.1, 0.3).with_rotation(Quat::from_rotation_y(0.5))
}

/// The skeleton's parent entity's transform (any: the inverse bind matrices undo it).
fn rig_transform() -> Transform {
    Transform::from_xyz(-0.6, 0.2, 0.1).with_rotation(Quat::from_rotation_y(-0.3))
}

/// Joint `j`'s pivot in the mesh's (centred) space.
pub fn pivot(j: usize) -> glam::Vec3 {
    glam::Vec3::from_array(PIVOTS[j]) - glam::Vec3::from_array(CENTRE)
}

/// The creature and its skin: every vertex of a leg, the tail or the head (with snout
/// and ears) follows that joint alone; the body blends hips into chest with a
/// smoothstep over the middle 0.7 of its length.
pub fn character() -> Result<(pelage::scene::Mesh, pelage::scene::Skin)> {
    use glam::{Affine3A, Quat as Q, Vec3 as V};
    // (radii, rotation, centre, subdivision level, joint: None for the body).
    let parts: [(V, Q, V, u32, Option<u32>); 10] = [
        (
            V::new(0.5, 0.42, 0.7),
            Q::IDENTITY,
            V::new(0.0, -0.1, -0.15),
            3,
            None,
        ),
        (
            V::splat(0.36),
            Q::IDENTITY,
            V::new(0.0, 0.32, 0.5),
            2,
            Some(2),
        ),
        (
            V::new(0.15, 0.12, 0.14),
            Q::IDENTITY,
            V::new(0.0, 0.24, 0.82),
            1,
            Some(2),
        ),
        (
            V::new(0.1, 0.22, 0.05),
            Q::from_rotation_z(-0.35),
            V::new(0.2, 0.66, 0.45),
            2,
            Some(2),
        ),
        (
            V::new(0.1, 0.22, 0.05),
            Q::from_rotation_z(0.35),
            V::new(-0.2, 0.66, 0.45),
            2,
            Some(2),
        ),
        (
            V::new(0.12, 0.12, 0.3),
            Q::from_rotation_x(0.6),
            V::new(0.0, 0.12, -0.88),
            1,
            Some(3),
        ),
        (
            V::new(0.12, 0.22, 0.12),
            Q::IDENTITY,
            V::new(0.28, -0.5, 0.25),
            1,
            Some(4),
        ),
        (
            V::new(0.12, 0.22, 0.12),
            Q::IDENTITY,
            V::new(-0.28, -0.5, 0.25),
            1,
            Some(5),
        ),
        (
            V::new(0.12, 0.22, 0.12),
            Q::IDENTITY,
            V::new(0.28, -0.5, -0.5),
            1,
            Some(6),
        ),
        (
            V::new(0.12, 0.22, 0.12),
            Q::IDENTITY,
            V::new(-0.28, -0.5, -0.5),
            1,
            Some(7),
        ),
    ];
    let mut mesh = pelage::scene::Mesh::default();
    let mut skin = pelage::scene::Skin {
        joint_count: JOINTS as u32,
        ..Default::default()
    };
    let centre = V::from_array(CENTRE);
    for (radii, rotation, at, level, joint) in parts {
        let part = pelage::scene::Mesh::icosphere(1.0, level)?.transformed(
            Affine3A::from_scale_rotation_translation(radii, rotation, at - centre),
        );
        for p in &part.positions {
            let (joints, weights) = match joint {
                Some(j) => ([j, 0, 0, 0], [1.0, 0.0, 0.0, 0.0]),
                None => {
                    // Hips at the back, chest at the front, blended around z = -0.15.
                    let x = ((p.z + centre.z + 0.15) / 0.35 * 0.5 + 0.5).clamp(0.0, 1.0);
                    let chest = x * x * (3.0 - 2.0 * x);
                    ([0, 1, 0, 0], [1.0 - chest, chest, 0.0, 0.0])
                }
            };
            skin.joints.push(joints);
            skin.weights.push(weights);
        }
        mesh.append(&part)?;
    }
    Ok((mesh, skin))
}

/// Joint `j`'s rotation at time `t` relative to its bind pose (the identity when
/// `walking` is false): the legs swing in diagonal pairs (a trot), the spine sways,
/// the head nods twice a cycle and the tail wags.
pub fn rotation(j: usize, t: f32, walking: bool) -> glam::Quat {
    use glam::Quat as Q;
    if !walking {
        return Q::IDENTITY;
    }
    let phase = std::f32::consts::TAU * CYCLES_PER_SECOND * t;
    let (s, s2) = (phase.sin(), (2.0 * phase).sin());
    match j {
        0 => Q::from_rotation_y(0.1 * s),
        1 => Q::from_rotation_y(-0.2 * s),
        2 => Q::from_rotation_x(0.15 * s2),
        3 => Q::from_rotation_y(0.5 * s),
        4 | 7 => Q::from_rotation_x(0.5 * s),
        _ => Q::from_rotation_x(-0.5 * s),
    }
}

/// The joint matrices of the pose at `t` in the mesh's own space, computed from the
/// pivots alone (not from Bevy's hierarchy): each joint turns its part about its pivot,
/// after its parent's turn.
pub fn pose(t: f32, walking: bool) -> Vec<glam::Mat4> {
    use glam::Mat4 as M;
    let mut matrices: Vec<M> = Vec::with_capacity(JOINTS);
    for (j, parent) in PARENTS.iter().enumerate() {
        let turn = M::from_translation(pivot(j))
            * M::from_quat(rotation(j, t, walking))
            * M::from_translation(-pivot(j));
        let parent = parent.map_or(M::IDENTITY, |p| matrices[p]);
        matrices.push(parent * turn);
    }
    matrices
}

/// A box in the mesh's space that holds every pose of the trot: the bind pose's box
/// grown by 0.25 on every side (a leg's foot swings 0.15 at most, the tail's tip 0.2).
pub fn reach(mesh: &pelage::scene::Mesh) -> (glam::Vec3, glam::Vec3) {
    let (lo, hi) = mesh.bounds();
    (lo - 0.25, hi + 0.25)
}

/// The scene as pelage's own renderer takes it: the creature at rest, 8 000 strands,
/// pelage's default wind, one directional key light, pelage's default camera,
/// single-sampled shading.
pub fn scene() -> Result<pelage::scene::Scene> {
    let mut scene = pelage::scene::Scene {
        mesh: character()?.0,
        ..Default::default()
    };
    scene.hair.roots.count = STRANDS;
    scene.shade.sample_count = 1;
    scene.lights = vec![pelage::scene::Light::Directional(
        pelage::scene::DirectionalLight::default(),
    )];
    Ok(scene)
}

/// Marks joint `index` and its bind-pose local transform.
#[derive(Component)]
struct Joint {
    index: usize,
    rest: Transform,
}

/// Whether the joints move.
#[derive(Resource)]
struct Walking(bool);

/// Turns every joint to its rotation at Bevy's time.
fn trot(time: Res<Time>, walking: Res<Walking>, mut joints: Query<(&Joint, &mut Transform)>) {
    let t = time.elapsed_secs();
    for (joint, mut transform) in &mut joints {
        let turn = rotation(joint.index, t, walking.0);
        transform.rotation = joint.rest.rotation * Quat::from_array(turn.to_array());
        transform.translation = joint.rest.translation;
    }
}

/// A Bevy app, headless, that renders the trotting (or, with `walking` false, still)
/// creature into an image each `update`: returns the app and the image.
pub fn app(walking: bool) -> Result<(App, Handle<Image>)> {
    let scene = scene()?;
    let (mesh, skin) = character()?;
    let mut app = App::new();
    app.add_plugins(headless::plugins())
        .add_plugins(PelagePlugin)
        .insert_resource(TimeUpdateStrategy::ManualDuration(FRAME_STEP))
        .insert_resource(Walking(walking))
        .add_systems(Update, trot);
    let bg = scene.shade.background;
    app.insert_resource(ClearColor(Color::linear_rgb(bg.x, bg.y, bg.z)));

    let world = app.world_mut();
    let image = headless::target(world);

    // The Bevy mesh: pelage's, with the skin as Bevy's joint attributes.
    let joint_index: Vec<[u16; 4]> = (skin.joints.iter()).map(|j| j.map(|j| j as u16)).collect();
    let bevy_mesh = bevy_pelage::bevy_mesh(&mesh)
        .with_inserted_attribute(
            Mesh::ATTRIBUTE_JOINT_INDEX,
            VertexAttributeValues::Uint16x4(joint_index),
        )
        .with_inserted_attribute(Mesh::ATTRIBUTE_JOINT_WEIGHT, skin.weights.clone());
    let mesh_handle = world.resource_mut::<Assets<Mesh>>().add(bevy_mesh);

    // The skeleton: joint j's bind pose puts its frame at its pivot, axes along the
    // mesh's, wherever the mesh entity stands: world_from_joint = M · T(pivot_j), so the
    // inverse bind matrix (mesh space into joint space) is T(-pivot_j).
    let v3 = |v: glam::Vec3| Vec3::from_array(v.to_array());
    let m = mesh_transform();
    let rig = world.spawn(rig_transform()).id();
    let mut joints: Vec<Entity> = Vec::with_capacity(JOINTS);
    for (j, parent) in PARENTS.iter().enumerate() {
        let rest = match parent {
            None => Transform::from_matrix(
                rig_transform().to_matrix().inverse()
                    * m.to_matrix()
                    * Mat4::from_translation(v3(pivot(j))),
            ),
            Some(p) => Transform::from_translation(v3(pivot(j) - pivot(*p))),
        };
        let parent = parent.map_or(rig, |p| joints[p]);
        let joint = world
            .spawn((Joint { index: j, rest }, rest, ChildOf(parent)))
            .id();
        joints.push(joint);
    }
    let inverse_bindposes = world
        .resource_mut::<Assets<SkinnedMeshInverseBindposes>>()
        .add(SkinnedMeshInverseBindposes::from(
            (0..JOINTS)
                .map(|j| Mat4::from_translation(-v3(pivot(j))))
                .collect::<Vec<_>>(),
        ));

    // pelage's camera and key light, placed relative to the mesh as pelage's scene
    // places them relative to its mesh.
    world.spawn(headless::camera(&scene, &image, m, Msaa::Off));
    world.spawn(headless::key_light(&scene, m.rotation)?);

    world.spawn((
        Mesh3d(mesh_handle),
        SkinnedMesh {
            inverse_bindposes,
            joints,
        },
        headless::fur(&scene, Some(reach(&mesh))),
        m,
    ));

    headless::finish(&mut app);
    Ok((app, image))
}

fn main() {
    if let Err(e) = run() {
        eprintln!("character: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<()> {
    let mut frames = 12u32;
    let mut out = PathBuf::from("out/bevy");
    let mut walking = true;
    let mut args = std::env::args().skip(1);
    while let Some(flag) = args.next() {
        match flag.as_str() {
            "--still" => walking = false,
            "--frames" => frames = args.next().ok_or("--frames needs a value")?.parse()?,
            "--out" => out = PathBuf::from(args.next().ok_or("--out needs a value")?),
            other => {
                return Err(format!("unknown argument {other} (--frames, --out, --still)").into());
            }
        }
    }
    let (mut app, image) = app(walking)?;
    std::fs::create_dir_all(&out)?;
    let (mut plugin_ms, mut extract_ms) = (Vec::new(), Vec::new());
    for frame in 0..frames {
        app.update();
        let render = app.sub_app(bevy::render::RenderApp).world();
        if let Some(cpu) = render.get_resource::<bevy_pelage::PelageCpuTime>() {
            plugin_ms.push((cpu.extract + cpu.prepare + cpu.record).as_secs_f64() * 1e3);
            extract_ms.push(cpu.extract.as_secs_f64() * 1e3);
        }
        let picture = read(&mut app, &image)?;
        let path = out.join(format!("character_{frame:04}.png"));
        picture.save(&path)?;
        println!("t = {:.3} s: wrote {}", time(&app), path.display());
    }
    // The plugin's own systems (PelageCpuTime: extracting with the joint matrices,
    // preparing with their upload, recording), the first two frames (set-up) left out.
    let median = |mut ms: Vec<f64>| {
        let mut steady = ms.split_off(ms.len().min(2));
        steady.sort_by(f64::total_cmp);
        steady.get(steady.len() / 2).map(|m| (*m, steady.len()))
    };
    if let (Some((all, n)), Some((extract, _))) = (median(plugin_ms), median(extract_ms)) {
        println!(
            "the plugin's systems: median {all:.3} ms of CPU per frame over {n} frames \
             (extraction with the joint matrices: {extract:.3} ms)"
        );
    }
    Ok(())
}
