//! Voxel shadows on a real adapter: the scan against its CPU mirror, transmittance
//! against ray tracing through the real strands, self-shadowing and saturation.

mod common;

use common::*;
use glam::Vec3;
use pelage_gpu::{Gpu, read_buffer, wgpu};
use pelage_reference::voxel::exclusive_scan_column;
use pelage_scene::{GrowthParams, HairParams, Mesh, Splat, VoxelParams, WindParams};
use pelage_shadow::{ShadowMethod, TransmittanceProbe, VoxelShadow};
use pelage_strands::{GrowStrands, StrandBuffers, StrandStage};

/// The voxel method on `strands` alone (a dummy mesh, no mesh map needed), reach box `reach`.
fn isolated(
    gpu: &Gpu,
    params: &VoxelParams,
    growth: &GrowthParams,
    strands: &StrandBuffers,
    reach: (Vec3, Vec3),
) -> Result<VoxelShadow, pelage_shadow::ShadowError> {
    VoxelShadow::new(
        gpu,
        params,
        &styled(strands, growth),
        &dummy_mesh(gpu),
        reach,
    )
}

fn voxel_params(resolution: u32) -> VoxelParams {
    VoxelParams {
        resolution: [resolution; 3],
        mesh_map_size: 0,
        ..VoxelParams::default()
    }
}

#[test]
fn scan_equals_cpu_scan_on_columns_of_every_length() {
    let gpu = gpu();
    let strands = strand_buffers(&gpu, &[vec![Vec3::ZERO, Vec3::X]], 0.01);
    let (rx, ry, rz) = (9u32, 7u32, 40u32);
    let params = VoxelParams {
        resolution: [rx, ry, rz],
        mesh_map_size: 0,
        ..VoxelParams::default()
    };
    let shadow = isolated(
        &gpu,
        &params,
        &growth(0.01, 0.5),
        &strands,
        (Vec3::ZERO, Vec3::ONE),
    )
    .unwrap();
    let layers = rz + 1;
    // Column c has random densities in its first c % (layers + 1) layers: every length
    // from 0 to the whole column. Every fifth column holds huge values, so it saturates.
    let mut h = 12345u32;
    let mut columns = vec![vec![0u32; layers as usize]; (rx * ry) as usize];
    for (c, column) in columns.iter_mut().enumerate() {
        let length = c % (layers as usize + 1);
        for v in column.iter_mut().take(length) {
            h = pelage_strands::pcg_hash(h);
            *v = if c % 5 == 4 {
                u32::MAX / 3 + (h >> 4)
            } else {
                h >> 12
            };
        }
    }
    let mut volume = vec![0u32; (rx * ry * layers) as usize];
    for (c, column) in columns.iter().enumerate() {
        for (z, &v) in column.iter().enumerate() {
            volume[z * (rx * ry) as usize + c] = v;
        }
    }
    gpu.queue
        .write_buffer(shadow.volume(), 0, bytemuck::cast_slice(&volume));
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    shadow.encode_scan(&mut encoder, None);
    gpu.submit_and_wait([encoder.finish()]).unwrap();
    let scanned: Vec<f32> =
        bytemuck::cast_slice(&read_buffer(&gpu, shadow.volume()).unwrap()).to_vec();
    let mut saturated = 0;
    for (c, column) in columns.iter().enumerate() {
        let expected = exclusive_scan_column(column, shadow.base_uniforms().inv_fixed_scale);
        for (z, e) in expected.iter().enumerate() {
            let got = scanned[z * (rx * ry) as usize + c];
            assert_eq!(
                got.to_bits(),
                e.to_bits(),
                "column {c}, layer {z}: GPU {got}, CPU {e}"
            );
        }
        saturated += usize::from(
            *expected.last().unwrap() == u32::MAX as f32 * shadow.base_uniforms().inv_fixed_scale,
        );
    }
    assert!(
        saturated >= 5,
        "only {saturated} columns saturated: the test does not cover saturation"
    );
}

/// RMSE and p95 of voxel transmittance against the reference.
fn voxel_error(gpu: &Gpu, r: &Reference, params: &VoxelParams) -> (f32, f32) {
    let shadow = VoxelShadow::new(
        gpu,
        params,
        r.strands.buffers(),
        &r.mesh_buffers,
        (Vec3::ZERO, Vec3::ONE),
    )
    .unwrap();
    error(gpu, r, &shadow)
}

