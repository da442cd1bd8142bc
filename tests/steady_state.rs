//! A frame in steady state creates nothing: no buffer and no bind group, for every
//! shadow method and every transparency method, counted by pelage-gpu
//! ([`pelage::gpu::Created`]); and a frame recorded as an engine records it (prepare,
//! record, the caller's submit, after-submit) never waits for the GPU, counted likewise
//! ([`pelage::gpu::waits`]). Every buffer and bind group the library creates and every
//! wait goes through those counted functions (a scan of the sources), so the counts are
//! complete.

use pelage::gpu::{Created, Gpu};
use pelage::scene::{ShadowParams, Transparency};
use pelage::shade::{TargetFormat, Targets};
use pelage::{Frame, FrameTarget, Renderer, scene::Scene};

fn scene(shadow: ShadowParams, transparency: Transparency) -> Scene {
    let mut scene = Scene::default();
    scene.hair.roots.count = 1500;
    scene.shadow = shadow;
    scene.shade.transparency = transparency;
    scene.shade.sample_count = 1;
    scene
}

/// Every shadow method over the opaque hair pass, then every transparency method under
/// the default shadow.
fn cases() -> Vec<(ShadowParams, Transparency)> {
    let shadows = [
        ShadowParams::None,
        ShadowParams::default(),
        ShadowParams::DeepOpacity(Default::default()),
        ShadowParams::ShadowMap(Default::default()),
        ShadowParams::Adsm(Default::default()),
    ];
    let methods = [
        Transparency::Opaque,
        Transparency::wboit(),
        Transparency::KBuffer { k: 8 },
        Transparency::a_buffer(),
        Transparency::Dbk {
            depth_shift: 0.05,
            nodes_per_pixel: 8.0,
            resolve_k: 16,
        },
        Transparency::RandomSubsets { k: 8 },
        Transparency::strand_raster(),
    ];
    shadows
        .iter()
        .map(|s| (s.clone(), Transparency::Opaque))
        .chain(methods.iter().map(|m| (ShadowParams::default(), m.clone())))
        .collect()
}

#[test]
fn frames_in_steady_state_create_no_buffer_and_no_bind_group() {
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
    for (shadow, method) in cases() {
        let s = scene(shadow.clone(), method.clone());
        let mut renderer = match Renderer::new(&gpu, &s, 96, 72) {
            Ok(r) => r,
            Err(pelage::Error::Shade(pelage::shade::ShadeError::Unsupported(why))) => {
                println!("{method:?}: skipped, this adapter cannot run it: {why}");
                continue;
            }
            Err(e) => panic!("{shadow:?} {method:?}: {e}"),
        };
        // The first frame may build what waits for the targets' views.
        renderer.render(&gpu, 0.0, &s.camera).unwrap();
        let before = Created::now();
        for frame in 1..=6 {
            // Time and camera move (so the level of detail may change): still nothing new.
            let camera = s.camera.orbited(0.05 * frame as f32);
            renderer.render(&gpu, frame as f32 / 24.0, &camera).unwrap();
        }
        renderer.finish(&gpu).unwrap();
        let created = Created::now().since(&before);
        println!("{shadow:?} / {method:?}: {created:?} over 6 frames");
        assert_eq!(
            created,
            Created::default(),
            "{shadow:?} / {method:?} created GPU objects in steady state"
        );
    }
}

#[test]
fn a_frame_recorded_as_an_engine_records_it_never_waits_for_the_gpu() {
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
    for (shadow, method) in cases() {
        let s = scene(shadow.clone(), method.clone());
        let format = TargetFormat::for_params(&s.shade);
        let mut frame = match Frame::new(&gpu, &s, &FrameTarget::new(format, 96, 72)) {
            Ok(f) => f,
            Err(pelage::Error::Shade(pelage::shade::ShadeError::Unsupported(why))) => {
                println!("{method:?}: skipped, this adapter cannot run it: {why}");
                continue;
            }
            Err(e) => panic!("{shadow:?} {method:?}: {e}"),
        };
        let targets = Targets::with_format(&gpu, 96, 72, &format).unwrap();
        let view_set = targets.view_set();
        let views = view_set.views();
        let before = pelage::gpu::waits();
        for n in 0..6 {
            // Time and camera move; the frames queue up behind each other unwaited.
            let camera = s.camera.orbited(0.05 * n as f32);
            let camera = camera.matrices(96, 72);
            frame.prepare(&gpu.queue, n as f32 / 24.0, &camera).unwrap();
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            frame.record(&mut encoder, &views, None).unwrap();
            gpu.submit([encoder.finish()]).unwrap();
            frame.after_submit(&gpu).unwrap();
        }
        let waited = pelage::gpu::waits() - before;
        println!("{shadow:?} / {method:?}: {waited} waits over 6 frames");
        assert_eq!(
            waited, 0,
            "{shadow:?} / {method:?} waited for the GPU in a frame"
        );
        // The count sees a wait (so the check above can fail): the frames' end.
        pelage::gpu::wait(&gpu.device, None).unwrap();
        assert_eq!(pelage::gpu::waits() - before, 1);
        gpu.check().unwrap();
    }
}

#[test]
fn every_buffer_and_bind_group_of_the_library_is_counted() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut direct = Vec::new();
    let dirs = [
        "src",
        "crates/pelage-gpu/src",
        "crates/pelage-strands/src",
        "crates/pelage-shadow/src",
        "crates/pelage-shade/src",
    ];
    let mut files = 0;
    for dir in dirs {
        let mut stack = vec![root.join(dir)];
        while let Some(path) = stack.pop() {
            for entry in std::fs::read_dir(&path).unwrap() {
                let path = entry.unwrap().path();
                if path.is_dir() {
                    stack.push(path);
                } else if path.extension().is_some_and(|e| e == "rs")
                    && !path.ends_with("counters.rs")
                    && !path.ends_with("audit.rs")
                {
                    files += 1;
                    let text = std::fs::read_to_string(&path).unwrap();
                    for (n, line) in text.lines().enumerate() {
                        // Binding and render passes go through pelage_gpu::audit, so that
                        // the frame plan test sees what every pass binds.
                        // Every blocking wait for the GPU goes through pelage_gpu::wait,
                        // so that the no-wait test counts it. (`pollster::block_on` in
                        // pelage-gpu builds the device and pops error scopes, which wgpu
                        // answers at once on native: no wait for the GPU.)
                        for call in [
                            ".create_bind_group(",
                            ".create_buffer(",
                            ".create_buffer_init(",
                            ".set_bind_group(",
                            ".begin_render_pass(",
                            "PollType::Wait",
                            "wait_indefinitely",
                        ] {
                            if line.contains(call) {
                                direct.push(format!(
                                    "{}:{}: {}",
                                    path.display(),
                                    n + 1,
                                    line.trim()
                                ));
                            }
                        }
                    }
                }
            }
        }
    }
    assert!(
        files > 30,
        "scanned only {files} files: the paths are wrong"
    );
    assert!(
        direct.is_empty(),
        "uncounted creations, unaudited bindings or uncounted waits (use \
         pelage_gpu::create_*, pelage_gpu::set_bind_group, \
         pelage_gpu::audit::begin_render_pass, pelage_gpu::wait):\n{}",
        direct.join("\n")
    );
}
