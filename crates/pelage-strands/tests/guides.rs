//! Guide strands on a real adapter: the interpolated strands equal the CPU mirror
//! (`pelage_reference::guides`) for every k with and without noise and clumping, one
//! guide gives copies of itself, full clumping brings
//! the tips onto the nearest guide, a build is deterministic, bad input is a typed error,
//! a device with WebGPU's default limits runs it, the memory against storing every
//! strand, and simulated guides drive the render strands (`pelage_reference::simulate`
//! then `pelage_reference::guides`).

use glam::{Quat, Vec3, Vec4};
use pelage_gpu::{Gpu, read_buffer, wgpu};
use pelage_reference::guides::{Choice, choose_guides, guide_count, interpolate};
use pelage_reference::simulate::{Step, simulate_frame};
use pelage_reference::strands::{Level, deform_groom, drawn_width};
use pelage_scene::{
    DynamicsParams, Groom, GuideParams, HairParams, Mesh, ParamError, Resampled, Transition,
    WindParams,
};
use pelage_strands::{
    GroomStrands, GuideMemory, GuideStrands, LodLevel, MeshBuffers, StrandRoot, StrandStage,
    StrandsError,
};

mod common;
use common::{gpu, grow_on_gpu, mirror_roots, read_vertices};

/// The head every test grows on: a sphere of radius 0.5 at the origin.
fn head(subdivisions: u32) -> Mesh {
    Mesh::icosphere(0.5, subdivisions).unwrap()
}

/// `count` guides rooted on the upper half of the head (a golden-angle spiral), each
/// leaving the head outward, hanging and waving with a phase of its own.
fn guides(count: usize) -> Groom {
    let strands: Vec<Vec<Vec3>> = (0..count)
        .map(|i| {
            let a = i as f32 * 2.399_963;
            let y = 1.0 - (i as f32 + 0.5) / count as f32;
            let r = (1.0 - y * y).sqrt();
            let n = Vec3::new(r * a.cos(), y, r * a.sin());
            let out = Vec3::new(n.x, 0.0, n.z).normalize_or(Vec3::X);
            let side = out.cross(Vec3::Y);
            (0..24)
                .map(|k| {
                    let s = k as f32 / 23.0;
                    let wave = (s * 9.0 + i as f32).sin() * 0.04 * s;
                    n * 0.5 + n * (0.15 * s) + out * (0.25 * s) - Vec3::Y * (0.7 * s * s)
                        + side * wave
                })
                .collect()
        })
        .collect();
    Groom::from_strands(&strands).unwrap()
}

fn windy() -> HairParams {
    HairParams {
        wind: WindParams {
            strength: 1.5,
            turbulence: 1.0,
            ..WindParams::default()
        },
        ..HairParams::default()
    }
}

fn calm() -> HairParams {
    HairParams {
        wind: WindParams {
            strength: 0.0,
            gust_strength: 0.0,
            turbulence: 0.0,
            ..WindParams::default()
        },
        ..HairParams::default()
    }
}

fn size(guides: &Resampled) -> f32 {
    let (lo, hi) = guides.bounds();
    (hi - lo).length()
}

/// The largest component difference between two vertex lists of the same length.
fn worst(a: &[Vec4], b: &[Vec4]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).abs().max_element())
        .fold(0.0f32, f32::max)
}

/// The guides' root points, in buffer order (the first rest point of each).
fn guide_roots(guides: &GroomStrands) -> Vec<Vec3> {
    let per_guide = guides.params().growth.segments as usize + 1;
    guides
        .rest_points()
        .iter()
        .step_by(per_guide)
        .copied()
        .collect()
}

/// Each render strand's guides and weights as the mirror chooses them on the rest `mesh`
/// (the one the strands were built on) for `params`.
fn choices(
    strands: &GuideStrands,
    guides: &GroomStrands,
    mesh: &Mesh,
    params: &GuideParams,
) -> Vec<Choice> {
    let guide_roots = guide_roots(guides);
    let k = guide_count(params, guide_roots.len());
    choose_guides(mesh, &mirror_roots(strands.roots()), &guide_roots, k)
}

