//! The transparency lab: every stage 3 method and parameter on several scenes and two
//! hair opacities, measured for GPU time, memory and image error against the exact
//! composite (every fragment of every pixel, captured from the A-buffer, sorted and
//! blended on the CPU by `pelage_reference::oit`).
//!
//! ```text
//! pelage lab oit [--quick] [--out DIR]
//! ```
//!
//! Writes `DIR/oit.csv` (default `out/lab`), one chart per scene and opacity
//! (`oit_<scene>_<opacity>.png|svg`: mean FLIP against GPU time, marker area =
//! memory), `oit_memory.csv` (every method built at 656x861 and 1920x1080), and prints
//! both tables. `--quick` runs one small scene and a few configurations (CI).
//!
//! Time is the median wall clock of the method's hair passes recorded alone (the method
//! built without the mesh, drawing over loaded targets) and submitted alone
//! (`crate::hair_timing`), the same measure for every method: lavapipe misplaces the
//! timestamps of compute passes recorded after a render pass, which the strand
//! rasterizer's are. `gpu_ms` keeps the timestamp sum of the passes (the mesh left
//! out), which is right for the raster methods only. Flicker is
//! the mean absolute change of linear RGB between consecutive frames while the camera
//! turns 0.25 degrees a frame around the scene, per method; the exact composite's
//! own flicker is the A-buffer row with the largest resolve depth.

use std::time::Instant;

use glam::{Quat, Vec3};
use pelage::gpu::{Gpu, GpuTimer};
use pelage::scene::{
    Camera, DirectionalLight, HairParams, Light, Mesh, ShadeParams, Transparency, WboitWeight,
    WindParams,
};
use pelage::shade::{ABuffer, HairInputs, HairPass, TargetFormat, Targets};
use pelage::strands::{GrowStrands, MeshBuffers, StrandFrame, StrandStage};
use pelage_lab::{ScatterChart, ScatterPoint, Table, pareto_front};
use pelage_reference::flip::{DEFAULT_PIXELS_PER_DEGREE, LinearImage, flip, rmse_linear};
use pelage_reference::oit::{Fragment, composite_sorted, linear_to_srgb8, srgb8_to_linear};
use pelage_reference::oit_raster::{
    RasterView, RibbonStrand, RibbonStyle, SamplePattern, rasterize,
};

use super::LabOpts;
use crate::progress;

struct Case {
    name: &'static str,
    mesh: Mesh,
    hair: HairParams,
    camera: Camera,
}

fn cases(quick: bool) -> Vec<Case> {
    let scale = |full: u32, small: u32| if quick { small } else { full };
    let mut fur = HairParams::default();
    fur.roots.count = scale(20_000, 4_000);
    fur.wind = WindParams::calm();
    let mut long = HairParams::default();
    long.roots.count = scale(6_000, 1_500);
    long.growth.segments = 16;
    long.growth.length = 0.9;
    long.growth.force_weight = 0.12;
    long.growth.direction_jitter = 0.15;
    long.wind = WindParams::calm();
    let head = Mesh::icosphere(0.5, 3).unwrap_or_else(|_| Mesh::creature());
    let creature = Case {
        name: "creature",
        mesh: Mesh::creature(),
        hair: fur.clone(),
        camera: Camera::default(),
    };
    if quick {
        return vec![creature];
    }
    vec![
        creature,
        // Closer: the fur's silhouettes fill most of the screen.
        Case {
            name: "close_up",
            mesh: Mesh::creature(),
            hair: fur,
            camera: Camera {
                eye: Vec3::new(1.2, 0.5, 1.3),
                target: Vec3::new(0.0, 0.0, 0.2),
                ..Default::default()
            },
        },
        // Long hair covering the whole screen: the deepest pixels.
        Case {
            name: "long_hair",
            mesh: head,
            hair: long,
            camera: Camera {
                eye: Vec3::new(1.6, 0.3, 2.0),
                target: Vec3::new(0.0, -0.15, 0.0),
                ..Default::default()
            },
        },
    ]
}

