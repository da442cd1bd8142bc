//! The WGSL shading models on a real adapter (lavapipe in CI), against their CPU twins in
//! `pelage_reference::shading`, and Marschner's lookup tables against the analytic model.
//!
//! Run with `--nocapture` to see the measured errors.

use std::f64::consts::PI;

use encase::ShaderType;
use glam::{DVec3, Vec3};
use pelage_gpu::{
    Gpu, UniformBuffer, bind_buffers, compute_pipeline, dispatch_size, read_buffer, storage_buffer,
    wgpu, zeroed_storage,
};
use pelage_reference::shading::{kajiya_kay, marschner_radiance, sadeghi_radiance};
use pelage_scene::{KajiyaKayParams, MarschnerParams, SadeghiParams};
use pelage_shade::{KajiyaKayUniforms, MarschnerLut, MarschnerUniforms, SadeghiUniforms};
use pelage_strands::{hash_to_unit, pcg_hash};

fn gpu() -> Gpu {
    Gpu::headless().unwrap_or_else(|e| panic!("these tests need a GPU adapter: {e}"))
}

/// `EvalSettings` in `wgsl/shade/models/eval.wgsl`.
#[derive(Clone, Copy, Debug, ShaderType)]
struct EvalSettings {
    model: u32,
    count: u32,
    _pad0: u32,
    _pad1: u32,
}

/// Model numbers of `eval.wgsl`.
const KAJIYA_KAY: u32 = 0;
const MARSCHNER: u32 = 1;
const MARSCHNER_LUT: u32 = 2;
const SADEGHI: u32 = 3;

/// One evaluation: tangent, light and eye directions, base colour, strand random number.
#[derive(Clone, Copy, Debug)]
struct Case {
    t: Vec3,
    l: Vec3,
    v: Vec3,
    color: Vec3,
    random: f32,
}

impl Case {
    /// `EvalCase` of `eval.wgsl`: four vec4, the random number in `t.w`.
    fn pack(&self) -> [[f32; 4]; 4] {
        [
            self.t.extend(self.random).to_array(),
            self.l.extend(0.0).to_array(),
            self.v.extend(0.0).to_array(),
            self.color.extend(1.0).to_array(),
        ]
    }
}

/// Directions on a Fibonacci sphere.
fn fibonacci(n: usize) -> Vec<Vec3> {
    let golden = PI * (3.0 - 5.0f64.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - y * y).sqrt();
            let a = golden * i as f64;
            DVec3::new(r * a.cos(), y, r * a.sin()).as_vec3()
        })
        .collect()
}

/// The dense sweep: tangents (axes, diagonals, near-axis, random) × lights × eyes from a
/// Fibonacci set, plus the degenerate eyes `v = l`, `v = -l`, `v = ±t` and lights `l = ±t`,
/// each with a strand random number and colour drawn from a hash.
fn sweep() -> Vec<Case> {
    let tangents = [
        Vec3::Y,
        Vec3::X,
        Vec3::Z,
        -Vec3::Y,
        Vec3::new(1.0, 1.0, 1.0).normalize(),
        Vec3::new(0.3, -0.2, 0.93).normalize(),
        Vec3::new(1e-4, 1.0, -2e-4).normalize(),
        Vec3::new(-0.8, 0.1, 0.4).normalize(),
    ];
    let dirs = fibonacci(40);
    let mut cases = Vec::new();
    let mut seed = 1u32;
    let mut next = || {
        seed = pcg_hash(seed);
        hash_to_unit(seed)
    };
    for &t in &tangents {
        for &l in dirs.iter().chain([t, -t].iter()) {
            for &v in dirs.iter().chain([l, -l, t, -t].iter()) {
                let color = Vec3::new(0.2 + 0.6 * next(), 0.15 + 0.4 * next(), 0.1 + 0.3 * next());
                let random = next().min(0.999_999);
                cases.push(Case {
                    t,
                    l,
                    v,
                    color,
                    random,
                });
            }
        }
    }
    cases
}

/// The evaluation kernel with its inputs bound.
struct Eval {
    pipeline: wgpu::ComputePipeline,
    cases: wgpu::Buffer,
    results: wgpu::Buffer,
    count: u32,
}

