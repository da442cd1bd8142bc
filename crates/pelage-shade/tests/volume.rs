//! The volume method's grid (`wgsl/shade/volume.wgsl`) against its CPU mirror
//! `pelage_reference::volume`, its energy bookkeeping, and degenerate hair.

mod support;

use glam::{DVec4, Vec2, Vec3, Vec4};
use pelage_gpu::{Gpu, read_buffer, storage_buffer, wgpu};
use pelage_reference::volume::{VolumeGridCpu, VolumeInput, VolumeMesh, volume_grid};
use pelage_scene::{
    Camera, ChiangParams, DirectionalLight, Light, Mesh, MultipleScattering, PointLight,
    ShadeParams, ShadingModel,
};
use pelage_shade::{FrameUniforms, HairModel, VolumeField, VolumeGrid};
use pelage_strands::{MeshBuffers, StrandBuffers, StrandLayout, StrandRoot, StrandStyle};
use support::gpu;

/// Strands, as the GPU and the mirror both read them.
struct Hair {
    vertices: Vec<Vec4>,
    widths: Vec<f32>,
    colors: Vec<Vec3>,
    segments: u32,
}

impl Hair {
    fn strands(&self) -> u32 {
        self.widths.len() as u32
    }
}

/// `count` wavy strands of `segments` segments hanging in a box of side `size` (a
/// deterministic hash places them).
fn wavy(count: u32, segments: u32, size: f32, width: f32) -> Hair {
    let hash = |i: u32, k: u32| {
        let mut h = i.wrapping_mul(0x9e37_79b9) ^ k.wrapping_mul(0x85eb_ca6b);
        h ^= h >> 15;
        h = h.wrapping_mul(0x2c1b_3c6d);
        h ^= h >> 12;
        (h >> 8) as f32 / 16_777_216.0
    };
    let mut vertices = Vec::new();
    for i in 0..count {
        let root = Vec3::new(hash(i, 1) - 0.5, 0.5, hash(i, 2) - 0.5) * size;
        let phase = hash(i, 3) * std::f32::consts::TAU;
        for k in 0..=segments {
            let f = k as f32 / segments as f32;
            let wave = Vec3::new((phase + 9.0 * f).sin(), 0.0, (phase + 7.0 * f).cos()) * 0.12;
            vertices.push((root + Vec3::new(0.0, -f * size, 0.0) + wave * size).extend(f));
        }
    }
    Hair {
        vertices,
        widths: vec![width; count as usize],
        colors: vec![Vec3::new(0.8, 0.6, 0.4); count as usize],
        segments,
    }
}

fn lights() -> Vec<Light> {
    vec![
        Light::Directional(DirectionalLight {
            direction: Vec3::new(-0.6, -0.7, 0.4),
            color: Vec3::new(1.0, 0.95, 0.9),
            intensity: 2.0,
        }),
        Light::Point(PointLight {
            position: Vec3::new(0.9, 0.3, -1.2),
            color: Vec3::ONE,
            intensity: 3.0,
        }),
    ]
}

/// `shade.ambient` of the tests that light the hair by the sky too (the default's).
const AMBIENT: f32 = 0.18;

/// One light of no intensity (a frame needs a light): the sky alone.
fn dark() -> Vec<Light> {
    vec![Light::Directional(DirectionalLight {
        direction: -Vec3::Y,
        color: Vec3::ONE,
        intensity: 0.0,
    })]
}

fn volume_params(grid: u32, iterations: u32, sigma_a: Vec3) -> ChiangParams {
    ChiangParams {
        sigma_a: Some(sigma_a),
        multiple_scattering: MultipleScattering::Volume,
        volume_grid: grid,
        volume_iterations: iterations,
        ..Default::default()
    }
}

