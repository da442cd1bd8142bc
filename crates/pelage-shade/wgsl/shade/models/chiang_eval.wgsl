// shade/models/chiang_eval.wgsl: test-only kernel that evaluates the Chiang model per case,
// so it can be compared with its CPU twin (crates/pelage-shade/tests/models.rs).
//
// Reads:  settings (uniform: mode, case count), cases (storage: per case the tangent t with
//         the visibility in t.w, light direction l, eye direction v, base colour), the
//         model and its tables at group 2 (shade/models/chiang.wgsl).
// Writes: results (storage: per case vec4(radiance, 1)).
// Dispatch: workgroups of 64 over the cases, flattened as
//         gid.y * num_workgroups.x * 64 + gid.x (pelage_gpu::dispatch_size).
// Modes: 0 = single scattering (chiang_radiance), 1 = what the hair passes' hair_light
//        returns for the model's `dual` (chiang_dual_model.wgsl: chiang_dual_radiance through
//        the visibility; chiang_model.wgsl: chiang_radiance times it), 2 and 3 = the dual-scattering
//        energies as chiang_dual_at reads them, forward (2) or backward (3), per lobe
//        (R, TT, TRT, residual) at |theta| = t.x and absorption coordinate t.y.

#import shared/math.wgsl
#import shade/models/chiang.wgsl

struct ChiangEvalSettings {
    mode: u32,
    count: u32,
    _pad0: u32,
    _pad1: u32,
}

struct ChiangEvalCase {
    // xyz: tangent; w: visibility.
    t: vec4<f32>,
    l: vec4<f32>,
    v: vec4<f32>,
    color: vec4<f32>,
}

@group(0) @binding(0) var<uniform> settings: ChiangEvalSettings;
@group(0) @binding(1) var<storage, read> cases: array<ChiangEvalCase>;
@group(0) @binding(2) var<storage, read_write> results: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.y * groups.x * 64u + gid.x;
    if (i >= settings.count) {
        return;
    }
    let c = cases[i];
    if (settings.mode >= 2u) {
        let e = chiang_dual_at(c.t.x, c.t.y);
        results[i] = select(e.backward, e.forward, settings.mode == 2u);
        return;
    }
    var out = vec3<f32>(0.0);
    if (settings.mode == 0u) {
        out = chiang_radiance(chiang, c.t.xyz, c.l.xyz, c.v.xyz, c.color.xyz, 0.0);
    } else if (chiang.dual != 0u) {
        out = chiang_dual_radiance(chiang, c.t.xyz, c.l.xyz, c.v.xyz, c.color.xyz, c.t.w);
    } else {
        out = chiang_radiance(chiang, c.t.xyz, c.l.xyz, c.v.xyz, c.color.xyz, 0.0) * c.t.w;
    }
    results[i] = vec4<f32>(out, 1.0);
}