/// The CPU mirror of a frame at `t` and `level` of render strands built on `mesh` with
/// `params`: the guides bent by `deform_groom`, then interpolated from the guides the
/// mirror chooses.
fn mirror_at(
    strands: &GuideStrands,
    mesh: &Mesh,
    params: &GuideParams,
    t: f32,
    level: Level,
) -> Vec<Vec4> {
    let g = strands.guides().expect("the guides are bent");
    let guide_params = g.params();
    let bent = deform_groom(
        g.rest_points(),
        &mirror_roots(g.roots()),
        guide_params,
        t,
        Level::full(guide_params),
    );
    interpolate(
        mesh,
        &mirror_roots(strands.roots()),
        &choices(strands, g, mesh, params),
        &bent,
        strands.params(),
        params,
        level,
    )
}

/// [`mirror_at`] every strand and segment.
fn mirror(strands: &GuideStrands, mesh: &Mesh, params: &GuideParams, t: f32) -> Vec<Vec4> {
    mirror_at(strands, mesh, params, t, Level::full(strands.params()))
}

struct Built {
    mesh: Mesh,
    buffers: MeshBuffers,
    guides: Resampled,
}

fn build(gpu: &Gpu, count: usize, segments: u32) -> Built {
    let mesh = head(2);
    let buffers = MeshBuffers::upload(gpu, &mesh).unwrap();
    let guides = guides(count).resample(segments).unwrap();
    Built {
        mesh,
        buffers,
        guides,
    }
}

impl Built {
    fn strands(&self, gpu: &Gpu, hair: &HairParams, params: &GuideParams) -> GuideStrands {
        GuideStrands::new(gpu, &self.mesh, &self.buffers, &self.guides, hair, params).unwrap()
    }
}

#[test]
fn interpolated_strands_equal_the_cpu_mirror_in_wind_and_at_a_lower_level_of_detail() {
    let gpu = gpu();
    let built = build(&gpu, 80, 16);
    let params = GuideParams {
        strands: 1500,
        clump: 0.4,
        noise: 0.2,
        ..GuideParams::default()
    };
    let mut hair = windy();
    hair.roots.seed = 3;
    let mut strands = built.strands(&gpu, &hair, &params);
    let tolerance = 1e-5 * size(&built.guides);
    let reach = strands.buffers().reach;
    let mut frames = Vec::new();
    for t in [0.0, 0.37, 5.0, 1234.5] {
        let out = grow_on_gpu(&gpu, &mut strands, t);
        let cpu = mirror(&strands, &built.mesh, &params, t);
        let err = worst(&out, &cpu);
        println!("guides t={t}: max |GPU - CPU| = {err:.2e} (tolerance {tolerance:.1e})");
        assert!(err <= tolerance, "t={t}: {err} > {tolerance}");
        for v in &out {
            let p = v.truncate();
            assert!(
                p.cmpge(reach.0).all() && p.cmple(reach.1).all(),
                "{p} leaves the reach {reach:?}"
            );
        }
        frames.push(out);
    }
    let moved = worst(&frames[0], &frames[2]);
    println!("largest change between t=0 and t=5: {moved:.3}");
    assert!(moved > 0.05, "the wind does not move the strands ({moved})");
    // Every root is on its triangle, and the strand parameter runs from 0 to 1.
    for (strand, root) in frames[0].chunks(17).zip(strands.roots()).step_by(41) {
        let corner = |k: usize| {
            built.mesh.positions[built.mesh.indices[root.triangle as usize * 3 + k] as usize]
        };
        let b = root.bary;
        let on = corner(0) * b.x + corner(1) * b.y + corner(2) * (1.0 - b.x - b.y);
        assert!(strand[0].truncate().distance(on) < 1e-6);
        assert_eq!((strand[0].w, strand[16].w), (0.0, 1.0));
    }

    // A prefix of the strands at 4 of 16 segments, widened by the level of detail.
    let p = strands.params().clone();
    let zone = Transition::new(0.3, p.lod.transition);
    let level = LodLevel {
        pixels: 0.0,
        extent_pixels: 0.0,
        zone,
        strands: zone.drawn(p.roots.count),
        segments: 4,
        segment_error_pixels: 0.0,
    };
    strands.set_lod(level).unwrap();
    let out = grow_on_gpu(&gpu, &mut strands, 0.8);
    let mirror_level = Level {
        strands: level.strands,
        segments: 4,
    };
    let cpu = mirror_at(&strands, &built.mesh, &params, 0.8, mirror_level);
    assert_eq!(cpu.len() as u64, strands.frame().unwrap().layout.vertices());
    let err = worst(&out[..cpu.len()], &cpu);
    println!(
        "{} strands x 4 segments: max |GPU - CPU| = {err:.2e}",
        level.strands
    );
    assert!(err <= tolerance, "{err}");
    let bytes = read_buffer(&gpu, &strands.buffers().roots).unwrap();
    let drawn: Vec<StrandRoot> = encase::StorageBuffer::new(&bytes[..])
        .create()
        .expect("roots decode");
    let roots = mirror_roots(strands.roots());
    for (i, (root, gpu_root)) in roots.iter().zip(drawn).enumerate() {
        if i as u32 >= level.strands {
            break;
        }
        let want = drawn_width(root, i as u32, p.roots.count, &zone);
        assert!((gpu_root.width - want).abs() <= 1e-6 * want.max(1.0));
    }
}

