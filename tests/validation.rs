//! Bad input, case by case: every entry of `CASES` breaks one thing in an otherwise
//! good scene and names the error it must produce. Nothing may panic, and the error
//! must name what was wrong.

use glam::Vec3;
use pelage::contract::ContractError;
use pelage::scene::{
    AdsmParams, ChiangParams, DeepOpacityParams, DirectionalLight, HairType, KajiyaKayParams,
    LayerSpacing, Light, MarschnerParams, PointLight, ShadingModel, ShadowMapParams, ShadowParams,
    Transparency, VoxelParams,
};
use pelage::{Error, Renderer, gpu::Gpu, gpu::GpuError, scene::Scene, strands::StrandsError};

/// The kind of error a case must produce.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    /// A parameter out of range, whose name the message must contain.
    Param(&'static str),
    /// An unusable mesh; the message must contain this text.
    Mesh(&'static str),
    /// More than the device can hold; the message must name the buffer.
    TooLarge(&'static str),
}

type Case = (&'static str, fn(&mut Scene), Kind);

fn drop_all(v: &mut Vec<Vec3>) {
    v.clear();
}

const CASES: &[Case] = &[
    // Growth.
    (
        "length NaN",
        |s| s.hair.growth.length = f32::NAN,
        Kind::Param("growth.length"),
    ),
    (
        "length zero",
        |s| s.hair.growth.length = 0.0,
        Kind::Param("growth.length"),
    ),
    (
        "length negative",
        |s| s.hair.growth.length = -1.0,
        Kind::Param("growth.length"),
    ),
    (
        "length infinite",
        |s| s.hair.growth.length = f32::INFINITY,
        Kind::Param("growth.length"),
    ),
    (
        "no segments",
        |s| s.hair.growth.segments = 0,
        Kind::Param("growth.segments"),
    ),
    (
        "segments beyond the limit",
        |s| s.hair.growth.segments = 257,
        Kind::Param("growth.segments"),
    ),
    (
        "width zero",
        |s| s.hair.growth.width = 0.0,
        Kind::Param("growth.width"),
    ),
    (
        "width NaN",
        |s| s.hair.growth.width = f32::NAN,
        Kind::Param("growth.width"),
    ),
    (
        "tip width above 1",
        |s| s.hair.growth.tip_width = 1.5,
        Kind::Param("growth.tip_width"),
    ),
    (
        "length jitter 1",
        |s| s.hair.growth.length_jitter = 1.0,
        Kind::Param("growth.length_jitter"),
    ),
    (
        "direction jitter past 90 degrees",
        |s| s.hair.growth.direction_jitter = 2.0,
        Kind::Param("growth.direction_jitter"),
    ),
    (
        "negative force weight",
        |s| s.hair.growth.force_weight = -1.0,
        Kind::Param("growth.force_weight"),
    ),
    (
        "gravity NaN",
        |s| s.hair.growth.gravity = Vec3::NAN,
        Kind::Param("growth.gravity"),
    ),
    (
        "opacity above 1",
        |s| s.hair.growth.opacity = 2.0,
        Kind::Param("growth.opacity"),
    ),
    (
        "negative colour",
        |s| s.hair.growth.color = Vec3::new(-1.0, 0.0, 0.0),
        Kind::Param("growth.color"),
    ),
    (
        "wave amplitude NaN",
        |s| {
            s.hair.growth.hair_type = HairType::Wavy {
                amplitude: f32::NAN,
                frequency: 1.0,
            }
        },
        Kind::Param("growth.hair_type.amplitude"),
    ),
    (
        "curl pitch zero",
        |s| {
            s.hair.growth.hair_type = HairType::Curly {
                radius: 0.01,
                pitch: 0.0,
            }
        },
        Kind::Param("growth.hair_type.pitch"),
    ),
    // Wind.
    (
        "wind infinite",
        |s| s.hair.wind.strength = f32::INFINITY,
        Kind::Param("wind.strength"),
    ),
    (
        "wind beyond the largest force",
        |s| s.hair.wind.strength = 1e7,
        Kind::Param("wind.strength"),
    ),
    (
        "gusts above 1",
        |s| s.hair.wind.gust_strength = 2.0,
        Kind::Param("wind.gust_strength"),
    ),
    (
        "wind direction NaN",
        |s| s.hair.wind.direction = Vec3::NAN,
        Kind::Param("wind.direction"),
    ),
    (
        "negative turbulence scale",
        |s| s.hair.wind.turbulence_scale = -1.0,
        Kind::Param("wind.turbulence_scale"),
    ),
    // Roots.
    (
        "zero strands",
        |s| s.hair.roots.count = 0,
        Kind::Param("roots.count"),
    ),
    (
        "density map of the wrong length",
        |s| s.hair.roots.density = Some(vec![1.0; 3]),
        Kind::Param("roots.density"),
    ),
    (
        "negative density",
        |s| {
            let mut d = vec![1.0; s.mesh.positions.len()];
            d[7] = -1.0;
            s.hair.roots.density = Some(d);
        },
        Kind::Param("roots.density[7]"),
    ),
    (
        "length map NaN",
        |s| s.hair.roots.length_scale = Some(vec![f32::NAN; s.mesh.positions.len()]),
        Kind::Param("roots.length_scale[0]"),
    ),
    // Mesh.
    (
        "no triangles",
        |s| s.mesh.indices.clear(),
        Kind::Mesh("no triangles"),
    ),
    (
        "index out of range",
        |s| s.mesh.indices[4] = 1_000_000,
        Kind::Mesh("1000000"),
    ),
    (
        "indices not in threes",
        |s| s.mesh.indices.push(0),
        Kind::Mesh("multiple of 3"),
    ),
    (
        "NaN position",
        |s| s.mesh.positions[3].y = f32::NAN,
        Kind::Mesh("position"),
    ),
    (
        "zero-length normal",
        |s| s.mesh.normals[2] = Vec3::ZERO,
        Kind::Mesh("normal"),
    ),
    (
        "normals missing",
        |s| drop_all(&mut s.mesh.normals),
        Kind::Mesh("normal"),
    ),
    (
        "every triangle degenerate",
        |s| {
            for p in &mut s.mesh.positions {
                *p = Vec3::ONE;
            }
        },
        Kind::Mesh("zero or near-zero area"),
    ),
    // Shading.
    (
        "shininess zero",
        |s| {
            s.shade.model = ShadingModel::KajiyaKay(KajiyaKayParams {
                shininess: 0.0,
                ..Default::default()
            })
        },
        Kind::Param("shading.kajiya_kay.shininess"),
    ),
    (
        "Marschner eta of 1",
        |s| {
            s.shade.model = ShadingModel::Marschner {
                params: MarschnerParams {
                    eta: 1.0,
                    ..Default::default()
                },
                lut: true,
            }
        },
        Kind::Param("shading.marschner.eta"),
    ),
    (
        "Marschner absorption negative",
        |s| {
            s.shade.model = ShadingModel::Marschner {
                params: MarschnerParams {
                    sigma_a: Vec3::new(0.1, -1.0, 0.1),
                    ..Default::default()
                },
                lut: false,
            }
        },
        Kind::Param("shading.marschner.sigma_a"),
    ),
    (
        "Chiang eumelanin negative",
        |s| {
            s.shade.model = ShadingModel::Chiang(ChiangParams {
                eumelanin: Some(-0.5),
                ..Default::default()
            })
        },
        Kind::Param("shading.chiang.eumelanin"),
    ),
    (
        "Chiang eumelanin NaN",
        |s| {
            s.shade.model = ShadingModel::Chiang(ChiangParams {
                eumelanin: Some(f32::NAN),
                ..Default::default()
            })
        },
        Kind::Param("shading.chiang.eumelanin"),
    ),
    (
        "Chiang pheomelanin negative",
        |s| {
            s.shade.model = ShadingModel::Chiang(ChiangParams {
                pheomelanin: Some(-1.0),
                ..Default::default()
            })
        },
        Kind::Param("shading.chiang.pheomelanin"),
    ),
    (
        "Chiang pheomelanin NaN",
        |s| {
            s.shade.model = ShadingModel::Chiang(ChiangParams {
                pheomelanin: Some(f32::NAN),
                ..Default::default()
            })
        },
        Kind::Param("shading.chiang.pheomelanin"),
    ),
    (
        "Chiang melanin beyond black",
        |s| {
            s.shade.model = ShadingModel::Chiang(ChiangParams {
                eumelanin: Some(100.0),
                ..Default::default()
            })
        },
        Kind::Param("shading.chiang.eumelanin"),
    ),
    (
        "Chiang beta_m zero",
        |s| {
            s.shade.model = ShadingModel::Chiang(ChiangParams {
                beta_m: 0.0,
                ..Default::default()
            })
        },
        Kind::Param("shading.chiang.beta_m"),
    ),
    (
        "Chiang beta_m above 1",
        |s| {
            s.shade.model = ShadingModel::Chiang(ChiangParams {
                beta_m: 1.5,
                ..Default::default()
            })
        },
        Kind::Param("shading.chiang.beta_m"),
    ),
    (
        "Chiang beta_m NaN",
        |s| {
            s.shade.model = ShadingModel::Chiang(ChiangParams {
                beta_m: f32::NAN,
                ..Default::default()
            })
        },
        Kind::Param("shading.chiang.beta_m"),
    ),
    (
        "Chiang beta_n zero",
        |s| {
            s.shade.model = ShadingModel::Chiang(ChiangParams {
                beta_n: 0.0,
                ..Default::default()
            })
        },
        Kind::Param("shading.chiang.beta_n"),
    ),
    (
        "Chiang beta_n negative",
        |s| {
            s.shade.model = ShadingModel::Chiang(ChiangParams {
                beta_n: -0.3,
                ..Default::default()
            })
        },
        Kind::Param("shading.chiang.beta_n"),
    ),
    (
        "Chiang beta_n NaN",
        |s| {
            s.shade.model = ShadingModel::Chiang(ChiangParams {
                beta_n: f32::NAN,
                ..Default::default()
            })
        },
        Kind::Param("shading.chiang.beta_n"),
    ),
    (
        "Chiang alpha NaN",
        |s| {
            s.shade.model = ShadingModel::Chiang(ChiangParams {
                alpha_deg: f32::NAN,
                ..Default::default()
            })
        },
        Kind::Param("shading.chiang.alpha_deg"),
    ),
    (
        "Chiang eta of 1",
        |s| {
            s.shade.model = ShadingModel::Chiang(ChiangParams {
                eta: 1.0,
                ..Default::default()
            })
        },
        Kind::Param("shading.chiang.eta"),
    ),
    (
        "Chiang eta below 1",
        |s| {
            s.shade.model = ShadingModel::Chiang(ChiangParams {
                eta: 0.8,
                ..Default::default()
            })
        },
        Kind::Param("shading.chiang.eta"),
    ),
    (
        "Chiang eta NaN",
        |s| {
            s.shade.model = ShadingModel::Chiang(ChiangParams {
                eta: f32::NAN,
                ..Default::default()
            })
        },
        Kind::Param("shading.chiang.eta"),
    ),
    (
        "Chiang sigma_a NaN",
        |s| {
            s.shade.model = ShadingModel::Chiang(ChiangParams {
                sigma_a: Some(Vec3::new(0.1, f32::NAN, 0.1)),
                ..Default::default()
            })
        },
        Kind::Param("shading.chiang.sigma_a"),
    ),
    (
        "Chiang sigma_a and melanin",
        |s| {
            s.shade.model = ShadingModel::Chiang(ChiangParams {
                sigma_a: Some(Vec3::splat(0.2)),
                eumelanin: Some(1.0),
                ..Default::default()
            })
        },
        Kind::Param("shading.chiang.sigma_a"),
    ),
    (
        "two samples per pixel",
        |s| s.shade.sample_count = 2,
        Kind::Param("shade.sample_count"),
    ),
    (
        "root occlusion above 1",
        |s| s.shade.root_occlusion = 3.0,
        Kind::Param("shade.root_occlusion"),
    ),
    // Transparency.
    (
        "k-buffer with k = 0",
        |s| s.shade.transparency = Transparency::k_buffer(0),
        Kind::Param("transparency.k"),
    ),
    (
        "random subsets beyond 64",
        |s| s.shade.transparency = Transparency::random_subsets(65),
        Kind::Param("transparency.k"),
    ),
    (
        "A-buffer pool NaN",
        |s| {
            s.shade.transparency = Transparency::ABuffer {
                nodes_per_pixel: f32::NAN,
                resolve_k: 8,
            }
        },
        Kind::Param("transparency.nodes_per_pixel"),
    ),
    (
        "DBK negative depth shift",
        |s| s.shade.transparency = Transparency::dbk(-0.1),
        Kind::Param("transparency.depth_shift"),
    ),
    (
        "A-buffer resolve of 0",
        |s| {
            s.shade.transparency = Transparency::ABuffer {
                nodes_per_pixel: 4.0,
                resolve_k: 0,
            }
        },
        Kind::Param("transparency.resolve_k"),
    ),
    (
        "light without direction",
        |s| {
            s.lights = vec![Light::Directional(DirectionalLight {
                direction: Vec3::ZERO,
                ..Default::default()
            })]
        },
        Kind::Param("lights[0].direction"),
    ),
    ("no light", |s| s.lights.clear(), Kind::Param("lights")),
    (
        "five lights",
        |s| s.lights = vec![Light::default(); 5],
        Kind::Param("lights"),
    ),
    (
        "point light at NaN",
        |s| {
            s.lights.push(Light::Point(PointLight {
                position: Vec3::NAN,
                ..Default::default()
            }))
        },
        Kind::Param("lights[1].position"),
    ),
    (
        "point light of negative intensity",
        |s| {
            s.lights.push(Light::Point(PointLight {
                intensity: -1.0,
                ..Default::default()
            }))
        },
        Kind::Param("lights[1].intensity"),
    ),
    // Shadows.
    (
        "voxel grid of 1",
        |s| {
            s.shadow = ShadowParams::Voxel(VoxelParams {
                resolution: [1, 64, 64],
                ..Default::default()
            })
        },
        Kind::Param("shadow.resolution"),
    ),
    (
        "voxel grid beyond the device",
        |s| {
            s.shadow = ShadowParams::Voxel(VoxelParams {
                resolution: [512; 3],
                ..Default::default()
            })
        },
        Kind::TooLarge("voxel shadow grid"),
    ),
    (
        "fixed point of 4 bits",
        |s| {
            s.shadow = ShadowParams::Voxel(VoxelParams {
                fixed_point_bits: 4,
                ..Default::default()
            })
        },
        Kind::Param("shadow.fixed_point_bits"),
    ),
    (
        "negative voxel size",
        |s| {
            s.shadow = ShadowParams::Voxel(VoxelParams {
                voxel_size: Some(-0.1),
                ..Default::default()
            })
        },
        Kind::Param("shadow.voxel_size"),
    ),
    (
        "nine opacity layers",
        |s| {
            s.shadow = ShadowParams::DeepOpacity(DeepOpacityParams {
                layers: 9,
                ..Default::default()
            })
        },
        Kind::Param("shadow.deep_opacity.layers"),
    ),
    (
        "layer ends that go back",
        |s| {
            s.shadow = ShadowParams::DeepOpacity(DeepOpacityParams {
                spacing: LayerSpacing::Fractions {
                    ends: vec![0.3, 0.1],
                },
                ..Default::default()
            })
        },
        Kind::Param("shadow.deep_opacity.spacing.ends"),
    ),
    (
        "shadow map of 8 texels",
        |s| {
            let mut p = ShadowMapParams::default();
            p.map.size = 8;
            s.shadow = ShadowParams::ShadowMap(p);
        },
        Kind::Param("shadow.shadow_map.size"),
    ),
    (
        "zero fibre spacing",
        |s| {
            s.shadow = ShadowParams::Adsm(AdsmParams {
                fiber_spacing: 0.0,
                ..Default::default()
            })
        },
        Kind::Param("shadow.adsm.fiber_spacing"),
    ),
    // Device limits.
    (
        "strands beyond the device",
        |s| s.hair.roots.count = 2_000_000,
        Kind::TooLarge("strand vertices"),
    ),
];

fn small_scene() -> Scene {
    let mut scene = Scene {
        shadow: ShadowParams::None,
        ..Scene::default()
    };
    scene.hair.roots.count = 500;
    scene
}

#[test]
fn every_bad_input_gets_the_error_that_names_it() {
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
    assert!(CASES.len() >= 30, "only {} cases", CASES.len());
    let mut failures = Vec::new();
    for (name, spoil, kind) in CASES {
        let mut scene = small_scene();
        spoil(&mut scene);
        let result = Renderer::new(&gpu, &scene, 32, 32)
            .and_then(|mut r| r.render(&gpu, 0.0, &scene.camera).map(|_| ()));
        let Err(err) = result else {
            failures.push(format!("{name}: accepted"));
            continue;
        };
        let message = err.to_string();
        let ok = match (kind, &err) {
            (
                Kind::Param(p),
                Error::Param(_)
                | Error::Strands(StrandsError::Param(_))
                | Error::Shade(_)
                | Error::Shadow(_),
            ) => message.contains(p),
            (
                Kind::Mesh(text),
                Error::Contract(ContractError::Mesh(_)) | Error::Strands(StrandsError::Mesh(_)),
            ) => message.contains(text),
            (Kind::TooLarge(what), e) => {
                let too_large = matches!(
                    e,
                    Error::Gpu(GpuError::TooLarge { .. })
                        | Error::Contract(ContractError::Gpu(GpuError::TooLarge { .. }))
                        | Error::Strands(StrandsError::Gpu(GpuError::TooLarge { .. }))
                        | Error::Shadow(pelage::shadow::ShadowError::Gpu(
                            GpuError::TooLarge { .. }
                        ))
                );
                too_large && message.contains(what) && message.contains("over")
            }
            _ => false,
        };
        if !ok {
            failures.push(format!("{name}: expected {kind:?}, got {message}"));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        CASES.len(),
        failures.join("\n")
    );
}

#[test]
fn a_few_zero_area_triangles_are_skipped_and_counted() {
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
    let mut scene = small_scene();
    // Collapse three triangles of the creature to points: legal, but they carry no hair.
    let collapsed: Vec<u32> = vec![10, 20, 30];
    for &t in &collapsed {
        let i = scene.mesh.indices[3 * t as usize] as usize;
        let p = scene.mesh.positions[i];
        scene.mesh.positions.push(p);
        scene.mesh.normals.push(scene.mesh.normals[i]);
        scene.mesh.uvs.push(scene.mesh.uvs[i]);
        let n = (scene.mesh.positions.len() - 1) as u32;
        scene.mesh.indices[3 * t as usize + 1] = n;
        scene.mesh.indices[3 * t as usize + 2] = n;
    }
    let report = scene.mesh.validate().unwrap();
    assert_eq!(report.degenerate_triangles, collapsed);
    let mut renderer = Renderer::new(&gpu, &scene, 32, 32).unwrap();
    renderer.render(&gpu, 0.0, &scene.camera).unwrap();
    assert!(
        renderer
            .frame()
            .strands()
            .roots()
            .iter()
            .all(|r| !collapsed.contains(&r.triangle))
    );
}

/// The safety net behind "no blank picture with exit code 0": a frame read back before
/// anything was drawn into it (wgpu zero-fills the target, so every pixel has alpha 0)
/// is `Error::Undrawn`, counting every pixel, and never an image.
#[test]
fn a_frame_never_drawn_is_refused() {
    let gpu = Gpu::headless().expect("an adapter");
    let mut scene = Scene::default();
    scene.hair.roots.count = 200;
    let renderer = Renderer::new(&gpu, &scene, 32, 24).expect("a renderer");
    match renderer.rgba8(&gpu) {
        Err(Error::Undrawn {
            transparent,
            pixels,
            ..
        }) => {
            assert_eq!((transparent, pixels), (32 * 24, 32 * 24));
        }
        Err(other) => panic!("expected Undrawn, got {other}"),
        Ok(_) => panic!("an undrawn frame was read back as a picture"),
    }
}