/// Runs the grid passes on the GPU for `hair`, grown in a frame of `layout_strands`
/// strands, and reads back the fluence and the medium.
fn run_gpu(
    gpu: &Gpu,
    hair: &Hair,
    layout_strands: u32,
    params: &ChiangParams,
    lights: &[Light],
    ambient: f32,
    mesh: Option<&Body>,
) -> (Vec<f32>, Vec<f32>) {
    let model = HairModel::new(gpu, &ShadingModel::Chiang(params.clone())).unwrap();
    let field: &VolumeField = model.volume().expect("a volume field");
    let strands = hair.strands().max(1);
    let mut vertices = hair.vertices.clone();
    vertices.resize((strands * (hair.segments + 1)) as usize, Vec4::ZERO);
    let roots: Vec<StrandRoot> = (0..strands as usize)
        .map(|i| StrandRoot {
            triangle: 0,
            seed: i as u32,
            bary: Vec2::ZERO,
            length: 1.0,
            width: hair.widths.get(i).copied().unwrap_or(0.0),
            phase: 0.0,
            tilt: 0.0,
            azimuth: 0.0,
            color: hair.colors.get(i).copied().unwrap_or(Vec3::ONE),
            region: 0,
        })
        .collect();
    let usage = wgpu::BufferUsages::STORAGE;
    let vb = storage_buffer(gpu, "test vertices", &vertices, usage).unwrap();
    let rb = storage_buffer(gpu, "test roots", &roots, usage).unwrap();
    let style = StrandStyle {
        width: 0.01,
        max_width: 0.01,
        tip_width: 0.5,
        opacity: 1.0,
    };
    let buffers = StrandBuffers::new(
        vb,
        rb,
        strands,
        hair.segments,
        style,
        (Vec3::splat(-10.0), Vec3::splat(10.0)),
    )
    .unwrap();
    let camera = Camera::default().matrices(64, 64);
    let shade = ShadeParams {
        ambient,
        ..Default::default()
    };
    let frame = FrameUniforms::new(&camera, lights, &shade, 64, 0).unwrap();
    let frame_buffer = pelage_gpu::UniformBuffer::new(gpu, "test frame", &frame).unwrap();
    let tables = model.chiang().expect("tables");
    let mesh_buffers = mesh.map(|m| MeshBuffers::upload(gpu, &m.mesh).unwrap());
    let grid = VolumeGrid::new(
        gpu,
        field,
        tables,
        &frame_buffer.buffer,
        &buffers,
        mesh_buffers.as_ref(),
        mesh.map_or(Vec3::ZERO, |m| m.color),
    )
    .unwrap();
    grid.prepare(
        &gpu.queue,
        StrandLayout {
            strands: layout_strands,
            segments: hair.segments,
        },
        style.tip_width,
    )
    .unwrap();
    assert_eq!(
        grid.memory_bytes(),
        VolumeGrid::bytes_for(params.volume_grid),
        "memory"
    );
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    grid.encode(&mut encoder, None);
    gpu.submit_and_wait([encoder.finish()]).unwrap();
    let floats = |b: &wgpu::Buffer| -> Vec<f32> {
        read_buffer(gpu, b)
            .unwrap()
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    };
    let fluence = floats(field.fluence_buffer());
    let medium = floats(grid.scratch_buffers().1);
    (fluence, medium)
}

/// The GPU's fluence and the mirror's grid of `hair` around `body` under the sky alone
/// ([`AMBIENT`], one light of no intensity).
fn sky_alone(
    gpu: &Gpu,
    hair: &Hair,
    params: &ChiangParams,
    body: &Body,
) -> (Vec<f32>, VolumeGridCpu) {
    let (fluence, _) = run_gpu(
        gpu,
        hair,
        hair.strands(),
        params,
        &dark(),
        AMBIENT,
        Some(body),
    );
    let cpu = mirror(hair, params, &dark(), AMBIENT, 0.5, Some(body));
    (fluence, cpu)
}

/// A body under the hair: its mesh and `shade.mesh_color`.
struct Body {
    mesh: Mesh,
    color: Vec3,
}

fn mirror(
    hair: &Hair,
    params: &ChiangParams,
    lights: &[Light],
    ambient: f32,
    tip_width: f32,
    body: Option<&Body>,
) -> VolumeGridCpu {
    volume_grid(&VolumeInput {
        mesh: body.map(|b| VolumeMesh {
            positions: &b.mesh.positions,
            normals: &b.mesh.normals,
            indices: &b.mesh.indices,
            color: b.color,
        }),
        vertices: &hair.vertices,
        segments: hair.segments,
        widths: &hair.widths,
        colors: &hair.colors,
        tip_width,
        lights,
        ambient,
        params,
    })
}

