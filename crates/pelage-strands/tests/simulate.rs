//! Stage 1 with dynamics on a real adapter: the GPU against the CPU mirror, segments at
//! their rest length and vertices out of the colliders after every step, no NaN under
//! the strongest wind with dt spikes, teleports and NaN in the mesh, and bit-identical
//! runs.

use std::time::Instant;

use glam::{Quat, Vec3, Vec4};
use pelage_gpu::{Gpu, read_buffer};
use pelage_reference::simulate::{Step, simulate_frame};
use pelage_reference::strands::Level;
use pelage_scene::{Collider, DynamicsParams, HairParams, MAX_FORCE, Mesh, WindParams};
use pelage_strands::{MeshBuffers, SimulateStrands, StrandStage};

mod common;
use common::{gpu, grow_on_gpu, mirror_roots};

const SEGMENTS: u32 = 16;
/// The collider inside the head (an icosphere of radius 1, whose flat faces come within
/// about 0.95 of the centre): below every root.
const BODY_RADIUS: f32 = 0.9;

fn head() -> Mesh {
    Mesh::icosphere(1.0, 2).unwrap()
}

fn hair(count: u32, wind: WindParams) -> HairParams {
    let mut p = HairParams::default();
    p.roots.count = count;
    p.growth.segments = SEGMENTS;
    p.growth.length = 1.5;
    p.growth.width = 0.01;
    p.wind = wind;
    p
}

fn windy() -> WindParams {
    WindParams {
        strength: 1.5,
        turbulence: 1.0,
        ..WindParams::default()
    }
}

fn strongest() -> WindParams {
    WindParams {
        strength: MAX_FORCE,
        turbulence: MAX_FORCE,
        gust_strength: 1.0,
        ..WindParams::default()
    }
}

fn body() -> Collider {
    Collider::sphere(Vec3::ZERO, BODY_RADIUS)
}

/// A simulation of `count` strands on the head, with the body collider.
fn simulation(
    gpu: &Gpu,
    mesh: &Mesh,
    buffers: &MeshBuffers,
    count: u32,
    wind: WindParams,
) -> SimulateStrands {
    let mut sim = SimulateStrands::grown(
        gpu,
        mesh,
        buffers,
        &hair(count, wind),
        &DynamicsParams::default(),
    )
    .unwrap();
    sim.set_colliders(&[body()]).unwrap();
    sim
}

/// `mesh` turned by `rotation` about the origin and moved by `offset`.
fn posed(mesh: &Mesh, rotation: Quat, offset: Vec3) -> Mesh {
    Mesh {
        positions: mesh
            .positions
            .iter()
            .map(|&p| rotation * p + offset)
            .collect(),
        normals: mesh.normals.iter().map(|&n| rotation * n).collect(),
        indices: mesh.indices.clone(),
        uvs: Vec::new(),
    }
}

/// The head's pose at time `t`: turning and nodding.
fn head_pose(t: f32) -> Quat {
    Quat::from_rotation_y(1.2 * (2.0 * t).sin()) * Quat::from_rotation_x(0.5 * (3.0 * t).sin())
}

/// The simulation state, as the GPU holds it.
fn read_state(gpu: &Gpu, sim: &SimulateStrands) -> Vec<Vec4> {
    let bytes = read_buffer(gpu, sim.state()).unwrap();
    bytemuck::cast_slice::<u8, [f32; 4]>(&bytes)
        .iter()
        .map(|v| Vec4::from_array(*v))
        .collect()
}

/// The worst relative difference of a segment's length from its rest length.
fn worst_stretch(vertices: &[Vec4], sim: &SimulateStrands) -> f32 {
    let per = SEGMENTS as usize + 1;
    let mut worst = 0.0f32;
    for (s, r) in vertices.chunks(per).zip(sim.rest_local().chunks(per)) {
        for (sw, rw) in s.windows(2).zip(r.windows(2)) {
            let now = sw[0].truncate().distance(sw[1].truncate());
            let rest = rw[0].distance(rw[1]);
            worst = worst.max((now - rest).abs() / rest);
        }
    }
    worst
}

