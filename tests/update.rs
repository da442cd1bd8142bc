//! `Frame::update` (through `Renderer::frame_mut`): a change made in place draws the
//! picture a new renderer of the changed scene draws (RGBA8, every pixel equal), and a
//! change that shapes buffers, passes or pipelines is `Error::NeedsRebuild` with nothing
//! applied.

use glam::Vec3;
use pelage::scene::{
    ChiangParams, DirectionalLight, Light, MarschnerParams, SadeghiParams, ShadingModel,
    ShadowParams, Transparency,
};
use pelage::{Error, Renderer, gpu::Gpu, scene::Scene};

const SIZE: (u32, u32) = (96, 72);

/// A change to a scene.
type Edit = Box<dyn Fn(&mut Scene)>;
const T: f32 = 0.7;

fn gpu() -> Gpu {
    Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"))
}

fn base() -> Scene {
    let mut scene = Scene::default();
    scene.hair.roots.count = 3000;
    scene
}

fn picture(gpu: &Gpu, renderer: &mut Renderer, scene: &Scene) -> image::RgbaImage {
    renderer.render(gpu, T, &scene.camera).unwrap();
    renderer.image(gpu).unwrap()
}

/// Pixels whose channels differ at all, and the largest difference.
fn diff(a: &image::RgbaImage, b: &image::RgbaImage) -> (usize, u8) {
    let mut count = 0;
    let mut worst = 0;
    for (p, q) in a.pixels().zip(b.pixels()) {
        let d = (0..4).map(|c| p.0[c].abs_diff(q.0[c])).max().unwrap_or(0);
        count += usize::from(d > 0);
        worst = worst.max(d);
    }
    (count, worst)
}

/// Renders `from`, updates the renderer to `to` in place (what changed: `changes`),
/// renders again and compares with a new renderer of `to`: every pixel must be equal, and
/// the change must show (the picture of `from` differs).
fn in_place_matches_a_new_renderer(gpu: &Gpu, from: &Scene, to: &Scene, changes: &str) {
    let mut renderer = Renderer::new(gpu, from, SIZE.0, SIZE.1).unwrap();
    let before = picture(gpu, &mut renderer, from);
    renderer
        .frame_mut()
        .update(gpu, to)
        .unwrap_or_else(|e| panic!("{changes}: {e}"));
    let in_place = picture(gpu, &mut renderer, to);
    let mut fresh = Renderer::new(gpu, to, SIZE.0, SIZE.1).unwrap();
    let fresh = picture(gpu, &mut fresh, to);
    let (shown, _) = diff(&before, &fresh);
    let (count, worst) = diff(&in_place, &fresh);
    println!(
        "{changes}: the change moves {shown} pixels; in place vs new: {count} pixels differ, by at most {worst}"
    );
    assert!(shown > 20, "{changes}: the change does not show");
    assert_eq!(
        (count, worst),
        (0, 0),
        "{changes}: in place differs from a new renderer"
    );
    // Nothing left to change: the same scene again changes nothing.
    renderer.frame_mut().update(gpu, to).unwrap();
    let again = picture(gpu, &mut renderer, to);
    assert_eq!(
        diff(&again, &fresh),
        (0, 0),
        "{changes}: a second update changed it"
    );
}

#[test]
fn wind_in_place_draws_what_a_new_renderer_draws() {
    let gpu = gpu();
    let from = base();
    let mut to = from.clone();
    to.hair.wind.strength = 2.5;
    to.hair.wind.direction = Vec3::new(-1.0, 0.2, 0.5);
    to.hair.wind.turbulence = 1.2;
    in_place_matches_a_new_renderer(&gpu, &from, &to, "wind");
}

#[test]
fn hair_colour_in_place_draws_what_a_new_renderer_draws() {
    let gpu = gpu();
    let from = base();
    let mut to = from.clone();
    to.hair.growth.color = Vec3::new(0.8, 0.6, 0.3);
    to.hair.growth.color_jitter = 0.5;
    in_place_matches_a_new_renderer(&gpu, &from, &to, "hair colour");
}

