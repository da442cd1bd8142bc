//! The shadow-map methods (deep opacity maps, hair shadow map with PCF, ADSM) on a
//! real adapter, against the ray-traced reference.

mod common;

use common::*;
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

fn method(gpu: &Gpu, r: &Reference, params: &ShadowParams) -> Box<dyn ShadowMethod> {
    pelage_shadow::build(gpu, params, r.strands.buffers(), &r.mesh_buffers)
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
fn every_map_method_tracks_the_reference() {
    let gpu = gpu();
    let (long_mesh, long) = long_hair();
    let scenes = [
        ("default fur", Mesh::creature(), HairParams::default()),
        ("long hair", long_mesh, long),
    ];
    for (name, mesh, mut hair) in scenes {
        hair.wind = WindParams::calm();
        let r = reference(&gpu, &mesh, &hair);
        // Drawing no shadow at all scores this:
        let unshadowed =
            (r.truth.iter().map(|t| (1.0 - t).powi(2)).sum::<f32>() / r.truth.len() as f32).sqrt();
        println!(
            "{name}: mean reference T {:.3}, RMSE without shadows {unshadowed:.3}",
            mean(&r.truth)
        );
        let mut rmse = Vec::new();
        for params in candidates() {
            let m = method(&gpu, &r, &params);
            let (e, p95) = error(&gpu, &r, m.as_ref());
            println!(
                "  {:<52} RMSE {e:.4} p95 {p95:.4} memory {:.1} MB",
                m.name(),
                m.memory_bytes() as f64 / 1e6
            );
            assert!(
                e < unshadowed,
                "{}: RMSE {e} is no better than no shadows ({unshadowed})",
                m.name()
            );
            assert!(m.memory_bytes() > 0);
            rmse.push(e);
        }
        let [voxel, dom3, dom4, dom8, map1, map5, adsm] = rmse[..] else {
            unreachable!()
        };
        assert!(
            voxel < 0.12 && dom3 < 0.16 && dom4 < 0.16,
            "{name}: {rmse:?}"
        );
        assert!(
            dom8 > dom3,
            "{name}: 8-bit layers ({dom8}) beat float ones ({dom3})"
        );
        assert!(
            map5 < map1,
            "{name}: 5x5 PCF ({map5}) no better than one tap ({map1})"
        );
        assert!(
            adsm < map1,
            "{name}: ADSM ({adsm}) no better than a plain shadow map ({map1})"
        );
    }
}