/// Non-root vertices inside `collider`, and the deepest, in scene units.
fn penetration(vertices: &[Vec4], collider: &Collider) -> (usize, f32) {
    let per = SEGMENTS as usize + 1;
    let mut inside = 0;
    let mut deepest = 0.0f32;
    for strand in vertices.chunks(per) {
        for v in &strand[1..] {
            let depth = collider.depth(v.truncate());
            if depth > 0.0 {
                inside += 1;
                deepest = deepest.max(depth);
            }
        }
    }
    (inside, deepest)
}

fn max_diff(a: &[Vec4], b: &[Vec4]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x.truncate() - y.truncate()).abs().max_element())
        .fold(0.0f32, f32::max)
}

#[test]
fn gpu_matches_the_cpu_mirror_after_one_substep_and_stays_close_for_100_frames() {
    let gpu = gpu();
    let rest_mesh = head();
    let buffers = MeshBuffers::upload(&gpu, &rest_mesh).unwrap();
    let mut sim = simulation(&gpu, &rest_mesh, &buffers, 200, windy());
    let size = 2.0 * (1.0 + 1.5);
    let h = DynamicsParams::default().max_substep;
    // The mirror's inputs: the parameters the simulation was made with, its colliders, and
    // the roots it sampled.
    let (params, dynamics, colliders) = (hair(200, windy()), DynamicsParams::default(), [body()]);
    let roots = mirror_roots(sim.roots());
    let frame = |time: f32, dt: f32| Step {
        hair: &params,
        dynamics: &dynamics,
        colliders: &colliders,
        time,
        dt: Some(dt),
        level: Level::full(&params),
    };

    // Frame 0 puts the strands at rest; frame 1 is one substep.
    grow_on_gpu(&gpu, &mut sim, 0.0);
    let mut cpu_state = read_state(&gpu, &sim);
    let mut mesh = posed(&rest_mesh, head_pose(h), Vec3::ZERO);
    buffers.update(&gpu.queue, &mesh).unwrap();
    let gpu_vertices = grow_on_gpu(&gpu, &mut sim, h);
    // One step of h from frame 0 at t = 0.
    let (cpu_vertices, held) = simulate_frame(&mesh, &roots, &mut cpu_state, &frame(h, h));
    assert_eq!(held, 0);
    let one = max_diff(&gpu_vertices, &cpu_vertices);
    println!("1 substep: max |GPU - CPU| = {one:.2e} (scene size {size})");
    assert!(one <= 1e-5 * size, "{one}");

    // 100 frames of 1/60 s (2 substeps each) with the head turning. Each frame the
    // mirror also steps from the GPU's own state before it: the GPU computes every frame
    // as the code says, in the states the simulation reaches (hair on the body,
    // collisions). And the mirror carries its own state: how far two runs that differ by
    // rounding alone drift apart. (Friction applied in every collision round made that
    // hinge on rounding; it is applied in the first round only.)
    let mut drift = 0.0f32;
    let mut per_frame = 0.0f32;
    let mut t = h;
    for _ in 0..100 {
        let last = t;
        t += 1.0 / 60.0;
        mesh = posed(&rest_mesh, head_pose(t), Vec3::ZERO);
        buffers.update(&gpu.queue, &mesh).unwrap();
        let mut gpu_state = read_state(&gpu, &sim);
        let g = grow_on_gpu(&gpu, &mut sim, t);
        let (from_gpu, _) = simulate_frame(&mesh, &roots, &mut gpu_state, &frame(t, t - last));
        per_frame = per_frame.max(max_diff(&g, &from_gpu));
        let (c, _) = simulate_frame(&mesh, &roots, &mut cpu_state, &frame(t, t - last));
        drift = drift.max(max_diff(&g, &c));
    }
    println!(
        "100 frames: each frame from the GPU's state, max |GPU - CPU| = {per_frame:.2e} \
         ({:.2e} of the scene size); each side its own state, {drift:.2e} ({:.2e})",
        per_frame / size,
        drift / size
    );
    assert!(per_frame <= 1e-5 * size, "{per_frame}");
    assert!(drift <= 1e-2 * size, "{drift}");

    // Frames whose substeps are not the stiffness interval (1/120 s), where the
    // stiffnesses per substep differ from those given: 1/50 s (3 substeps of 1/150 s),
    // 1/24 s (5 of 1/120 s, rounded), a 0.3 s hitch (cut to max_frame, 12 substeps) and
    // 1/144 s (1 substep), each from the GPU's state.
    let mut odd = 0.0f32;
    for dt in [
        1.0 / 50.0,
        1.0 / 50.0,
        1.0 / 24.0,
        0.3,
        1.0 / 144.0,
        1.0 / 50.0,
    ] {
        let last = t;
        t += dt;
        mesh = posed(&rest_mesh, head_pose(t), Vec3::ZERO);
        buffers.update(&gpu.queue, &mesh).unwrap();
        let mut gpu_state = read_state(&gpu, &sim);
        let g = grow_on_gpu(&gpu, &mut sim, t);
        let (from_gpu, _) = simulate_frame(&mesh, &roots, &mut gpu_state, &frame(t, t - last));
        odd = odd.max(max_diff(&g, &from_gpu));
    }
    println!(
        "frames of 1/50, 1/24, 0.3 and 1/144 s: each from the GPU's state, max |GPU - CPU| = \
         {odd:.2e} ({:.2e} of the scene size)",
        odd / size
    );
    assert!(odd <= 1e-5 * size, "{odd}");
}