#[test]
fn lights_in_place_draw_what_a_new_renderer_draws() {
    let gpu = gpu();
    let mut from = base();
    from.lights = Light::key_and_back(&from.camera);
    let mut to = from.clone();
    to.lights[0] = Light::Directional(DirectionalLight {
        direction: Vec3::new(-0.6, -0.5, 0.4),
        color: Vec3::new(1.0, 0.9, 0.8),
        intensity: 2.0,
    });
    in_place_matches_a_new_renderer(&gpu, &from, &to, "lights");
}

#[test]
fn shading_in_place_draws_what_a_new_renderer_draws() {
    let gpu = gpu();
    let from = base();
    // Frame uniforms, ribbon style, mesh style, the clear colour and Kajiya-Kay's uniform.
    let mut to = from.clone();
    to.shade.ambient = 0.5;
    to.shade.root_occlusion = 0.1;
    to.shade.mesh_color = Vec3::new(0.1, 0.3, 0.5);
    to.shade.background = Vec3::new(0.3, 0.1, 0.1);
    if let ShadingModel::KajiyaKay(p) = &mut to.shade.model {
        p.specular *= 2.0;
        p.shininess = 20.0;
    }
    in_place_matches_a_new_renderer(&gpu, &from, &to, "shading");
}

#[test]
fn every_model_takes_its_parameters_in_place_tables_included() {
    let gpu = gpu();
    let marschner = MarschnerParams::default();
    let changed_marschner = MarschnerParams {
        eta: 1.8,
        beta_r_deg: marschner.beta_r_deg * 1.6,
        diffuse: 0.3,
        ..marschner.clone()
    };
    let chiang = ChiangParams::default();
    let sadeghi = SadeghiParams::default();
    let cases = [
        (
            ShadingModel::Marschner {
                params: marschner.clone(),
                lut: false,
            },
            ShadingModel::Marschner {
                params: changed_marschner.clone(),
                lut: false,
            },
        ),
        // The tables are filled again.
        (
            ShadingModel::Marschner {
                params: marschner.clone(),
                lut: true,
            },
            ShadingModel::Marschner {
                params: changed_marschner,
                lut: true,
            },
        ),
        (
            ShadingModel::Sadeghi(sadeghi.clone()),
            ShadingModel::Sadeghi(SadeghiParams {
                intensity_r: sadeghi.intensity_r * 2.0,
                intensity_tt: 0.2,
                ..sadeghi
            }),
        ),
        // η and β_n are tabulated: the tables are filled again.
        (
            ShadingModel::Chiang(chiang.clone()),
            ShadingModel::Chiang(ChiangParams {
                eta: 1.7,
                beta_n: 0.6,
                beta_m: 0.5,
                ..chiang
            }),
        ),
    ];
    for (a, b) in cases {
        let mut from = base();
        from.shade.model = a;
        let mut to = from.clone();
        to.shade.model = b;
        in_place_matches_a_new_renderer(&gpu, &from, &to, "shading");
    }
}

#[test]
fn several_changes_at_once_under_a_transparency_method() {
    let gpu = gpu();
    let mut from = base();
    from.shade.transparency = Transparency::wboit();
    let mut to = from.clone();
    to.hair.wind.strength = 0.2;
    to.hair.growth.color = Vec3::new(0.2, 0.2, 0.25);
    to.shade.ambient = 0.4;
    to.lights[0] = Light::Directional(DirectionalLight {
        direction: Vec3::new(0.5, -0.7, -0.3),
        ..Default::default()
    });
    in_place_matches_a_new_renderer(&gpu, &from, &to, "shading, wind, hair colour and lights");
}

