//! The strand rasterizer (`StrandRaster`, `shade/oit/strand_raster.wgsl`) on a real
//! adapter: against the exact composite, its CPU mirror, and the regimes where a
//! compute rasterizer breaks (huge and sub-pixel segments, the near plane, overflow).

mod support;

use pelage_gpu::{Gpu, wgpu};
use pelage_reference::strand_raster as mirror;
use pelage_scene::{Camera, Light, Transparency};
use pelage_shade::{
    HairInputs, HairPass, OitStats, RasterCapture, StrandRaster, TargetFormat, Targets,
};
use pelage_strands::{MeshBuffers, StrandBuffers, StrandFrame, StrandStage};
use support::*;

#[test]
fn draws_the_creature_close_to_exact() {
    let gpu = gpu();
    for opacity in [0.3, 0.8] {
        let s = scene(&gpu, 3000, opacity, Camera::default());
        let truth = exact(&gpu, &s);
        let (raster, stats) = render(&gpu, &s, Transparency::strand_raster());
        let (k8, _) = render(&gpu, &s, Transparency::k_buffer(8));
        let fr = mean_flip(&truth.image, &raster);
        let fk = mean_flip(&truth.image, &k8);
        println!(
            "opacity {opacity}: mean FLIP strand raster {fr:.4}, k-buffer k=8 {fk:.4}; {stats:?}"
        );
        let differs = (0..truth.depth.len())
            .filter(|&p| raster[4 * p..4 * p + 3] != truth.background[4 * p..4 * p + 3])
            .count();
        println!("  {differs} pixels differ from the background");
        // Measured 0.0034 and 0.0049 (k=8: 0.0024): analytic coverage against the
        // widened ribbons the exact composite is made of.
        assert!(fr < 0.01, "opacity {opacity}: mean FLIP {fr}");
    }
}

/// One frame of `StrandRaster` against its CPU mirror (`pelage_reference::strand_raster`):
/// every cell's list equal exactly, the composite within 1/255. The depth target is the
/// test's own (with `COPY_SRC`, so the opaque depth `cs_fine` tested against is read
/// back); with `draw_mesh` the creature's body occludes part of the hair.
fn against_the_mirror(
    gpu: &Gpu,
    name: &str,
    s: &Scene,
    (tile, bins): (u32, u32),
    reverse_z: bool,
    draw_mesh: bool,
) {
    let drawn = Drawn {
        mesh: &s.buffers,
        strands: s.strands.buffers(),
        frame: &s.frame,
        camera: &s.camera,
    };
    let checked = mirror_frame(gpu, name, &drawn, (tile, bins, 64.0), reverse_z, draw_mesh);
    let references: usize = checked.capture.cells.iter().map(Vec::len).sum();
    let pixels = checked
        .capture
        .composite
        .iter()
        .filter(|p| p[3] > 0.0)
        .count();
    assert!(
        references > 1000 && pixels > 300,
        "{name}: too little to compare: {references} references, {pixels} pixels drawn"
    );
    assert_eq!(
        checked.stats.dropped, 0,
        "{name}: the pool overflowed: {:?}",
        checked.stats
    );
}

/// What a frame is drawn from.
struct Drawn<'a> {
    mesh: &'a MeshBuffers,
    strands: &'a StrandBuffers,
    frame: &'a StrandFrame,
    camera: &'a Camera,
}

/// What [`mirror_frame`] found.
struct Checked {
    capture: RasterCapture,
    stats: OitStats,
}

