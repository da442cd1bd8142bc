// shade/models/eval.wgsl: test-only kernel that evaluates one shading model per case, so the
// WGSL models can be compared with their CPU twins (crates/pelage-shade/tests/models.rs).
//
// Reads:  settings (uniform: which model, how many cases), cases (storage: per case the
//         tangent t, light direction l, eye direction v, base colour, and in t.w the
//         strand random number), the three models' parameters (uniforms, group 1) and the
//         Marschner lookup tables (group 2, shade/models/marschner_lut_lookup.wgsl).
// Writes: results (storage: per case vec4(radiance, 1)).
// Dispatch: workgroups of 64 over the cases, flattened as
//         gid.y * num_workgroups.x * 64 + gid.x (pelage_gpu::dispatch_size).
// Models: 0 = Kajiya-Kay, 1 = Marschner analytic, 2 = Marschner from the tables,
//         3 = Sadeghi.

#import shared/math.wgsl
#import shade/models/kajiya_kay.wgsl
#import shade/models/marschner.wgsl
#import shade/models/marschner_lut_lookup.wgsl
#import shade/models/sadeghi.wgsl

struct EvalSettings {
    model: u32,
    count: u32,
    _pad0: u32,
    _pad1: u32,
}

struct EvalCase {
    // xyz: tangent; w: strand random number in [0, 1).
    t: vec4<f32>,
    l: vec4<f32>,
    v: vec4<f32>,
    color: vec4<f32>,
}

@group(0) @binding(0) var<uniform> settings: EvalSettings;
@group(0) @binding(1) var<storage, read> cases: array<EvalCase>;
@group(0) @binding(2) var<storage, read_write> results: array<vec4<f32>>;
@group(1) @binding(0) var<uniform> eval_kajiya_kay: KajiyaKayModel;
@group(1) @binding(1) var<uniform> eval_marschner: MarschnerModel;
@group(1) @binding(2) var<uniform> eval_sadeghi: SadeghiModel;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.y * groups.x * 64u + gid.x;
    if (i >= settings.count) {
        return;
    }
    let c = cases[i];
    let t = c.t.xyz;
    let l = c.l.xyz;
    let v = c.v.xyz;
    let base = c.color.xyz;
    let r = c.t.w;
    var out = vec3<f32>(0.0);
    switch settings.model {
        case 0u: {
            out = kajiya_kay_radiance(eval_kajiya_kay, t, l, v, base, r);
        }
        case 1u: {
            out = marschner_radiance(eval_marschner, t, l, v, base, r);
        }
        case 2u: {
            out = marschner_radiance_lut(eval_marschner, t, l, v, base, r);
        }
        default: {
            out = sadeghi_radiance(eval_sadeghi, t, l, v, base, r);
        }
    }
    results[i] = vec4<f32>(out, 1.0);
}
