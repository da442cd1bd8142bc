//! The frame as a list of passes over named resources: the renderer's plan is valid for
//! every shadow and transparency method, it declares exactly the passes a real frame
//! records (its labels against the GPU timer's), and a plan in the wrong order is
//! refused, naming the pass to record first.

use pelage::gpu::audit::Audit;
use pelage::gpu::{Gpu, PlanError};
use std::path::Path;

use pelage::scene::{DynamicsParams, Named, ShadowParams, Transparency};
use pelage::shade::TargetFormat;
use pelage::{Renderer, scene::Scene};

fn scene(shadow: ShadowParams, transparency: Transparency, lights: usize) -> Scene {
    let mut scene = Scene::default();
    scene.hair.roots.count = 1500;
    scene.shadow = shadow;
    scene.shade.transparency = transparency;
    scene.shade.sample_count = 1;
    scene.lights = vec![pelage::scene::Light::default(); lights];
    scene
}

/// The shadow x transparency x light-count combinations every plan test runs.
fn cases() -> Vec<(ShadowParams, Transparency, usize)> {
    vec![
        (ShadowParams::None, Transparency::Opaque, 1),
        (ShadowParams::default(), Transparency::Opaque, 2),
        (
            ShadowParams::DeepOpacity(Default::default()),
            Transparency::wboit(),
            1,
        ),
        (
            ShadowParams::ShadowMap(Default::default()),
            Transparency::a_buffer(),
            1,
        ),
        (
            ShadowParams::Adsm(Default::default()),
            Transparency::KBuffer { k: 8 },
            1,
        ),
        (ShadowParams::default(), Transparency::dbk(0.05), 1),
        (
            ShadowParams::default(),
            Transparency::RandomSubsets { k: 8 },
            1,
        ),
        (ShadowParams::default(), Transparency::strand_raster(), 2),
    ]
}

/// Targets a transparency method draws through the frame's target bridge
/// (`src/bridge.rs`): multisampled, reversed depth for a method that compares one way,
/// both; each with its scene.
fn bridged() -> Vec<(String, Scene, TargetFormat)> {
    let base = TargetFormat::default();
    let msaa = TargetFormat { samples: 4, ..base };
    let reversed = TargetFormat {
        reverse_z: true,
        ..base
    };
    let both = TargetFormat {
        samples: 4,
        reverse_z: true,
        ..base
    };
    [
        (Transparency::wboit(), msaa, "4x MSAA"),
        (Transparency::a_buffer(), reversed, "reverse-Z"),
        (Transparency::strand_raster(), both, "4x MSAA, reverse-Z"),
    ]
    .into_iter()
    .map(|(method, format, targets)| {
        (
            format!("{} on {targets}", method.name()),
            scene(ShadowParams::default(), method, 1),
            format,
        )
    })
    .collect()
}

#[test]
fn the_plan_declares_the_passes_a_frame_records_through_the_target_bridge() {
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
    if !gpu.has_timestamps() {
        panic!("this test compares with timestamp labels; the adapter has no timestamp queries");
    }
    for (name, s, format) in bridged() {
        let mut renderer = Renderer::with_format(&gpu, &s, 96, 72, &format)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let plan = renderer.frame().plan([]).unwrap();
        plan.validate().unwrap();
        assert!(
            plan.labels().iter().any(|l| l.starts_with("bridge: ")),
            "{name}: {:?}",
            plan.labels()
        );
        renderer.render(&gpu, 0.0, &s.camera).unwrap();
        let stats = renderer.finish(&gpu).unwrap();
        let by_label = stats.by_label();
        let timed: Vec<&str> = by_label.iter().map(|(l, _)| l.as_str()).collect();
        println!("{name}: {:?}", plan.labels());
        assert_eq!(plan.labels(), timed, "{name}");
    }
}

#[test]
fn the_plan_declares_the_passes_a_frame_records() {
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
    if !gpu.has_timestamps() {
        panic!("this test compares with timestamp labels; the adapter has no timestamp queries");
    }
    for (shadow, method, lights) in cases() {
        let s = scene(shadow.clone(), method.clone(), lights);
        let mut renderer = match Renderer::new(&gpu, &s, 96, 72) {
            Ok(r) => r,
            Err(pelage::Error::Shade(pelage::shade::ShadeError::Unsupported(why))) => {
                println!("{method:?}: skipped, this adapter cannot run it: {why}");
                continue;
            }
            Err(e) => panic!("{shadow:?} {method:?}: {e}"),
        };
        let plan = renderer.frame().plan([]).unwrap();
        plan.validate().unwrap();
        renderer.render(&gpu, 0.0, &s.camera).unwrap();
        let stats = renderer.finish(&gpu).unwrap();
        let by_label = stats.by_label();
        let timed: Vec<&str> = by_label.iter().map(|(l, _)| l.as_str()).collect();
        println!(
            "{method:?}, {lights} light(s): {} passes: {:?}",
            plan.passes().len(),
            plan.labels()
        );
        assert_eq!(
            plan.labels(),
            timed,
            "{shadow:?} / {method:?}: the plan's passes differ from what the frame recorded"
        );
        // Light i's resources are its own.
        if lights == 2 {
            assert!(
                plan.passes()
                    .iter()
                    .any(|p| p.writes.iter().any(|w| w == "shadow1.volume"))
            );
        }
    }
}