/// `guides.wgsl` is built per `k`, noise and clumping, with the terms that add exactly 0
/// left out: every combination equals the mirror, which evaluates the whole formula.
#[test]
fn every_k_with_and_without_noise_and_clumping_equals_the_cpu_mirror() {
    let gpu = gpu();
    let built = build(&gpu, 40, 8);
    let tolerance = 1e-5 * size(&built.guides);
    let mut hair = windy();
    hair.roots.seed = 11;
    for k in 1..=4 {
        let mut outputs = Vec::new();
        for (clump, noise) in [(0.0, 0.0), (0.4, 0.0), (0.0, 0.2), (0.4, 0.2)] {
            let params = GuideParams {
                strands: 300,
                k,
                clump,
                noise,
                ..GuideParams::default()
            };
            let mut strands = built.strands(&gpu, &hair, &params);
            let out = grow_on_gpu(&gpu, &mut strands, 0.7);
            let cpu = mirror(&strands, &built.mesh, &params, 0.7);
            let err = worst(&out, &cpu);
            println!("k={k} clump={clump} noise={noise}: max |GPU - CPU| = {err:.2e}");
            assert!(
                err <= tolerance,
                "k={k} clump={clump} noise={noise}: {err} > {tolerance}"
            );
            outputs.push(out);
        }
        // Each of clumping and noise changes the strands (the shader does not leave it out).
        for other in &outputs[1..] {
            assert!(worst(&outputs[0], other) > 1e-3, "k={k}");
        }
    }
}

#[test]
fn one_guide_without_clump_or_noise_is_copied_to_every_root() {
    let gpu = gpu();
    let built = build(&gpu, 1, 12);
    let params = GuideParams {
        strands: 400,
        ..GuideParams::default()
    };
    let mut strands = built.strands(&gpu, &calm(), &params);
    let out = grow_on_gpu(&gpu, &mut strands, 2.0);
    let guide = &built.guides.points;
    let mut err = 0.0f32;
    for strand in out.chunks(13) {
        let root = strand[0].truncate();
        for (v, g) in strand.iter().zip(guide) {
            err = err.max(
                (v.truncate() - (root + (*g - guide[0])))
                    .abs()
                    .max_element(),
            );
        }
    }
    println!("one guide: max |strand - translated guide| = {err:.2e}");
    assert!(err <= 1e-5 * size(&built.guides), "{err}");
}

#[test]
fn with_full_clumping_the_tips_meet_the_nearest_guide() {
    let gpu = gpu();
    let built = build(&gpu, 40, 8);
    let params = GuideParams {
        strands: 600,
        clump: 1.0,
        noise: 0.3,
        ..GuideParams::default()
    };
    let mut strands = built.strands(&gpu, &windy(), &params);
    let out = grow_on_gpu(&gpu, &mut strands, 1.3);
    let bent = read_vertices(&gpu, &strands.guides().unwrap().buffers().vertices);
    // Each strand's nearest guide, as the mirror chooses it (the GPU's records are
    // checked against that choice in pelage-strands' unit tests).
    let choices = choices(&strands, strands.guides().unwrap(), &built.mesh, &params);
    let mut err = 0.0f32;
    let mut spread = 0.0f32;
    for (strand, choice) in out.chunks(9).zip(&choices) {
        let guide = &bent[choice.guides[0] as usize * 9..][..9];
        err = err.max((strand[8] - guide[8]).abs().max_element());
        // Halfway, the strand is only halfway there.
        spread = spread.max(strand[4].truncate().distance(guide[4].truncate()));
    }
    println!("clump 1: max |tip - guide tip| = {err:.2e}; halfway up to {spread:.3} apart");
    assert!(err <= 1e-5 * size(&built.guides), "{err}");
    assert!(
        spread > 1e-3,
        "the strands collapse before the tip ({spread})"
    );
}