fn configurations(quick: bool) -> Vec<Transparency> {
    let mut out = vec![Transparency::Opaque];
    let weights: &[WboitWeight] = if quick {
        &[WboitWeight::Eq7]
    } else {
        &[
            WboitWeight::Eq7,
            WboitWeight::Eq8,
            WboitWeight::Eq9,
            WboitWeight::Eq10,
            WboitWeight::Constant,
        ]
    };
    out.extend(weights.iter().map(|&weight| Transparency::Wboit { weight }));
    let ks: &[u32] = if quick { &[8] } else { &[4, 8, 16] };
    out.extend(ks.iter().map(|&k| Transparency::k_buffer(k)));
    out.extend(ks.iter().map(|&k| Transparency::random_subsets(k)));
    let shifts: &[f32] = if quick { &[0.05] } else { &[0.02, 0.05, 0.1] };
    out.extend(shifts.iter().map(|&s| Transparency::dbk(s)));
    let resolves: &[u32] = if quick { &[32] } else { &[8, 16, 64] };
    out.extend(resolves.iter().map(|&resolve_k| Transparency::ABuffer {
        nodes_per_pixel: 16.0,
        resolve_k,
    }));
    // The strand rasterizer's tile size and depth bins, swept.
    let rasters: &[(u32, u32)] = if quick {
        &[(16, 16)]
    } else {
        &[(8, 4), (8, 16), (8, 64), (16, 4), (16, 16), (16, 64)]
    };
    out.extend(
        rasters
            .iter()
            .map(|&(tile, bins)| Transparency::StrandRaster {
                tile,
                bins,
                pool: 4.0,
            }),
    );
    out
}

/// Stage 1 for one case, grown once at t = 0.
struct Grown {
    mesh: MeshBuffers,
    strands: GrowStrands,
    /// The frame the strands were grown in, which every method is prepared and recorded with.
    frame: StrandFrame,
}

fn grow(gpu: &Gpu, case: &Case) -> Result<Grown, Box<dyn std::error::Error>> {
    let mesh = MeshBuffers::upload(gpu, &case.mesh)?;
    let mut strands = GrowStrands::new(gpu, &case.mesh, &mesh, &case.hair)?;
    let frame = strands.prepare(&gpu.queue, 0.0)?;
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    strands.encode(&mut encoder, &frame, None)?;
    gpu.submit_and_wait([encoder.finish()])?;
    Ok(Grown {
        mesh,
        strands,
        frame,
    })
}

/// The camera of frame `i`: turned 0.25 degrees a frame about the vertical through the target.
fn camera_at(base: &Camera, i: usize) -> Camera {
    let turn = Quat::from_rotation_y((0.25 * i as f32).to_radians());
    Camera {
        eye: base.target + turn * (base.eye - base.target),
        ..base.clone()
    }
}

fn linear(
    bytes: &[u8],
    width: u32,
    height: u32,
) -> Result<LinearImage, Box<dyn std::error::Error>> {
    Ok(LinearImage::from_srgb8_rgba(width, height, bytes)?)
}

struct Measured {
    frames: Vec<Vec<u8>>,
    gpu_ms: f64,
    wall_ms: f64,
    memory_mb: f64,
    slices: u32,
    dropped: u64,
}

fn render_method(
    gpu: &Gpu,
    grown: &Grown,
    case: &Case,
    shade: &ShadeParams,
    size: (u32, u32),
    frames: usize,
) -> Result<Measured, Box<dyn std::error::Error>> {
    let (width, height) = size;
    let inputs = HairInputs {
        params: shade,
        mesh: &grown.mesh,
        strands: grown.strands.buffers(),
        shadows: &[],
        visibility: None,
        target: TargetFormat::for_params(shade),
        draw_mesh: true,
        grid_apart: false,
    };
    let method = pelage::shade::build(gpu, &inputs, width, height)?;
    let targets = Targets::new(gpu, width, height, shade.samples())?;
    let mut timer = GpuTimer::new(gpu, 64)?;
    let light = [Light::default()];
    let mut images = Vec::new();
    let mut times = Vec::new();
    for i in 0..frames {
        method.prepare(
            &gpu.queue,
            &grown.frame,
            &camera_at(&case.camera, i).matrices(width, height),
            &light,
            width,
            height,
        )?;
        let (color, resolve) = targets.color_views();
        let depth = targets.depth_view();
        let views = targets.views(&color, resolve.as_ref(), &depth);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        method.encode(&mut encoder, &grown.frame, &views, timer.as_mut())?;
        if let Some(t) = &timer {
            t.resolve(&mut encoder);
        }
        gpu.submit_and_wait([encoder.finish()])?;
        method.after_submit(gpu)?;
        if let Some(t) = &mut timer {
            let report = t.read(gpu)?;
            times.push(
                report
                    .scopes
                    .iter()
                    .filter(|(label, _)| label != "shade: mesh")
                    .map(|(_, ms)| ms)
                    .sum::<f64>(),
            );
        }
        images.push(targets.read_color(gpu)?.data);
    }
    times.sort_by(f64::total_cmp);
    let wall_ms = crate::hair_timing::hair_wall_ms(
        gpu,
        &crate::hair_timing::HairCase {
            mesh: &case.mesh,
            hair: &case.hair,
            shade,
            camera: &case.camera,
        },
        width,
        height,
        frames,
    )?;
    Ok(Measured {
        frames: images,
        gpu_ms: times.get(times.len() / 2).copied().unwrap_or(f64::NAN),
        wall_ms,
        memory_mb: method.memory_bytes() as f64 / 1e6,
        slices: method.slices(),
        dropped: method.stats(gpu)?.dropped,
    })
}