impl Eval {
    fn new(gpu: &Gpu, cases: &[Case]) -> Eval {
        let module = pelage_shade::SHADERS
            .library()
            .module(gpu, "shade/models/eval.wgsl")
            .unwrap();
        let pipeline = compute_pipeline(&gpu.device, "eval models", &module, "main");
        let vecs: Vec<glam::Vec4> = cases
            .iter()
            .flat_map(|c| c.pack())
            .map(glam::Vec4::from_array)
            .collect();
        let cases_buffer =
            storage_buffer(gpu, "eval cases", &vecs, wgpu::BufferUsages::STORAGE).unwrap();
        let results = zeroed_storage(
            gpu,
            "eval results",
            16 * cases.len() as u64,
            wgpu::BufferUsages::STORAGE,
        )
        .unwrap();
        Eval {
            pipeline,
            cases: cases_buffer,
            results,
            count: cases.len() as u32,
        }
    }

    /// Runs `model` over every case and reads back the radiances.
    fn run(
        &self,
        gpu: &Gpu,
        model: u32,
        params: (&KajiyaKayParams, &MarschnerParams, &SadeghiParams),
        lut: &MarschnerLut,
    ) -> Vec<Vec3> {
        let settings = UniformBuffer::new(
            gpu,
            "eval settings",
            &EvalSettings {
                model,
                count: self.count,
                _pad0: 0,
                _pad1: 0,
            },
        )
        .unwrap();
        let kk =
            UniformBuffer::new(gpu, "eval kk", &KajiyaKayUniforms::from_params(params.0)).unwrap();
        let marschner = UniformBuffer::new(
            gpu,
            "eval marschner",
            &MarschnerUniforms::from_params(params.1),
        )
        .unwrap();
        let sadeghi =
            UniformBuffer::new(gpu, "eval sadeghi", &SadeghiUniforms::from_params(params.2))
                .unwrap();
        let device = &gpu.device;
        let group0 = bind_buffers(
            device,
            "eval group 0",
            &self.pipeline.get_bind_group_layout(0),
            &[&settings.buffer, &self.cases, &self.results],
        );
        let group1 = bind_buffers(
            device,
            "eval group 1",
            &self.pipeline.get_bind_group_layout(1),
            &[&kk.buffer, &marschner.buffer, &sadeghi.buffer],
        );
        let group2 = lut.bind_group(device, &self.pipeline.get_bind_group_layout(2));
        let (x, y) = dispatch_size(gpu.limits(), u64::from(self.count), 64);
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &group0, &[]);
            pass.set_bind_group(1, &group1, &[]);
            pass.set_bind_group(2, &group2, &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
        gpu.submit_and_wait([encoder.finish()]).unwrap();
        let bytes = read_buffer(gpu, &self.results).unwrap();
        bytemuck::cast_slice::<u8, [f32; 4]>(&bytes)
            .iter()
            .map(|v| Vec3::new(v[0], v[1], v[2]))
            .collect()
    }
}

/// Builds a table for `params` at `resolution` and fills it.
fn built_lut(gpu: &Gpu, params: &MarschnerParams, resolution: u32) -> MarschnerLut {
    let lut = MarschnerLut::new(gpu, params, resolution).unwrap();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    lut.encode(&mut encoder);
    gpu.submit_and_wait([encoder.finish()]).unwrap();
    lut
}

/// GPU against CPU: relative tolerance plus an absolute one, per channel.
const RELATIVE: f32 = 1e-3;
const ABSOLUTE: f32 = 1e-4;

/// Compares `gpu` with `cpu` case by case; returns (worst error in units of the tolerance,
/// its case index, max relative error where |cpu| > 1e-2).
fn compare(cases: &[Case], gpu: &[Vec3], cpu: &[Vec3]) -> (f32, usize, f32) {
    let mut worst = (0.0f32, 0usize);
    let mut worst_relative = 0.0f32;
    for (i, (g, c)) in gpu.iter().zip(cpu).enumerate() {
        assert!(
            g.is_finite() && g.min_element() >= 0.0,
            "case {i} {:?}: GPU gives {g} (CPU {c})",
            cases[i]
        );
        for k in 0..3 {
            let err = (g[k] - c[k]).abs();
            let allowed = RELATIVE * c[k].abs() + ABSOLUTE;
            if err / allowed > worst.0 {
                worst = (err / allowed, i);
            }
            if c[k].abs() > 1e-2 {
                worst_relative = worst_relative.max(err / c[k].abs());
            }
        }
    }
    (worst.0, worst.1, worst_relative)
}