#[test]
fn the_same_inputs_give_the_same_strands() {
    let gpu = gpu();
    let built = build(&gpu, 30, 8);
    let params = GuideParams {
        strands: 500,
        clump: 0.3,
        noise: 0.1,
        ..GuideParams::default()
    };
    let mut a = built.strands(&gpu, &windy(), &params);
    let mut b = built.strands(&gpu, &windy(), &params);
    assert_eq!(a.roots(), b.roots());
    let first = grow_on_gpu(&gpu, &mut a, 0.9);
    let _ = grow_on_gpu(&gpu, &mut a, 4.0);
    let again = grow_on_gpu(&gpu, &mut a, 0.9);
    let other = grow_on_gpu(&gpu, &mut b, 0.9);
    let bits = |v: &[Vec4]| -> Vec<u32> {
        v.iter()
            .flat_map(|x| x.to_array())
            .map(f32::to_bits)
            .collect()
    };
    assert_eq!(
        bits(&first),
        bits(&again),
        "a frame depends on its time alone"
    );
    assert_eq!(bits(&first), bits(&other), "two builds differ");
    // Another seed places other roots.
    let mut hair = windy();
    hair.roots.seed = 99;
    let c = built.strands(&gpu, &hair, &params);
    assert_ne!(a.roots(), c.roots());
}

#[test]
fn bad_input_is_a_typed_error_naming_it() {
    let gpu = gpu();
    let built = build(&gpu, 20, 8);
    let hair = windy();
    let new = |guides: &Resampled, params: &GuideParams| {
        GuideStrands::new(&gpu, &built.mesh, &built.buffers, guides, &hair, params).unwrap_err()
    };
    let name = |e: StrandsError| match e {
        StrandsError::Param(ParamError { name, .. }) => name,
        other => panic!("not a parameter error: {other}"),
    };
    let with = |clump: f32, k: u32| GuideParams {
        strands: 100,
        clump,
        k,
        ..GuideParams::default()
    };
    assert_eq!(name(new(&built.guides, &with(f32::NAN, 4))), "guides.clump");
    assert_eq!(name(new(&built.guides, &with(0.5, 0))), "guides.k");
    let none = Resampled {
        points: Vec::new(),
        widths: None,
        segments: 8,
        strands: 0,
        skipped: 0,
        source_strands: Vec::new(),
        colors: None,
    };
    assert_eq!(name(new(&none, &with(0.5, 4))), "groom.strands");

    // Guide 7 moved 0.4 away from the head: the error names it and its distance.
    let mut far = built.guides.clone();
    let guide = 7 * 9;
    for p in &mut far.points[guide..guide + 9] {
        *p += Vec3::new(0.0, 0.4, 0.0);
    }
    match new(&far, &with(0.5, 4)) {
        StrandsError::GuideOffMesh {
            guide,
            distance,
            limit,
        } => {
            println!("far guide: {guide} at {distance:.3} (limit {limit:.3})");
            assert_eq!(guide, 7);
            assert!(distance > 0.3 && distance > limit, "{distance}");
        }
        other => panic!("{other}"),
    }
    // Allowing that far accepts it.
    let loose = GuideParams {
        max_root_distance: 0.5,
        ..with(0.5, 4)
    };
    GuideStrands::new(&gpu, &built.mesh, &built.buffers, &far, &hair, &loose).unwrap();
    // Mesh buffers of another mesh.
    let other = MeshBuffers::upload(&gpu, &head(1)).unwrap();
    let e = GuideStrands::new(
        &gpu,
        &built.mesh,
        &other,
        &built.guides,
        &hair,
        &with(0.5, 4),
    );
    assert!(matches!(
        e,
        Err(StrandsError::Contract(
            pelage_strands::ContractError::MeshMismatch { .. }
        ))
    ));
}

