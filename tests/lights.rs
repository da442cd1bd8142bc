//! Several lights, each with its own shadow from stage 2.

use glam::Vec3;
use pelage::scene::{DirectionalLight, Light, PointLight};
use pelage::{Renderer, Scene, gpu::Gpu};

fn gpu() -> Gpu {
    Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"))
}

fn scene(lights: Vec<Light>) -> Scene {
    let mut scene = Scene::default();
    scene.hair.roots.count = 4000;
    scene.lights = lights;
    scene
}

fn directional(direction: Vec3) -> Light {
    Light::Directional(DirectionalLight {
        direction,
        ..Default::default()
    })
}

/// Mean visibility of the strand tips (the last vertex of each strand) on each side of x = 0.
fn sides(renderer: &Renderer, gpu: &Gpu, light: usize) -> (f32, f32) {
    let vis = renderer.light_visibility(gpu).unwrap();
    let vertices = pelage::gpu::read_buffer(gpu, &renderer.strands().buffers().vertices).unwrap();
    let points: &[[f32; 4]] = bytemuck::cast_slice(&vertices);
    let (mut plus, mut minus) = (Vec::new(), Vec::new());
    for (p, v) in points.iter().zip(&vis[light]) {
        if p[0] > 0.2 {
            plus.push(*v);
        } else if p[0] < -0.2 {
            minus.push(*v);
        }
    }
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len().max(1) as f32;
    (mean(&plus), mean(&minus))
}

#[test]
fn each_light_has_its_own_shadow() {
    let gpu = gpu();
    // Light 0 shines from +x (travels towards -x), light 1 from -x.
    let s = scene(vec![directional(Vec3::NEG_X), directional(Vec3::X)]);
    let mut renderer = Renderer::new(&gpu, &s, 96, 72).unwrap();
    renderer.render(&gpu, 0.0, &s.camera).unwrap();
    let (l0_plus, l0_minus) = sides(&renderer, &gpu, 0);
    let (l1_plus, l1_minus) = sides(&renderer, &gpu, 1);
    println!("light 0 (from +x): +x side {l0_plus:.3}, -x side {l0_minus:.3}");
    println!("light 1 (from -x): +x side {l1_plus:.3}, -x side {l1_minus:.3}");
    assert!(
        l0_plus > l0_minus + 0.2,
        "light 0 does not shadow the far side"
    );
    assert!(
        l1_minus > l1_plus + 0.2,
        "light 1 does not shadow the far side"
    );
}

#[test]
fn four_lights_and_the_key_plus_back_preset_render() {
    let gpu = gpu();
    let base = scene(vec![Light::default()]);
    let mut renderer = Renderer::new(&gpu, &base, 96, 72).unwrap();
    renderer.render(&gpu, 0.0, &base.camera).unwrap();
    let key_only = renderer.image(&gpu).unwrap();

    let preset = scene(Light::key_and_back(&base.camera));
    let mut renderer = Renderer::new(&gpu, &preset, 96, 72).unwrap();
    renderer.render(&gpu, 0.0, &preset.camera).unwrap();
    let key_back = renderer.image(&gpu).unwrap();
    let sum = |img: &image::RgbaImage| img.as_raw().iter().map(|&v| u64::from(v)).sum::<u64>();
    println!("key only {}, key + back {}", sum(&key_only), sum(&key_back));
    assert_ne!(key_only.as_raw(), key_back.as_raw());

    let four = scene(vec![
        directional(Vec3::NEG_X),
        directional(Vec3::X),
        Light::Point(PointLight::default()),
        Light::Point(PointLight {
            position: Vec3::new(0.0, 3.0, 0.0),
            ..Default::default()
        }),
    ]);
    let mut renderer = Renderer::new(&gpu, &four, 96, 72).unwrap();
    renderer.render(&gpu, 0.0, &four.camera).unwrap();
    assert_eq!(renderer.light_visibility(&gpu).unwrap().len(), 4);
}

#[test]
fn a_point_light_falls_off_with_distance() {
    let gpu = gpu();
    let brightness = |distance: f32| {
        let s = scene(vec![Light::Point(PointLight {
            position: Vec3::new(2.2, 0.9, 2.9).normalize() * distance,
            color: Vec3::ONE,
            intensity: 4.0 * distance * distance,
        })]);
        let mut renderer = Renderer::new(&gpu, &s, 96, 72).unwrap();
        renderer.render(&gpu, 0.0, &s.camera).unwrap();
        let img = renderer.image(&gpu).unwrap();
        img.as_raw().iter().map(|&v| u64::from(v)).sum::<u64>()
    };
    // Intensity scaled with distance squared: the irradiance at the scene stays about
    // the same, so the images do too (within a few percent; the light's angle changes a little).
    let (near, far) = (brightness(3.0), brightness(6.0));
    let ratio = near as f64 / far as f64;
    println!("near {near}, far {far}, ratio {ratio:.3}");
    assert!(
        (ratio - 1.0).abs() < 0.1,
        "inverse-square falloff is off: {ratio}"
    );
}
