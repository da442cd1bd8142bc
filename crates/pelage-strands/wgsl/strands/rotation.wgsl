// Rotations shared by stage 1's passes: unit quaternions (groom.wgsl turns a groom's rest
// shape by them, simulate.wgsl its local shape targets) and the perpendicular that gives
// a root its tangent (grow.wgsl, simulate.wgsl).
//
// Reads and writes nothing; functions only, no entry point.
//
// The CPU mirrors are `quat_rotate`, `quat_mul` and `quat_between` in
// pelage-reference/src/strands.rs: change both together.

#import shared/math.wgsl

// `v` turned by the unit quaternion `q` (xyz = vector part, w = scalar part).
fn quat_rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    return v + 2.0 * cross(q.xyz, cross(q.xyz, v) + q.w * v);
}

// The rotation `a` after `b`.
fn quat_mul(a: vec4<f32>, b: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(a.w * b.xyz + b.w * a.xyz + cross(a.xyz, b.xyz), a.w * b.w - dot(a.xyz, b.xyz));
}

// The shortest rotation taking unit `a` to unit `b`; half a turn about an axis
// perpendicular to `a` when they are opposite.
fn quat_between(a: vec3<f32>, b: vec3<f32>) -> vec4<f32> {
    let w = 1.0 + dot(a, b);
    if w < 1e-6 {
        var hint = vec3<f32>(1.0, 0.0, 0.0);
        if abs(a.x) > 0.9 {
            hint = vec3<f32>(0.0, 1.0, 0.0);
        }
        return vec4<f32>(safe_normalize(cross(a, hint), vec3<f32>(0.0, 0.0, 1.0)), 0.0);
    }
    let q = vec4<f32>(cross(a, b), w);
    return q / length(q);
}

// A unit vector perpendicular to unit `n`, as close to `hint` as possible.
fn perpendicular(n: vec3<f32>, hint: vec3<f32>) -> vec3<f32> {
    var fallback = vec3<f32>(1.0, 0.0, 0.0);
    if abs(n.x) > 0.9 {
        fallback = vec3<f32>(0.0, 1.0, 0.0);
    }
    let f = safe_normalize(fallback - dot(fallback, n) * n, vec3<f32>(0.0, 0.0, 1.0));
    return safe_normalize(hint - dot(hint, n) * n, f);
}
