//! Several lights, each with its own shadow from stage 2.

use glam::Vec3;
use pelage::scene::{DirectionalLight, Light, PointLight};
use pelage::{Renderer, gpu::Gpu, scene::Scene};

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

/// Each light's visibility at every strand vertex after the last frame (up to `lights`).
fn visibility(renderer: &Renderer, gpu: &Gpu, lights: usize) -> Vec<Vec<f32>> {
    let frame = renderer.frame();
    let vertices = frame.strands().buffers().full_layout().vertices() as usize;
    frame
        .visibility()
        .expect("the scene has shadows")
        .read(gpu, lights, vertices)
        .unwrap()
}

/// Mean visibility of the strand tips (the last vertex of each strand) on each side of x = 0.
fn sides(renderer: &Renderer, gpu: &Gpu, light: usize) -> (f32, f32) {
    let vis = visibility(renderer, gpu, 4);
    let vertices =
        pelage::gpu::read_buffer(gpu, &renderer.frame().strands().buffers().vertices).unwrap();
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
    assert_eq!(visibility(&renderer, &gpu, 8).len(), 4);
}

#[test]
fn a_point_light_falls_off_with_distance() {
    let gpu = gpu();
    // Linear light from an HDR target, nothing but the point light: no ambient, no
    // shadows (the shadow grid would be aimed anew from each position), so what the
    // hair and mesh reflect is the light's irradiance at them, times the same BRDF.
    let linear_sum = |intensity: f32, distance: f32| {
        let mut s = scene(vec![Light::Point(PointLight {
            position: Vec3::new(2.2, 0.9, 2.9).normalize() * distance,
            color: Vec3::ONE,
            intensity,
        })]);
        s.shade.ambient = 0.0;
        s.shadow = pelage::scene::ShadowParams::None;
        let format = pelage::shade::TargetFormat {
            color: pelage::gpu::wgpu::TextureFormat::Rgba16Float,
            ..pelage::shade::TargetFormat::for_params(&s.shade)
        };
        let mut renderer = Renderer::with_format(&gpu, &s, 96, 72, &format).unwrap();
        renderer.render(&gpu, 0.0, &s.camera).unwrap();
        let data = pelage::gpu::read_texture(&gpu, renderer.color_texture()).unwrap();
        let halves: &[u16] = bytemuck::cast_slice(&data.data);
        halves
            .chunks_exact(4)
            .map(|p| {
                p[..3]
                    .iter()
                    .map(|&h| f64::from(pelage::gpu::f16_to_f32(h)))
                    .sum::<f64>()
            })
            .sum::<f64>()
    };
    // The same light at 20 and 40 units from the hair (about 0.8 units in radius): at half
    // the distance, four times the light. The background's share comes out with a
    // black light.
    let intensity = 400.0;
    let background = linear_sum(0.0, 20.0);
    let near = linear_sum(intensity, 20.0) - background;
    let far = linear_sum(intensity, 40.0) - background;
    let ratio = near / far;
    println!("near {near:.2}, far {far:.2}, background {background:.2}, ratio {ratio:.3}");
    assert!(far > 0.0, "the far light lit nothing");
    // The hair's depth along the light moves each point's distance by up to 4% (2% at
    // 40 units), nearer points weigh more: the ratio of sums lies within a few percent
    // of 4 (4.25 at 10 and 20 units, measured).
    assert!(
        (ratio - 4.0).abs() < 0.25,
        "inverse-square falloff is off: {ratio}"
    );
}

/// Every light with a shadow shadows the mesh, not only the key light: the key light
/// split into two lights of half its intensity (the same direction, so the same shadow
/// twice) draws the picture the key light draws alone, mesh included (the mesh's
/// second light is an additive draw shadowed by its own shadow). Drawn into an HDR
/// target, so the sum is not rounded to 8 bits between the draws.
#[test]
fn every_shadowed_light_shadows_the_mesh() {
    let gpu = gpu();
    let one = scene(vec![Light::default()]);
    let Light::Directional(key) = Light::default() else {
        panic!("the default light is directional");
    };
    let half = Light::Directional(DirectionalLight {
        intensity: key.intensity * 0.5,
        ..key
    });
    let two = scene(vec![half.clone(), half]);
    let picture = |s: &Scene| {
        let format = pelage::shade::TargetFormat {
            color: pelage::gpu::wgpu::TextureFormat::Rgba16Float,
            ..pelage::shade::TargetFormat::for_params(&s.shade)
        };
        let mut renderer = Renderer::with_format(&gpu, s, 96, 72, &format).unwrap();
        renderer.render(&gpu, 0.0, &s.camera).unwrap();
        renderer.rgba8(&gpu).unwrap().2
    };
    let (a, b) = (picture(&one), picture(&two));
    let diffs: Vec<u8> = a.iter().zip(&b).map(|(x, y)| x.abs_diff(*y)).collect();
    let largest = diffs.iter().copied().max().unwrap_or(0);
    let differing = diffs.iter().filter(|&&d| d > 1).count();
    println!(
        "one light vs two half lights: largest difference {largest}/255, {differing} of {} \
         channels differ by more than 1",
        diffs.len()
    );
    assert!(
        largest <= 2 && differing * 1000 <= diffs.len(),
        "{largest}, {differing}"
    );
}