#[test]
fn transmittance_matches_ray_tracing_and_improves_with_resolution() {
    let gpu = gpu();
    let (long_mesh, long) = long_hair();
    let scenes = [
        ("default fur", Mesh::creature(), HairParams::default()),
        ("long hair", long_mesh, long),
    ];
    for (name, mesh, mut hair) in scenes {
        hair.wind = WindParams::calm();
        let r = reference(&gpu, &mesh, &hair);
        let mean = r.truth.iter().sum::<f32>() / r.truth.len() as f32;
        println!(
            "{name}: {} vertices, mean reference T {mean:.3}",
            r.truth.len()
        );
        let mut previous = f32::INFINITY;
        for resolution in [32, 64, 128] {
            let (rmse, p95) = voxel_error(&gpu, &r, &voxel_params(resolution));
            println!("{name} {resolution}^3: RMSE {rmse:.4}, p95 {p95:.4}");
            assert!(
                rmse < previous,
                "{name}: error did not fall from {previous} at {resolution}^3 ({rmse})"
            );
            previous = rmse;
        }
        assert!(previous < 0.1, "{name}: RMSE {previous} at 128^3");
    }
}

#[test]
fn an_isolated_strand_does_not_shadow_itself() {
    let gpu = gpu();
    let to_light = light().to_light().unwrap();
    // Straight strands at several angles to the light, 1 unit long, 32 segments, at the
    // default bias. At 45 degrees or more the strand must not shadow itself (T >= 0.99);
    // closer to the light's direction the voxels it fills lie in front of its own
    // lookups: the measured floor there is asserted too, so a regression shows.
    for (angle_deg, floor) in [
        (90.0f32, 0.99),
        (75.0, 0.99),
        (60.0, 0.99),
        (45.0, 0.99),
        (30.0, 0.975),
    ] {
        let across = to_light.cross(Vec3::Z).normalize();
        let (sin, cos) = angle_deg.to_radians().sin_cos();
        let dir = (across * sin + to_light * cos).normalize();
        let strand: Vec<Vec3> = (0..=32).map(|i| dir * (i as f32 / 32.0)).collect();
        let buffers = strand_buffers(&gpu, &[strand], 0.005);
        for resolution in [64, 128] {
            let params = voxel_params(resolution);
            let shadow = isolated(
                &gpu,
                &params,
                &growth(0.005, 0.8),
                &buffers,
                (Vec3::ZERO, Vec3::ONE),
            )
            .unwrap();
            let t = transmittance(&gpu, &shadow, &buffers);
            let worst = t.iter().copied().fold(1.0f32, f32::min);
            println!(
                "isolated strand at {angle_deg} deg to the light, {resolution}^3: min T {worst:.4}"
            );
            assert!(
                worst >= floor,
                "strand at {angle_deg} deg shadows itself: T = {worst} < {floor}"
            );
        }
    }
}