/// Draws one frame at W x H and checks it against the mirror (see [`against_the_mirror`]).
fn mirror_frame(
    gpu: &Gpu,
    name: &str,
    s: &Drawn<'_>,
    (tile, bins, pool): (u32, u32, f32),
    reverse_z: bool,
    draw_mesh: bool,
) -> Checked {
    let p = params(Transparency::StrandRaster { tile, bins, pool });
    let target = TargetFormat {
        reverse_z,
        ..TargetFormat::for_params(&p)
    };
    let hair = HairInputs {
        params: &p,
        mesh: s.mesh,
        strands: s.strands,
        shadows: &[],
        visibility: None,
        target,
        draw_mesh,
        grid_apart: false,
    };
    let raster = StrandRaster::new(gpu, &hair, tile, bins, pool, W, H).unwrap();
    let targets = Targets::with_format(gpu, W, H, &target).unwrap();
    let depth = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("mirror test depth"),
        size: wgpu::Extent3d {
            width: W,
            height: H,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: target.depth,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let depth_view = depth.create_view(&Default::default());
    let camera = if reverse_z {
        s.camera.matrices_reverse_z(W, H)
    } else {
        s.camera.matrices(W, H)
    };
    raster
        .prepare(&gpu.queue, s.frame, &camera, &[Light::default()], W, H)
        .unwrap();
    let (color, resolve) = targets.color_views();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    raster
        .encode(
            &mut encoder,
            s.frame,
            &targets.views(&color, resolve.as_ref(), &depth_view),
            None,
        )
        .unwrap();
    gpu.submit_and_wait([encoder.finish()]).unwrap();
    let stats = raster.stats(gpu).unwrap();
    // An overflowing pool holds part of the lists (which part is the atomics' order).
    assert_eq!(stats.dropped, 0, "{name}: the pool overflowed: {stats:?}");
    let capture = raster.capture(gpu).unwrap();
    let opaque: Vec<f32> = pelage_gpu::read_texture(gpu, &depth)
        .unwrap()
        .data
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    assert_eq!(opaque.len(), (W * H) as usize);

    let u = capture.uniforms;
    let mp = mirror::RasterParams {
        width: u.width,
        height: u.height,
        tile: u.tile,
        tiles_x: u.tiles_x,
        tiles_y: u.tiles_y,
        bins: u.bins,
        capacity: u.capacity,
        bin_near: u.bin_near,
        bin_scale: u.bin_scale,
        opacity: u.opacity,
        reverse_z: u.reverse_z != 0,
    };
    let segments: Vec<mirror::RasterSegment> = capture.segments.iter().map(|&v| v.into()).collect();
    let live = segments.iter().filter(|s| !s.culled()).count();

    // Binning: every cell's list exactly the mirror's, in its order (cs_sort sorts
    // each cell by segment index, as the mirror lists them).
    let cells = mirror::bin(&mp, &segments, &opaque).unwrap();
    assert_eq!(cells.len(), capture.cells.len(), "{name}: cell count");
    let mut references = 0;
    let mut mismatched = Vec::new();
    // Cells longer than the sort takes stay in the scatter's order: compared as sets.
    let mut unsorted = 0u64;
    for (c, (gpu_list, cpu_list)) in capture.cells.iter().zip(&cells).enumerate() {
        references += gpu_list.len();
        let mut list = gpu_list.clone();
        if list.len() > SORT_MAX {
            list.sort_unstable();
            unsorted += 1;
        }
        if &list != cpu_list {
            mismatched.push(c);
        }
    }
    assert_eq!(
        raster.unsorted_cells(gpu).unwrap(),
        unsorted,
        "{name}: cells left unsorted"
    );
    let longest = cells.iter().map(Vec::len).max().unwrap_or(0);
    let occupied = cells.iter().filter(|c| !c.is_empty()).count();
    println!(
        "{name}: tile {tile}, bins {bins}, reverse_z {reverse_z}, mesh {draw_mesh}: {} segments ({live} drawn), {} cells ({occupied} occupied, longest {longest}), {references} references compared",
        segments.len(),
        cells.len(),
    );
    for &c in mismatched.iter().take(5) {
        let (g, m) = (&capture.cells[c], &cells[c]);
        let only_gpu: Vec<_> = g.iter().filter(|s| !m.contains(s)).collect();
        let only_cpu: Vec<_> = m.iter().filter(|s| !g.contains(s)).collect();
        println!("  cell {c}: only on the GPU {only_gpu:?}, only in the mirror {only_cpu:?}");
    }
    assert!(
        mismatched.is_empty(),
        "{name}: {} of {} cells differ from the mirror",
        mismatched.len(),
        cells.len()
    );
    println!(
        "{name}: {} cells, {references} references equal",
        cells.len()
    );

    // Compositing: from the GPU's cells (what cs_fine read: the mirror's, but for the
    // order of cells left unsorted).
    let drawn = capture.composite.iter().filter(|p| p[3] > 0.0).count();
    let from_mirror = mirror::composite(&mp, &segments, &capture.cells, &opaque).unwrap();
    assert_eq!(from_mirror.len(), capture.composite.len());
    let largest = from_mirror
        .iter()
        .zip(&capture.composite)
        .flat_map(|(a, b)| (0..4).map(move |k| (a[k] - b[k]).abs()))
        .fold(0.0f32, f32::max);
    // The GPU stores rgba16float: where its float operations agree with the mirror's
    // (no fused multiply-adds), the mirror rounded to f16 matches bit for bit.
    let same = from_mirror
        .iter()
        .zip(&capture.composite)
        .filter(|(a, b)| (0..4).all(|k| f16_of(a[k], b[k])))
        .count();
    println!(
        "  {drawn} pixels drawn; largest composite difference {largest:.2e}; {same} of {} pixels equal after rounding to f16",
        capture.composite.len()
    );
    assert!(
        largest <= 1.0 / 255.0,
        "{name}: composite differs by {largest}"
    );
    Checked { capture, stats }
}

/// The longest cell `cs_sort` sorts (`SORT_MAX` in the WGSL).
const SORT_MAX: usize = 1024;

/// Whether `gpu` is `v` rounded to f16 toward zero or to the nearest (ties to even):
/// the rgba16float store may do either (lavapipe truncates). No overflow handling: the
/// composite stays far below 65504.
fn f16_of(v: f32, gpu: f32) -> bool {
    if v == 0.0 || !v.is_finite() {
        return v == gpu;
    }
    let exponent = ((v.to_bits() >> 23) & 0xff) as i32 - 127;
    let ulp = 2f32.powi(exponent.max(-14) - 10);
    (v / ulp).trunc() * ulp == gpu || (v / ulp).round_ties_even() * ulp == gpu
}

#[test]
fn binning_and_compositing_match_the_cpu_mirror() {
    let gpu = gpu();
    let creature = scene(&gpu, 1000, 0.5, Camera::default());
    for (tile, bins) in [(8, 1), (8, 16), (16, 1), (16, 16)] {
        against_the_mirror(&gpu, "creature", &creature, (tile, bins), false, true);
    }
    against_the_mirror(&gpu, "creature, no mesh", &creature, (16, 16), false, false);
    against_the_mirror(&gpu, "creature, reverse-Z", &creature, (16, 16), true, true);
    let long = long_hair(&gpu, 0.3);
    for (tile, bins) in [(8, 16), (16, 1), (16, 16)] {
        against_the_mirror(&gpu, "long hair", &long, (tile, bins), false, true);
    }
}

/// Strands placed by hand: each a polyline (all of the same length) with its width.
struct Hand {
    mesh: MeshBuffers,
    strands: StrandBuffers,
    frame: StrandFrame,
}

fn by_hand(gpu: &Gpu, lines: &[(Vec<glam::Vec3>, f32)], opacity: f32) -> Hand {
    use glam::{Vec3, Vec4};
    let segments = lines[0].0.len() - 1;
    let mut vertices: Vec<Vec4> = Vec::new();
    let mut roots = Vec::new();
    for (i, (points, width)) in lines.iter().enumerate() {
        assert_eq!(points.len(), segments + 1);
        for (k, p) in points.iter().enumerate() {
            vertices.push(p.extend(k as f32 / segments as f32));
        }
        roots.push(pelage_strands::StrandRoot {
            triangle: 0,
            seed: 0x9e37_79b9 ^ i as u32,
            bary: glam::Vec2::ZERO,
            length: 1.0,
            width: *width,
            phase: 0.0,
            tilt: 0.0,
            azimuth: 0.0,
            color: Vec3::new(0.8, 0.5, 0.3),
            region: 0,
        });
    }
    let usage = wgpu::BufferUsages::STORAGE;
    let vertex_buffer = pelage_gpu::storage_buffer(gpu, "hand vertices", &vertices, usage).unwrap();
    let root_buffer = pelage_gpu::storage_buffer(gpu, "hand roots", &roots, usage).unwrap();
    let widest = lines.iter().map(|l| l.1).fold(0.0, f32::max);
    let style = pelage_strands::StrandStyle {
        width: widest,
        max_width: widest,
        tip_width: 1.0,
        opacity,
    };
    let (lo, hi) = vertices
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v.truncate()), hi.max(v.truncate()))
        });
    let mesh = MeshBuffers::upload(gpu, &pelage_scene::Mesh::icosphere(0.05, 1).unwrap()).unwrap();
    let strands = StrandBuffers::new(
        vertex_buffer,
        root_buffer,
        lines.len() as u32,
        segments as u32,
        style,
        (lo - Vec3::splat(widest), hi + Vec3::splat(widest)),
    )
    .unwrap();
    Hand {
        mesh,
        frame: StrandFrame::next(strands.full_layout()),
        strands,
    }
}

