//! GPU skinning (`strands/skin.wgsl`) on a real adapter: against the CPU mirror in
//! pelage-reference, roots of grown and simulated fur riding the skinned surface over an
//! animation, and bad input (joint indices, weights, matrices) refused or counted.

use glam::{Mat4, Quat, Vec3};
use pelage_gpu::{Gpu, read_buffer};
use pelage_reference::skin::{mesh_size, skin_mesh};
use pelage_reference::strands::{Level, eval_surface, grow_strands};
use pelage_scene::{DynamicsParams, HairParams, Mesh, Skin, SkinBend, SurfaceInterpolation};
use pelage_strands::{
    GrowStrands, MeshBuffers, MeshSkin, SimulateStrands, StrandStage, StrandsError,
};

mod common;
use common::{gpu, grow_on_gpu, mirror_roots};

/// The f32 x3 values of `buffer`.
fn read_vec3(gpu: &Gpu, buffer: &pelage_gpu::wgpu::Buffer) -> Vec<Vec3> {
    let bytes = read_buffer(gpu, buffer).unwrap();
    bytemuck::cast_slice::<u8, [f32; 3]>(&bytes)
        .iter()
        .map(|v| Vec3::from_array(*v))
        .collect()
}

/// A 32-bit hash in [0, 1) (the test's own, not the crate's).
fn unit(i: u32) -> f32 {
    let mut x = i.wrapping_mul(0x9e37_79b9) ^ 0x85eb_ca6b;
    x ^= x >> 15;
    x = x.wrapping_mul(0x2c1b_3c6d);
    x ^= x >> 12;
    (x >> 8) as f32 / (1u32 << 24) as f32
}

/// Four joints of `joint_count` per vertex, hashed, with weights that sum to 1 within
/// 0.5% (the upload normalises them).
fn hashed_skin(vertices: usize, joint_count: u32) -> Skin {
    let mut joints = Vec::new();
    let mut weights = Vec::new();
    for v in 0..vertices as u32 {
        let j: [u32; 4] = std::array::from_fn(|k| {
            (unit(v * 8 + k as u32) * joint_count as f32) as u32 % joint_count
        });
        let raw: [f32; 4] = std::array::from_fn(|k| unit(v * 8 + 4 + k as u32) + 0.05);
        let sum: f32 = raw.iter().sum();
        let off = 1.0 + 0.005 * (unit(v ^ 0xabcd) * 2.0 - 1.0);
        joints.push(j);
        weights.push(raw.map(|w| w / sum * off));
    }
    Skin {
        joints,
        weights,
        joint_count,
    }
}

/// Joint matrices of pose `t`: rotations, translations and a mild non-uniform scale (so
/// that normals need the inverse transpose), built here from their parts.
fn pose(joint_count: u32, t: f32) -> Vec<Mat4> {
    (0..joint_count)
        .map(|j| {
            let a = j as f32 * 0.7 + t;
            Mat4::from_scale_rotation_translation(
                Vec3::new(1.0 + 0.1 * a.sin(), 1.0, 1.0 - 0.08 * a.cos()),
                Quat::from_axis_angle(Vec3::new(a.cos(), 1.0, a.sin()).normalize(), 0.9 * a.sin()),
                Vec3::new(0.2 * a.cos(), 0.1 * a.sin(), -0.15 * (2.0 * a).sin()),
            )
        })
        .collect()
}

/// Records and submits the skinning pass, and waits (stage 1 then runs in a later
/// submission, as it would later in the same encoder).
fn skin_frame(gpu: &Gpu, skin: &MeshSkin) {
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    skin.encode(&mut encoder, None);
    gpu.submit_and_wait([encoder.finish()]).unwrap();
}