#[test]
fn segments_keep_their_length_and_vertices_stay_out_of_the_body_while_the_head_turns() {
    let gpu = gpu();
    let rest_mesh = head();
    let buffers = MeshBuffers::upload(&gpu, &rest_mesh).unwrap();
    let mut sim = simulation(&gpu, &rest_mesh, &buffers, 500, windy());
    let width = 0.01;
    let dts = [0.001, 0.1, 1.0 / 60.0, 0.033, 0.001, 0.1];
    let mut t = 0.0;
    let (mut stretch, mut inside_most, mut deepest) = (0.0f32, 0usize, 0.0f32);
    let mut total = 0;
    for frame in 0..120 {
        t += dts[frame % dts.len()];
        let mesh = posed(&rest_mesh, head_pose(t), Vec3::ZERO);
        buffers.update(&gpu.queue, &mesh).unwrap();
        let v = grow_on_gpu(&gpu, &mut sim, t);
        stretch = stretch.max(worst_stretch(&v, &sim));
        let (inside, depth) = penetration(&v, &body());
        inside_most = inside_most.max(inside);
        deepest = deepest.max(depth);
        total = v.len() - v.len() / (SEGMENTS as usize + 1);
    }
    println!(
        "120 frames: worst stretch {stretch:.2e}; at most {inside_most} of {total} vertices inside the body, deepest {deepest:.2e} (strand width {width})"
    );
    assert!(stretch <= 1e-3, "{stretch}");
    assert!(
        inside_most as f64 <= 0.001 * total as f64,
        "{inside_most} of {total}"
    );
    assert!(deepest <= width, "{deepest}");
}