/// The GPU's fluence cell by cell against the mirror's, relative to the largest fluence of
/// the grid: (median, p99, max) over cells and channels of every coefficient.
fn compare(gpu_fluence: &[f32], cpu: &VolumeGridCpu) -> (f64, f64, f64) {
    let header = &gpu_fluence[..4];
    assert!(
        (f64::from(header[3]) - cpu.cell).abs() <= 1e-5 * cpu.cell,
        "cell {} vs {}",
        header[3],
        cpu.cell
    );
    let scale = cpu
        .fluence
        .iter()
        .flat_map(|c| c.iter().map(|v| v.x))
        .fold(0.0f64, f64::max);
    assert!(scale > 0.0, "the mirror's grid holds no light");
    let mut errors = Vec::new();
    for (i, cell) in cpu.fluence.iter().enumerate() {
        for (ch, want) in cell.iter().enumerate() {
            let at = 4 * (1 + 3 * i + ch);
            let got = DVec4::new(
                f64::from(gpu_fluence[at]),
                f64::from(gpu_fluence[at + 1]),
                f64::from(gpu_fluence[at + 2]),
                f64::from(gpu_fluence[at + 3]),
            );
            errors.push((got - *want).abs().max_element() / scale);
        }
    }
    errors.sort_by(f64::total_cmp);
    let q = |f: f64| errors[((errors.len() - 1) as f64 * f) as usize];
    (q(0.5), q(0.99), q(1.0))
}

/// The GPU's grid is the mirror's: fit, splat, injection from a directional and a point
/// light through the grid's own transmittance, and propagation with Chiang's energies.
#[test]
fn volume_grid_matches_cpu_mirror() {
    let gpu = gpu();
    let hair = wavy(300, 12, 1.0, 0.004);
    let lights = lights();
    for (sigma, iterations) in [
        (Vec3::new(0.12, 0.2, 0.4), 8),
        (Vec3::new(0.5, 0.9, 1.7), 3),
    ] {
        let params = volume_params(16, iterations, sigma);
        let (fluence, _) = run_gpu(&gpu, &hair, hair.strands(), &params, &lights, AMBIENT, None);
        let cpu = mirror(&hair, &params, &lights, AMBIENT, 0.5, None);
        let (median, p99, max) = compare(&fluence, &cpu);
        println!(
            "sigma_a {sigma}, {iterations} steps: GPU - mirror over the largest fluence: median {median:.2e}, p99 {p99:.2e}, max {max:.2e}"
        );
        // Measured 2.2e-4 and 5.6e-4 with the sky.
        assert!(max < 2e-3, "max {max}");
    }
}

/// White fibres (σ_a = 0) in a dense cube, lit from four sides: the fibres' energy
/// (a_f + a_b, from the GPU's tables) is 1 at every cell, no propagation step adds energy
/// (the mirror's total after each step never exceeds the one before), the transport
/// loses only what leaves the grid, and the scattering keeps exactly what arrives.
#[test]
fn volume_white_fibres_gain_no_energy() {
    let gpu = gpu();
    let hair = wavy(800, 16, 1.0, 0.01);
    let sky: Vec<Light> = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y]
        .into_iter()
        .map(|d| {
            Light::Directional(DirectionalLight {
                direction: d,
                color: Vec3::ONE,
                intensity: 1.0,
            })
        })
        .collect();
    let params = volume_params(12, 24, Vec3::ZERO);
    let (_, medium) = run_gpu(&gpu, &hair, hair.strands(), &params, &sky, 0.0, None);
    let mut worst: f32 = 0.0;
    let mut with_fibres = 0;
    // A cell without fibres has no phase function (`describe` leaves it 0).
    for cell in medium.chunks_exact(12).filter(|cell| cell[3] > 0.0) {
        with_fibres += 1;
        for ch in 0..3 {
            worst = worst.max((cell[4 + ch] - 1.0).abs());
        }
    }
    assert!(with_fibres > 0);
    println!("white fibres: largest |A_iso - 1| on the GPU {worst:.2e}");
    assert!(worst < 2e-3, "A_iso off 1 by {worst}");
    let cpu = mirror(&hair, &params, &sky, 0.0, 0.5, None);
    let e = &cpu.step_energy;
    println!(
        "white fibres: energy leaving the cells, injection then each step: {:?}",
        e.iter().map(|x| format!("{x:.4}")).collect::<Vec<_>>()
    );
    for w in e.windows(2) {
        assert!(w[1] <= w[0] * (1.0 + 1e-6), "a step gained energy: {w:?}");
    }
    // Step by step, closed as a furnace: the transport only loses what leaves the grid,
    // and white fibres neither gain nor lose (departures = arrivals within the CPU
    // energies' quadrature).
    let mut worst_scatter: f64 = 0.0;
    for (k, &arrived) in cpu.step_arrivals.iter().enumerate() {
        let (before, after) = (e[k], e[k + 1]);
        assert!(
            arrived <= before * (1.0 + 1e-12),
            "step {k}: transport gained energy"
        );
        worst_scatter = worst_scatter.max((after / arrived - 1.0).abs());
    }
    println!("white fibres: largest |departures / arrivals - 1| of a step {worst_scatter:.2e}");
    assert!(
        worst_scatter < 1e-5,
        "white fibres changed the energy by {worst_scatter}"
    );
    // And the grid holds light, the dense cube losing it only through its faces.
    assert!(e[0] > 0.0 && e[e.len() - 1] > 0.0);
}