#[test]
fn skinning_matches_the_cpu_mirror_within_1e_5_of_the_mesh_size() {
    let gpu = gpu();
    let bind = Mesh::creature();
    let size = mesh_size(&bind);
    let buffers = MeshBuffers::upload(&gpu, &bind).unwrap();
    let joint_count = 12;
    let skin = hashed_skin(bind.positions.len(), joint_count);
    let pass = MeshSkin::new(&gpu, &bind, &skin, &buffers).unwrap();
    let (mut worst_p, mut worst_n) = (0.0f32, 0.0f32);
    for t in [0.0, 0.4, 1.3, 2.9] {
        let matrices = pose(joint_count, t);
        pass.set_joint_matrices(&gpu.queue, &matrices).unwrap();
        skin_frame(&gpu, &pass);
        let expected = skin_mesh(&bind, &skin, &matrices);
        let positions = read_vec3(&gpu, &buffers.positions);
        let normals = read_vec3(&gpu, &buffers.normals);
        assert_eq!(positions.len(), expected.positions.len());
        for v in 0..positions.len() {
            worst_p = worst_p.max(positions[v].distance(expected.positions[v]));
            worst_n = worst_n.max(normals[v].distance(expected.normals[v]));
        }
        assert_eq!(pass.non_finite_vertices(&gpu).unwrap(), 0);
    }
    println!(
        "{} vertices, {joint_count} joints, 4 poses: worst position error {:.2e} of the mesh size ({size:.3}), worst unit-normal error {worst_n:.2e}",
        bind.positions.len(),
        worst_p / size
    );
    assert!(worst_p <= 1e-5 * size, "{worst_p}");
    assert!(worst_n <= 1e-5, "{worst_n}");
}

#[test]
fn grown_roots_ride_the_skinned_surface_over_an_animation() {
    let gpu = gpu();
    let bind = Mesh::creature();
    let size = mesh_size(&bind);
    let rig = SkinBend::default();
    let skin = rig.skin(&bind);
    let buffers = MeshBuffers::upload(&gpu, &bind).unwrap();
    let pass = MeshSkin::new(&gpu, &bind, &skin, &buffers).unwrap();
    let mut hair = HairParams::default();
    hair.roots.count = 2000;
    hair.growth.segments = 8;
    hair.growth.surface = SurfaceInterpolation::PnTriangle;
    let mut grow = GrowStrands::new(&gpu, &bind, &buffers, &hair).unwrap();
    let per = hair.growth.segments as usize + 1;
    let (mut worst_root, mut worst_vertex, mut moved) = (0.0f32, 0.0f32, 0.0f32);
    let rest = {
        skin_frame(&gpu, &pass);
        grow_on_gpu(&gpu, &mut grow, 0.0)
    };
    for frame in 1..=24 {
        let t = frame as f32 * 0.125;
        let matrices = rig.joint_matrices(t);
        pass.set_joint_matrices(&gpu.queue, &matrices).unwrap();
        skin_frame(&gpu, &pass);
        let gpu_vertices = grow_on_gpu(&gpu, &mut grow, t);
        let skinned = skin_mesh(&bind, &skin, &matrices);
        for (strand, root) in gpu_vertices.chunks(per).zip(grow.roots()) {
            let on = eval_surface(&skinned, root.triangle, root.bary, true).position;
            worst_root = worst_root.max(strand[0].truncate().distance(on));
        }
        let expected = grow_strands(
            &skinned,
            &mirror_roots(grow.roots()),
            &hair,
            t,
            Level::full(&hair),
        );
        for (a, b) in gpu_vertices.iter().zip(&expected) {
            worst_vertex = worst_vertex.max(a.truncate().distance(b.truncate()));
        }
        for (a, b) in gpu_vertices
            .iter()
            .step_by(per)
            .zip(rest.iter().step_by(per))
        {
            moved = moved.max(a.truncate().distance(b.truncate()));
        }
    }
    println!(
        "24 frames of the bend rig: roots at most {:.2e} of the mesh size from their skinned PN surface point, strands at most {:.2e} from the mirror grown on the mirror's skinned mesh; roots moved up to {moved:.3}",
        worst_root / size,
        worst_vertex / size
    );
    assert!(
        moved > 0.1 * size,
        "the rig did not move the roots: {moved}"
    );
    assert!(worst_root <= 1e-5 * size, "{worst_root}");
    assert!(worst_vertex <= 1e-5 * size, "{worst_vertex}");
}

