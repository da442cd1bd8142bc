// shade/models/kajiya_kay.wgsl: Kajiya-Kay (1989) hair shading with Scheuermann's (2004) two
// shifted highlights. Twin of `kajiya_kay` in crates/pelage-reference/src/shading.rs.
// Reads nothing, writes nothing: pure functions and structs, no bindings, no entry point.
//
// kajiya_kay_radiance returns the radiance toward v for a light of unit irradiance from l
// (l, v pointing away from the fibre):
//   diffuse * base * sin(t, l)
//   + specular * specular_color * cone(t1)^shininess
//   + secondary_specular * secondary_color * base * cone(t2)^secondary_shininess
// cone(t) = max(0, -(t.l)(t.v) + sin(t, l) sin(t, v)) = max(0, cos(theta_i + theta_r)),
// t1,2 = normalize(t + shift * n), n = normalize(v - (t.v) t), the normal of the
// camera-facing ribbon. With no shift and no secondary highlight this is ribbons.wgsl's
// shading (without the frame's ambient term).

#import shared/math.wgsl

// Mirrors `KajiyaKayUniforms` in crates/pelage-shade/src/models.rs.
struct KajiyaKayModel {
    diffuse: f32,
    specular: f32,
    shininess: f32,
    shift_primary: f32,
    specular_color: vec3<f32>,
    secondary_specular: f32,
    secondary_color: vec3<f32>,
    secondary_shininess: f32,
    shift_secondary: f32,
}

// The cosine between v and the nearest direction of the cone of mirror directions around t.
fn kajiya_kay_cone(t: vec3<f32>, l: vec3<f32>, v: vec3<f32>) -> f32 {
    let tl = clamp(dot(t, l), -1.0, 1.0);
    let tv = clamp(dot(t, v), -1.0, 1.0);
    let sin_l = sqrt(max(1.0 - tl * tl, 0.0));
    let sin_v = sqrt(max(1.0 - tv * tv, 0.0));
    return max(-tl * tv + sin_l * sin_v, 0.0);
}

// cone^exponent, 0 where the cone term is 0.
fn kajiya_kay_power(cone: f32, exponent: f32) -> f32 {
    if (cone > 0.0) {
        return pow(cone, exponent);
    }
    return 0.0;
}

// Scheuermann's shifted tangent along the ribbon normal; t itself for no shift or when v
// lies along t (the ribbon has no normal there).
fn kajiya_kay_shifted_tangent(t: vec3<f32>, v: vec3<f32>, shift: f32) -> vec3<f32> {
    if (shift == 0.0) {
        return t;
    }
    let n = v - dot(t, v) * t;
    let len = length(n);
    if (len < 1e-5) {
        return t;
    }
    return safe_normalize(t + (shift / len) * n, t);
}

// strand_random is unused (the shape is common to every model).
fn kajiya_kay_radiance(
    m: KajiyaKayModel,
    t: vec3<f32>,
    l: vec3<f32>,
    v: vec3<f32>,
    base_color: vec3<f32>,
    strand_random: f32,
) -> vec3<f32> {
    let tl = clamp(dot(t, l), -1.0, 1.0);
    let sin_l = sqrt(max(1.0 - tl * tl, 0.0));
    let t1 = kajiya_kay_shifted_tangent(t, v, m.shift_primary);
    let t2 = kajiya_kay_shifted_tangent(t, v, m.shift_secondary);
    let primary = kajiya_kay_power(kajiya_kay_cone(t1, l, v), m.shininess);
    let secondary = kajiya_kay_power(kajiya_kay_cone(t2, l, v), m.secondary_shininess);
    return base_color * (m.diffuse * sin_l)
        + m.specular_color * (m.specular * primary)
        + m.secondary_color * base_color * (m.secondary_specular * secondary);
}