/// The exact composite of frame 0 (sRGB8 RGBA) and the fragments per pixel it took.
fn exact(
    gpu: &Gpu,
    grown: &Grown,
    case: &Case,
    shade: &ShadeParams,
    size: (u32, u32),
) -> Result<(Vec<u8>, u64, usize), Box<dyn std::error::Error>> {
    let (width, height) = size;
    let inputs = HairInputs {
        params: shade,
        mesh: &grown.mesh,
        strands: grown.strands.buffers(),
        shadows: &[],
        visibility: None,
        // The reference A-buffer draws single-sampled, whatever the case's own method.
        target: TargetFormat::default(),
        draw_mesh: true,
        grid_apart: false,
    };
    let targets = Targets::new(gpu, width, height, 1)?;
    let light = [Light::default()];
    // Grow the pool until nothing is dropped.
    let mut nodes_per_pixel = 32.0f32;
    loop {
        let abuffer = ABuffer::new(gpu, &inputs, nodes_per_pixel, 64, width, height)?;
        abuffer.prepare(
            &gpu.queue,
            &grown.frame,
            &case.camera.matrices(width, height),
            &light,
            width,
            height,
        )?;
        let capture = abuffer.capture(gpu, &targets)?;
        let stats = abuffer.stats(gpu)?;
        if stats.dropped > 0 {
            nodes_per_pixel *= 4.0;
            continue;
        }
        let mut out = Vec::with_capacity(capture.background.len());
        let mut deepest = 0;
        for (p, list) in capture.lists.iter().enumerate() {
            let bg = &capture.background[4 * p..4 * p + 4];
            let background = [
                srgb8_to_linear(bg[0]),
                srgb8_to_linear(bg[1]),
                srgb8_to_linear(bg[2]),
            ];
            let mut fragments: Vec<Fragment> = list
                .iter()
                .map(|f| Fragment {
                    depth: f.depth,
                    color: f.color,
                    alpha: f.alpha,
                })
                .collect();
            deepest = deepest.max(fragments.len());
            let c = composite_sorted(&mut fragments, background);
            out.extend([
                linear_to_srgb8(c[0]),
                linear_to_srgb8(c[1]),
                linear_to_srgb8(c[2]),
                255,
            ]);
        }
        return Ok((out, stats.stored, deepest));
    }
}

fn mean_abs_change(frames: &[Vec<u8>]) -> f64 {
    let mut total = 0.0;
    let mut count = 0usize;
    for pair in frames.windows(2) {
        for (a, b) in pair[0]
            .iter()
            .zip(&pair[1])
            .enumerate()
            .filter(|(i, _)| i % 4 != 3)
            .map(|(_, x)| x)
        {
            total += f64::from((srgb8_to_linear(*a) - srgb8_to_linear(*b)).abs());
            count += 1;
        }
    }
    if count == 0 {
        0.0
    } else {
        total / count as f64
    }
}