/// No NaN or infinity, and no negative fluence, for hair that gives the grid nothing to
/// work with: no strands, one strand, and every strand in one cell (a zero-sized hair).
#[test]
fn volume_degenerate_hair_is_finite() {
    let gpu = gpu();
    let lights = lights();
    let params = volume_params(8, 6, Vec3::new(0.3, 0.5, 0.9));
    let one = wavy(1, 8, 1.0, 0.004);
    let mut point = wavy(50, 4, 1.0, 0.004);
    for v in &mut point.vertices {
        *v = Vec3::new(0.25, 0.25, 0.25).extend(v.w);
    }
    let mut near = wavy(50, 4, 1.0, 0.004);
    for v in &mut near.vertices {
        *v = (Vec3::new(0.25, 0.25, 0.25) + v.truncate() * 1e-4).extend(v.w);
    }
    for (name, hair, strands) in [
        ("no strands", &one, 0),
        ("one strand", &one, 1),
        ("one point", &point, 50),
        ("one cell", &near, 50),
    ] {
        let (fluence, medium) = run_gpu(&gpu, hair, strands, &params, &lights, AMBIENT, None);
        assert!(
            fluence.iter().chain(&medium).all(|x| x.is_finite()),
            "{name}: a non-finite value"
        );
        let negative = fluence[4..].chunks_exact(4).filter(|c| c[0] < 0.0).count();
        assert_eq!(negative, 0, "{name}: negative fluence");
        let total: f32 = fluence[4..].chunks_exact(4).map(|c| c[0]).sum();
        println!("{name}: cell {:.3e}, total fluence {total:.4e}", fluence[3]);
        if strands == 0 {
            // Nothing but the sky, unshadowed: 4 ambient in every cell.
            let worst = fluence[4..]
                .chunks_exact(4)
                .map(|c| (c[0] - 4.0 * AMBIENT).abs())
                .fold(0.0f32, f32::max);
            assert!(worst < 1e-5, "no strands, yet light in the grid: {worst}");
        }
    }
}

/// No cells or no steps are refused naming the key and the range, and the default grid
/// fits the device.
#[test]
fn volume_bad_sizes_are_refused() {
    let gpu = gpu();
    let max = VolumeField::max_resolution(&gpu);
    let default = pelage_scene::DEFAULT_VOLUME_GRID;
    println!(
        "largest volume_grid on this device: {max}; the default {default}³ grid holds {} \
         bytes, 32³ {}",
        VolumeGrid::bytes_for(default),
        VolumeGrid::bytes_for(32)
    );
    // The bound: at most 8 MB at the default size.
    assert!(VolumeGrid::bytes_for(default) <= 8_000_000);
    assert!(max >= 32, "a 32³ grid must fit: {max}");
    let params = volume_params(0, 4, Vec3::ONE);
    let e = HairModel::new(&gpu, &ShadingModel::Chiang(params)).unwrap_err();
    assert!(e.to_string().contains("shading.chiang.volume_grid"), "{e}");
    let params = volume_params(16, 0, Vec3::ONE);
    let e = HairModel::new(&gpu, &ShadingModel::Chiang(params)).unwrap_err();
    assert!(
        e.to_string().contains("shading.chiang.volume_iterations"),
        "{e}"
    );
}

/// A body under the hair: an icosphere of radius 0.3 inside the hanging strands, skin
/// coloured.
fn skin_body() -> Body {
    Body {
        mesh: Mesh::icosphere(0.3, 2).unwrap(),
        color: Vec3::new(0.25, 0.16, 0.11),
    }
}

/// The GPU's grid of `params` over `wavy(300, 12, 1.0, 0.004)` around `body`, lit by
/// [`lights`] and the sky, against the mirror's: prints the differences (labelled `what`)
/// over the largest fluence and returns the largest.
fn body_against_mirror(gpu: &Gpu, params: &ChiangParams, body: &Body, what: &str) -> f64 {
    let hair = wavy(300, 12, 1.0, 0.004);
    let lights = lights();
    let (fluence, _) = run_gpu(
        gpu,
        &hair,
        hair.strands(),
        params,
        &lights,
        AMBIENT,
        Some(body),
    );
    let cpu = mirror(&hair, params, &lights, AMBIENT, 0.5, Some(body));
    let (median, p99, max) = compare(&fluence, &cpu);
    println!(
        "{what}: GPU - mirror over the largest fluence: median {median:.2e}, p99 {p99:.2e}, max {max:.2e}"
    );
    max
}