/// A device with WebGPU's default limits (8 storage buffers per shader stage).
fn default_limits_gpu() -> Gpu {
    pollster::block_on(async {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let mut adapter = None;
        for force_fallback_adapter in [false, true] {
            let options = wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter,
                compatible_surface: None,
                apply_limit_buckets: false,
            };
            if let Ok(found) = instance.request_adapter(&options).await {
                adapter = Some(found);
                break;
            }
        }
        let adapter = adapter.unwrap_or_else(|| panic!("this test needs a GPU adapter"));
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("pelage default limits"),
                required_limits: wgpu::Limits::default(),
                ..Default::default()
            })
            .await
            .unwrap_or_else(|e| panic!("a device with the default limits: {e}"));
        Gpu::from_device(device, queue, Some(adapter.get_info()))
    })
}

#[test]
fn a_device_with_default_limits_runs_both_passes() {
    let gpu = default_limits_gpu();
    assert_eq!(gpu.limits().max_storage_buffers_per_shader_stage, 8);
    let built = build(&gpu, 25, 8);
    let params = GuideParams {
        strands: 300,
        clump: 0.2,
        noise: 0.1,
        ..GuideParams::default()
    };
    let mut strands = built.strands(&gpu, &windy(), &params);
    let out = grow_on_gpu(&gpu, &mut strands, 0.5);
    let err = worst(&out, &mirror(&strands, &built.mesh, &params, 0.5));
    assert!(err <= 1e-5 * size(&built.guides), "{err}");
    gpu.check().unwrap();
}

#[test]
fn memory_of_1000_guides_for_50000_strands_against_storing_every_strand() {
    let gpu = gpu();
    let mesh = head(3);
    let buffers = MeshBuffers::upload(&gpu, &mesh).unwrap();
    let guides = guides(1000).resample(16).unwrap();
    let params = GuideParams {
        strands: 50_000,
        ..GuideParams::default()
    };
    let strands = GuideStrands::new(&gpu, &mesh, &buffers, &guides, &windy(), &params).unwrap();
    let memory = strands.memory();
    let groom = GuideMemory::groom_rest_bytes(50_000, 16);
    let ratio = memory.total() as f64 / groom as f64;
    println!(
        "1000 guides -> 50000 strands x 16 segments: guide rest {} + bent guides {} + guide roots {} + records {} = {} bytes; \
         GroomStrands' rest points for 50000 strands {} bytes: {ratio:.3}x",
        memory.guide_rest,
        memory.guide_vertices,
        memory.guide_roots,
        memory.records,
        memory.total(),
        groom
    );
    assert_eq!(memory.records, 50_000 * 12);
    assert!(ratio <= 0.1, "{ratio}");

    // Simulated guides keep the simulation's state (root pose, rest shape, positions,
    // previous positions) instead of the rest points, and no bend pass.
    let simulated = GuideStrands::simulated(
        &gpu,
        &mesh,
        &buffers,
        &guides,
        &windy(),
        &params,
        &DynamicsParams::default(),
    )
    .unwrap();
    let sim = simulated.memory();
    println!(
        "simulated: guide state {} + simulated guides {} + guide roots {} + records {} = {} bytes: {:.3}x",
        sim.guide_state,
        sim.guide_vertices,
        sim.guide_roots,
        sim.records,
        sim.total(),
        sim.total() as f64 / groom as f64
    );
    assert_eq!(sim.guide_rest, 0);
    assert_eq!(sim.records, memory.records);
    assert_eq!(sim.guide_vertices, memory.guide_vertices);
}

/// `mesh` turned by `rotation` about the origin.
fn turned(mesh: &Mesh, rotation: Quat) -> Mesh {
    Mesh {
        positions: mesh.positions.iter().map(|&p| rotation * p).collect(),
        normals: mesh.normals.iter().map(|&n| rotation * n).collect(),
        uvs: mesh.uvs.clone(),
        indices: mesh.indices.clone(),
    }
}

