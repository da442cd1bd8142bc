//! The ribbon pass on a real adapter: width on screen, depth test against the mesh.

use glam::Vec3;
use pelage_gpu::Gpu;
use pelage_scene::{Camera, HairParams, Light, Mesh, RootParams, ShadeParams, WindParams};
use pelage_shade::{HairInputs, HairPass, Opaque, TargetFormat, Targets};
use pelage_strands::{GrowStrands, MeshBuffers, StrandStage};

const SIZE: u32 = 128;

fn gpu() -> Gpu {
    Gpu::headless().unwrap_or_else(|e| panic!("these tests need a GPU adapter: {e}"))
}

/// One straight strand of `width` growing up (+y) from the origin, 1 unit long, no wind or jitter.
fn single_strand(width: f32) -> (Mesh, HairParams) {
    // A tiny horizontal triangle around the origin, normal +y.
    let mesh = Mesh {
        positions: vec![
            Vec3::new(-1e-3, 0.0, -1e-3),
            Vec3::new(0.0, 0.0, 1e-3),
            Vec3::new(1e-3, 0.0, -1e-3),
        ],
        normals: vec![Vec3::Y; 3],
        indices: vec![0, 1, 2],
        uvs: Vec::new(),
    };
    let mut hair = HairParams {
        roots: RootParams {
            count: 1,
            ..Default::default()
        },
        wind: WindParams::calm(),
        ..Default::default()
    };
    hair.growth.length = 1.0;
    hair.growth.length_jitter = 0.0;
    hair.growth.direction_jitter = 0.0;
    hair.growth.force_weight = 0.0;
    hair.growth.width = width;
    hair.growth.tip_width = 1.0;
    hair.growth.color = Vec3::ONE;
    hair.growth.color_jitter = 0.0;
    (mesh, hair)
}

fn shade_params() -> ShadeParams {
    ShadeParams {
        background: Vec3::ZERO,
        mesh_color: Vec3::ZERO,
        ambient: 1.0,
        min_pixels: 0.0,
        root_occlusion: 0.0,
        sample_count: 1,
        ..Default::default()
    }
}

/// Renders `mesh` with its hair from `camera`; returns the red channel of every pixel.
fn render(gpu: &Gpu, mesh: &Mesh, hair: &HairParams, camera: &Camera) -> Vec<u8> {
    let mesh_buffers = MeshBuffers::upload(gpu, mesh).unwrap();
    let mut strands = GrowStrands::new(gpu, mesh, &mesh_buffers, hair).unwrap();
    let params = shade_params();
    let inputs = HairInputs {
        params: &params,
        mesh: &mesh_buffers,
        strands: strands.buffers(),
        shadows: &[],
        visibility: None,
        target: TargetFormat::for_params(&params),
        draw_mesh: true,
        grid_apart: false,
    };
    let pass = Opaque::new(gpu, &inputs).unwrap();
    let targets = Targets::new(gpu, SIZE, SIZE, params.sample_count).unwrap();
    let frame = strands.prepare(&gpu.queue, 0.0).unwrap();
    pass.prepare(
        &gpu.queue,
        &frame,
        &camera.matrices(SIZE, SIZE),
        &[Light::default()],
        SIZE,
        SIZE,
    )
    .unwrap();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    strands.encode(&mut encoder, &frame, None).unwrap();
    let (color, resolve) = targets.color_views();
    let depth = targets.depth_view();
    pass.encode(
        &mut encoder,
        &frame,
        &targets.views(&color, resolve.as_ref(), &depth),
        None,
    )
    .unwrap();
    gpu.submit_and_wait([encoder.finish()]).unwrap();
    let data = targets.read_color(gpu).unwrap();
    data.data.chunks(4).map(|p| p[0]).collect()
}

#[test]
fn ribbon_is_as_wide_on_screen_as_the_strand() {
    let gpu = gpu();
    let camera = Camera {
        eye: Vec3::new(0.0, 0.5, 3.0),
        target: Vec3::new(0.0, 0.5, 0.0),
        fov_y: 40f32.to_radians(),
        ..Default::default()
    };
    let pixel_scale = 2.0 * (camera.fov_y * 0.5).tan() / SIZE as f32;
    for width in [0.05f32, 0.1, 0.2] {
        let (mesh, hair) = single_strand(width);
        let red = render(&gpu, &mesh, &hair, &camera);
        // The middle row crosses the strand halfway up, 3 units from the eye.
        let row = &red[(SIZE / 2 * SIZE) as usize..((SIZE / 2 + 1) * SIZE) as usize];
        let covered = row.iter().filter(|&&r| r > 0).count() as f32;
        let expected = width / (pixel_scale * 3.0);
        println!("width {width}: {covered} pixels covered, {expected:.2} expected");
        assert!(
            (covered - expected).abs() <= 1.0,
            "strand of width {width} covers {covered} pixels, expected {expected:.2}"
        );
    }
}

#[test]
fn mesh_in_front_hides_the_hair() {
    let gpu = gpu();
    let camera = Camera {
        eye: Vec3::new(0.0, 0.5, 3.0),
        target: Vec3::new(0.0, 0.5, 0.0),
        ..Default::default()
    };
    let (mut mesh, hair) = single_strand(0.2);
    let bare = render(&gpu, &mesh, &hair, &camera);
    assert!(
        bare.iter().any(|&r| r > 0),
        "the strand is not drawn at all"
    );
    // A black wall between the strand and the camera.
    let wall = Mesh::plane(4.0, 4.0, 1, 1).unwrap().transformed(
        glam::Affine3A::from_rotation_translation(
            glam::Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
            Vec3::new(0.0, 0.5, 1.0),
        ),
    );
    mesh.append(&wall).unwrap();
    let hidden = render(&gpu, &mesh, &hair, &camera);
    assert!(
        hidden.iter().all(|&r| r == 0),
        "hair shows through the mesh"
    );
}
