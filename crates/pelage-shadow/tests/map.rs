//! The shadow-map methods (deep opacity maps, hair shadow map with PCF, ADSM) on a
//! real adapter, against the ray-traced reference.

mod common;

use common::*;
use glam::Vec3;
use pelage_gpu::Gpu;
use pelage_scene::{
    AdsmParams, DeepOpacityParams, HairParams, LayerSpacing, MapParams, Mesh, OpacityFormat,
    ShadowMapParams, ShadowParams, VoxelParams, WindParams,
};
use pelage_shadow::ShadowMethod;

fn map(size: u32, pcf_radius: u32) -> MapParams {
    MapParams {
        size,
        pcf_radius,
        mesh_map_size: 0,
    }
}

fn method(
    gpu: &Gpu,
    r: &Reference,
    hair: &HairParams,
    params: &ShadowParams,
) -> Box<dyn ShadowMethod> {
    pelage_shadow::build(
        gpu,
        params,
        &hair.growth,
        r.strands.buffers(),
        &r.mesh_buffers,
        (Vec3::ZERO, Vec3::ONE),
    )
    .unwrap()
    .unwrap()
}

fn candidates() -> Vec<ShadowParams> {
    vec![
        ShadowParams::Voxel(VoxelParams {
            mesh_map_size: 0,
            ..VoxelParams::default()
        }),
        ShadowParams::DeepOpacity(DeepOpacityParams {
            map: map(512, 1),
            ..DeepOpacityParams::default()
        }),
        ShadowParams::DeepOpacity(DeepOpacityParams {
            map: map(512, 1),
            layers: 4,
            spacing: LayerSpacing::Linear { depth: 0.05 },
            ..DeepOpacityParams::default()
        }),
        ShadowParams::DeepOpacity(DeepOpacityParams {
            map: map(512, 1),
            format: OpacityFormat::Unorm8,
            ..DeepOpacityParams::default()
        }),
        ShadowParams::ShadowMap(ShadowMapParams {
            map: map(1024, 0),
            ..ShadowMapParams::default()
        }),
        ShadowParams::ShadowMap(ShadowMapParams {
            map: map(1024, 2),
            ..ShadowMapParams::default()
        }),
        ShadowParams::Adsm(AdsmParams {
            map: map(1024, 1),
            ..AdsmParams::default()
        }),
    ]
}

#[test]
fn explore() {
    let gpu = gpu();
    let (long_mesh, long) = long_hair();
    let scenes = [
        ("default fur", Mesh::creature(), HairParams::default()),
        ("long hair", long_mesh, long),
    ];
    for (name, mesh, mut hair) in scenes {
        hair.wind = WindParams::calm();
        let r = reference(&gpu, &mesh, &hair);
        println!(
            "{name}: mean reference T {:.3}, RMSE of T = 1: {:.3}",
            mean(&r.truth),
            (r.truth.iter().map(|t| (1.0 - t).powi(2)).sum::<f32>() / r.truth.len() as f32).sqrt()
        );
        for params in candidates() {
            let m = method(&gpu, &r, &hair, &params);
            let t = transmittance(&gpu, m.as_ref(), r.strands.buffers());
            let (rmse, p95) = error(&gpu, &r, m.as_ref());
            println!(
                "  {:<50} RMSE {rmse:.4} p95 {p95:.4} mean T {:.3} memory {:.1} MB",
                m.name(),
                mean(&t),
                m.memory_bytes() as f64 / 1e6
            );
        }
    }
}