#[test]
fn a_simulation_anchors_its_roots_on_the_skinned_surface() {
    let gpu = gpu();
    let bind = Mesh::creature();
    let size = mesh_size(&bind);
    let rig = SkinBend {
        bend_frequency: 1.5,
        ..SkinBend::default()
    };
    let skin = rig.skin(&bind);
    let buffers = MeshBuffers::upload(&gpu, &bind).unwrap();
    let pass = MeshSkin::new(&gpu, &bind, &skin, &buffers).unwrap();
    let mut hair = HairParams::default();
    hair.roots.count = 500;
    hair.growth.segments = 8;
    let mut sim =
        SimulateStrands::grown(&gpu, &bind, &buffers, &hair, &DynamicsParams::default()).unwrap();
    let per = hair.growth.segments as usize + 1;
    let (mut worst_root, mut worst_reach) = (0.0f32, 0.0f32);
    for frame in 0..40 {
        let t = frame as f32 / 30.0;
        let matrices = rig.joint_matrices(t);
        pass.set_joint_matrices(&gpu.queue, &matrices).unwrap();
        skin_frame(&gpu, &pass);
        let vertices = grow_on_gpu(&gpu, &mut sim, t);
        let skinned = skin_mesh(&bind, &skin, &matrices);
        for (strand, root) in vertices.chunks(per).zip(sim.roots()) {
            assert!(strand.iter().all(|v| v.is_finite()));
            // The simulation binds roots to the flat triangle.
            let on = eval_surface(&skinned, root.triangle, root.bary, false).position;
            worst_root = worst_root.max(strand[0].truncate().distance(on));
            // No strand stretches past its length from the anchor.
            let tip = strand[per - 1].truncate().distance(on);
            worst_reach = worst_reach.max(tip / root.length);
        }
    }
    assert_eq!(sim.held_strands(&gpu).unwrap(), 0);
    println!(
        "40 frames at 30 fps, bend at 1.5 Hz: simulated roots at most {:.2e} of the mesh size from their skinned triangle point; tips at most {worst_reach:.4} strand lengths from it",
        worst_root / size
    );
    assert!(worst_root <= 1e-5 * size, "{worst_root}");
    assert!(worst_reach <= 1.0 + 1e-3, "{worst_reach}");
}

/// The parameter name of a refused skin, or a panic.
fn refused(result: Result<MeshSkin, StrandsError>) -> String {
    match result {
        Err(StrandsError::Param(p)) => {
            println!("refused: {p}");
            p.name
        }
        other => panic!("expected a parameter error, got {other:?}"),
    }
}