/// Frames of the strongest wind with dt alternating 1 ms and 100 ms, the head teleported
/// 10 units and back every 250 frames and a NaN in the mesh for one frame every 300:
/// no vertex ever non-finite (read back every 1000 frames and at the end).
fn survive(frames: u32) {
    let gpu = gpu();
    let rest_mesh = head();
    let buffers = MeshBuffers::upload(&gpu, &rest_mesh).unwrap();
    let mut sim = simulation(&gpu, &rest_mesh, &buffers, 64, strongest());
    let start = Instant::now();
    let mut t = 0.0f32;
    for frame in 1..=frames {
        t += if frame % 2 == 0 { 0.1 } else { 0.001 };
        let offset = if (frame / 250) % 2 == 1 {
            Vec3::X * 10.0
        } else {
            Vec3::ZERO
        };
        let mut mesh = posed(&rest_mesh, head_pose(t), offset);
        if frame % 300 == 0 {
            mesh.positions[5] = Vec3::NAN;
        }
        buffers.update(&gpu.queue, &mesh).unwrap();
        let frame_id = sim.prepare(&gpu.queue, t).unwrap();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        sim.encode(&mut encoder, &frame_id, None).unwrap();
        gpu.queue.submit([encoder.finish()]);
        if frame % 1000 == 0 || frame == frames {
            let v = common::read_vertices(&gpu, &sim.buffers().vertices);
            assert!(
                v.iter().all(|v| v.is_finite()),
                "frame {frame}: a vertex is not finite"
            );
            let stretch = worst_stretch(&v, &sim);
            assert!(stretch <= 1e-3, "frame {frame}: stretch {stretch}");
        }
    }
    println!(
        "{frames} frames of the strongest wind, dt 1 ms <-> 100 ms, teleports, NaN: all finite, {:.1} s",
        start.elapsed().as_secs_f32()
    );
}

#[test]
fn no_vertex_goes_non_finite_in_10000_frames_of_the_strongest_wind_with_dt_spikes() {
    survive(10_000);
}

#[test]
fn a_teleported_root_puts_its_strand_at_rest_in_the_new_pose() {
    let gpu = gpu();
    let rest_mesh = head();
    let buffers = MeshBuffers::upload(&gpu, &rest_mesh).unwrap();
    let mut sim = simulation(&gpu, &rest_mesh, &buffers, 100, windy());
    let rest = grow_on_gpu(&gpu, &mut sim, 0.0);
    let mut t = 0.0;
    let mut moved = Vec::new();
    for _ in 0..20 {
        t += 1.0 / 30.0;
        moved = grow_on_gpu(&gpu, &mut sim, t);
    }
    let swing = max_diff(&moved, &rest);
    assert!(swing > 0.05, "the strands did not move ({swing})");
    let offset = Vec3::new(10.0, 0.0, 0.0);
    buffers
        .update(&gpu.queue, &posed(&rest_mesh, Quat::IDENTITY, offset))
        .unwrap();
    let after = grow_on_gpu(&gpu, &mut sim, t + 1.0 / 30.0);
    let shifted: Vec<Vec4> = rest.iter().map(|v| *v + offset.extend(0.0)).collect();
    let worst = max_diff(&after, &shifted);
    println!(
        "teleport by 10: strands {swing:.3} from rest before, {worst:.2e} from the moved rest after"
    );
    assert!(worst <= 1e-5 * 12.0, "{worst}");
}

#[test]
fn nan_in_the_mesh_holds_the_strands_on_it_and_counts_them() {
    let gpu = gpu();
    let rest_mesh = head();
    let buffers = MeshBuffers::upload(&gpu, &rest_mesh).unwrap();
    let mut sim = simulation(&gpu, &rest_mesh, &buffers, 300, windy());
    let mut t = 0.0;
    let mut before = Vec::new();
    for _ in 0..10 {
        before = grow_on_gpu(&gpu, &mut sim, t);
        t += 1.0 / 30.0;
    }
    let bad_vertex = rest_mesh.indices[sim.roots()[0].triangle as usize * 3];
    let on_bad: Vec<bool> = sim
        .roots()
        .iter()
        .map(|r| rest_mesh.indices[r.triangle as usize * 3..][..3].contains(&bad_vertex))
        .collect();
    let expected = on_bad.iter().filter(|b| **b).count() as u32;
    let mut mesh = rest_mesh.clone();
    mesh.positions[bad_vertex as usize] = Vec3::NAN;
    buffers.update(&gpu.queue, &mesh).unwrap();
    let after = grow_on_gpu(&gpu, &mut sim, t);
    let held = sim.held_strands(&gpu).unwrap();
    println!("NaN in mesh vertex {bad_vertex}: {held} strands held ({expected} grow on it)");
    assert_eq!(held, expected);
    let per = SEGMENTS as usize + 1;
    for ((a, b), bad) in after.chunks(per).zip(before.chunks(per)).zip(&on_bad) {
        assert!(a.iter().all(|v| v.is_finite()));
        if *bad {
            assert_eq!(a, b, "a held strand moved");
        }
    }
    assert!(worst_stretch(&after, &sim) <= 1e-3);
    // The mesh repaired: nothing held, and the held strands move again.
    buffers.update(&gpu.queue, &rest_mesh).unwrap();
    grow_on_gpu(&gpu, &mut sim, t + 1.0 / 30.0);
    assert_eq!(sim.held_strands(&gpu).unwrap(), 0);
}