fn looking_down_z() -> Camera {
    Camera {
        eye: glam::Vec3::new(0.0, 0.0, 3.0),
        target: glam::Vec3::ZERO,
        ..Default::default()
    }
}

/// A straight strand of `segments` segments from `a` to `b`.
fn line(a: glam::Vec3, b: glam::Vec3, segments: usize, width: f32) -> (Vec<glam::Vec3>, f32) {
    (
        (0..=segments)
            .map(|k| a.lerp(b, k as f32 / segments as f32))
            .collect(),
        width,
    )
}

#[test]
fn a_segment_across_the_whole_screen_is_drawn_from_edge_to_edge() {
    // One strand far wider than the view, a single segment, crossing every tile column.
    let gpu = gpu();
    let camera = looking_down_z();
    let hand = by_hand(
        &gpu,
        &[line(
            glam::Vec3::new(-50.0, 0.1, 0.0),
            glam::Vec3::new(50.0, -0.1, 0.0),
            1,
            0.02,
        )],
        0.9,
    );
    let drawn = Drawn {
        mesh: &hand.mesh,
        strands: &hand.strands,
        frame: &hand.frame,
        camera: &camera,
    };
    for tile in [8, 16] {
        let c = mirror_frame(
            &gpu,
            "across the screen",
            &drawn,
            (tile, 4, 4.0),
            false,
            false,
        );
        // Alpha summed down a column: opacity x the width in pixels.
        let pixel = 2.0 * (0.5 * camera.fov_y).tan() * 3.0 / H as f32;
        let expected = 0.9 * 0.02 / pixel;
        let columns = (0..W)
            .filter(|&x| {
                let sum: f32 = (0..H)
                    .map(|y| c.capture.composite[(y * W + x) as usize][3])
                    .sum();
                (sum - expected).abs() < 0.05 * expected
            })
            .count();
        println!("tile {tile}: {columns} of {W} columns drawn");
        let sums: Vec<String> = (0..W)
            .map(|x| {
                let sum: f32 = (0..H)
                    .map(|y| c.capture.composite[(y * W + x) as usize][3])
                    .sum();
                format!("{sum:.2}")
            })
            .collect();
        println!("expected {expected}: {}", sums.join(" "));
        assert_eq!(columns, W as usize, "tile {tile}: the strand has gaps");
        assert_eq!(c.stats.dropped, 0);
    }
}

