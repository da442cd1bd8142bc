//! The dynamics lab: the same long hair simulated and under the stateless wind, while the
//! head turns and nods, and the same for fur on a running creature. Issue 20 asks that fur
//! keep the stateless wind unless a scene needs more; this lab says how much more the
//! simulation shows, and what it costs.
//!
//! ```text
//! pelage lab dynamics [--quick] [--out DIR] [--scene FILE]
//! ```
//!
//! The scene is [`SCENE`]: `scenes/head_turn.toml`'s head, motion, wind, dynamics, light
//! and camera, with the hair grown on the head (the lab needs no file beside the
//! binary). Three renderers draw every frame (30 per second, 4 s; `--quick`: 1 s,
//! smaller and fewer strands), from the same roots:
//!
//! - **stateless**: `GrowStrands`, each frame grown for its time alone (the hair turns
//!   rigidly with the head, bent by the wind);
//! - **simulated**: `SimulateStrands` with the scene's `[dynamics]` (the hair lags,
//!   swings and settles, and rests on the head's collider);
//! - **floor**: the stateless hair grown from other random roots, whose difference from
//!   the stateless image is what any change of strands shows (the same hair, other
//!   strands): a simulated frame that differs from the stateless one by no more than
//!   this looks no different. (`--scene` with a groom: none, a groom's strands are the
//!   file's.)
//!
//! A second comparison, `fur`, does the same for [`FUR_SCENE`]: the creature of
//! `scenes/creature_skinned.toml` (its body bent and twisted by a two-joint rig, skinned
//! on the GPU every frame; 20 000 strands, `--quick` 2 000) with a `[dynamics]` table
//! whose shape stiffnesses hold the fur's groom (0.9 over the whole strand) against the
//! same fur stateless.
//!
//! Two more rows collide with the body's own shape (its signed distance field,
//! `dynamics.sdf_resolution` = [`LAB_SDF_RESOLUTION`]): `hair_sdf`, the head with the
//! field instead of the sphere inside it (built once, moved with the head), and
//! `fur_sdf`, the creature's fur at the default dynamics (which without a collider fall
//! into the body) on the field built once in the bind pose and read through the skin (the
//! default `dynamics.sdf_skinned`). Every row reports
//! how deep the simulated strands are inside the body (exact distances to the posed mesh
//! on the CPU, every k-th strand up to [`DEPTH_STRANDS`], in strand widths; strands
//! rooted inside another part of the mesh left out).
//!
//! `--scene FILE` takes a scene file with a `[dynamics]` table (`scenes/head_turn.toml`)
//! instead, compared with the same scene without the table.
//!
//! Per frame: mean LDR-FLIP of the simulated image against the stateless one and of the
//! floor against the stateless one (over the image and over the head and hair: pixels
//! where either image is not the background); the distance between each strand's
//! simulated and stateless tip as a fraction of its length (mean and largest, read back
//! from the strand buffers); how kinked the strands are (each strand's largest turn
//! between consecutive segments, in degrees, averaged over the strands); each renderer's
//! frame wall clock (render and wait). At the
//! end, each renderer's strand stage submitted alone (median of the repeats), one frame
//! step past the last.
//!
//! Writes `DIR/dynamics.csv` (a row per frame and comparison), `DIR/dynamics_summary.csv`
//! (means over the frames after the first second, when the body has moved, and the cost
//! ratios; a column per comparison), `DIR/dynamics_sheet.png` and, for the fur,
//! `DIR/dynamics_sheet_fur.png` (stateless over simulated at six times).

use std::path::Path;
use std::time::Instant;

use pelage::gpu::{Gpu, read_buffer};
use pelage::scene::SceneFile;
use pelage::{Renderer, scene::Scene};
use pelage_lab::{Table, contact_sheet};

use super::{LabOpts, background, flip_scores};
use crate::progress;
use crate::report::DroppedWork;

type LabResult<T> = Result<T, Box<dyn std::error::Error>>;

