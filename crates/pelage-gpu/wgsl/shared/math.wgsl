// shared/math.wgsl: constants and small numeric helpers used by several stages
// (hashing and noise live in shared/noise.wgsl).
// Reads nothing, writes nothing, no entry point: pull it in with
//   #import shared/math.wgsl

const PI: f32 = 3.14159265358979;
const TAU: f32 = 6.28318530717959;
const INV_PI: f32 = 0.318309886183791;

// True unless `x` is NaN or +-inf. Tests the exponent bits, because WGSL lets
// implementations assume floats are finite, so `x != x` may be folded away.
fn is_finite_f32(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

// True when every component of `v` is finite.
fn all_finite3(v: vec3<f32>) -> bool {
    let exponent = bitcast<vec3<u32>>(v) & vec3<u32>(0x7f800000u);
    return all(exponent != vec3<u32>(0x7f800000u));
}

// True when every component of `v` is finite.
fn all_finite4(v: vec4<f32>) -> bool {
    let exponent = bitcast<vec4<u32>>(v) & vec4<u32>(0x7f800000u);
    return all(exponent != vec4<u32>(0x7f800000u));
}

// `v` scaled to unit length, or `fallback` when `v` has a non-finite component
// or is shorter than about 1e-20 (its largest component is below 1e-20).
// Dividing by the largest component first keeps tiny and huge vectors from
// under- or overflowing when squared.
fn safe_normalize(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    if (!all_finite3(v)) {
        return fallback;
    }
    let largest = max(abs(v.x), max(abs(v.y), abs(v.z)));
    if (largest < 1e-20) {
        return fallback;
    }
    let u = v / largest; // length in [1, sqrt(3)]
    return u / length(u);
}