/// A body under the hair (an icosphere of radius 0.3 inside the hanging strands): the
/// GPU's mesh splat, occupancy, shadowing and Lambertian bounce are the mirror's.
#[test]
fn volume_grid_with_mesh_matches_cpu_mirror() {
    let params = volume_params(16, 8, Vec3::new(0.12, 0.2, 0.4));
    let max = body_against_mirror(&gpu(), &params, &skin_body(), "with a body");
    assert!(max < 2e-3, "max {max}");
}

/// `dual_volume`: the grid without the fibres' scattering of the lights (dual scattering
/// carries it) matches the mirror, and lit by the lights alone over a black body it holds
/// no light at all, where `volume`'s grid does.
#[test]
fn dual_volume_grid_leaves_the_lights_to_dual_scattering() {
    let gpu = gpu();
    let params = ChiangParams {
        multiple_scattering: MultipleScattering::DualVolume,
        ..volume_params(16, 8, Vec3::new(0.12, 0.2, 0.4))
    };
    let max = body_against_mirror(&gpu, &params, &skin_body(), "dual_volume");
    assert!(max < 2e-3, "max {max}");
    let hair = wavy(300, 12, 1.0, 0.004);
    let lights = lights();
    // The lights alone over a black body: nothing for the grid with dual_volume.
    let black = Body {
        color: Vec3::ZERO,
        ..skin_body()
    };
    let total = |p: &ChiangParams| -> f64 {
        let (fluence, _) = run_gpu(&gpu, &hair, hair.strands(), p, &lights, 0.0, Some(&black));
        fluence[4..]
            .chunks_exact(4)
            .map(|c| f64::from(c[0].abs()))
            .sum()
    };
    let with_grid = total(&volume_params(16, 8, Vec3::new(0.12, 0.2, 0.4)));
    let without = total(&params);
    println!(
        "lights alone, black body: fluence summed {with_grid:.3e} (volume), {without:.3e} (dual_volume)"
    );
    assert!(
        with_grid > 0.0,
        "volume's grid holds the lights' scattering"
    );
    assert!(without <= 1e-6 * with_grid, "{without} vs {with_grid}");
}

/// The sky alone (no lights) over hair around a body: the GPU's injection of the sky
/// (its unscattered fluence through the grid's hair and body, and what the fibres and the
/// body scatter of it, propagated) is the mirror's.
#[test]
fn volume_sky_injection_matches_cpu_mirror() {
    let gpu = gpu();
    let hair = wavy(300, 12, 1.0, 0.004);
    let body = Body {
        mesh: Mesh::icosphere(0.3, 2).unwrap(),
        color: Vec3::new(0.25, 0.16, 0.11),
    };
    let params = volume_params(16, 8, Vec3::new(0.12, 0.2, 0.4));
    let (fluence, cpu) = sky_alone(&gpu, &hair, &params, &body);
    let (median, p99, max) = compare(&fluence, &cpu);
    println!(
        "sky alone, with a body: GPU - mirror over the largest fluence: median {median:.2e}, p99 {p99:.2e}, max {max:.2e}"
    );
    // Measured 1.1e-4.
    assert!(max < 2e-3, "max {max}");
}