/// A frame's name of light i's shadow resource (`shadow0.grid`) as its shadow method
/// named it (`shadow.grid`).
fn as_named(declared: &str) -> String {
    match declared.strip_prefix("shadow") {
        Some(rest) => {
            let digits = rest.chars().take_while(char::is_ascii_digit).count();
            if digits > 0 && rest[digits..].starts_with('.') {
                format!("shadow{}", &rest[digits..])
            } else {
                declared.to_string()
            }
        }
        None => declared.to_string(),
    }
}

#[test]
fn every_pass_binds_only_what_the_plan_declares() {
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
    if !gpu.has_timestamps() {
        panic!(
            "this test attributes bindings to passes by their timer scopes; the adapter has no timestamp queries"
        );
    }
    let mut failures = Vec::new();
    let mut scenes: Vec<(String, Scene, TargetFormat)> = cases()
        .into_iter()
        .map(|(shadow, method, lights)| {
            let s = scene(shadow.clone(), method.clone(), lights);
            let format = TargetFormat::for_params(&s.shade);
            (
                format!(
                    "{} / {} / {lights} light(s)",
                    shadow.method_name(),
                    method.name()
                ),
                s,
                format,
            )
        })
        .collect();
    scenes.extend(bridged());
    // Every stage 1 method: a simulation, a groom, a simulated groom, guides, a skin.
    let mut simulated = scene(ShadowParams::default(), Transparency::default(), 1);
    simulated.dynamics = Some(DynamicsParams::default());
    let format = TargetFormat::for_params(&simulated.shade);
    scenes.push(("simulated fur".into(), simulated, format));
    for file in [
        "long_hair.toml",
        "head_turn.toml",
        "guides.toml",
        "creature_skinned.toml",
    ] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join(file);
        let mut s = Scene::from_file(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
        s.hair.roots.count = s.hair.roots.count.min(1500);
        let format = TargetFormat::for_params(&s.shade);
        scenes.push((file.into(), s, format));
    }
    // The body's distance field: built once and moved with the head; built once in the
    // bind pose and read through the skin (the skin's lattice pass after the skinning
    // pass, a pass of its own, declared); and rebuilt every frame after the skinning.
    for file in ["head_turn.toml", "creature_skinned.toml"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join(file);
        let mut s = Scene::from_file(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
        s.hair.roots.count = s.hair.roots.count.min(1500);
        let mut dynamics = s.dynamics.clone().unwrap_or_default();
        dynamics.sdf_resolution = 32;
        s.dynamics = Some(dynamics);
        let format = TargetFormat::for_params(&s.shade);
        scenes.push((format!("{file} with the body's field"), s.clone(), format));
        if s.skin.is_some() {
            let mut rebuilt = s;
            if let Some(d) = rebuilt.dynamics.as_mut() {
                d.sdf_skinned = pelage::scene::SkinnedSdf::Rebuilt;
            }
            scenes.push((
                format!("{file} with the body's field rebuilt"),
                rebuilt,
                format,
            ));
        }
    }
    for (name, s, format) in scenes {
        let audit = Audit::start();
        let mut renderer = match Renderer::with_format(&gpu, &s, 96, 72, &format) {
            Ok(r) => r,
            Err(pelage::Error::Shade(pelage::shade::ShadeError::Unsupported(why))) => {
                println!("{name}: skipped, this adapter cannot run it: {why}");
                continue;
            }
            Err(e) => panic!("{name}: {e}"),
        };
        audit.clear_passes();
        renderer.render(&gpu, 0.0, &s.camera).unwrap();
        let bound = audit.finish();
        let plan = renderer.frame().plan([]).unwrap();
        let labels: Vec<&str> = bound.iter().map(|p| p.label.as_str()).collect();
        assert_eq!(
            plan.labels(),
            labels,
            "{name}: the audited passes differ from the plan's"
        );
        for pass in &bound {
            let declared = plan.passes().iter().filter(|p| p.label == pass.label);
            let (mut reads, mut writes) = (Vec::new(), Vec::new());
            for p in declared {
                reads.extend(p.reads.iter().cloned());
                writes.extend(p.writes.iter().cloned());
            }
            println!("{name}: {}: {:?}", pass.label, pass.bound);
            for missing in pass.undeclared(&reads, &writes, as_named) {
                failures.push(format!("{name}: {missing}"));
            }
            for extra in pass.unbound(&reads, &writes, as_named) {
                failures.push(format!("{name}: {extra}"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "passes bind what their declarations do not name:\n{}",
        failures.join("\n")
    );
    // An audit started after the frame was built has seen none of its bind groups: it
    // reports every binding rather than passing a frame it cannot check.
    let s = scene(ShadowParams::default(), Transparency::default(), 1);
    let mut renderer = Renderer::new(&gpu, &s, 96, 72).unwrap();
    let late = Audit::start();
    renderer.render(&gpu, 0.0, &s.camera).unwrap();
    let bound = late.finish();
    let unseen: Vec<String> = bound
        .iter()
        .flat_map(|p| p.undeclared(&[], &[], as_named))
        .collect();
    assert!(
        bound.len() > 5 && unseen.len() >= bound.len(),
        "a late audit must report every pass: {unseen:?}"
    );
}

#[test]
fn a_plan_in_the_wrong_order_names_the_pass_to_record_first() {
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
    let s = scene(ShadowParams::default(), Transparency::Opaque, 1);
    let renderer = Renderer::new(&gpu, &s, 64, 48).unwrap();
    // Stage 3 before stage 1: the hair pass would read strands nothing wrote yet.
    let plan = renderer.frame().plan([]).unwrap();
    let mut wrong = pelage::gpu::FramePlan::new(plan.inputs().to_vec());
    let passes = plan.passes();
    let hair: Vec<_> = passes
        .iter()
        .filter(|p| p.label.starts_with("shade:"))
        .cloned()
        .collect();
    let rest: Vec<_> = passes
        .iter()
        .filter(|p| !p.label.starts_with("shade:"))
        .cloned()
        .collect();
    wrong.push(hair);
    wrong.push(rest);
    let err = wrong.validate().unwrap_err();
    println!("{err}");
    match &err {
        PlanError::Unwritten {
            pass,
            written_later_by,
            ..
        } => {
            assert!(pass.starts_with("shade:"), "{err}");
            assert!(written_later_by.is_some(), "{err}");
        }
    }
    // Without its shadow's passes the plan is refused: the hair pass's mesh samples the
    // key light's shadow, which nothing would write.
    let mut unshadowed = pelage::gpu::FramePlan::new(plan.inputs().to_vec());
    unshadowed.push(
        passes
            .iter()
            .filter(|p| !p.label.starts_with("shadow"))
            .cloned(),
    );
    match unshadowed.validate() {
        Err(PlanError::Unwritten { resource, .. }) => {
            assert!(resource.starts_with("shadow0."), "{resource}")
        }
        Ok(()) => panic!("a frame without the shadow the hair reads must be refused"),
    }
}

/// The contracts a frame hands an engine's own mesh shader name what they sample: each
/// light's shadow binding reads that light's shadow resources (`shadow0.*`, `shadow1.*`:
/// resources the frame's own passes write), the body's sky the volume grid's fluence;
/// a pass declaring those reads fits the plan between the two record parts, and one
/// reading a resource no pass writes does not.
#[test]
fn contract_bindings_name_what_they_sample() {
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
    let s = scene(ShadowParams::default(), Transparency::default(), 2);
    let renderer = Renderer::new(&gpu, &s, 64, 48).unwrap();
    let frame = renderer.frame();
    let plan = frame.plan([]).unwrap();
    let written: Vec<&String> = plan.passes().iter().flat_map(|p| &p.writes).collect();
    let mut reads = Vec::new();
    for light in 0..2 {
        let binding = frame.shadow_binding(light).unwrap();
        assert!(!binding.reads.is_empty(), "light {light}: {binding:?}");
        for name in &binding.reads {
            assert!(name.starts_with(&format!("shadow{light}.")), "{name}");
            assert!(
                written.contains(&name),
                "no pass of the frame writes {name}"
            );
        }
        reads.extend(binding.reads);
    }
    assert!(frame.shadow_binding(2).is_none());
    let sky = frame
        .body_sky_binding()
        .expect("the default shading has the grid");
    assert_eq!(sky.reads, [pelage::shade::VOLUME_FLUENCE]);
    reads.extend(sky.reads);
    let engine = |reads: Vec<String>| {
        pelage::gpu::PassInfo::new("engine mesh")
            .reads(reads)
            .writes([pelage::shade::TARGET_COLOR, pelage::shade::TARGET_DEPTH])
    };
    frame.plan([engine(reads)]).unwrap();
    let err = frame
        .plan([engine(vec!["shadow2.grid".into()])])
        .unwrap_err();
    assert!(err.to_string().contains("shadow2.grid"), "{err}");
}