/// The body under a thin layer of hair (three rows of strands across the light, 0.04
/// deep, within the lookup's 1.5-voxel bias at 32³): `surface_visibility`, the mesh
/// pass's, counts the whole layer right behind it, as far behind it; `light_visibility`
/// (a fibre's, read 1.5 voxels toward the light so a strand does not shadow itself)
/// skips most of it there.
#[test]
fn the_body_right_behind_the_hair_is_shadowed_by_all_of_it() {
    let gpu = gpu();
    let to_light = light().to_light().unwrap();
    let across = to_light.cross(Vec3::Z).normalize();
    let side = to_light.cross(across).normalize();
    let mut strands = Vec::new();
    for row in 0..3 {
        for k in 0..40 {
            let offset = side * (k as f32 * 0.025 - 0.5) - to_light * (row as f32 * 0.02);
            let strand: Vec<Vec3> = (0..=16)
                .map(|i| offset + across * (i as f32 / 16.0 - 0.5))
                .collect();
            strands.push(strand);
        }
    }
    let buffers = strand_buffers(&gpu, &strands, 0.005);
    let shadow = isolated(
        &gpu,
        &voxel_params(32),
        &growth(0.005, 0.8),
        &buffers,
        (Vec3::splat(-1.0), Vec3::splat(1.0)),
    )
    .unwrap();
    // Points behind the layer (away from the light), over its middle: 0.01 behind the
    // last row, and 0.5 behind it.
    let points = |behind: f32| -> Vec<glam::Vec4> {
        (0..100)
            .map(|i| {
                let (u, v) = ((i % 10) as f32 / 10.0 - 0.45, (i / 10) as f32 / 10.0 - 0.45);
                (across * u * 0.6 + side * v * 0.6 - to_light * (0.04 + behind)).extend(0.0)
            })
            .collect()
    };
    let probe = |surface: bool, p: &[glam::Vec4]| -> f32 {
        let points =
            pelage_gpu::storage_buffer(&gpu, "points", p, wgpu::BufferUsages::STORAGE).unwrap();
        let out = pelage_gpu::zeroed_storage(
            &gpu,
            "visibility",
            4 * p.len() as u64,
            wgpu::BufferUsages::STORAGE,
        )
        .unwrap();
        let probe = if surface {
            TransmittanceProbe::surface(&gpu, &shadow.binding())
        } else {
            TransmittanceProbe::new(&gpu, &shadow.binding())
        }
        .unwrap();
        let frame = full_frame(&buffers);
        shadow.prepare(&gpu.queue, &frame, &light()).unwrap();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        shadow.encode(&mut encoder, &frame, None).unwrap();
        probe.encode(&gpu, &mut encoder, &points, &out).unwrap();
        gpu.submit_and_wait([encoder.finish()]).unwrap();
        let v: Vec<f32> = bytemuck::cast_slice(&read_buffer(&gpu, &out).unwrap()).to_vec();
        v.iter().sum::<f32>() / v.len() as f32
    };
    let (near, far) = (points(0.01), points(0.5));
    let (surface_near, surface_far) = (probe(true, &near), probe(true, &far));
    let (light_near, light_far) = (probe(false, &near), probe(false, &far));
    println!(
        "behind a layer of hair 0.04 deep (32³): surface_visibility {surface_near:.3} right \
         behind, {surface_far:.3} 0.5 behind; light_visibility {light_near:.3} and {light_far:.3}"
    );
    assert!(surface_far < 0.9, "the layer hides little: {surface_far}");
    assert!(
        (surface_near - surface_far).abs() < 0.05,
        "{surface_near} vs {surface_far}"
    );
    assert!(
        (light_far - surface_far).abs() < 0.02,
        "{light_far} vs {surface_far}"
    );
    assert!(
        light_near > surface_near + 0.05,
        "{light_near} vs {surface_near}"
    );
}

#[test]
fn a_thousand_strands_through_one_voxel_saturate_and_never_wrap() {
    let gpu = gpu();
    let to_light = light().to_light().unwrap();
    let across = to_light.cross(Vec3::Z).normalize();
    // 1000 opaque strands crossing the same point across the light. At 26 fixed-point
    // bits a column saturates at an optical depth of 64; each strand adds about 0.25 to
    // the voxel at the crossing (width / cell), so their sum passes the ceiling.
    let strands: Vec<Vec<Vec3>> = (0..1000)
        .map(|i| {
            let spin = glam::Quat::from_axis_angle(to_light, i as f32 * 0.37);
            let d = spin * across;
            vec![-d * 0.5, d * 0.5]
        })
        .collect();
    let buffers = strand_buffers(&gpu, &strands, 0.05);
    for splat in [Splat::Nearest, Splat::Trilinear] {
        // An odd resolution puts the crossing at a voxel centre.
        let params = VoxelParams {
            splat,
            fixed_point_bits: 26,
            ..voxel_params(15)
        };
        let shadow = isolated(
            &gpu,
            &params,
            &growth(0.05, 1.0),
            &buffers,
            (Vec3::ZERO, Vec3::ONE),
        )
        .unwrap();
        shadow
            .prepare(&gpu.queue, &full_frame(&buffers), &light())
            .unwrap();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        shadow.encode_density(&mut encoder, None);
        gpu.submit_and_wait([encoder.finish()]).unwrap();
        let density: Vec<u32> =
            bytemuck::cast_slice(&read_buffer(&gpu, shadow.volume()).unwrap()).to_vec();
        let saturated = density.iter().filter(|&&d| d == u32::MAX).count();
        assert!(
            saturated >= 1,
            "{splat:?}: no voxel saturated (max {:?})",
            density.iter().max()
        );

        // After the scan every column is non-decreasing and the saturated ones end at the ceiling.
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        shadow.encode_scan(&mut encoder, None);
        gpu.submit_and_wait([encoder.finish()]).unwrap();
        let depth: Vec<f32> =
            bytemuck::cast_slice(&read_buffer(&gpu, shadow.volume()).unwrap()).to_vec();
        let columns = 15 * 15;
        let ceiling = u32::MAX as f32 * shadow.base_uniforms().inv_fixed_scale;
        let mut at_ceiling = 0;
        for c in 0..columns {
            let column: Vec<f32> = (0..=15).map(|z| depth[z * columns + c]).collect();
            assert!(
                column.windows(2).all(|w| w[1] >= w[0]),
                "{splat:?}: column {c} decreases: {column:?}"
            );
            at_ceiling += usize::from(column[15] == ceiling);
        }
        println!(
            "{splat:?}: {saturated} voxels saturated, {at_ceiling} columns at the ceiling {ceiling}"
        );
        assert!(at_ceiling >= 1);
    }
}