/// `scenes/head_turn.toml` with the hair grown on the head instead of read from
/// `long_hair.hair` (same head, motion, wind, dynamics, shading, camera and light). A copy,
/// since a packaged crate cannot read the repository's `scenes/`; the test
/// `the_built_in_scene_is_head_turn_with_grown_hair` keeps the two the same.
pub const SCENE: &str = r#"
[mesh]
kind = "icosphere"
radius = 0.5
subdivisions = 3

[dynamics]
gravity = [0.0, -9.8, 0.0]
wind_response = 2.0
damping = 3.0
local_stiffness = 0.3
global_stiffness = 0.25
global_range = 0.4
friction = 0.3
colliders = [{ center = [0.0, 0.0, 0.0], radius = 0.48 }]

[motion]
pivot = [0.0, -0.3, 0.0]
turn = 0.9
turn_frequency = 0.4
nod = 0.3
nod_frequency = 0.7

[hair.roots]
count = 3000
seed = 7

[hair.growth]
segments = 16
length = 0.9
direction_jitter = 0.15
width = 0.003
tip_width = 0.4
color = [0.52, 0.36, 0.2]
color_jitter = 0.2
opacity = 0.55

[hair.wind]
direction = [1.0, 0.0, 0.4]
strength = 0.8
gust_strength = 0.6
gust_frequency = 0.5
turbulence = 0.4
turbulence_scale = 2.0
turbulence_speed = 1.0
phase_spread = 0.4

[shadow]
method = "voxel"
resolution = [96, 96, 96]

[shade]
mesh_color = [0.55, 0.4, 0.33]

[shade.transparency]
method = "k_buffer"
k = 8

[camera]
eye = [1.6, 0.2, 3.0]
target = [0.0, -0.35, 0.0]
fov_y = 0.75
near = 0.05
far = 20.0

[[lights]]
kind = "directional"
direction = [-0.6, -0.5, -0.6]
color = [1.0, 1.0, 1.0]
intensity = 1.8
"#;

/// The wind force weight of the built-in scene's stateless hair (see [`scenes`]).
const STATELESS_FORCE_WEIGHT: f32 = 0.12;

/// Frames per second of the lab's animation.
const FPS: f32 = 30.0;

/// `scenes/creature_skinned.toml` (the creature's fur on its skinned, bending body) with
/// a `[dynamics]` table that holds the fur's shape: the lab's fur row. A copy, as [`SCENE`]; the test
/// `the_built_in_fur_is_the_skinned_creature_simulated` keeps the two the same.
pub const FUR_SCENE: &str = r#"
[skin]
origin = [0.0, 0.1, 0.2]
axis = [0.0, 0.0, 1.0]
bend_axis = [0.0, 1.0, 0.0]
blend = 0.25
bend = 0.6
bend_frequency = 0.5
twist = 0.3
twist_frequency = 0.7

[hair.roots]
count = 20000

[hair.wind]
strength = 0.3

# Fur holds its groomed shape: the shape stiffnesses high over the whole strand (the
# defaults are long hair's; with them, and no collider, the fur falls into the body).
[dynamics]
local_stiffness = 0.9
global_stiffness = 0.9
global_range = 1.0
"#;

/// The resolution of the body's distance field in the lab's `hair_sdf` and `fur_sdf`
/// rows (nodes along the longest axis of the box the body moves in).
pub const LAB_SDF_RESOLUTION: u32 = 64;

/// Strands whose depth inside the body is measured each frame (every k-th strand up to
/// this many: exact distances on the CPU cost `O(vertices · triangles)`).
const DEPTH_STRANDS: usize = 400;

/// One comparison of the lab: the same hair stateless and simulated, and (grown hair
/// only) the stateless hair from other roots.
struct Scenario {
    /// Its name in the tables (`hair`, `hair_sdf`, `fur` or `fur_sdf`, or `scene` for
    /// `--scene`).
    name: &'static str,
    stateless: Scene,
    simulated: Scene,
    floor: Option<Scene>,
}