#[test]
fn a_tile_holding_a_whole_groom_is_drawn_exactly_and_within_its_pool() {
    // The long-hair groom (96 000 segments) seen from far away: a few tiles hold it all.
    let gpu = gpu();
    let s = long_hair(&gpu, 0.5);
    let far = Camera {
        eye: s.camera.eye * 25.0,
        far: 200.0,
        ..s.camera.clone()
    };
    let drawn = Drawn {
        mesh: &s.buffers,
        strands: s.strands.buffers(),
        frame: &s.frame,
        camera: &far,
    };
    let c = mirror_frame(&gpu, "groom in a tile", &drawn, (16, 16, 4.0), false, true);
    let tiles = c.capture.uniforms.tiles_x * c.capture.uniforms.tiles_y;
    let per_tile: Vec<usize> = (0..tiles as usize)
        .map(|t| (0..16).map(|b| c.capture.cells[t * 16 + b].len()).sum())
        .collect();
    let fullest = per_tile.iter().max().copied().unwrap_or(0);
    println!("fullest tile: {fullest} segments; {:?}", c.stats);
    assert!(
        fullest > 20_000,
        "no tile holds most of the groom: {fullest}"
    );
    assert_eq!(c.stats.dropped, 0);
}

#[test]
fn strands_through_the_near_plane_are_clipped_and_those_behind_the_eye_culled() {
    let gpu = gpu();
    let camera = looking_down_z();
    // Through the eye's plane (z = 3), crossing the near plane (0.01 in front of it);
    // wholly behind the eye; and one in front for reference.
    let hand = by_hand(
        &gpu,
        &[
            line(
                glam::Vec3::new(-0.05, -0.05, 0.0),
                glam::Vec3::new(0.02, 0.02, 4.0),
                4,
                0.01,
            ),
            line(
                glam::Vec3::new(-0.5, 0.0, 3.5),
                glam::Vec3::new(0.5, 0.0, 5.0),
                4,
                0.01,
            ),
            line(
                glam::Vec3::new(-0.5, 0.3, 0.0),
                glam::Vec3::new(0.5, 0.3, 0.0),
                4,
                0.01,
            ),
        ],
        0.8,
    );
    let drawn = Drawn {
        mesh: &hand.mesh,
        strands: &hand.strands,
        frame: &hand.frame,
        camera: &camera,
    };
    for reverse_z in [false, true] {
        let c = mirror_frame(&gpu, "near plane", &drawn, (8, 8, 64.0), reverse_z, false);
        let culled: Vec<usize> = (0..c.capture.segments.len())
            .filter(|&s| c.capture.segments[s][3] < 0.0)
            .collect();
        let finite = c.capture.composite.iter().flatten().all(|v| v.is_finite());
        let drawn_px = c.capture.composite.iter().filter(|p| p[3] > 0.0).count();
        println!("reverse_z {reverse_z}: culled segments {culled:?}, {drawn_px} pixels drawn");
        assert!(finite, "non-finite composite");
        // The strand behind the eye (segments 4..8) is culled whole; the one through the
        // near plane loses its last segment (from z = 3 to 4: behind the eye).
        assert!((4..8).all(|s| culled.contains(&s)), "{culled:?}");
        assert!(culled.contains(&3) && !culled.contains(&2), "{culled:?}");
        assert!(drawn_px > 100);
    }
}

