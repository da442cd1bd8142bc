// shade/models/volume_field.wgsl: the volume method's grid as its readers bind it, the
// hair's shading (chiang_volume_common_model.wgsl) and the body's sky
// (shade/body_sky_volume.wgsl), both in the hair model's group (crates/pelage-shade/src/
// hair_model.rs binds the grid's uniform and fluence at 3 and 4); the trilinear read.
//
// Reads: @group(2) @binding(3) the grid's uniform (VolumeUniforms), @binding(4) its
//        fluence (a header and 3 vec4 per cell, volume_common.wgsl), filled this frame by
//        shade/volume.wgsl.
// Writes: nothing; no entry point.

#import shade/models/volume_common.wgsl

@group(2) @binding(3) var<uniform> volume: VolumeUniforms;
@group(2) @binding(4) var<storage, read> volume_fluence: array<vec4<f32>>;

// Fluence and flux of the three channels at p (trilinear between cell centres, clamped
// at the grid's border).
struct VolumeSample {
    r: vec4<f32>,
    g: vec4<f32>,
    b: vec4<f32>,
}

// Whether the grid holds anything this frame (its header's cell edge is set by the grid's
// `finalize` pass).
fn volume_filled() -> bool {
    return volume_fluence[0].w > 0.0;
}

// Whether p lies in the grid's cube.
fn volume_contains(p: vec3<f32>) -> bool {
    let header = volume_fluence[0];
    let q = (p - header.xyz) / header.w;
    return all(q >= vec3<f32>(0.0)) && all(q <= vec3<f32>(f32(volume.resolution)));
}

fn volume_sample(p: vec3<f32>) -> VolumeSample {
    let header = volume_fluence[0];
    let n = i32(volume.resolution);
    let q = (p - header.xyz) / header.w - vec3<f32>(0.5);
    let base = floor(q);
    let f = clamp(q - base, vec3<f32>(0.0), vec3<f32>(1.0));
    var out = VolumeSample(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    for (var corner = 0u; corner < 8u; corner += 1u) {
        let o = vec3<u32>(corner & 1u, (corner >> 1u) & 1u, (corner >> 2u) & 1u);
        let w = select(1.0 - f.x, f.x, o.x == 1u) * select(1.0 - f.y, f.y, o.y == 1u) * select(1.0 - f.z, f.z, o.z == 1u);
        let c = clamp(vec3<i32>(base) + vec3<i32>(o), vec3<i32>(0), vec3<i32>(n - 1));
        let i = u32((c.z * n + c.y) * n + c.x);
        out.r += w * volume_fluence[1u + 3u * i];
        out.g += w * volume_fluence[2u + 3u * i];
        out.b += w * volume_fluence[3u + 3u * i];
    }
    return out;
}