#[test]
fn the_same_inputs_give_bit_identical_strands() {
    let gpu = gpu();
    let rest_mesh = head();
    let buffers_a = MeshBuffers::upload(&gpu, &rest_mesh).unwrap();
    let buffers_b = MeshBuffers::upload(&gpu, &rest_mesh).unwrap();
    let mut a = simulation(&gpu, &rest_mesh, &buffers_a, 200, windy());
    let mut b = simulation(&gpu, &rest_mesh, &buffers_b, 200, windy());
    let mut t = 0.0;
    for frame in 0..40 {
        t += if frame % 3 == 0 { 0.1 } else { 0.004 };
        let mesh = posed(&rest_mesh, head_pose(t), Vec3::ZERO);
        buffers_a.update(&gpu.queue, &mesh).unwrap();
        buffers_b.update(&gpu.queue, &mesh).unwrap();
        grow_on_gpu(&gpu, &mut a, t);
        grow_on_gpu(&gpu, &mut b, t);
    }
    let va = read_buffer(&gpu, &a.buffers().vertices).unwrap();
    let vb = read_buffer(&gpu, &b.buffers().vertices).unwrap();
    assert_eq!(va, vb, "vertices differ");
    assert_eq!(read_state(&gpu, &a), read_state(&gpu, &b), "state differs");
}

#[test]
fn time_going_backwards_and_reset_put_the_strands_at_rest() {
    let gpu = gpu();
    let mesh = head();
    let buffers = MeshBuffers::upload(&gpu, &mesh).unwrap();
    let mut sim = simulation(&gpu, &mesh, &buffers, 100, windy());
    let rest = grow_on_gpu(&gpu, &mut sim, 0.0);
    for k in 1..=10 {
        grow_on_gpu(&gpu, &mut sim, k as f32 * 0.05);
    }
    let back = grow_on_gpu(&gpu, &mut sim, 0.1);
    assert_eq!(max_diff(&back, &rest), 0.0);
    grow_on_gpu(&gpu, &mut sim, 0.2);
    sim.reset();
    let reset = grow_on_gpu(&gpu, &mut sim, 0.3);
    assert_eq!(max_diff(&reset, &rest), 0.0);
}