#[test]
fn simulated_guides_drive_the_render_strands_as_the_two_mirrors_composed() {
    let gpu = gpu();
    let built = build(&gpu, 60, 8);
    let params = GuideParams {
        strands: 800,
        clump: 0.4,
        noise: 0.2,
        ..GuideParams::default()
    };
    let dynamics = DynamicsParams::default();
    let mut strands = GuideStrands::simulated(
        &gpu,
        &built.mesh,
        &built.buffers,
        &built.guides,
        &windy(),
        &params,
        &dynamics,
    )
    .unwrap();
    let tolerance = 1e-5 * size(&built.guides);
    // The simulation holds the guides in the order the records index.
    let sim = strands.simulation().unwrap();
    let seeds = |roots: &[StrandRoot]| roots.iter().map(|r| r.seed).collect::<Vec<_>>();
    let bend_order = GroomStrands::new(&gpu, &built.guides, &windy()).unwrap();
    assert_eq!(seeds(sim.roots()), seeds(bend_order.roots()));
    assert_eq!(seeds(strands.guide_roots()), seeds(bend_order.roots()));
    let labels: Vec<String> = strands.passes().into_iter().map(|p| p.label).collect();
    assert_eq!(labels, ["strands: simulate", "strands: guides"]);
    // No bend pass is built: the rest shape is counted once, in the simulation's state.
    assert!(strands.guides().is_none());
    let memory = strands.memory();
    assert_eq!(memory.guide_rest, 0);
    assert_eq!(memory.guide_state, sim.state().size());
    assert_eq!(memory.guide_vertices, sim.buffers().vertices.size());

    // Frame 0 puts the guides at rest; frame 1 is one substep of a turning head: the GPU
    // against the simulation's mirror followed by the interpolation's.
    let rest = grow_on_gpu(&gpu, &mut strands, 0.0);
    let read_state =
        |strands: &GuideStrands| read_vertices(&gpu, strands.simulation().unwrap().state());
    let mut state = read_state(&strands);
    let h = dynamics.max_substep;
    let mut mesh = turned(&built.mesh, Quat::from_rotation_y(0.02));
    built.buffers.update(&gpu.queue, &mesh).unwrap();
    let out = grow_on_gpu(&gpu, &mut strands, h);
    let sim = strands.simulation().unwrap();
    // The guides' parameters (those the groom amounts to), simulated one step of h from
    // frame 0 at t = 0 with the dynamics' colliders (none).
    let guide_params = sim.params();
    let (bent, held) = simulate_frame(
        &mesh,
        &mirror_roots(sim.roots()),
        &mut state,
        &Step {
            hair: guide_params,
            dynamics: &dynamics,
            colliders: &dynamics.colliders,
            time: h,
            dt: Some(h),
            level: Level::full(guide_params),
        },
    );
    assert_eq!(held, 0);
    // The guides chosen on the rest head, whose rest roots the bend pass holds in the
    // simulation's order.
    let chosen = choices(&strands, &bend_order, &built.mesh, &params);
    let render_roots = mirror_roots(strands.roots());
    let full = Level::full(strands.params());
    let cpu = interpolate(
        &mesh,
        &render_roots,
        &chosen,
        &bent,
        strands.params(),
        &params,
        full,
    );
    let err = worst(&out, &cpu);
    println!(
        "simulated guides, 1 substep: max |GPU - CPU| = {err:.2e} (tolerance {tolerance:.1e})"
    );
    assert!(err <= tolerance, "{err} > {tolerance}");

    // 40 frames of 1/60 s with the head turning 0.8 rad: each frame the render strands
    // are the mirror's interpolation of the GPU's simulated guides, their roots on the
    // turned head, and they have left the turned rest pose (inertia and gravity: a
    // rigid turn would carry every vertex).
    let mut t = h;
    let mut err = 0.0f32;
    let mut out = rest.clone();
    for frame in 1..=40 {
        t += 1.0 / 60.0;
        let rotation = Quat::from_rotation_y(0.02 * frame as f32);
        mesh = turned(&built.mesh, rotation);
        built.buffers.update(&gpu.queue, &mesh).unwrap();
        out = grow_on_gpu(&gpu, &mut strands, t);
        let guides = read_vertices(&gpu, &strands.simulation().unwrap().buffers().vertices);
        let cpu = interpolate(
            &mesh,
            &render_roots,
            &chosen,
            &guides,
            strands.params(),
            &params,
            full,
        );
        err = err.max(worst(&out, &cpu));
    }
    println!("40 frames: max |GPU - mirror of the GPU's guides| = {err:.2e}");
    assert!(err <= tolerance, "{err} > {tolerance}");
    let rotation = Quat::from_rotation_y(0.8);
    let reach = strands.buffers().reach;
    let (mut root_off, mut lag) = (0.0f32, 0.0f32);
    for (now, then) in out.chunks(9).zip(rest.chunks(9)) {
        root_off = root_off.max(now[0].truncate().distance(rotation * then[0].truncate()));
        lag = lag.max(now[8].truncate().distance(rotation * then[8].truncate()));
        for v in now {
            let p = v.truncate();
            assert!(
                p.cmpge(reach.0).all() && p.cmple(reach.1).all(),
                "{p} leaves the reach"
            );
        }
    }
    println!(
        "after the turn: roots {root_off:.1e} from the turned rest roots, tips up to {lag:.3} from the turned rest tips"
    );
    assert!(root_off < 1e-5, "{root_off}");
    assert!(lag > 0.05, "the render strands do not move ({lag})");
}