#[test]
fn sub_pixel_strands_fade_and_wide_strands_cover_by_their_true_width() {
    // Horizontal strands across the view at z = 0, 3 units from the eye: 1 pixel is
    // about 0.031 units at 128x96 (fov 45 degrees).
    let gpu = gpu();
    let camera = looking_down_z();
    let pixel = 2.0 * (0.5 * camera.fov_y).tan() * 3.0 / H as f32;
    for (name, width_px) in [("sub-pixel", 0.2f32), ("wide", 100.0f32)] {
        let hand = by_hand(
            &gpu,
            &[line(
                glam::Vec3::new(-0.8, 0.013, 0.0),
                glam::Vec3::new(0.8, 0.013, 0.0),
                8,
                width_px * pixel,
            )],
            0.6,
        );
        let drawn = Drawn {
            mesh: &hand.mesh,
            strands: &hand.strands,
            frame: &hand.frame,
            camera: &camera,
        };
        // The wide strand touches every tile: 8 segments x 192 tiles.
        let c = mirror_frame(&gpu, name, &drawn, (8, 4, 256.0), false, false);
        // Alpha summed down a column in the middle: opacity x the covered width in
        // pixels (capped at opacity per pixel).
        let x = W / 2;
        let column: f32 = (0..H)
            .map(|y| c.capture.composite[(y * W + x) as usize][3])
            .sum();
        let expected = 0.6 * width_px.min(H as f32);
        println!("{name}: column alpha {column:.3}, expected {expected:.3}");
        assert!(
            (column - expected).abs() < 0.05 * expected + 0.01,
            "{name}: {column} against {expected}"
        );
    }
}