#[test]
fn bad_joints_weights_and_matrices_are_refused_naming_the_field() {
    let gpu = gpu();
    let bind = Mesh::icosphere(1.0, 1).unwrap();
    let buffers = MeshBuffers::upload(&gpu, &bind).unwrap();
    let n = bind.positions.len();
    let good = Skin {
        joints: vec![[0, 1, 0, 0]; n],
        weights: vec![[0.5, 0.5, 0.0, 0.0]; n],
        joint_count: 2,
    };
    let with = |f: &dyn Fn(&mut Skin)| {
        let mut s = good.clone();
        f(&mut s);
        MeshSkin::new(&gpu, &bind, &s, &buffers)
    };
    assert_eq!(refused(with(&|s| s.joints[7][1] = 2)), "skin.joints[7][1]");
    assert_eq!(
        refused(with(&|s| s.weights[3][0] = -0.5)),
        "skin.weights[3][0]"
    );
    assert_eq!(
        refused(with(&|s| s.weights[4][2] = f32::NAN)),
        "skin.weights[4][2]"
    );
    assert_eq!(
        refused(with(&|s| s.weights[5] = [0.5, 0.6, 0.0, 0.0])),
        "skin.weights[5]"
    );
    assert_eq!(
        refused(with(&|s| s.weights[5] = [0.0; 4])),
        "skin.weights[5]"
    );
    assert_eq!(refused(with(&|s| s.joint_count = 0)), "skin.joint_count");
    assert_eq!(
        refused(with(&|s| {
            s.joints.pop();
        })),
        "skin.joints"
    );
    assert_eq!(
        refused(with(&|s| {
            s.weights.push([1.0, 0.0, 0.0, 0.0]);
        })),
        "skin.weights"
    );
    // A mesh of another vertex count than the buffers.
    let other = Mesh::icosphere(1.0, 2).unwrap();
    assert!(matches!(
        MeshSkin::new(&gpu, &other, &good, &buffers),
        Err(StrandsError::Contract(
            pelage_strands::ContractError::MeshMismatch { .. }
        ))
    ));
    // Matrices: a NaN and a wrong count are refused and nothing is written.
    let pass = with(&|_| {}).unwrap();
    let mut bad = [Mat4::IDENTITY; 2];
    bad[1].w_axis.y = f32::NAN;
    let err = pass.set_joint_matrices(&gpu.queue, &bad).unwrap_err();
    assert!(
        matches!(&err, StrandsError::Param(p) if p.name == "skin.joint_matrices[1]"),
        "{err}"
    );
    let err = pass
        .set_joint_matrices(&gpu.queue, &[Mat4::IDENTITY])
        .unwrap_err();
    assert!(
        matches!(&err, StrandsError::Param(p) if p.name == "skin.joint_matrices"),
        "{err}"
    );
    skin_frame(&gpu, &pass);
    assert_eq!(read_vec3(&gpu, &buffers.positions), bind.positions);
}

#[test]
fn a_nan_matrix_written_straight_into_the_buffer_leaves_its_vertices_at_the_bind_pose_and_counts_them()
 {
    let gpu = gpu();
    let bind = Mesh::icosphere(1.0, 2).unwrap();
    let buffers = MeshBuffers::upload(&gpu, &bind).unwrap();
    // Vertices above the equator on joint 1 alone, the rest on joint 0 alone.
    let on_one: Vec<bool> = bind.positions.iter().map(|p| p.y > 0.0).collect();
    let skin = Skin {
        joints: vec![[0, 1, 0, 0]; bind.positions.len()],
        weights: on_one
            .iter()
            .map(|&one| {
                if one {
                    [0.0, 1.0, 0.0, 0.0]
                } else {
                    [1.0, 0.0, 0.0, 0.0]
                }
            })
            .collect(),
        joint_count: 2,
    };
    let pass = MeshSkin::new(&gpu, &bind, &skin, &buffers).unwrap();
    let shift = Mat4::from_translation(Vec3::new(0.5, 0.0, 0.0));
    let mut nan = shift;
    nan.x_axis.x = f32::NAN;
    // An engine's own write, which nothing checks.
    let matrices: [[f32; 16]; 2] = [shift.to_cols_array(), nan.to_cols_array()];
    gpu.queue
        .write_buffer(pass.joint_matrices(), 0, bytemuck::cast_slice(&matrices));
    skin_frame(&gpu, &pass);
    let positions = read_vec3(&gpu, &buffers.positions);
    let expected = on_one.iter().filter(|b| **b).count() as u32;
    let counted = pass.non_finite_vertices(&gpu).unwrap();
    println!(
        "NaN in joint 1: {counted} vertices held at the bind pose ({expected} weighted on it)"
    );
    assert_eq!(counted, expected);
    for ((p, b), one) in positions.iter().zip(&bind.positions).zip(&on_one) {
        assert!(p.is_finite());
        let want = if *one {
            *b
        } else {
            *b + Vec3::new(0.5, 0.0, 0.0)
        };
        assert!(p.distance(want) <= 1e-6, "{p} {want}");
    }
    // Fixed matrices: nothing counted.
    pass.set_joint_matrices(&gpu.queue, &[shift, shift])
        .unwrap();
    skin_frame(&gpu, &pass);
    assert_eq!(pass.non_finite_vertices(&gpu).unwrap(), 0);
}