/// The long-hair groom grown at t = 0 and a voxel method of `resolution`^3 on it.
fn long_hair_shadow(gpu: &Gpu, resolution: u32) -> (GrowStrands, VoxelShadow) {
    let (mesh, hair) = long_hair();
    let (strands, mesh_buffers) = grow(gpu, &mesh, &hair);
    let shadow = VoxelShadow::new(
        gpu,
        &voxel_params(resolution),
        strands.buffers(),
        &mesh_buffers,
        (Vec3::ZERO, Vec3::ONE),
    )
    .unwrap();
    (strands, shadow)
}

#[test]
fn the_grid_is_fitted_to_the_hair_on_the_gpu() {
    let gpu = gpu();
    let (strands, shadow) = long_hair_shadow(&gpu, 64);
    let frame = strands.frame().unwrap();
    shadow.prepare(&gpu.queue, &frame, &light()).unwrap();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    shadow.encode(&mut encoder, &frame, None).unwrap();
    gpu.submit_and_wait([encoder.finish()]).unwrap();
    let grid: Vec<f32> = bytemuck::cast_slice(&read_buffer(&gpu, shadow.grid()).unwrap()).to_vec();
    let (origin, cell) = (
        Vec3::new(grid[0], grid[1], grid[2]),
        Vec3::new(grid[4], grid[5], grid[6]),
    );
    let far = origin + cell * 64.0;
    let u = shadow.base_uniforms();
    let space = pelage_shadow::LightSpace::new(light().to_light().unwrap());
    let vertices = read_vec4(&gpu, &strands.buffers().vertices);
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for v in &vertices {
        let p = space.project(v.truncate());
        lo = lo.min(p);
        hi = hi.max(p);
    }
    // Every vertex inside; no more than the padding plus one cell of slack on any side.
    let slack = Vec3::splat(u.padding) + cell;
    assert!(
        lo.cmpge(origin).all() && hi.cmple(far).all(),
        "grid {origin}..{far} misses hair {lo}..{hi}"
    );
    assert!(
        (lo - origin).cmple(slack).all() && (far - hi).cmple(slack).all(),
        "grid {origin}..{far} is loose around {lo}..{hi}"
    );
}

#[test]
fn shadows_only_darken_and_the_far_side_is_darker() {
    let gpu = gpu();
    let (strands, shadow) = long_hair_shadow(&gpu, 64);
    let t = transmittance(&gpu, &shadow, strands.buffers());
    assert!(t.iter().all(|v| (0.0..=1.0).contains(v)));
    let vertices = read_vec4(&gpu, &strands.buffers().vertices);
    let to_light = light().to_light().unwrap();
    let (mut near, mut far) = (Vec::new(), Vec::new());
    for (v, t) in vertices.iter().zip(&t) {
        let side = v.truncate().dot(to_light);
        if side > 0.3 {
            near.push(*t);
        } else if side < -0.3 {
            far.push(*t);
        }
    }
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
    println!(
        "mean T on the lit side {:.3}, on the far side {:.3}",
        mean(&near),
        mean(&far)
    );
    assert!(mean(&near) > mean(&far) + 0.3);
}

#[test]
fn resolution_follows_a_target_voxel_size() {
    let gpu = gpu();
    let strands = strand_buffers(&gpu, &[vec![Vec3::ZERO, Vec3::X]], 0.01);
    let params = VoxelParams {
        voxel_size: Some(0.05),
        ..voxel_params(8)
    };
    let reach = (Vec3::splat(-1.0), Vec3::splat(1.0));
    let shadow = isolated(&gpu, &params, &growth(0.01, 0.5), &strands, reach).unwrap();
    // The box's diagonal is 2 sqrt(3) = 3.46 units: 70 voxels of 0.05.
    let u = shadow.base_uniforms();
    assert_eq!([u.resolution_x, u.resolution_y, u.resolution_z], [70; 3]);
    let bad = VoxelParams {
        voxel_size: Some(-1.0),
        ..params
    };
    let err = isolated(&gpu, &bad, &growth(0.01, 0.5), &strands, reach).unwrap_err();
    assert!(err.to_string().contains("shadow.voxel_size"), "{err}");
}