/// White fibres (σ_a = 0) in a cube under the sky alone, a white furnace: in a medium
/// that absorbs nothing, under a uniform sky of radiance `ambient / π`, the light is the
/// sky's everywhere (fluence `4 ambient`). The GPU is the mirror's. The grid is brighter
/// than the sky: at an optical depth of 0.64 per cell 1.09x to 1.41x (mean 1.22x), at 3.8
/// per cell 1.11x to 1.27x (mean 1.17x). Before the injection took each cell's mean
/// transmittance over the cube's chords (`volume_cell_transmittance`) rather than along
/// its mean chord: 1.15x to 1.49x (mean 1.28x; with light held to the six axes, no spread
/// and a path of one cell edge per step: 0.97x to 1.38x, mean 1.15x) and 1.23x to 1.43x
/// (mean 1.31x; before the spread: 1.25x to 1.51x, mean 1.39x). A path of one cell edge per step with the spread measured 1.01x to
/// 1.26x and 1.19x to 1.33x, but the cone's path is the geometry's (and the lab's blond
/// hair and the Monte Carlo check of scripts/volume_transport.py prefer it). Light
/// scattered near a dense cell's lit face, treated as born evenly through the cell, was
/// measured as a cause: sending it back toward the light took the dense mean to 1.21x
/// and moved no lab row (not kept); the thin excess is not explained. The measured
/// values are held (a few percent of margin) so that the error cannot grow unnoticed, and
/// the lower bounds keep the sky in.
#[test]
fn volume_white_fibres_under_the_sky_are_the_sky() {
    let gpu = gpu();
    let sky = 4.0 * f64::from(AMBIENT);
    // (width, the brightest cell's bound, the least inner cell's bound), from the
    // measured values printed below with a margin of a few percent.
    for (width, brightest_bound, inside_bound) in [(0.01, 1.45, 1.05), (0.06, 1.31, 1.07)] {
        let hair = wavy(800, 16, 1.0, width);
        let params = volume_params(12, 64, Vec3::ZERO);
        let (fluence, _) = run_gpu(&gpu, &hair, hair.strands(), &params, &dark(), AMBIENT, None);
        let cpu = mirror(&hair, &params, &dark(), AMBIENT, 0.5, None);
        let (median, p99, max) = compare(&fluence, &cpu);
        let n = cpu.resolution as usize;
        let (mut brightest, mut inside_least, mut inside_sum, mut inside_count) =
            (0.0f64, f64::INFINITY, 0.0, 0);
        for (i, cell) in fluence[4..].chunks_exact(12).enumerate() {
            let c = [i % n, (i / n) % n, i / (n * n)];
            let inner = c.iter().all(|&k| (3..n - 3).contains(&k));
            for ch in 0..3 {
                let phi = f64::from(cell[4 * ch]) / sky;
                brightest = brightest.max(phi);
                if inner {
                    inside_least = inside_least.min(phi);
                    inside_sum += phi;
                    inside_count += 1;
                }
            }
        }
        let centre = (n / 2 * n + n / 2) * n + n / 2;
        println!(
            "white furnace, width {width} (optical depth {:.2} per cell): GPU - mirror over \
             the largest fluence: median {median:.2e}, p99 {p99:.2e}, max {max:.2e}; fluence \
             over the sky's: brightest cell {brightest:.4}, cells 3 or more from the border: \
             least {inside_least:.4}, mean {:.4}",
            cpu.depth[centre],
            inside_sum / f64::from(inside_count)
        );
        assert!(max < 2e-3, "max {max}");
        assert!(
            brightest <= brightest_bound,
            "brighter than measured: {brightest}"
        );
        assert!(
            inside_least >= inside_bound,
            "darker than measured: {inside_least}"
        );
    }
}

/// The mirror's share of each cell inside a sphere (from its normals alone): cells whose
/// centre lies a cell or more inside are (nearly) solid, a cell or more outside empty,
/// and the solid volume is the sphere's.
#[test]
fn volume_mesh_occupancy_is_the_sphere() {
    let hair = wavy(300, 12, 1.0, 0.004);
    let radius = 0.3;
    let body = Body {
        mesh: Mesh::icosphere(radius, 3).unwrap(),
        color: Vec3::ZERO,
    };
    let params = volume_params(16, 1, Vec3::ONE);
    let cpu = mirror(&hair, &params, &lights(), 0.0, 0.5, Some(&body));
    let n = cpu.resolution as usize;
    let (mut inside, mut outside, mut volume) = (1.0f64, 0.0f64, 0.0);
    for (i, &solid) in cpu.solid.iter().enumerate() {
        let c = glam::DVec3::new((i % n) as f64, ((i / n) % n) as f64, (i / (n * n)) as f64);
        let r = (cpu.origin + (c + 0.5) * cpu.cell).length();
        if r < f64::from(radius) - cpu.cell {
            inside = inside.min(solid);
        }
        if r > f64::from(radius) + cpu.cell {
            outside = outside.max(solid);
        }
        volume += solid * cpu.cell.powi(3);
    }
    let sphere = 4.0 / 3.0 * std::f64::consts::PI * f64::from(radius).powi(3);
    println!(
        "sphere in a 16³ grid: least solid share inside {inside:.3}, most outside {outside:.3}, solid volume {:.3} of the sphere's",
        volume / sphere
    );
    // Measured: 0.916 (the surface's samples in a column of cells sum to its projected
    // area only approximately), 0.000 and 0.976.
    assert!(inside > 0.85 && outside < 0.05, "{inside} {outside}");
    assert!((volume / sphere - 1.0).abs() < 0.05, "{}", volume / sphere);
}