#[test]
fn a_groom_is_bound_to_the_nearest_triangles_and_starts_at_its_rest_shape() {
    let gpu = gpu();
    let mesh = head();
    let buffers = MeshBuffers::upload(&gpu, &mesh).unwrap();
    // Strands from points just above the head, hanging down and out.
    let strands: Vec<Vec<Vec3>> = (0..150)
        .map(|i| {
            let a = i as f32 * 2.399_963;
            let z = 1.0 - (i as f32 + 0.5) / 150.0;
            let r = (1.0 - z * z).sqrt();
            let dir = Vec3::new(r * a.cos(), z, r * a.sin());
            (0..9)
                .map(|k| dir * 1.01 + (dir * 0.5 - Vec3::Y) * 0.1 * k as f32)
                .collect()
        })
        .collect();
    let groom = pelage_scene::Groom::from_strands(&strands)
        .unwrap()
        .resample(SEGMENTS)
        .unwrap();
    let params = hair(150, windy());
    let mut sim = SimulateStrands::groom(
        &gpu,
        &groom,
        &mesh,
        &buffers,
        &params,
        &DynamicsParams::default(),
    )
    .unwrap();
    let rest = grow_on_gpu(&gpu, &mut sim, 0.0);
    let stateless = pelage_strands::GroomStrands::new(&gpu, &groom, &params).unwrap();
    let points: Vec<Vec4> = stateless
        .rest_points()
        .iter()
        .map(|p| p.extend(0.0))
        .collect();
    let worst = max_diff(&rest, &points);
    println!("groom at rest: max |GPU - file| = {worst:.2e}");
    assert!(worst <= 1e-5 * 4.0, "{worst}");
    for root in sim.roots() {
        assert!(
            root.bary.x >= 0.0 && root.bary.y >= 0.0 && root.bary.x + root.bary.y <= 1.0 + 1e-6
        );
    }
    // A turned head carries the groom along: the first frame after a turn of the mesh
    // by 90 degrees puts every root on the turned surface.
    let turn = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    buffers
        .update(&gpu.queue, &posed(&mesh, turn, Vec3::ZERO))
        .unwrap();
    sim.reset();
    let turned = grow_on_gpu(&gpu, &mut sim, 0.1);
    let expected: Vec<Vec4> = points
        .iter()
        .map(|p| (turn * p.truncate()).extend(0.0))
        .collect();
    let worst = max_diff(&turned, &expected);
    assert!(worst <= 1e-5 * 4.0, "{worst}");
    assert!(
        SimulateStrands::groom(
            &gpu,
            &groom,
            &mesh,
            &buffers,
            &params,
            &DynamicsParams {
                damping: -1.0,
                ..DynamicsParams::default()
            }
        )
        .is_err_and(|e| e.to_string().contains("dynamics.damping"))
    );
}

/// With no gravity, no wind and a still head, strands stay at rest: nothing in the scheme
/// may feed energy into them. (Before the shape pulls kept the strands' speed unchanged
/// they became velocity, and the free ends of grown strands drifted into kinks of 20° and
/// more within a second, from rounding alone.)
#[test]
fn strands_with_no_force_stay_at_rest() {
    let gpu = gpu();
    let mesh = head();
    let buffers = MeshBuffers::upload(&gpu, &mesh).unwrap();
    let still = DynamicsParams {
        gravity: Vec3::ZERO,
        ..DynamicsParams::default()
    };
    let mut sim = SimulateStrands::grown(
        &gpu,
        &mesh,
        &buffers,
        &hair(300, WindParams::calm()),
        &still,
    )
    .unwrap();
    sim.set_colliders(&[body()]).unwrap();
    let rest = grow_on_gpu(&gpu, &mut sim, 0.0);
    let mut last = rest.clone();
    for frame in 1..=300 {
        last = grow_on_gpu(&gpu, &mut sim, frame as f32 / 60.0);
    }
    let drift = max_diff(&last, &rest);
    eprintln!("largest drift from rest after 5 s at 60 fps: {drift:.3e} (strands 1.5 long)");
    assert!(
        drift < 1e-4,
        "strands drifted {drift} from rest with no force"
    );
}