/// Runs the transparency lab: writes `oit.csv`, `oit_memory.csv` and a chart per scene
/// and opacity under `opts.out`.
pub fn run(opts: &LabOpts) -> Result<(), Box<dyn std::error::Error>> {
    let started = Instant::now();
    let size = if opts.quick { (160, 120) } else { (320, 240) };
    let frames = if opts.quick { 3 } else { 5 };
    let opacities: &[f32] = if opts.quick { &[0.8] } else { &[0.3, 0.8] };
    let configs = configurations(opts.quick);
    let mut table = Table::new(&[
        "scene",
        "opacity",
        "method",
        "config",
        "gpu_ms",
        "wall_ms",
        "memory_mb",
        "slices",
        "mean_flip",
        "p99_flip",
        "rmse_linear",
        "flicker",
        "dropped",
    ]);
    let mut notes = String::new();
    let mut true_rows: Vec<Vec<String>> = Vec::new();
    let all_cases = cases(opts.quick);
    let bar = progress::bar(
        (all_cases.len() * opacities.len() * configs.len()) as u64,
        "methods",
    )?;
    for case in all_cases {
        for &opacity in opacities {
            let mut case_hair = case.hair.clone();
            case_hair.growth.opacity = opacity;
            let case = Case {
                hair: case_hair,
                mesh: case.mesh.clone(),
                camera: case.camera.clone(),
                name: case.name,
            };
            let gpu = Gpu::headless()?;
            let grown = grow(&gpu, &case)?;
            let shade = ShadeParams::default();
            let (reference, fragments, deepest) = exact(&gpu, &grown, &case, &shade, size)?;
            let pixels = size.0 as usize * size.1 as usize;
            let line = format!(
                "{} opacity {opacity}: {fragments} fragments, {:.2} per pixel, deepest pixel {deepest}; \
                 an A-buffer holding them all needs {:.2} MB\n",
                case.name,
                fragments as f64 / pixels as f64,
                (fragments * 16 + pixels as u64 * 4) as f64 / 1e6
            );
            bar.println(line.trim_end());
            notes.push_str(&line);
            let reference_image = linear(&reference, size.0, size.1)?;
            let mut points = Vec::new();
            for config in &configs {
                bar.set_message(format!("{} {opacity} {}", case.name, config.label()));
                let params = ShadeParams {
                    transparency: config.clone(),
                    ..ShadeParams::default()
                };
                let m = render_method(&gpu, &grown, &case, &params, size, frames)?;
                let first = linear(&m.frames[0], size.0, size.1)?;
                let map = flip(&reference_image, &first, DEFAULT_PIXELS_PER_DEGREE)?;
                let (rmse, _) = rmse_linear(&reference_image, &first)?;
                let mean = map.mean();
                let p99 = map.percentile(99.0);
                let flicker = mean_abs_change(&m.frames);
                table.push(vec![
                    case.name.into(),
                    format!("{opacity}"),
                    config.name().into(),
                    config.label(),
                    format!("{:.3}", m.gpu_ms),
                    format!("{:.3}", m.wall_ms),
                    format!("{:.3}", m.memory_mb),
                    m.slices.to_string(),
                    format!("{mean:.4}"),
                    format!("{p99:.4}"),
                    format!("{rmse:.4}"),
                    format!("{flicker:.5}"),
                    m.dropped.to_string(),
                ])?;
                bar.println(format!(
                    "  {:<44} {:8.2} ms {:7.2} MB  FLIP {mean:.4} (p99 {p99:.3})  flicker {flicker:.5}",
                    config.label(),
                    m.wall_ms,
                    m.memory_mb
                ));
                points.push(ScatterPoint {
                    series: config.name().into(),
                    label: config.label(),
                    x: m.wall_ms,
                    y: mean,
                    size: Some(m.memory_mb.max(0.01)),
                });
                if case.name == "creature" && (opacity - 0.8).abs() < 1e-6 {
                    let path = opts.out.join(format!("oit_{}.png", config.name()));
                    if let Some(img) =
                        image::RgbaImage::from_raw(size.0, size.1, m.frames[0].clone())
                    {
                        crate::output::save_png(&img, &path)?;
                    }
                }
                bar.inc(1);
            }
            if case.name == "creature" && (opacity - 0.8).abs() < 1e-6 {
                if let Some(img) = image::RgbaImage::from_raw(size.0, size.1, reference.clone()) {
                    crate::output::save_png(&img, &opts.out.join("oit_exact.png"))?;
                }
            }
            // The strand rasterizer against the k-buffer of 8 (issue 18's targets): time
            // ratio and mean FLIP, each configuration.
            if let Some(k8) = points.iter().find(|p| p.label == "k_buffer k=8") {
                for p in points.iter().filter(|p| p.series == "strand_raster") {
                    let line = format!(
                        "  {} opacity {opacity}: {} {:.3}x the k-buffer k=8's time, FLIP {:.4} against its {:.4}\n",
                        case.name,
                        p.label,
                        p.x / k8.x,
                        p.y,
                        k8.y
                    );
                    bar.println(line.trim_end());
                    notes.push_str(&line);
                }
            }
            // Coverage and compositing alone, against a reference that shares neither the
            // ribbons' widening nor the rasterizer's analytic coverage.
            for (label, f) in against_true_width(&gpu, &grown, &case, &configs, size)? {
                let line = format!(
                    "  {} opacity {opacity}, flat, against the true-width picture: {label}: mean FLIP {f:.4}\n",
                    case.name
                );
                bar.println(line.trim_end());
                notes.push_str(&line);
                true_rows.push(vec![
                    case.name.into(),
                    format!("{opacity}"),
                    label,
                    format!("{f:.4}"),
                ]);
            }
            let xy: Vec<(f64, f64)> = points.iter().map(|p| (p.x, p.y)).collect();
            notes.push_str(&format!(
                "  Pareto front ({} opacity {opacity}):",
                case.name
            ));
            for i in pareto_front(&xy) {
                notes.push_str(&format!(
                    " [{} {:.1} ms FLIP {:.4}]",
                    points[i].label, points[i].x, points[i].y
                ));
            }
            notes.push('\n');
            let chart = ScatterChart {
                title: format!(
                    "Transparency on {} (opacity {opacity}): error against time",
                    case.name.replace('_', " ")
                ),
                x_label: "hair passes, wall clock submitted alone, ms (log)".into(),
                y_label: "mean FLIP vs exact sorted composite".into(),
                x_log: true,
                y_log: false,
                points,
                mark_pareto: true,
                size_label: Some("memory, MB".into()),
            };
            let stem = format!("oit_{}_{}", case.name, (opacity * 10.0).round() as u32);
            chart.write_svg(&opts.out.join(format!("{stem}.svg")), 900, 600)?;
            chart.write_png(&opts.out.join(format!("{stem}.png")), 900, 600)?;
        }
    }
    bar.finish_and_clear();
    table.write_csv(&opts.out.join("oit.csv"))?;
    let mut truth = Table::new(&["scene", "opacity", "config", "mean_flip_true_width"]);
    for row in true_rows {
        truth.push(row)?;
    }
    truth.write_csv(&opts.out.join("oit_true_width.csv"))?;
    println!("{}", table.to_text());
    print!("{notes}");

    // Memory at the seed's viewport and at 1080p: every method built, nothing drawn.
    let mut memory = Table::new(&["method", "config", "width", "height", "memory_mb", "slices"]);
    let gpu = Gpu::headless()?;
    let quick_cases = cases(true);
    let case = quick_cases.first().ok_or("no scene for the memory table")?;
    let grown = grow(&gpu, case)?;
    for (w, h) in [(656, 861), (1920, 1080)] {
        for config in &configs {
            let params = ShadeParams {
                transparency: config.clone(),
                ..ShadeParams::default()
            };
            let inputs = HairInputs {
                params: &params,
                mesh: &grown.mesh,
                strands: grown.strands.buffers(),
                shadows: &[],
                visibility: None,
                target: TargetFormat::for_params(&params),
                draw_mesh: true,
                grid_apart: false,
            };
            let method = pelage::shade::build(&gpu, &inputs, w, h)?;
            memory.push(vec![
                config.name().into(),
                config.label(),
                w.to_string(),
                h.to_string(),
                format!("{:.2}", method.memory_bytes() as f64 / 1e6),
                method.slices().to_string(),
            ])?;
        }
    }
    memory.write_csv(&opts.out.join("oit_memory.csv"))?;
    println!("{}", memory.to_text());
    println!(
        "wrote {}/oit.csv, oit_memory.csv and oit_<scene>_<opacity>.png|svg in {:.0} s",
        opts.out.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// The picture the strands really make, flat and unlit: each ribbon at its true width
/// (no widening to a pixel), `samples` x `samples` samples per pixel composited exactly
/// and averaged (`pelage_reference::oit_raster`, on the CPU, from the strands read back),
/// with no mesh. Linear RGB.
fn true_width(
    gpu: &Gpu,
    grown: &Grown,
    case: &Case,
    size: (u32, u32),
    samples: u32,
) -> Result<Vec<[f32; 3]>, Box<dyn std::error::Error>> {
    let buffers = grown.strands.buffers();
    let vertices: Vec<[f32; 4]> =
        bytemuck::cast_slice::<u8, [f32; 4]>(&pelage::gpu::read_buffer(gpu, &buffers.vertices)?)
            .to_vec();
    let per = (buffers.segments + 1) as usize;
    let strands: Vec<RibbonStrand> = grown
        .strands
        .roots()
        .iter()
        .zip(vertices.chunks_exact(per))
        .map(|(root, points)| RibbonStrand {
            points: points.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect(),
            width: root.width,
            color: root.color.into(),
        })
        .collect();
    let style = RibbonStyle {
        tip_width: buffers.style.tip_width,
        min_pixels: 1e-3,
        opacity: buffers.style.opacity,
    };
    let view = RasterView::new(&case.camera.matrices(size.0, size.1), size.0, size.1);
    let background = ShadeParams::default().background;
    Ok(
        rasterize(&strands, &style, &view, SamplePattern::grid(samples))?.composite([
            background.x,
            background.y,
            background.z,
        ]),
    )
}

/// `transparency` drawn flat and unlit (ambient 1, no root occlusion, a light of no
/// intensity: every strand its base colour) without the mesh: linear RGB.
fn render_flat(
    gpu: &Gpu,
    grown: &Grown,
    case: &Case,
    transparency: &Transparency,
    size: (u32, u32),
) -> Result<Vec<[f32; 3]>, Box<dyn std::error::Error>> {
    let params = ShadeParams {
        transparency: transparency.clone(),
        ambient: 1.0,
        root_occlusion: 0.0,
        sample_count: 1,
        ..ShadeParams::default()
    };
    let inputs = HairInputs {
        params: &params,
        mesh: &grown.mesh,
        strands: grown.strands.buffers(),
        shadows: &[],
        visibility: None,
        target: TargetFormat::for_params(&params),
        draw_mesh: false,
        grid_apart: false,
    };
    let method = pelage::shade::build(gpu, &inputs, size.0, size.1)?;
    let targets = Targets::new(gpu, size.0, size.1, 1)?;
    let dark = Light::Directional(DirectionalLight {
        intensity: 0.0,
        ..Default::default()
    });
    method.prepare(
        &gpu.queue,
        &grown.frame,
        &case.camera.matrices(size.0, size.1),
        &[dark],
        size.0,
        size.1,
    )?;
    let (color, resolve) = targets.color_views();
    let depth = targets.depth_view();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    method.encode(
        &mut encoder,
        &grown.frame,
        &targets.views(&color, resolve.as_ref(), &depth),
        None,
    )?;
    gpu.submit_and_wait([encoder.finish()])?;
    Ok(targets
        .read_color(gpu)?
        .data
        .chunks_exact(4)
        .map(|p| {
            [
                srgb8_to_linear(p[0]),
                srgb8_to_linear(p[1]),
                srgb8_to_linear(p[2]),
            ]
        })
        .collect())
}

/// Mean FLIP of flat, unlit pictures of the A-buffer (every widened-ribbon fragment),
/// the k-buffer of 8 and each strand rasterizer configuration against the true-width
/// picture ([`true_width`], 8 x 8 samples), with that reference's own floor (8 x 8
/// against 16 x 16 samples): `(label, mean FLIP)`, the floor first.
fn against_true_width(
    gpu: &Gpu,
    grown: &Grown,
    case: &Case,
    configs: &[Transparency],
    size: (u32, u32),
) -> Result<Vec<(String, f64)>, Box<dyn std::error::Error>> {
    let image = |pixels: Vec<[f32; 3]>| LinearImage::new(size.0, size.1, pixels);
    let reference = image(true_width(gpu, grown, case, size, 8)?)?;
    let finer = image(true_width(gpu, grown, case, size, 16)?)?;
    let mut out = vec![(
        "reference floor (8x8 against 16x16 samples)".to_string(),
        flip(&reference, &finer, DEFAULT_PIXELS_PER_DEGREE)?.mean(),
    )];
    let wanted = configs.iter().filter(|t| {
        matches!(
            t,
            Transparency::ABuffer { .. } | Transparency::StrandRaster { .. }
        ) || **t == Transparency::k_buffer(8)
    });
    for t in wanted {
        let picture = match render_flat(gpu, grown, case, t, size) {
            Ok(p) => p,
            Err(e) if e.to_string().contains("lacks") => continue,
            Err(e) => return Err(e),
        };
        out.push((
            t.label(),
            flip(&reference, &image(picture)?, DEFAULT_PIXELS_PER_DEGREE)?.mean(),
        ));
    }
    Ok(out)
}
