//! Stage 1 for groom files on a real adapter: the rest shape comes out unchanged without
//! wind, the GPU matches the CPU mirror with it, no segment stretches, and segment
//! reduction stays within the bound it predicts.

use glam::Vec3;
use pelage_gpu::read_buffer;
use pelage_reference::strands::{Level, deform_groom, drawn_width};
use pelage_scene::{Groom, HairParams, Resampled, Transition, WindParams};
use pelage_strands::{
    GroomStrands, LodLevel, StrandRoot, StrandStage, StrandsError, bend_error, bend_per_segment,
};

mod common;
use common::{gpu, grow_on_gpu, mirror_roots};

/// A head of `count` strands: roots on the upper half of a unit sphere, each strand a
/// helix of its own radius and pitch hanging down and out, with 6 to 40 points.
fn groom(count: usize) -> Groom {
    let strands: Vec<Vec<Vec3>> = (0..count)
        .map(|i| {
            let a = i as f32 * 2.399_963; // golden angle
            let z = 1.0 - (i as f32 + 0.5) / count as f32;
            let r = (1.0 - z * z).sqrt();
            let root = Vec3::new(r * a.cos(), z, r * a.sin());
            let out = Vec3::new(root.x, 0.0, root.z).normalize_or_zero();
            let points = 6 + (i * 7) % 35;
            let curl = 0.02 + 0.03 * ((i % 5) as f32 / 4.0);
            (0..points)
                .map(|k| {
                    let s = k as f32 / (points - 1) as f32;
                    let phase = s * 9.0 + i as f32;
                    let side = out.cross(Vec3::Y);
                    root + out * (0.3 * s) - Vec3::Y * (0.9 * s)
                        + (side * phase.cos() + out * phase.sin()) * curl * s.min(0.1) * 10.0
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

fn size(resampled: &Resampled) -> f32 {
    let (lo, hi) = resampled.bounds();
    (hi - lo).length()
}

#[test]
fn without_wind_the_groom_comes_out_as_it_went_in() {
    let gpu = gpu();
    let resampled = groom(400).resample(12).unwrap();
    let mut strands = GroomStrands::new(&gpu, &resampled, &calm()).unwrap();
    let out = grow_on_gpu(&gpu, &mut strands, 3.5);
    let rest = strands.rest_points();
    assert_eq!(out.len(), rest.len());
    let worst = out
        .iter()
        .zip(rest)
        .map(|(g, r)| (g.truncate() - *r).abs().max_element())
        .fold(0.0f32, f32::max);
    println!("calm groom: max |GPU - rest| = {worst:.2e}");
    assert!(worst <= 1e-5 * size(&resampled), "{worst}");
    // The buffer holds every strand of the file once, shuffled, each with its own points.
    let mut sources = strands.source_strands().to_vec();
    sources.sort_unstable();
    assert_eq!(sources, (0..400).collect::<Vec<u32>>());
    assert_ne!(strands.source_strands(), &sources[..], "not shuffled");
    let per_strand = 13;
    for (index, &source) in strands.source_strands().iter().enumerate().step_by(37) {
        let file = &resampled.points[source as usize * per_strand..][..per_strand];
        assert_eq!(&rest[index * per_strand..][..per_strand], file);
    }
    // The strand parameter runs from 0 at the root to 1 at the tip.
    assert_eq!(out[0].w, 0.0);
    assert_eq!(out[12].w, 1.0);
}

#[test]
fn in_wind_the_gpu_matches_the_cpu_mirror_and_no_segment_stretches() {
    let gpu = gpu();
    let resampled = groom(300).resample(16).unwrap();
    let hair = windy();
    let mut strands = GroomStrands::new(&gpu, &resampled, &hair).unwrap();
    let tolerance = 1e-5 * size(&resampled);
    let reach = GroomStrands::reach_of(&resampled, &hair).unwrap();
    let rest = strands.rest_points().to_vec();
    let rest = rest.as_slice();
    let roots = mirror_roots(strands.roots());
    // The parameters the groom's strands amount to (segments, strand count), and the wind.
    let params = strands.params().clone();
    let mut moved = 0.0f32;
    for t in [0.0, 0.37, 5.0, 1234.5] {
        let gpu_vertices = grow_on_gpu(&gpu, &mut strands, t);
        let cpu = deform_groom(rest, &roots, &params, t, Level::full(&params));
        assert_eq!(gpu_vertices.len(), cpu.len());
        let worst = gpu_vertices
            .iter()
            .zip(&cpu)
            .map(|(g, c)| (*g - *c).abs().max_element())
            .fold(0.0f32, f32::max);
        println!("wind t={t}: max |GPU - CPU| = {worst:.2e}");
        assert!(worst <= tolerance, "t={t}: {worst} > {tolerance}");

        let mut stretch = 0.0f32;
        for (s, r) in gpu_vertices.chunks(17).zip(rest.chunks(17)) {
            assert_eq!(s[0].truncate(), r[0], "a root moved");
            for (sw, rw) in s.windows(2).zip(r.windows(2)) {
                let now = sw[0].truncate().distance(sw[1].truncate());
                let then = rw[0].distance(rw[1]);
                stretch = stretch.max((now - then).abs() / then);
            }
            moved = moved.max(s[16].truncate().distance(r[16]));
            for v in s {
                let p = v.truncate();
                assert!(
                    p.cmpge(reach.0).all() && p.cmple(reach.1).all(),
                    "{p} leaves the reach {reach:?}"
                );
            }
        }
        println!("wind t={t}: worst relative segment stretch {stretch:.2e}");
        assert!(stretch < 1e-4, "{stretch}");
    }
    println!("largest tip displacement {moved:.3}");
    assert!(moved > 0.05, "the wind does not move the groom ({moved})");
}

#[test]
fn level_of_detail_draws_a_prefix_with_seed_002_widths_within_the_segment_bound() {
    let gpu = gpu();
    let resampled = groom(600).resample(12).unwrap();
    let mut hair = windy();
    hair.lod.enabled = true;
    let mut strands = GroomStrands::new(&gpu, &resampled, &hair).unwrap();
    let full = grow_on_gpu(&gpu, &mut strands, 0.8);
    let params = strands.params().clone();
    let turn = bend_per_segment(&params.growth, &params.wind);
    let longest = strands
        .rest_points()
        .chunks(13)
        .flat_map(|s| s.windows(2).map(|w| w[0].distance(w[1])))
        .fold(0.0f32, f32::max);
    for (lambda, segments) in [(0.5, 6), (0.2, 4), (0.1, 3)] {
        let zone = Transition::new(lambda, params.lod.transition);
        let level = LodLevel {
            pixels: 0.0,
            extent_pixels: 0.0,
            zone,
            strands: zone.drawn(params.roots.count),
            segments,
            segment_error_pixels: 0.0,
        };
        strands.set_lod(level).unwrap();
        let reduced = grow_on_gpu(&gpu, &mut strands, 0.8);
        let roots = mirror_roots(strands.roots());
        let mirror_level = Level {
            strands: level.strands,
            segments,
        };
        let cpu = deform_groom(strands.rest_points(), &roots, &params, 0.8, mirror_level);
        assert_eq!(cpu.len() as u64, strands.frame().unwrap().layout.vertices());
        let worst = cpu
            .iter()
            .zip(&reduced)
            .map(|(c, g)| (*c - *g).abs().max_element())
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-5, "lambda {lambda}: {worst}");

        // Every kept vertex is the full strand's, and the full strand stays within the
        // rest chord error plus the wind's bend of the reduced one.
        let step = (12 / segments) as usize;
        let mut measured = 0.0f32;
        let mut rest_chord = 0.0f32;
        for (s, (f, r)) in reduced
            .chunks(segments as usize + 1)
            .zip(full.chunks(13).zip(strands.rest_points().chunks(13)))
            .take(level.strands as usize)
        {
            for (j, v) in s.iter().enumerate() {
                let d = (*v - f[j * step]).abs().max_element();
                assert!(d < 1e-6, "vertex {j}: {v} against {}: {d}", f[j * step]);
            }
            for k in 0..segments as usize {
                for i in 1..step {
                    let (a, b) = (s[k].truncate(), s[k + 1].truncate());
                    measured = measured.max(distance_to_segment(f[k * step + i].truncate(), a, b));
                    rest_chord = rest_chord.max(distance_to_segment(
                        r[k * step + i],
                        r[k * step],
                        r[(k + 1) * step],
                    ));
                }
            }
        }
        let bound = rest_chord + bend_error(step as u32, longest, turn);
        println!(
            "lambda {lambda}, {segments} segments: farthest full vertex {measured:.4} from the reduced strand, bound {bound:.4}"
        );
        assert!(measured <= bound * 1.0001 + 1e-6, "{measured} > {bound}");

        let bytes = read_buffer(&gpu, &strands.buffers().roots).unwrap();
        let drawn: Vec<StrandRoot> = encase::StorageBuffer::new(&bytes[..])
            .create()
            .expect("roots decode");
        for (i, (root, gpu_root)) in roots.iter().zip(drawn).enumerate() {
            if i as u32 >= level.strands {
                break;
            }
            let want = drawn_width(root, i as u32, params.roots.count, &zone);
            assert!((gpu_root.width - want).abs() <= 1e-6 * want.max(1.0));
        }
    }
}

fn distance_to_segment(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}

#[test]
fn a_straight_groom_is_reduced_further_than_a_curly_one() {
    let gpu = gpu();
    let straight: Vec<Vec<Vec3>> = (0..50)
        .map(|i| {
            vec![
                Vec3::X * i as f32 * 0.02,
                Vec3::X * i as f32 * 0.02 - Vec3::Y,
            ]
        })
        .collect();
    let straight = Groom::from_strands(&straight)
        .unwrap()
        .resample(12)
        .unwrap();
    let curly = groom(50).resample(12).unwrap();
    let mut hair = calm();
    hair.lod.enabled = true;
    let camera = pelage_scene::Camera {
        eye: Vec3::new(0.0, 0.0, 6.0),
        target: Vec3::ZERO,
        ..Default::default()
    };
    let level = |g: &Resampled| {
        let s = GroomStrands::new(&gpu, g, &hair).unwrap();
        let reach = GroomStrands::reach_of(g, &hair).unwrap();
        s.level_for_view(reach, &camera.matrices(320, 240), 320, 240)
    };
    let (a, b) = (level(&straight), level(&curly));
    println!(
        "straight: {} segments, curly: {} segments",
        a.segments, b.segments
    );
    assert_eq!(a.segments, 1, "a straight strand needs one segment");
    assert!(b.segments > a.segments);
    assert!(b.segment_error_pixels <= hair.lod.segment_error_pixels);
}

#[test]
fn inconsistent_grooms_are_refused_naming_what_is_wrong() {
    let gpu = gpu();
    let good = groom(10).resample(4).unwrap();
    let hair = HairParams::default();
    let cases: Vec<(Resampled, &str)> = vec![
        (
            Resampled {
                points: good.points[1..].to_vec(),
                ..good.clone()
            },
            "groom.points",
        ),
        (
            Resampled {
                points: {
                    let mut p = good.points.clone();
                    p[7].y = f32::NAN;
                    p
                },
                ..good.clone()
            },
            "groom.points",
        ),
        (
            Resampled {
                widths: Some(vec![0.01; 3]),
                ..good.clone()
            },
            "groom.widths",
        ),
        (
            Resampled {
                strands: 0,
                points: Vec::new(),
                ..good.clone()
            },
            "groom.strands",
        ),
        (
            Resampled {
                segments: 0,
                ..good.clone()
            },
            "groom.segments",
        ),
        // Finite but past what 32-bit squared distances hold: named, not blamed on
        // growth.length (the longest strand such points make).
        (
            Resampled {
                points: good.points.iter().map(|p| *p * 1e37).collect(),
                ..good.clone()
            },
            "groom.points",
        ),
    ];
    for (bad, name) in cases {
        match GroomStrands::new(&gpu, &bad, &hair) {
            Err(StrandsError::Param(e)) => assert_eq!(e.name, name, "{e}"),
            other => panic!("{name}: expected a parameter error, got {other:?}"),
        }
    }
    let mut nan_wind = HairParams::default();
    nan_wind.wind.strength = f32::NAN;
    assert!(matches!(
        GroomStrands::new(&gpu, &good, &nan_wind),
        Err(StrandsError::Param(e)) if e.name.starts_with("wind.")
    ));
}

/// A `.hair` file's per-point colours reach the strands: each strand takes its root
/// point's colour, in place of `growth.color`, in the roots the pass draws (the
/// colours were never read: an all-red file drew in `growth.color`).
#[test]
fn a_hair_files_colours_colour_the_strands() {
    let gpu = gpu();
    let strands: Vec<Vec<Vec3>> = (0..8)
        .map(|i| {
            (0..5)
                .map(|k| Vec3::new(i as f32, -(k as f32), 0.0))
                .collect()
        })
        .collect();
    let mut hair = pelage_scene::HairFile::from_strands(&strands).unwrap();
    hair.has_colors = true;
    // Red at every root, green further out: only the roots' colour is drawn.
    hair.colors = (0..hair.points.len())
        .map(|p| {
            if p % 5 == 0 {
                Vec3::new(0.8, 0.05, 0.02)
            } else {
                Vec3::Y
            }
        })
        .collect();
    let path = std::env::temp_dir().join(format!("pelage-red-{}.hair", std::process::id()));
    std::fs::write(&path, hair.write().unwrap()).unwrap();
    let source = pelage_scene::GroomSource::new(&path);
    let resampled = source.load().unwrap();
    std::fs::remove_file(&path).unwrap();
    let mut params = calm();
    params.growth.color = Vec3::new(0.1, 0.1, 0.9);
    params.growth.color_jitter = 0.0;
    let mut pass = GroomStrands::new(&gpu, &resampled, &params).unwrap();
    let red = Vec3::new(0.8, 0.05, 0.02);
    let file_colors = pass.file_colors().expect("the .hair file's colours");
    assert_eq!(file_colors.len(), 8);
    assert!(file_colors.iter().all(|&c| c == red), "{file_colors:?}");
    assert!(pass.roots().iter().all(|r| r.color == red));
    // The roots the GPU draws hold the file's colour too.
    grow_on_gpu(&gpu, &mut pass, 0.0);
    let bytes = read_buffer(&gpu, &pass.buffers().roots).unwrap();
    let drawn: Vec<StrandRoot> = encase::StorageBuffer::new(&bytes[..])
        .create()
        .expect("roots decode");
    assert_eq!(drawn.len(), 8);
    for root in drawn {
        assert!(
            (root.color - red).abs().max_element() < 1e-6,
            "{}",
            root.color
        );
    }
}