/// The comparisons the lab runs: with `path` (a scene file with a `[dynamics]` table,
/// its strand count kept) that scene alone; otherwise [`SCENE`]'s long hair on the
/// turning head with `strands` strands and [`FUR_SCENE`]'s fur on the running creature
/// with `fur_strands`.
fn scenarios(path: Option<&Path>, strands: u32, fur_strands: u32) -> LabResult<Vec<Scenario>> {
    if let Some(path) = path {
        let scene = Scene::from_file(path)?;
        if scene.dynamics.is_none() {
            return Err(format!(
                "{}: the scene has no [dynamics] table, so there is no simulation to \
                 compare with its stateless wind; add one (see the book's Dynamics page, docs/src/dynamics.md)",
                path.display()
            )
            .into());
        }
        return Ok(vec![compared("scene", scene)]);
    }
    let file = SceneFile::parse(SCENE)?;
    let mut hair = Scene::from_scene_file(&file, Path::new("lab dynamics"))?;
    hair.hair.roots.count = strands;
    // The stateless hair's wind force weight. A scene file with [dynamics] may not set it
    // (the simulation's rest shape is grown without gravity or wind, so there it has no
    // effect), but the stateless comparison uses it.
    hair.hair.growth.force_weight = STATELESS_FORCE_WEIGHT;
    let file = SceneFile::parse(FUR_SCENE)?;
    let mut fur = Scene::from_scene_file(&file, Path::new("lab dynamics fur"))?;
    fur.hair.roots.count = fur_strands;
    // The same head with the body's distance field instead of the sphere inside it, and
    // the fur at the default dynamics (the shape stiffnesses of long hair, which let it
    // fall into the body without a collider) on the creature's field rebuilt every frame.
    let mut hair_sdf = hair.clone();
    if let Some(d) = hair_sdf.dynamics.as_mut() {
        d.colliders.clear();
        d.sdf_resolution = LAB_SDF_RESOLUTION;
    }
    let mut fur_sdf = fur.clone();
    fur_sdf.dynamics = Some(pelage::scene::DynamicsParams {
        sdf_resolution: LAB_SDF_RESOLUTION,
        ..Default::default()
    });
    Ok(vec![
        compared("hair", hair),
        compared("hair_sdf", hair_sdf),
        compared("fur", fur),
        compared("fur_sdf", fur_sdf),
    ])
}

/// The scene's mesh in its pose at time `t` (its motion or its rig), on the CPU.
fn posed_mesh(scene: &Scene, t: f32) -> pelage::scene::Mesh {
    if let Some(motion) = &scene.motion {
        motion.apply(&scene.mesh, t)
    } else if let Some(rig) = &scene.skin {
        let skin = rig.skin(&scene.mesh);
        pelage_reference::skin::skin_mesh(&scene.mesh, &skin, &rig.joint_matrices(t))
    } else {
        scene.mesh.clone()
    }
}

/// How deep the vertices of every `every`-th strand (its root left out) are inside
/// `mesh`, in strand widths (the least over the mesh's parts of the exact signed
/// distance, `pelage_reference::sdf::depths`): the largest and the mean, depths outside
/// counting 0. Strands rooted inside another part of the mesh (a root on one part's
/// surface that the pose has inside another, by more than a hundredth of a width: float
/// rounding) are left out: they are inside whatever collisions do.
fn depth_in_widths(
    mesh: &pelage::scene::Mesh,
    vertices: &[[f32; 3]],
    per_strand: usize,
    every: usize,
    width: f32,
) -> (f64, f64) {
    let strands: Vec<&[[f32; 3]]> = vertices
        .chunks_exact(per_strand)
        .step_by(every.max(1))
        .collect();
    let roots: Vec<glam::Vec3> = strands.iter().map(|s| glam::Vec3::from(s[0])).collect();
    let root_depths = pelage_reference::sdf::depths(mesh, &roots);
    let points: Vec<glam::Vec3> = strands
        .iter()
        .zip(&root_depths)
        .filter(|&(_, &d)| d <= 0.01 * width)
        .flat_map(|(s, _)| s[1..].iter().map(|&v| glam::Vec3::from(v)))
        .collect();
    let depths = pelage_reference::sdf::depths(mesh, &points);
    let widths = depths.iter().map(|&d| f64::from(d.max(0.0) / width));
    (widths.clone().fold(0.0, f64::max), mean(widths))
}