/// The sky beside a black body: in a cell the body partly fills, the hair (all in the
/// cell's clear part) sees the sky the body leaves it. The GPU's fluence in cells at
/// most half solid against the sky a point at distance r from the centre of a sphere of
/// radius R sees, 1 - (1 - sqrt(1 - R²/r²)) / 2 of it, averaged over the cell's points
/// outside the sphere (a reference that knows the sphere, not the grid's cells), with
/// hair too thin to hide anything. (The sky's fluence was once not weighed by the clear
/// share before `settle` divided by it: such cells read up to twice the sky.)
#[test]
fn volume_sky_beside_a_body_is_what_the_body_leaves() {
    let gpu = gpu();
    let radius = 0.3f64;
    let body = Body {
        mesh: Mesh::icosphere(radius as f32, 3).unwrap(),
        color: Vec3::ZERO,
    };
    let hair = wavy(300, 12, 1.0, 1e-5);
    let params = volume_params(16, 12, Vec3::ONE);
    // The mirror's grid: the cells' solid shares and places (the GPU's, within 2e-3).
    let (fluence, cpu) = sky_alone(&gpu, &hair, &params, &body);
    let sky = 4.0 * f64::from(AMBIENT);
    let n = cpu.resolution as usize;
    let k = 6;
    let mut ratios = Vec::new();
    for (i, &solid) in cpu.solid.iter().enumerate() {
        if !(0.05..0.5).contains(&solid) {
            continue;
        }
        let c = glam::DVec3::new((i % n) as f64, ((i / n) % n) as f64, (i / (n * n)) as f64);
        let (mut seen, mut points) = (0.0, 0);
        for s in 0..k * k * k {
            let f = glam::DVec3::new((s % k) as f64, ((s / k) % k) as f64, (s / (k * k)) as f64);
            let p = cpu.origin + (c + (f + 0.5) / k as f64) * cpu.cell;
            let r = p.length();
            if r > radius {
                seen += 1.0 - 0.5 * (1.0 - (1.0 - (radius / r).powi(2)).sqrt());
                points += 1;
            }
        }
        if points == 0 {
            continue;
        }
        let got = f64::from(fluence[4 * (1 + 3 * i)]) / sky;
        ratios.push(got / (seen / f64::from(points)));
    }
    ratios.sort_by(f64::total_cmp);
    let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
    println!(
        "the sky beside a black sphere, {} cells 5% to 50% solid: the grid over the sphere's \
         own: least {:.3}, median {:.3}, mean {mean:.3}, most {:.3}",
        ratios.len(),
        ratios[0],
        ratios[ratios.len() / 2],
        ratios[ratios.len() - 1]
    );
    // Measured: 115 cells, 0.814 to 0.965, mean 0.890, with the marches starting from the
    // centroid of each cell's clear part; from the cell's centre, 0.688 to 0.947, mean
    // 0.825 (the march from a centre near the surface crosses more of the partly solid
    // cells at grazing directions). What is left is the grid's blocky body: a ray grazing
    // the sphere crosses cells partly inside it and is dimmed by their clear share. Before
    // the clear share, a cell half solid read twice its sky: the bound above 1 catches that.
    assert!(ratios.len() > 50, "{} cells", ratios.len());
    assert!((0.85..0.95).contains(&mean), "mean {mean}");
    assert!(
        ratios[0] > 0.75 && ratios[ratios.len() - 1] < 1.05,
        "{} to {}",
        ratios[0],
        ratios[ratios.len() - 1]
    );
}

/// A white body (albedo 1) under white fibres neither gains nor loses energy in a step,
/// and a black one only absorbs: the grid holds less light than with no body.
#[test]
fn volume_white_body_keeps_energy_black_body_absorbs() {
    let hair = wavy(800, 16, 1.0, 0.01);
    let params = volume_params(12, 24, Vec3::ZERO);
    let white = Body {
        mesh: Mesh::icosphere(0.3, 2).unwrap(),
        color: Vec3::splat(std::f32::consts::FRAC_1_PI),
    };
    let cpu = mirror(&hair, &params, &lights(), 0.0, 0.5, Some(&white));
    let mut worst: f64 = 0.0;
    for (k, &arrived) in cpu.step_arrivals.iter().enumerate() {
        worst = worst.max((cpu.step_energy[k + 1] / arrived - 1.0).abs());
    }
    println!("white body: largest |departures / arrivals - 1| of a step {worst:.2e}");
    assert!(worst < 1e-5, "{worst}");
    let black = Body {
        color: Vec3::ZERO,
        ..white
    };
    let total = |g: &VolumeGridCpu| {
        g.fluence
            .iter()
            .map(|c| c[0].x + c[1].x + c[2].x)
            .sum::<f64>()
    };
    let none = total(&mirror(&hair, &params, &lights(), 0.0, 0.5, None));
    let dark = total(&mirror(&hair, &params, &lights(), 0.0, 0.5, Some(&black)));
    let lit = total(&cpu);
    println!("total fluence: no body {none:.1}, black body {dark:.1}, white body {lit:.1}");
    assert!(dark < none && lit > dark, "{none} {dark} {lit}");
}