#[test]
fn an_8192_square_target_dispatches_its_tiles_in_two_dimensions() {
    // 512 x 512 tiles of 16: more workgroups than one dimension of a dispatch holds
    // (65 535). A strand in each corner must be drawn, the last tile's included.
    let gpu = gpu();
    let size = 8192;
    let camera = looking_down_z();
    let half_height = (0.5 * camera.fov_y).tan() * 3.0;
    let corner = |sx: f32, sy: f32| {
        let c = glam::Vec3::new(sx * half_height * 0.98, sy * half_height * 0.98, 0.0);
        line(
            c - glam::Vec3::new(0.01, 0.0, 0.0),
            c + glam::Vec3::new(0.01, 0.0, 0.0),
            2,
            0.001,
        )
    };
    let hand = by_hand(
        &gpu,
        &[
            corner(-1.0, -1.0),
            corner(1.0, -1.0),
            corner(-1.0, 1.0),
            corner(1.0, 1.0),
        ],
        1.0,
    );
    let p = params(Transparency::strand_raster());
    let target = TargetFormat::for_params(&p);
    let inputs = HairInputs {
        params: &p,
        mesh: &hand.mesh,
        strands: &hand.strands,
        shadows: &[],
        visibility: None,
        target,
        draw_mesh: false,
        grid_apart: false,
    };
    let raster = StrandRaster::new(&gpu, &inputs, 16, 4, 4.0, size, size).unwrap();
    let targets = Targets::with_format(&gpu, size, size, &target).unwrap();
    raster
        .prepare(
            &gpu.queue,
            &hand.frame,
            &camera.matrices(size, size),
            &[Light::default()],
            size,
            size,
        )
        .unwrap();
    let (color, resolve) = targets.color_views();
    let depth = targets.depth_view();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    raster
        .encode(
            &mut encoder,
            &hand.frame,
            &targets.views(&color, resolve.as_ref(), &depth),
            None,
        )
        .unwrap();
    gpu.submit_and_wait([encoder.finish()]).unwrap();
    let capture = raster.capture(&gpu).unwrap();
    let n = size as usize;
    let quadrant = |qx: usize, qy: usize| {
        (0..n / 2)
            .flat_map(|y| (0..n / 2).map(move |x| (qy * n / 2 + y) * n + qx * n / 2 + x))
            .filter(|&i| capture.composite[i][3] > 0.0)
            .count()
    };
    let counts = [
        quadrant(0, 0),
        quadrant(1, 0),
        quadrant(0, 1),
        quadrant(1, 1),
    ];
    println!("pixels drawn per quadrant: {counts:?}");
    assert!(counts.iter().all(|&c| c > 10), "{counts:?}");
}

#[test]
fn an_empty_frame_leaves_the_picture_alone() {
    // The camera turned away from every strand: all culled, nothing binned.
    let gpu = gpu();
    let s = scene(&gpu, 500, 0.8, Camera::default());
    let away = Camera {
        target: s.camera.eye * 2.0,
        ..s.camera.clone()
    };
    let drawn = Drawn {
        mesh: &s.buffers,
        strands: s.strands.buffers(),
        frame: &s.frame,
        camera: &away,
    };
    let c = mirror_frame(&gpu, "empty", &drawn, (16, 16, 4.0), false, false);
    assert!(c.capture.cells.iter().all(Vec::is_empty));
    assert!(c.capture.composite.iter().all(|p| *p == [0.0; 4]));
    assert_eq!(c.stats.stored, 0);
}