/// The shape stiffnesses pull as far per second whatever the substep: the head turns
/// for half a second and holds still for a quarter, under no gravity or wind, simulated
/// with substeps of 1/120 s and of 1/480 s; the strands' mean distance from their rest
/// pose stays within a fifth between the two. (Applied once per substep, as TressFX
/// does, the shorter substeps pulled four times as often and the strands lagged and
/// swung about half as far.)
#[test]
fn the_shape_pull_per_second_does_not_depend_on_the_substep() {
    let gpu = gpu();
    let rest_mesh = head();
    let buffers = MeshBuffers::upload(&gpu, &rest_mesh).unwrap();
    let params = hair(300, WindParams::calm());
    let run = |max_substep: f32| -> Vec<f32> {
        let dynamics = DynamicsParams {
            gravity: Vec3::ZERO,
            max_substep,
            ..DynamicsParams::default()
        };
        buffers.update(&gpu.queue, &rest_mesh).unwrap();
        let mut sim =
            SimulateStrands::grown(&gpu, &rest_mesh, &buffers, &params, &dynamics).unwrap();
        let mut out = Vec::new();
        for frame in 0..=45 {
            let t = frame as f32 / 60.0;
            let pose = head_pose(t.min(0.5));
            let mesh = posed(&rest_mesh, pose, Vec3::ZERO);
            buffers.update(&gpu.queue, &mesh).unwrap();
            let v = grow_on_gpu(&gpu, &mut sim, t);
            if frame % 15 == 0 && frame > 0 {
                // The rest pose here: a fresh simulation's first frame.
                let mut rest =
                    SimulateStrands::grown(&gpu, &rest_mesh, &buffers, &params, &dynamics).unwrap();
                let r = grow_on_gpu(&gpu, &mut rest, t);
                let mean = v
                    .iter()
                    .zip(&r)
                    .map(|(a, b)| (*a - *b).truncate().length())
                    .sum::<f32>()
                    / v.len() as f32;
                out.push(mean);
            }
        }
        out
    };
    let coarse = run(1.0 / 120.0);
    let fine = run(1.0 / 480.0);
    println!(
        "mean distance from rest at 0.25, 0.5 and 0.75 s: substeps of 1/120 s {coarse:.4?}, of 1/480 s {fine:.4?}"
    );
    for (c, f) in coarse.iter().zip(&fine) {
        assert!(*c > 1e-3, "the turn moved nothing: {coarse:?}");
        assert!(
            (c - f).abs() <= 0.2 * c,
            "1/120 s: {coarse:?}, 1/480 s: {fine:?}"
        );
    }
}

/// `max_substep` at the floor the simulation derives from its size and gravity
/// (`DynamicsParams::min_substep`) still lets gravity move the strands as far as the
/// default substep does; below the floor (1e-4 s, where the strands froze in their rest
/// pose: gravity's `a·h²` rounded away against 32-bit positions) it is refused, naming
/// the key.
#[test]
fn a_substep_at_its_floor_moves_the_strands_and_one_below_it_is_refused() {
    let gpu = gpu();
    let mesh = head();
    let buffers = MeshBuffers::upload(&gpu, &mesh).unwrap();
    let params = hair(200, WindParams::calm());
    let with = |max_substep: f32| DynamicsParams {
        max_substep,
        ..DynamicsParams::default()
    };
    let floor = SimulateStrands::grown(&gpu, &mesh, &buffers, &params, &with(1.0 / 120.0))
        .unwrap()
        .min_substep();
    let moved = |max_substep: f32| -> f32 {
        let mut sim =
            SimulateStrands::grown(&gpu, &mesh, &buffers, &params, &with(max_substep)).unwrap();
        let rest = grow_on_gpu(&gpu, &mut sim, 0.0);
        let mut last = rest.clone();
        for frame in 1..=12 {
            last = grow_on_gpu(&gpu, &mut sim, frame as f32 / 60.0);
        }
        last.iter()
            .zip(&rest)
            .map(|(a, b)| (*a - *b).truncate().length())
            .sum::<f32>()
            / last.len() as f32
    };
    let default = moved(1.0 / 120.0);
    let at_floor = moved(floor);
    println!(
        "floor {floor:.3e} s; mean distance from rest after 0.2 s: substeps of 1/120 s \
         {default:.4}, at the floor {at_floor:.4}"
    );
    assert!(default > 1e-2, "gravity moved nothing: {default}");
    assert!(
        (at_floor - default).abs() <= 0.2 * default,
        "at the floor {at_floor}, at 1/120 s {default}"
    );
    for below in [1e-4, floor * 0.9] {
        let e = SimulateStrands::grown(&gpu, &mesh, &buffers, &params, &with(below)).unwrap_err();
        assert!(
            e.to_string().contains("dynamics.max_substep"),
            "{below}: {e}"
        );
    }
}