/// A body brighter than a Lambertian can be (`mesh_color` above 1/π, as
/// `scenes/long_hair.toml`'s skin: albedo 1.73, 1.26, 1.04) under white fibres: no step
/// gains energy (light that reaches the body's inside bounces there from cell to cell,
/// and an albedo above 1 made it grow without bound: long hair 2.6x the path tracer's).
#[test]
fn volume_bright_body_gains_no_energy() {
    let hair = wavy(800, 16, 1.0, 0.01);
    let params = volume_params(12, 24, Vec3::ZERO);
    let body = Body {
        mesh: Mesh::icosphere(0.3, 2).unwrap(),
        color: Vec3::new(0.55, 0.4, 0.33),
    };
    let cpu = mirror(&hair, &params, &lights(), 0.0, 0.5, Some(&body));
    let e = &cpu.step_energy;
    let worst = e.windows(2).map(|w| w[1] / w[0]).fold(0.0f64, f64::max);
    println!("bright body: largest step energy over the step before {worst:.4}");
    assert!(worst <= 1.0 + 1e-9, "a step gained energy: x{worst}");
}

/// A white body (albedo 1) in the white furnace (white fibres under the sky alone): the
/// exact fluence is still the sky's everywhere, next to the body too, so a grid that lost
/// the body's light (or made light at it) would show it in the cells next to the body
/// against the cells away from it. The mirror: cells 3 or more from the border and at
/// most half solid, next to the body where they or a face neighbour hold part of it.
#[test]
fn volume_white_body_in_the_white_furnace() {
    let sky = 4.0 * f64::from(AMBIENT);
    let white = Body {
        mesh: Mesh::icosphere(0.3, 2).unwrap(),
        color: Vec3::splat(std::f32::consts::FRAC_1_PI),
    };
    for width in [0.01, 0.06] {
        let hair = wavy(800, 16, 1.0, width);
        let params = volume_params(12, 64, Vec3::ZERO);
        let cpu = mirror(&hair, &params, &dark(), AMBIENT, 0.5, Some(&white));
        let without = mirror(&hair, &params, &dark(), AMBIENT, 0.5, None);
        let n = cpu.resolution as usize;
        let index = |c: [usize; 3]| (c[2] * n + c[1]) * n + c[0];
        let (mut near, mut away, mut none) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..n * n * n {
            let c = [i % n, (i / n) % n, i / (n * n)];
            if !c.iter().all(|&k| (3..n - 3).contains(&k)) {
                continue;
            }
            none.push(without.fluence[i][0].x / sky);
            if cpu.solid[i] > 0.5 {
                continue;
            }
            let touching = cpu.solid[i] > 0.0
                || (0..6).any(|k| {
                    let mut y = c;
                    y[k / 2] = if k % 2 == 0 {
                        y[k / 2] + 1
                    } else {
                        y[k / 2] - 1
                    };
                    cpu.solid[index(y)] > 0.0
                });
            let phi = cpu.fluence[i][0].x / sky;
            if touching {
                near.push(phi)
            } else {
                away.push(phi)
            }
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
        println!(
            "white body in the white furnace, width {width}: fluence over the sky's next to \
             the body {:.4} ({} cells), away from it {:.4} ({}); without the body {:.4}",
            mean(&near),
            near.len(),
            mean(&away),
            away.len(),
            mean(&none)
        );
        assert!(!near.is_empty() && !away.is_empty());
        // Measured 1.1763 and 1.2742 next to the body, 1.2165 and 1.1743 without it (1.2466
        // and 1.4268, 1.2843 and 1.3150 before the cells' mean transmittance over their chords).
        assert!(
            (mean(&near) / mean(&none) - 1.0).abs() < 0.15,
            "the body moved the light next to it: {} against {}",
            mean(&near),
            mean(&none)
        );
    }
}
