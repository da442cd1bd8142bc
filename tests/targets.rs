//! Engine-chosen targets: the same scene drawn into an HDR colour target, a BGRA one, a
//! depth-stencil depth and reversed depth gives the picture of the default formats; a
//! target the method cannot draw is a typed error, not a wrong picture.

use pelage::gpu::{Gpu, wgpu};
use pelage::scene::{Camera, Transparency};
use pelage::shade::TargetFormat;
use pelage::{Renderer, Scene};

const W: u32 = 96;
const H: u32 = 72;

fn gpu() -> Gpu {
    Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"))
}

fn scene(transparency: Transparency) -> Scene {
    let mut scene = Scene::default();
    scene.hair.roots.count = 3000;
    scene.shade.transparency = transparency;
    scene
}

/// The frame as sRGB RGBA8 bytes.
fn render(gpu: &Gpu, scene: &Scene, format: &TargetFormat) -> Vec<u8> {
    let mut renderer = Renderer::with_format(gpu, scene, W, H, format)
        .unwrap_or_else(|e| panic!("{format:?}: {e}"));
    renderer.render(gpu, 0.5, &scene.camera).unwrap();
    renderer.image(gpu).unwrap().into_raw()
}

/// Mean absolute difference per channel (of 255) and the share of channels off by more than 24.
fn compare(a: &[u8], b: &[u8]) -> (f64, f64) {
    assert_eq!(a.len(), b.len());
    let d: Vec<u8> = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).collect();
    let mean = d.iter().map(|&v| f64::from(v)).sum::<f64>() / d.len() as f64;
    let large = d.iter().filter(|&&v| v > 24).count() as f64 / d.len() as f64;
    (mean, large)
}

#[test]
fn every_target_format_gives_the_default_picture() {
    let gpu = gpu();
    let methods = [
        Transparency::Opaque,
        Transparency::Wboit {
            weight: Default::default(),
        },
        Transparency::ABuffer {
            nodes_per_pixel: 24.0,
            resolve_k: 16,
        },
        Transparency::strand_raster(),
    ];
    for transparency in methods {
        let s = scene(transparency.clone());
        let base = TargetFormat::for_params(&s.shade);
        let reference = render(&gpu, &s, &base);
        // Something was drawn: the hair is not the background everywhere.
        let background = &reference[..4];
        assert!(
            reference.chunks(4).any(|p| p != background),
            "{transparency:?}: blank picture"
        );
        let variants = [
            (
                "Rgba16Float",
                TargetFormat {
                    color: wgpu::TextureFormat::Rgba16Float,
                    ..base
                },
            ),
            (
                "Bgra8UnormSrgb",
                TargetFormat {
                    color: wgpu::TextureFormat::Bgra8UnormSrgb,
                    ..base
                },
            ),
            (
                "Depth24PlusStencil8",
                TargetFormat {
                    depth: wgpu::TextureFormat::Depth24PlusStencil8,
                    ..base
                },
            ),
            (
                "reverse-Z",
                TargetFormat {
                    reverse_z: true,
                    ..base
                },
            ),
            (
                "Rgba16Float, Depth24PlusStencil8, reverse-Z",
                TargetFormat {
                    color: wgpu::TextureFormat::Rgba16Float,
                    depth: wgpu::TextureFormat::Depth24PlusStencil8,
                    reverse_z: true,
                    ..base
                },
            ),
        ];
        for (name, format) in variants {
            // The methods testing against the opaque depth in the shader refuse reversed
            // depth (see `a_reverse_z_target_is_refused_where_it_cannot_be_drawn`).
            if format.reverse_z && matches!(transparency, Transparency::ABuffer { .. }) {
                continue;
            }
            let image = render(&gpu, &s, &format);
            let (mean, large) = compare(&reference, &image);
            println!(
                "{transparency:?} {name}: mean {mean:.3}/255, {:.3}% large",
                large * 100.0
            );
            // 8-bit against 16-bit float storage, 24-bit against 32-bit depth: small
            // rounding differences only.
            assert!(
                mean < 1.0 && large < 0.002,
                "{transparency:?} {name}: mean {mean:.3}/255, {:.3}% of channels off by more than 24",
                large * 100.0
            );
        }
    }
}

#[test]
fn a_target_the_method_cannot_draw_is_an_error() {
    let gpu = gpu();
    // The transparency methods draw single-sampled.
    let s = scene(Transparency::Wboit {
        weight: Default::default(),
    });
    let msaa = TargetFormat {
        samples: 4,
        ..TargetFormat::default()
    };
    let err = Renderer::with_format(&gpu, &s, W, H, &msaa).unwrap_err();
    assert!(err.to_string().contains("target.samples"), "{err}");
    // A depth format as colour, a colour format as depth.
    for bad in [
        TargetFormat {
            color: wgpu::TextureFormat::Depth32Float,
            ..TargetFormat::default()
        },
        TargetFormat {
            depth: wgpu::TextureFormat::Rgba8Unorm,
            ..TargetFormat::default()
        },
    ] {
        let err = Renderer::with_format(&gpu, &scene(Transparency::Opaque), W, H, &bad)
            .unwrap_err()
            .to_string();
        assert!(err.contains("target."), "{bad:?}: {err}");
    }
}

#[test]
fn a_projection_that_disagrees_with_the_depth_direction_is_an_error() {
    let gpu = gpu();
    let s = scene(Transparency::Opaque);
    let mut renderer = Renderer::new(&gpu, &s, W, H).unwrap();
    let camera = Camera::default();
    let reversed = camera.matrices_reverse_z(W, H);
    assert!(reversed.reverse_z() && !camera.matrices(W, H).reverse_z());
    // The facade projects with standard depth for standard targets: fine.
    renderer.render(&gpu, 0.0, &camera).unwrap();
    // A stage 3 method built for standard depth refuses a reversed projection.
    let frame = renderer.strands().frame().unwrap();
    let err = renderer
        .hair_pass()
        .prepare(&gpu.queue, &frame, &reversed, &s.lights, W, H)
        .unwrap_err();
    assert!(err.to_string().contains("reverse_z"), "{err}");
}

#[test]
fn a_reverse_z_target_is_refused_where_it_cannot_be_drawn() {
    let gpu = gpu();
    let reversed = TargetFormat {
        reverse_z: true,
        ..TargetFormat::default()
    };
    for transparency in [
        Transparency::ABuffer {
            nodes_per_pixel: 8.0,
            resolve_k: 16,
        },
        Transparency::Dbk {
            depth_shift: 1.0,
            nodes_per_pixel: 8.0,
            resolve_k: 16,
        },
        Transparency::KBuffer { k: 8 },
        Transparency::RandomSubsets { k: 8 },
    ] {
        let err = Renderer::with_format(&gpu, &scene(transparency.clone()), W, H, &reversed)
            .unwrap_err()
            .to_string();
        assert!(err.contains("reverse-Z"), "{transparency:?}: {err}");
    }
}