/// The scenes one comparison draws: `simulated`, the same without its `[dynamics]`, and
/// (grown hair only: a groom's strands are the file's) the stateless hair from other
/// roots.
fn compared(name: &'static str, simulated: Scene) -> Scenario {
    let stateless = Scene {
        dynamics: None,
        ..simulated.clone()
    };
    let floor = simulated.groom.is_none().then(|| {
        let mut floor = stateless.clone();
        floor.hair.roots.seed = floor.hair.roots.seed.wrapping_add(1000);
        floor
    });
    Scenario {
        name,
        stateless,
        simulated,
        floor,
    }
}

/// Every strand's vertices (xyz) from the renderer's strand buffers, strand after strand.
fn read_strands(gpu: &Gpu, renderer: &Renderer) -> LabResult<(Vec<[f32; 3]>, usize)> {
    let buffers = renderer.frame().strands().buffers();
    let bytes = read_buffer(gpu, &buffers.vertices)?;
    let per_strand = buffers.vertices_per_strand() as usize;
    let vertices = bytes
        .chunks_exact(16)
        .take(buffers.strand_count as usize * per_strand)
        .map(|v| {
            let f = |i: usize| f32::from_le_bytes([v[i], v[i + 1], v[i + 2], v[i + 3]]);
            [f(0), f(4), f(8)]
        })
        .collect();
    Ok((vertices, per_strand))
}

/// The largest turn between consecutive segments of each strand, degrees: how kinked
/// the strands are (grown hair turns a few degrees a segment).
fn largest_turns(vertices: &[[f32; 3]], per_strand: usize) -> Vec<f64> {
    let sub = |a: [f32; 3], b: [f32; 3]| glam::Vec3::from(a) - glam::Vec3::from(b);
    vertices
        .chunks_exact(per_strand)
        .map(|strand| {
            strand
                .windows(3)
                .map(|w| {
                    let (a, b) = (sub(w[1], w[0]), sub(w[2], w[1]));
                    f64::from(a.angle_between(b).to_degrees())
                })
                .filter(|d| d.is_finite())
                .fold(0.0, f64::max)
        })
        .collect()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    if n == 0 { f64::NAN } else { sum / n as f64 }
}

/// One frame's measures.
struct Row {
    t: f32,
    flip_sim: (f64, f64),
    /// NaN for a groom (no other roots).
    flip_floor: (f64, f64),
    tip_mean: f64,
    tip_max: f64,
    /// Mean over strands of each strand's largest turn, stateless and simulated.
    turn: [f64; 2],
    wall_ms: [f64; 2],
    /// How deep the simulated strands are inside the body (strand widths): largest, mean.
    depth: (f64, f64),
}

/// What one comparison measured.
struct Outcome {
    rows: Vec<Row>,
    /// Each renderer's strand stage alone (ms): stateless, simulated.
    strand_ms: [f64; 2],
    /// The contact sheet's cells (stateless over simulated at six times).
    cells: Vec<(String, image::RgbaImage)>,
}

