//! Engine-chosen targets: the same scene drawn into an HDR colour target, a BGRA one, a
//! depth-stencil depth and reversed depth gives the picture of the default formats; a
//! target the method cannot draw is a typed error, not a wrong picture.

use pelage::gpu::{Gpu, wgpu};
use pelage::scene::{Camera, Transparency};
use pelage::shade::TargetFormat;
use pelage::{Renderer, scene::Scene};

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
    // A sample count the adapter lacks.
    let s = scene(Transparency::Wboit {
        weight: Default::default(),
    });
    let odd = TargetFormat {
        samples: 3,
        ..TargetFormat::default()
    };
    let err = Renderer::with_format(&gpu, &s, W, H, &odd).unwrap_err();
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
    let frame = renderer.frame().strands().frame().unwrap();
    let err = renderer
        .frame()
        .hair_pass()
        .prepare(&gpu.queue, &frame, &reversed, &s.lights, W, H)
        .unwrap_err();
    assert!(err.to_string().contains("reverse_z"), "{err}");
    // The frame checks it first, for every method, naming the camera's projection.
    let err = renderer
        .frame_mut()
        .prepare(&gpu.queue, 0.0, &reversed)
        .unwrap_err();
    assert!(err.to_string().contains("camera.projection"), "{err}");
    renderer
        .frame_mut()
        .prepare(&gpu.queue, 0.0, &camera.matrices(W, H))
        .unwrap();
}

/// Every transparency method the adapter runs draws multisampled targets and reversed
/// depth (an engine's: Bevy's are both) through the frame's target bridge
/// (`src/bridge.rs`): the picture of the single-sampled, standard-depth targets.
#[test]
fn every_method_draws_multisampled_and_reverse_z_targets() {
    let gpu = gpu();
    let supported = pelage::shade::supported_methods(&gpu);
    for transparency in Transparency::defaults() {
        if transparency == Transparency::Opaque {
            continue; // draws multisampled and reversed itself (the test above)
        }
        if !supported.contains(&transparency.name()) {
            println!(
                "{}: skipped, this adapter ({}) lacks what it needs",
                transparency.name(),
                gpu.describe()
            );
            continue;
        }
        let s = scene(transparency.clone());
        let base = TargetFormat::for_params(&s.shade);
        let reference = render(&gpu, &s, &base);
        let variants = [
            ("4x MSAA", TargetFormat { samples: 4, ..base }),
            (
                "reverse-Z",
                TargetFormat {
                    reverse_z: true,
                    ..base
                },
            ),
            (
                "4x MSAA, Rgba16Float, Depth24PlusStencil8, reverse-Z",
                TargetFormat {
                    samples: 4,
                    color: wgpu::TextureFormat::Rgba16Float,
                    depth: wgpu::TextureFormat::Depth24PlusStencil8,
                    reverse_z: true,
                },
            ),
        ];
        for (name, format) in variants {
            let image = render(&gpu, &s, &format);
            let (mean, large) = compare(&reference, &image);
            println!(
                "{} {name}: mean {mean:.3}/255, {:.3}% large",
                transparency.name(),
                large * 100.0
            );
            // The bridge writes the single-sampled picture into every sample: what is
            // left is 16-bit float storage, 24-bit depth and 1 - depth's rounding.
            assert!(
                mean < 1.0 && large < 0.002,
                "{} {name}: mean {mean:.3}/255, {:.3}% of channels off by more than 24",
                transparency.name(),
                large * 100.0
            );
        }
    }
}

/// `Transparency::draws_reverse_z` (which methods the frame bridges to standard depth) is
/// the list of methods stage 3 refuses reversed depth for.
#[test]
fn the_methods_that_draw_reverse_z_are_the_ones_stage_3_builds() {
    let gpu = gpu();
    let supported = pelage::shade::supported_methods(&gpu);
    let reversed = TargetFormat {
        reverse_z: true,
        ..TargetFormat::default()
    };
    for transparency in Transparency::defaults() {
        if !supported.contains(&transparency.name()) {
            continue;
        }
        let s = scene(transparency.clone());
        let frame = pelage::Frame::new(
            &gpu,
            &s,
            &pelage::FrameTarget::new(TargetFormat::for_params(&s.shade), W, H),
        )
        .unwrap();
        let built = pelage::shade::build(
            &gpu,
            &pelage::shade::HairInputs {
                params: &s.shade,
                mesh: frame.mesh_buffers(),
                strands: frame.strands().buffers(),
                shadows: &[],
                visibility: None,
                target: reversed,
                draw_mesh: true,
                grid_apart: false,
            },
            W,
            H,
        );
        assert_eq!(
            built.is_ok(),
            transparency.draws_reverse_z(),
            "{}: {:?}",
            transparency.name(),
            built.err()
        );
    }
}