#[test]
fn structural_changes_ask_for_a_rebuild_and_change_nothing() {
    let gpu = gpu();
    let from = base();
    let mut renderer = Renderer::new(&gpu, &from, SIZE.0, SIZE.1).unwrap();
    let before = picture(&gpu, &mut renderer, &from);
    let cases: Vec<(&str, Edit)> = vec![
        ("strand count", Box::new(|s| s.hair.roots.count = 2000)),
        ("length", Box::new(|s| s.hair.growth.length *= 1.5)),
        (
            "transparency",
            Box::new(|s| s.shade.transparency = Transparency::wboit()),
        ),
        ("sample count", Box::new(|s| s.shade.sample_count = 1)),
        ("shadow method", Box::new(|s| s.shadow = ShadowParams::None)),
        (
            "light count",
            Box::new(|s| s.lights = Light::key_and_back(&s.camera)),
        ),
        (
            "model kind",
            Box::new(|s| s.shade.model = ShadingModel::Sadeghi(Default::default())),
        ),
        (
            "mesh",
            Box::new(|s| s.mesh.positions[0] += Vec3::splat(0.01)),
        ),
    ];
    for (name, change) in cases {
        let mut to = from.clone();
        // A change that could be made in place rides along: it must not be applied either.
        to.hair.wind.strength = 3.0;
        to.shade.ambient = 0.9;
        change(&mut to);
        match renderer.frame_mut().update(&gpu, &to) {
            Err(Error::NeedsRebuild(why)) => println!("{name}: rebuild ({why})"),
            other => panic!("{name}: expected a rebuild, got {other:?}"),
        }
    }
    let after = picture(&gpu, &mut renderer, &from);
    assert_eq!(
        diff(&before, &after),
        (0, 0),
        "a refused update changed the picture"
    );
}

#[test]
fn updates_refuse_bad_values_and_structural_changes_with_typed_errors() {
    let gpu = gpu();
    let from = base();
    let mut renderer = Renderer::new(&gpu, &from, SIZE.0, SIZE.1).unwrap();
    let before = picture(&gpu, &mut renderer, &from);
    let frame = renderer.frame_mut();
    let two = Light::key_and_back(&from.camera);
    assert!(matches!(
        frame.set_lights(&two),
        Err(Error::NeedsRebuild(_))
    ));
    let edits: Vec<(&str, bool, Edit)> = vec![
        (
            "two lights",
            true,
            Box::new(move |s| s.lights = two.clone()),
        ),
        (
            "NaN wind",
            false,
            Box::new(|s| s.hair.wind.strength = f32::NAN),
        ),
        (
            "negative hair colour",
            false,
            Box::new(|s| s.hair.growth.color = Vec3::new(-1.0, 0.0, 0.0)),
        ),
        (
            "colour jitter 1",
            false,
            Box::new(|s| s.hair.growth.color_jitter = 1.0),
        ),
        (
            "another transparency method",
            true,
            Box::new(|s| s.shade.transparency = Transparency::wboit()),
        ),
        (
            "negative ambient",
            false,
            Box::new(|s| s.shade.ambient = -1.0),
        ),
        (
            "infinite ambient",
            false,
            Box::new(|s| s.shade.ambient = f32::INFINITY),
        ),
    ];
    for (name, structural, edit) in edits {
        let mut to = from.clone();
        edit(&mut to);
        match frame.update(&gpu, &to) {
            Err(Error::NeedsRebuild(why)) if structural => println!("{name}: rebuild ({why})"),
            Err(e) if !structural && !matches!(e, Error::NeedsRebuild(_)) => {
                println!("{name}: {e}")
            }
            other => panic!(
                "{name}: expected {}, got {other:?}",
                if structural {
                    "a rebuild"
                } else {
                    "a bad value"
                }
            ),
        }
    }
    let after = picture(&gpu, &mut renderer, &from);
    assert_eq!(
        diff(&before, &after),
        (0, 0),
        "a refused update changed the picture"
    );
}

#[test]
fn without_shadows_the_light_count_changes_in_place() {
    let gpu = gpu();
    let mut from = base();
    from.shadow = ShadowParams::None;
    let mut to = from.clone();
    to.lights = Light::key_and_back(&to.camera);
    in_place_matches_a_new_renderer(&gpu, &from, &to, "lights");
}