/// Draws `scenario`'s renderers `frames` frames at [`FPS`] at `size`, measuring every
/// frame, then each strand stage alone (`repeats`).
fn measure(
    gpu: &Gpu,
    scenario: &Scenario,
    size: (u32, u32),
    frames: usize,
    repeats: usize,
) -> LabResult<Outcome> {
    let Scenario {
        name,
        stateless,
        simulated,
        floor,
    } = scenario;
    let camera = stateless.camera.clone();
    let bg = background(stateless);
    let mut renderers = [stateless, simulated]
        .into_iter()
        .chain(floor)
        .map(|scene| Renderer::new(gpu, scene, size.0, size.1))
        .collect::<Result<Vec<_>, _>>()?;
    // What each variant's frames drop (a pool of the scene's method too small).
    let mut dropped = renderers
        .iter()
        .map(|r| DroppedWork::start(r, gpu))
        .collect::<Result<Vec<_>, _>>()?;
    let roots = renderers[0].frame().strands().roots();
    let lengths: Vec<f64> = roots.iter().map(|r| f64::from(r.length)).collect();
    println!(
        "{name}: {} strands x {} segments, {}x{}, {frames} frames at {FPS} fps{}",
        roots.len(),
        renderers[0].frame().strands().buffers().segments,
        size.0,
        size.1,
        if floor.is_none() {
            " (a groom: no floor of other roots)"
        } else {
            ""
        }
    );

    let bar = progress::bar(frames as u64, "frames")?;
    let mut rows = Vec::with_capacity(frames);
    let sheet_every = (frames / 6).max(1);
    let mut cells = Vec::new();
    for frame in 0..frames {
        let t = frame as f32 / FPS;
        let mut wall_ms = [0.0; 2];
        let mut images = Vec::with_capacity(3);
        for (i, (renderer, dropped)) in renderers.iter_mut().zip(&mut dropped).enumerate() {
            let began = Instant::now();
            renderer.render(gpu, t, &camera)?;
            renderer.finish(gpu)?;
            if let Some(ms) = wall_ms.get_mut(i) {
                *ms = began.elapsed().as_secs_f64() * 1e3;
            }
            dropped.after_frame(renderer, gpu, frame as u32)?;
            images.push(renderer.image(gpu)?);
        }
        let flip_sim = flip_scores(&images[0], &images[1], bg)?;
        let flip_floor = match images.get(2) {
            Some(other) => flip_scores(&images[0], other, bg)?,
            None => (f64::NAN, f64::NAN),
        };
        let (a, per_strand) = read_strands(gpu, &renderers[0])?;
        let (b, _) = read_strands(gpu, &renderers[1])?;
        let distances: Vec<f64> = (a.chunks_exact(per_strand).zip(b.chunks_exact(per_strand)))
            .zip(&lengths)
            .map(|((a, b), &length)| {
                let (a, b) = (a[per_strand - 1], b[per_strand - 1]);
                let d = glam::Vec3::from(a).distance(glam::Vec3::from(b));
                f64::from(d) / length.max(f64::MIN_POSITIVE)
            })
            .collect();
        let every = (b.len() / per_strand).div_ceil(DEPTH_STRANDS);
        let depth = depth_in_widths(
            &posed_mesh(simulated, t),
            &b,
            per_strand,
            every,
            simulated.hair.growth.width,
        );
        let row = Row {
            depth,
            t,
            flip_sim,
            flip_floor,
            tip_mean: mean(distances.iter().copied()),
            tip_max: distances.iter().copied().fold(0.0, f64::max),
            turn: [
                mean(largest_turns(&a, per_strand).into_iter()),
                mean(largest_turns(&b, per_strand).into_iter()),
            ],
            wall_ms,
        };
        if frame % sheet_every == sheet_every - 1 && cells.len() < 12 {
            cells.push((format!("stateless t = {t:.2} s"), images[0].clone()));
            cells.push((format!("simulated t = {t:.2} s"), images[1].clone()));
        }
        bar.set_message(format!(
            "{name}: t = {t:.2} s  FLIP {:.3} (floor {:.3}), largest turn {:.0} / {:.0} deg",
            row.flip_sim.1, row.flip_floor.1, row.turn[0], row.turn[1]
        ));
        rows.push(row);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let variants = [stateless, simulated].into_iter().chain(floor);
    for ((dropped, variant), scene) in dropped
        .iter()
        .zip(["stateless", "simulated", "other roots"])
        .zip(variants)
    {
        if let Some(line) = dropped.report(&scene.shade.transparency) {
            eprintln!("{name}, {variant}: {line}");
        }
    }
    // Each strand stage alone, one frame step past the last (the simulation steps 1/FPS
    // each repeat; the stateless growth does the same work at any time).
    let t_next = frames as f32 / FPS;
    let mut strand_ms = [0.0; 2];
    for (renderer, ms) in renderers.iter_mut().zip(&mut strand_ms) {
        let stages = renderer.stage_wall_times(gpu, t_next, &camera, repeats)?;
        *ms = stages
            .iter()
            .find(|(stage, _)| stage == "strands")
            .map_or(f64::NAN, |(_, ms)| *ms);
    }
    Ok(Outcome {
        rows,
        strand_ms,
        cells,
    })
}

/// The summary of one comparison: each measure over the frames after the first second
/// (the body has moved; before it the simulation starts from rest and the two differ
/// only by the wind's treatment), in the order of [`SUMMARY`].
fn summarise(outcome: &Outcome) -> Vec<f64> {
    let rows = &outcome.rows;
    let moving: Vec<&Row> = rows.iter().filter(|r| r.t >= 1.0).collect();
    let moving = if moving.is_empty() {
        rows.iter().collect()
    } else {
        moving
    };
    let frame_ratio = median(moving.iter().map(|r| r.wall_ms[1]).collect())
        / median(moving.iter().map(|r| r.wall_ms[0]).collect());
    let strand_ms = outcome.strand_ms;
    vec![
        mean(moving.iter().map(|r| r.flip_sim.0)),
        mean(moving.iter().map(|r| r.flip_sim.1)),
        mean(moving.iter().map(|r| r.flip_floor.0)),
        mean(moving.iter().map(|r| r.flip_floor.1)),
        mean(moving.iter().map(|r| r.tip_mean)),
        moving.iter().map(|r| r.tip_max).fold(0.0, f64::max),
        mean(moving.iter().map(|r| r.turn[0])),
        mean(moving.iter().map(|r| r.turn[1])),
        frame_ratio,
        strand_ms[1] / strand_ms[0],
        strand_ms[0],
        strand_ms[1],
        // Every frame: the body moves from the first.
        rows.iter().map(|r| r.depth.0).fold(0.0, f64::max),
        mean(rows.iter().map(|r| r.depth.1)),
    ]
}

/// The measures of the summary, in [`summarise`]'s order.
const SUMMARY: [&str; 14] = [
    "mean FLIP, simulated vs stateless (image)",
    "mean FLIP, simulated vs stateless (body and hair)",
    "mean FLIP, other roots vs stateless (image): the floor",
    "mean FLIP, other roots vs stateless (body and hair): the floor",
    "tip distance, mean over strands and frames (strand lengths)",
    "tip distance, largest (strand lengths)",
    "largest turn between segments, stateless (degrees, mean over strands)",
    "largest turn between segments, simulated (degrees, mean over strands)",
    "frame wall clock, simulated over stateless (median)",
    "strand stage alone, simulated over stateless (median)",
    "strand stage alone, stateless (ms)",
    "strand stage alone, simulated (ms)",
    "penetration depth into the body, largest (strand widths, every frame)",
    "penetration depth into the body, mean (strand widths, every frame)",
];

/// Runs the lab: writes `dynamics.csv`, `dynamics_summary.csv`, `dynamics_sheet.png`
/// and (built-in scenes) `dynamics_sheet_fur.png` under `opts.out`.
pub fn run(opts: &LabOpts, scene: Option<&Path>) -> LabResult<()> {
    let started = Instant::now();
    let (size, strands, fur_strands, seconds, repeats) = if opts.quick {
        ((160, 120), 600, 2_000, 1.0, 3)
    } else {
        ((320, 240), 3000, 20_000, 4.0, 9)
    };
    let frames = (seconds * FPS).round() as usize;
    let scenarios = scenarios(scene, strands, fur_strands)?;
    let gpu = Gpu::headless()?;
    println!("adapter: {}", gpu.describe());
    crate::report::notice_gl_compile(&gpu);
    let mut outcomes = Vec::new();
    for scenario in &scenarios {
        outcomes.push(measure(&gpu, scenario, size, frames, repeats)?);
    }

    let mut table = Table::new(&[
        "scenario",
        "t_s",
        "flip_simulated",
        "flip_simulated_subject",
        "flip_floor",
        "flip_floor_subject",
        "tip_distance_mean",
        "tip_distance_max",
        "largest_turn_deg_stateless",
        "largest_turn_deg_simulated",
        "frame_ms_stateless",
        "frame_ms_simulated",
        "depth_max_widths",
        "depth_mean_widths",
    ]);
    for (scenario, outcome) in scenarios.iter().zip(&outcomes) {
        for r in &outcome.rows {
            table.push(vec![
                scenario.name.to_string(),
                format!("{:.4}", r.t),
                format!("{:.4}", r.flip_sim.0),
                format!("{:.4}", r.flip_sim.1),
                format!("{:.4}", r.flip_floor.0),
                format!("{:.4}", r.flip_floor.1),
                format!("{:.4}", r.tip_mean),
                format!("{:.4}", r.tip_max),
                format!("{:.2}", r.turn[0]),
                format!("{:.2}", r.turn[1]),
                format!("{:.2}", r.wall_ms[0]),
                format!("{:.2}", r.wall_ms[1]),
                format!("{:.3}", r.depth.0),
                format!("{:.4}", r.depth.1),
            ])?;
        }
    }
    table.write_csv(&opts.out.join("dynamics.csv"))?;

    let mut header = vec!["measure"];
    header.extend(scenarios.iter().map(|s| s.name));
    let mut summary = Table::new(&header);
    let values: Vec<Vec<f64>> = outcomes.iter().map(summarise).collect();
    for (m, name) in SUMMARY.iter().enumerate() {
        let mut row = vec![name.to_string()];
        row.extend(values.iter().map(|v| format!("{:.4}", v[m])));
        summary.push(row)?;
    }
    summary.write_csv(&opts.out.join("dynamics_summary.csv"))?;
    for (scenario, outcome) in scenarios.iter().zip(&outcomes) {
        let file = match scenario.name {
            "hair" | "scene" => "dynamics_sheet.png".to_string(),
            other => format!("dynamics_sheet_{other}.png"),
        };
        crate::output::save_png(&contact_sheet(&outcome.cells, 2)?, &opts.out.join(file))?;
    }
    println!("frames from t = 1.0 s on (all frames if the run is shorter), {frames} frames:");
    println!("{}", summary.to_text());
    println!(
        "wrote {}/dynamics.csv, dynamics_summary.csv and the sheets in {:.0} s",
        opts.out.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`FUR_SCENE`] is `scenes/creature_skinned.toml` with a `[dynamics]` table.
    #[test]
    fn the_built_in_fur_is_the_skinned_creature_simulated() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/creature_skinned.toml");
        let mut creature = SceneFile::load(&path).unwrap();
        let lab = SceneFile::parse(FUR_SCENE).unwrap();
        assert!(lab.dynamics.is_some());
        creature.dynamics = lab.dynamics.clone();
        assert_eq!(lab, creature);
    }

    /// [`SCENE`] is `scenes/head_turn.toml` but for the hair grown instead of the groom.
    #[test]
    fn the_built_in_scene_is_head_turn_with_grown_hair() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/head_turn.toml");
        let mut head_turn = SceneFile::load(&path).unwrap();
        let lab = SceneFile::parse(SCENE).unwrap();
        head_turn.groom = None;
        let (roots, growth) = (&lab.hair.roots, &lab.hair.growth);
        head_turn.hair.roots.count = roots.count;
        let ours = &mut head_turn.hair.growth;
        ours.segments = growth.segments;
        ours.length = growth.length;
        ours.direction_jitter = growth.direction_jitter;
        assert_eq!(lab, head_turn);
    }
}