#[test]
fn a_pool_ten_times_too_small_drops_a_frame_visibly_then_grows() {
    let gpu = gpu();
    let s = long_hair(&gpu, 0.5);
    let truth = exact(&gpu, &s);
    // Long hair needs about 1.2 references per segment at tiles of 16: 0.12 is 10x short.
    let p = params(Transparency::StrandRaster {
        tile: 16,
        bins: 16,
        pool: 0.12,
    });
    let raster = StrandRaster::new(&gpu, &inputs(&s, &p), 16, 16, 0.12, W, H).unwrap();
    let before = raster.capacity();
    let (first, stats1) = render_with(&gpu, &s, &raster, 1);
    let (second, stats2) = render_with(&gpu, &s, &raster, 1);
    // The same tiles and bins with a pool that holds everything from the start.
    let (whole, _) = render(
        &gpu,
        &s,
        Transparency::StrandRaster {
            tile: 16,
            bins: 16,
            pool: 4.0,
        },
    );
    let f1 = mean_flip(&truth.image, &first);
    let f2 = mean_flip(&truth.image, &second);
    let fw = mean_flip(&truth.image, &whole);
    let same = mean_flip(&whole, &second);
    println!(
        "capacity {before}: frame 1 FLIP {f1:.4}, {stats1:?}; frame 2 FLIP {f2:.4}, {stats2:?}; \
         a pool holding everything: FLIP {fw:.4}, against frame 2 {same:.4}"
    );
    assert!(
        stats1.peak_nodes >= 8 * u64::from(before),
        "not 10x short: {stats1:?}"
    );
    assert_eq!(stats1.overflowed_frames, 1);
    assert_eq!(stats1.dropped, stats1.peak_nodes - u64::from(before));
    // The overflowing frame is visibly wrong, the next one (grown pool) is not.
    assert!(f1 > 3.0 * f2, "overflow invisible: {f1} against {f2}");
    assert_eq!(
        stats2.overflowed_frames, 1,
        "the second frame overflowed too"
    );
    assert!(stats2.capacity >= stats1.peak_nodes);
    // Equal: every cell is sorted by segment index, whatever the pool's size.
    assert!(
        second == whole,
        "the grown pool's frame differs: FLIP {same}"
    );
}

#[test]
fn the_same_frame_renders_the_same_bytes_twice() {
    // Long hair: dense cells, many fragments per pixel and bin (the window overflows),
    // and references scattered by racing atomics. Two frames of one method, and a frame
    // of a second method built alike, must be the same bytes.
    let gpu = gpu();
    for opacity in [0.3, 0.8] {
        let s = long_hair(&gpu, opacity);
        for tile in [8, 16] {
            let t = Transparency::StrandRaster {
                tile,
                bins: 64,
                pool: 4.0,
            };
            let p = params(t.clone());
            let method = pelage_shade::build(&gpu, &inputs(&s, &p), W, H).unwrap();
            let (first, stats) = render_with(&gpu, &s, method.as_ref(), 1);
            let (second, _) = render_with(&gpu, &s, method.as_ref(), 1);
            let (other, _) = render(&gpu, &s, t);
            let differ = |a: &[u8], b: &[u8]| {
                a.chunks_exact(4)
                    .zip(b.chunks_exact(4))
                    .filter(|(x, y)| x != y)
                    .count()
            };
            let drawn = first.chunks_exact(4).filter(|p| p[3] > 0).count();
            println!(
                "opacity {opacity}, tile {tile}: {drawn} pixels drawn, {} and {} differ \
                 (second frame, second method); {stats:?}",
                differ(&first, &second),
                differ(&first, &other),
            );
            assert!(stats.peak_nodes > 100_000, "too little hair: {stats:?}");
            assert_eq!(stats.dropped, 0);
            assert!(
                first == second,
                "opacity {opacity}, tile {tile}: frames differ"
            );
            assert!(
                first == other,
                "opacity {opacity}, tile {tile}: methods differ"
            );
        }
    }
}