#[test]
fn wgsl_models_match_their_cpu_twins() {
    let gpu = gpu();
    let cases = sweep();
    let eval = Eval::new(&gpu, &cases);
    let kk_params = [
        KajiyaKayParams::default(),
        KajiyaKayParams {
            shift_primary: -0.12,
            shift_secondary: 0.2,
            secondary_specular: 0.25,
            secondary_color: Vec3::new(1.0, 0.8, 0.6),
            ..Default::default()
        },
    ];
    let marschner_params = [
        MarschnerParams::default(),
        MarschnerParams {
            eccentricity: 1.0,
            diffuse: 0.3,
            ..Default::default()
        },
        MarschnerParams {
            eta: 2.2,
            glint_scale: 3.0,
            sigma_a: Vec3::new(0.05, 0.5, 2.0),
            ..Default::default()
        },
    ];
    let sadeghi_params = SadeghiParams::default();
    let lut = built_lut(&gpu, &MarschnerParams::default(), 16);
    println!("{} cases per model", cases.len());

    for (k, p) in kk_params.iter().enumerate() {
        let g = eval.run(
            &gpu,
            KAJIYA_KAY,
            (p, &marschner_params[0], &sadeghi_params),
            &lut,
        );
        let c: Vec<Vec3> = cases
            .iter()
            .map(|c| kajiya_kay(p, c.t, c.l, c.v, c.color))
            .collect();
        let (worst, at, rel) = compare(&cases, &g, &c);
        println!(
            "Kajiya-Kay {k}: worst error {worst:.3} x tolerance (case {at}), max relative {rel:.2e}"
        );
        assert!(
            worst <= 1.0,
            "Kajiya-Kay {k}: case {:?}: GPU {} CPU {}",
            cases[at],
            g[at],
            c[at]
        );
    }
    for (k, p) in marschner_params.iter().enumerate() {
        let g = eval.run(&gpu, MARSCHNER, (&kk_params[0], p, &sadeghi_params), &lut);
        let c: Vec<Vec3> = cases
            .iter()
            .map(|c| marschner_radiance(p, c.t, c.l, c.v, c.color, c.random))
            .collect();
        let (worst, at, rel) = compare(&cases, &g, &c);
        println!(
            "Marschner {k}: worst error {worst:.3} x tolerance (case {at}), max relative {rel:.2e}"
        );
        assert!(
            worst <= 1.0,
            "Marschner {k}: case {:?}: GPU {} CPU {}",
            cases[at],
            g[at],
            c[at]
        );
    }
    let g = eval.run(
        &gpu,
        SADEGHI,
        (&kk_params[0], &marschner_params[0], &sadeghi_params),
        &lut,
    );
    let c: Vec<Vec3> = cases
        .iter()
        .map(|c| sadeghi_radiance(&sadeghi_params, c.t, c.l, c.v, c.color, c.random))
        .collect();
    let (worst, at, rel) = compare(&cases, &g, &c);
    println!("Sadeghi: worst error {worst:.3} x tolerance (case {at}), max relative {rel:.2e}");
    assert!(
        worst <= 1.0,
        "Sadeghi: case {:?}: GPU {} CPU {}",
        cases[at],
        g[at],
        c[at]
    );
}

/// Error statistics of the table path against the analytic path.
struct LutError {
    rmse: f64,
    rms: f64,
    p99_relative: f64,
    max_relative: f64,
}

fn lut_error(analytic: &[Vec3], lut: &[Vec3]) -> LutError {
    let mut sq = 0.0;
    let mut sq_ref = 0.0;
    let mut relative = Vec::with_capacity(analytic.len());
    for (a, l) in analytic.iter().zip(lut) {
        assert!(l.is_finite(), "table path gives {l}");
        let d = (*l - *a).as_dvec3();
        sq += d.length_squared();
        sq_ref += a.as_dvec3().length_squared();
        // Relative to the larger of the value and 1% of a typical highlight (0.1), so that
        // near-black values do not dominate.
        let scale = f64::from(a.max_element()).max(1e-3);
        relative.push(d.abs().max_element() / scale);
    }
    let n = (3 * analytic.len()) as f64;
    relative.sort_by(f64::total_cmp);
    let p99 = relative[(0.99 * (relative.len() - 1) as f64) as usize];
    LutError {
        rmse: (sq / n).sqrt(),
        rms: (sq_ref / n).sqrt(),
        p99_relative: p99,
        max_relative: relative.last().copied().unwrap_or(0.0),
    }
}