#[test]
fn render_strands_take_the_weighted_blend_of_their_guides_colours() {
    let gpu = gpu();
    let mut built = build(&gpu, 40, 8);
    let count = built.guides.strands;
    built.guides.colors = Some(
        (0..count)
            .map(|i| Vec3::new(i as f32 / count as f32, 1.0 - i as f32 / count as f32, 0.25))
            .collect(),
    );
    let mut hair = calm();
    hair.growth.color_jitter = 0.0;
    let params = GuideParams {
        strands: 500,
        ..GuideParams::default()
    };
    let mut strands = built.strands(&gpu, &hair, &params);
    let guide_colors = strands.guides().unwrap().file_colors().unwrap().to_vec();
    let k = guide_count(&params, count as usize);
    let choices = choices(&strands, strands.guides().unwrap(), &built.mesh, &params);
    // The blend of each render strand's guides' colours with its record's weights, and
    // the colour the GPU's drawn roots hold, per strand.
    let colours = |strands: &mut GuideStrands| {
        grow_on_gpu(&gpu, strands, 0.0);
        let bytes = read_buffer(&gpu, &strands.buffers().roots).unwrap();
        let drawn: Vec<StrandRoot> = encase::StorageBuffer::new(&bytes[..])
            .create()
            .expect("roots decode");
        (choices.iter().zip(drawn))
            .map(|(choice, gpu_root)| {
                let blend: Vec3 = (0..k as usize)
                    .map(|n| guide_colors[choice.guides[n] as usize] * choice.weights[n])
                    .sum();
                (blend, gpu_root.color)
            })
            .collect::<Vec<_>>()
    };
    let mut worst = 0.0f32;
    let mut spread = (Vec3::MAX, Vec3::MIN);
    for (blend, colour) in colours(&mut strands) {
        worst = worst.max((blend - colour).abs().max_element());
        spread = (spread.0.min(colour), spread.1.max(colour));
    }
    println!(
        "guide colours: max |colour - weighted blend| = {worst:.1e}, red from {:.2} to {:.2}",
        spread.0.x, spread.1.x
    );
    assert!(worst <= 1e-6, "{worst}");
    assert!(spread.1.x - spread.0.x > 0.5, "{spread:?}");

    // A new jitter keeps the blended colours, each strand scaled by its brightness.
    strands.set_color(&gpu.queue, Vec3::ONE, 0.3).unwrap();
    for (blend, colour) in colours(&mut strands) {
        let b = colour.z / blend.z;
        assert!((0.7..=1.3).contains(&b), "{b}");
        assert!(
            (colour - blend * b).abs().max_element() <= 1e-6,
            "{colour} {blend}"
        );
    }

    // Guides without colours: the render strands take growth.color.
    built.guides.colors = None;
    let plain = built.strands(&gpu, &hair, &params);
    assert!(plain.roots().iter().all(|r| r.color == hair.growth.color));
}
