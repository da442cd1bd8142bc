//! The body's sky (`shade/body_sky.wgsl`; the volume method's `shade/body_sky_volume.wgsl`):
//! with the volume method the skin under the hair sees the sky the grid leaves it, the
//! irradiance `φ/4 − Φ·n/2` of the grid's order-1 radiance; with the other methods the
//! whole sky, `ambient`. The hair is grown with opacity 0: it fills the grid but draws
//! nothing, so every pixel of the sphere is skin.

mod support;

use glam::Vec3;
use pelage_gpu::Gpu;
use pelage_reference::oit::srgb8_to_linear;
use pelage_scene::{
    Camera, ChiangParams, DirectionalLight, HairParams, Light, Mesh, MultipleScattering,
    ShadeParams, ShadingModel, Transparency,
};
use support::{H, Scene, W, gpu, grown, inputs, render_lit};

const AMBIENT: f32 = 0.5;
const SKIN: Vec3 = Vec3::new(0.2, 0.2, 0.2);

/// Hair all over a sphere of radius 0.5, `width` wide, 0.3 long; the camera in front.
fn head(gpu: &Gpu, width: f32) -> Scene {
    let mut hair = HairParams::default();
    hair.roots.count = 4000;
    hair.growth.segments = 8;
    hair.growth.length = 0.3;
    hair.growth.width = width;
    let camera = Camera {
        eye: Vec3::new(0.0, 0.0, 2.4),
        target: Vec3::ZERO,
        ..Default::default()
    };
    grown(gpu, Mesh::icosphere(0.5, 3).unwrap(), hair, 0.0, camera)
}

/// The linear luminance of the pixel at the image's centre (the skin facing the
/// camera) under the sky alone, shaded by Chiang with `multiple_scattering`.
fn centre_skin(gpu: &Gpu, s: &Scene, multiple_scattering: MultipleScattering) -> f32 {
    let params = ShadeParams {
        transparency: Transparency::KBuffer { k: 4 },
        model: ShadingModel::Chiang(ChiangParams {
            multiple_scattering,
            ..Default::default()
        }),
        ambient: AMBIENT,
        mesh_color: SKIN,
        ..Default::default()
    };
    let method = pelage_shade::build(gpu, &inputs(s, &params), W, H).unwrap();
    // A frame needs a light: one of no intensity, so the sky lights the skin alone.
    let dark = [Light::Directional(DirectionalLight {
        direction: -Vec3::Y,
        color: Vec3::ONE,
        intensity: 0.0,
    })];
    let (image, _) = render_lit(gpu, s, method.as_ref(), params.samples(), &dark);
    let at = ((H / 2 * W + W / 2) * 4) as usize;
    let px = &image[at..at + 3];
    // The skin is grey: any channel is the luminance.
    srgb8_to_linear(px[1])
}

#[test]
fn the_skin_under_the_hair_sees_the_sky_the_grid_leaves_it() {
    let gpu = gpu();
    let open = SKIN.y * AMBIENT;
    let dense = head(&gpu, 0.03);
    let thin = head(&gpu, 0.0001);
    let none = centre_skin(&gpu, &dense, MultipleScattering::None);
    let under = centre_skin(&gpu, &dense, MultipleScattering::Volume);
    let bare = centre_skin(&gpu, &thin, MultipleScattering::Volume);
    let dual = centre_skin(&gpu, &dense, MultipleScattering::DualVolume);
    println!(
        "the skin facing the camera over mesh_color x ambient: without the grid {:.3}, \
         under hair 0.03 wide {:.3} (dual_volume {:.3}), under hair 0.0001 wide {:.3}",
        none / open,
        under / open,
        dual / open,
        bare / open
    );
    // Without the grid the whole sky (to the sRGB target's step, about 1%).
    assert!((none / open - 1.0).abs() < 0.02, "{none} vs {open}");
    // Under the hair the skin sees part of the sky (and the light the hair returns);
    // `dual_volume`'s grid holds the same sky.
    assert!(
        under < 0.8 * open && under > 0.05 * open,
        "{under} vs {open}"
    );
    assert!((dual - under).abs() < 0.02 * open, "{dual} vs {under}");
    // Hair too thin to hide anything: the sphere's own half of the sky, the whole of
    // what a convex body's skin sees, `ambient`, within the grid's blocky body.
    assert!((bare / open - 1.0).abs() < 0.1, "{bare} vs {open}");
}
