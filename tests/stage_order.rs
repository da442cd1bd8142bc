//! The order of the stages is data: stage 1's `prepare` returns the frame every later
//! stage is prepared and recorded with, and a pass recorded for another frame than it
//! was prepared for is an error, never a picture drawn with a stale strand count.

use pelage::gpu::Gpu;
use pelage::scene::{Camera, HairParams, Light, Mesh, ShadeParams, VoxelParams};
use pelage::shade::{HairInputs, HairPass, Opaque, TargetFormat, Targets};
use pelage::shadow::{ShadowMethod, VoxelShadow};
use pelage::strands::{GrowStrands, MeshBuffers, StrandStage};
use pelage::{Error, strands::StrandsError};

const W: u32 = 64;
const H: u32 = 48;

#[test]
fn a_stage_recorded_for_another_frame_than_it_was_prepared_for_is_an_error() {
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
    let mesh = Mesh::creature();
    let buffers = MeshBuffers::upload(&gpu, &mesh).unwrap();
    let mut hair = HairParams::default();
    hair.roots.count = 500;
    let mut strands = GrowStrands::new(&gpu, &mesh, &buffers, &hair).unwrap();
    let b = strands.buffers();
    let voxel = VoxelShadow::new(
        &gpu,
        &VoxelParams::default(),
        b,
        &buffers,
        pelage::shadow::reach(b, &buffers),
    )
    .unwrap();
    let params = ShadeParams {
        sample_count: 1,
        ..ShadeParams::default()
    };
    let pass = Opaque::new(
        &gpu,
        &HairInputs {
            params: &params,
            mesh: &buffers,
            strands: b,
            shadow: None,
            visibility: None,
            target: TargetFormat::default(),
            draw_mesh: true,
        },
    )
    .unwrap();
    let targets = Targets::new(&gpu, W, H, 1).unwrap();
    let (color, resolve) = targets.color_views();
    let depth = targets.depth_view();
    let views = targets.views(&color, resolve.as_ref(), &depth);
    let camera = Camera::default().matrices(W, H);
    let lights = [Light::default()];
    let light = lights[0].as_directional(glam::Vec3::ZERO);

    // Nothing prepared yet: even stage 1 refuses a frame it did not return.
    let first = strands.prepare(&gpu.queue, 0.0).unwrap();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let err = voxel.encode(&mut encoder, &first, None).unwrap_err();
    assert!(
        err.to_string().contains("prepared for strand frame 0"),
        "{err}"
    );

    // The later stages prepared with the first frame; stage 1 then moves on.
    voxel.prepare(&gpu.queue, &first, &light).unwrap();
    pass.prepare(&gpu.queue, &first, &camera, &lights, W, H)
        .unwrap();
    let second = strands.prepare(&gpu.queue, 0.5).unwrap();
    assert_ne!(first.id, second.id);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    // Stage 1 records only its latest frame.
    let err = strands.encode(&mut encoder, &first, None).unwrap_err();
    assert!(matches!(err, StrandsError::FrameOrder(_)), "{err}");
    strands.encode(&mut encoder, &second, None).unwrap();
    // Shadow and shade were prepared for the first: they refuse the second.
    let err = voxel.encode(&mut encoder, &second, None).unwrap_err();
    assert!(err.to_string().contains("prepare stage 1 first"), "{err}");
    let err = pass
        .encode(&mut encoder, &second, &views, None)
        .unwrap_err();
    assert!(
        matches!(
            Error::from(err),
            Error::Shade(pelage::shade::ShadeError::FrameOrder(_))
        ),
        "shade accepted a frame it was not prepared for"
    );
    // Prepared in order, every stage records.
    voxel.prepare(&gpu.queue, &second, &light).unwrap();
    pass.prepare(&gpu.queue, &second, &camera, &lights, W, H)
        .unwrap();
    voxel.encode(&mut encoder, &second, None).unwrap();
    pass.encode(&mut encoder, &second, &views, None).unwrap();
    gpu.submit_and_wait([encoder.finish()]).unwrap();
}
