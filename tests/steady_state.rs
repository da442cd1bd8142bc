//! A frame in steady state creates nothing: no buffer and no bind group, for every
//! shadow method and every transparency method, counted by pelage-gpu
//! ([`pelage::gpu::Created`]). And every buffer and bind group the library creates goes
//! through those counted functions (a scan of the sources), so the count is complete.

use pelage::gpu::{Created, Gpu};
use pelage::scene::{ShadowParams, Transparency};
use pelage::{Renderer, scene::Scene};

fn scene(shadow: ShadowParams, transparency: Transparency) -> Scene {
    let mut scene = Scene::default();
    scene.hair.roots.count = 1500;
    scene.shadow = shadow;
    scene.shade.transparency = transparency;
    scene.shade.sample_count = 1;
    scene
}

#[test]
fn frames_in_steady_state_create_no_buffer_and_no_bind_group() {
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
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
    let cases = shadows
        .iter()
        .map(|s| (s.clone(), Transparency::Opaque))
        .chain(methods.iter().map(|m| (ShadowParams::default(), m.clone())));
    for (shadow, method) in cases {
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
                        for call in [
                            ".create_bind_group(",
                            ".create_buffer(",
                            ".create_buffer_init(",
                            ".set_bind_group(",
                            ".begin_render_pass(",
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
        "uncounted creations or unaudited bindings (use pelage_gpu::create_*, \
         pelage_gpu::set_bind_group, pelage_gpu::audit::begin_render_pass):\n{}",
        direct.join("\n")
    );
}