#[test]
fn lookup_tables_converge_to_the_analytic_model() {
    let gpu = gpu();
    let cases = sweep();
    let eval = Eval::new(&gpu, &cases);
    let kk = KajiyaKayParams::default();
    let sadeghi = SadeghiParams::default();
    // (name, parameters, largest p99 relative error allowed at N = 128). At N = 128 the
    // RMSE must also be at most 5e-4 of the RMS of the analytic values.
    for (name, params, p99_at_128) in [
        (
            "circular",
            MarschnerParams {
                eccentricity: 1.0,
                ..Default::default()
            },
            1e-2,
        ),
        ("eccentric 0.85", MarschnerParams::default(), 2e-2),
    ] {
        let small = built_lut(&gpu, &params, 16);
        let analytic = eval.run(&gpu, MARSCHNER, (&kk, &params, &sadeghi), &small);
        println!(
            "Marschner tables vs analytic, {name} fibre, {} cases:",
            cases.len()
        );
        println!("  size slices    memory    RMSE      RMSE/RMS  p99 rel   max rel");
        let mut previous: Option<LutError> = None;
        for resolution in [16, 32, 64, 128, 256] {
            let lut = built_lut(&gpu, &params, resolution);
            let tabulated = eval.run(&gpu, MARSCHNER_LUT, (&kk, &params, &sadeghi), &lut);
            let e = lut_error(&analytic, &tabulated);
            println!(
                "  {resolution:>4} {:>6} {:>9} {:.3e} {:.3e} {:.3e} {:.3e}",
                lut.slices(),
                lut.memory_bytes(),
                e.rmse,
                e.rmse / e.rms,
                e.p99_relative,
                e.max_relative
            );
            if let Some(p) = &previous {
                assert!(
                    e.rmse < p.rmse,
                    "{name}: RMSE does not fall at {resolution}"
                );
                assert!(
                    e.p99_relative < p.p99_relative,
                    "{name}: p99 does not fall at {resolution}"
                );
            }
            if resolution == 128 {
                assert!(
                    e.rmse / e.rms <= 5e-4,
                    "{name}: RMSE/RMS {} at N = 128 (allowed 5e-4)",
                    e.rmse / e.rms
                );
                assert!(
                    e.p99_relative <= p99_at_128,
                    "{name}: p99 relative error {} at N = 128 (allowed {p99_at_128})",
                    e.p99_relative
                );
            }
            previous = Some(e);
        }
    }
}

#[test]
fn lut_rejects_bad_resolution_and_layout_changes() {
    let gpu = gpu();
    let p = MarschnerParams::default();
    assert!(MarschnerLut::new(&gpu, &p, 2).is_err());
    assert!(MarschnerLut::new(&gpu, &p, 100_000).is_err());
    let bad = MarschnerParams {
        eta: f32::NAN,
        ..Default::default()
    };
    let err = MarschnerLut::new(&gpu, &bad, 32).unwrap_err();
    assert!(format!("{err}").contains("shading.marschner.eta"), "{err}");
    let lut = MarschnerLut::new(&gpu, &p, 32).unwrap();
    assert_eq!(lut.slices(), 8);
    assert!(
        lut.update(
            &gpu.queue,
            &MarschnerParams {
                eta: 1.6,
                ..p.clone()
            }
        )
        .is_ok()
    );
    assert!(
        lut.update(
            &gpu.queue,
            &MarschnerParams {
                eccentricity: 1.0,
                ..p.clone()
            }
        )
        .is_err()
    );
    // M: 16 x 32 texels; N0: 32 x 32; N1: 32 x 32 x 8; uniforms 80 + 16 bytes.
    assert_eq!(
        lut.memory_bytes(),
        16 * (16 * 32 + 32 * 32 * (1 + 8)) + 80 + 16
    );
    let circular = MarschnerLut::new(
        &gpu,
        &MarschnerParams {
            eccentricity: 1.0,
            ..p.clone()
        },
        32,
    )
    .unwrap();
    assert_eq!(circular.slices(), 1);
}
