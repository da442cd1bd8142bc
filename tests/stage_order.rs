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
            shadows: &[],
            visibility: None,
            target: TargetFormat::default(),
            draw_mesh: true,
            grid_apart: false,
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

/// A [`pelage::Frame`] recorded into the caller's own targets draws the picture the
/// [`pelage::Renderer`] (a `Frame` plus its targets) draws, and recording it before any
/// prepare is an error, never a picture.
#[test]
fn a_frame_in_the_callers_targets_is_the_renderers_picture() {
    use pelage::{Frame, FrameTarget, Renderer, scene::Scene};
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
    let mut scene = Scene::default();
    scene.hair.roots.count = 2_000;
    let format = TargetFormat::for_params(&scene.shade);
    let mut frame = Frame::new(&gpu, &scene, &FrameTarget::new(format, W, H)).unwrap();
    let targets = Targets::with_format(&gpu, W, H, &format).unwrap();
    let views = targets.view_set();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let early = frame.record(&mut encoder, &views.views(), None);
    assert!(
        matches!(early, Err(Error::Strands(StrandsError::FrameOrder(_)))),
        "recorded before any prepare: {early:?}"
    );
    let t = 0.25;
    frame
        .prepare(&gpu.queue, t, &scene.camera.matrices(W, H))
        .unwrap();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    frame.record(&mut encoder, &views.views(), None).unwrap();
    gpu.submit_and_wait([encoder.finish()]).unwrap();
    frame.after_submit(&gpu).unwrap();
    let ours = targets.read_color(&gpu).unwrap().data;

    let mut renderer = Renderer::new(&gpu, &scene, W, H).unwrap();
    renderer.render(&gpu, t, &scene.camera).unwrap();
    renderer.finish(&gpu).unwrap();
    let (_, _, theirs) = renderer.rgba8(&gpu).unwrap();
    let differing = ours.iter().zip(&theirs).filter(|(a, b)| a != b).count();
    println!("{differing} of {} bytes differ", ours.len());
    assert_eq!(ours.len(), theirs.len());
    assert_eq!(differing, 0, "the frame in the caller's targets differs");
}
