// shade/models/sadeghi.wgsl: Sadeghi et al. 2010, the artist-friendly hair shading model.
// Twin of `sadeghi_radiance` in crates/pelage-reference/src/shading.rs.
// Reads nothing, writes nothing: pure functions and structs, no bindings, no entry point.
//
// f = sum_p C_p I_p M'_p(theta_h) N'_p(phi) / cos^2(theta_d), with unit-height Gaussians
// g'(w; x) = exp(-x^2 / (2 w^2)):
//   M'_p = g'(beta_p; theta_h - alpha_p)
//   N'_R = cos(phi/2), N'_TT = g'(gamma_TT; pi - phi),
//   N'_TRT = cos(phi/2) + I_G g'(gamma_G; G_angle - phi),  phi in [0, pi].
// TT and TRT are tinted by the strand colour; the glint half angle G_angle is
// mix(glint_angle_min, glint_angle_max, strand_random). sadeghi_radiance returns
// (f + diffuse * base) * cos(theta_i): radiance for a light of unit irradiance.

#import shared/math.wgsl
#import shade/models/fibre.wgsl

// Mirrors `SadeghiUniforms` in crates/pelage-shade/src/models.rs (angles in radians).
struct SadeghiModel {
    color_r: vec3<f32>,
    intensity_r: f32,
    color_tt: vec3<f32>,
    intensity_tt: f32,
    color_trt: vec3<f32>,
    intensity_trt: f32,
    // Longitudinal shifts alpha_R, alpha_TT, alpha_TRT.
    shift: vec3<f32>,
    // gamma_TT, the azimuthal width of TT around phi = pi.
    azimuthal_width_tt: f32,
    // Longitudinal widths beta_R, beta_TT, beta_TRT.
    width: vec3<f32>,
    glint_intensity: f32,
    glint_width: f32,
    glint_angle_min: f32,
    glint_angle_max: f32,
    diffuse: f32,
}

fn sadeghi_gaussian(width: f32, x: f32) -> f32 {
    let y = x / width;
    return exp(-0.5 * y * y);
}

fn sadeghi_radiance(
    m: SadeghiModel,
    t: vec3<f32>,
    l: vec3<f32>,
    v: vec3<f32>,
    base_color: vec3<f32>,
    strand_random: f32,
) -> vec3<f32> {
    let a = fibre_angles(t, l, v, 0.0);
    let inv = 1.0 / (a.cos_theta_d * a.cos_theta_d);
    let glint_angle = mix(m.glint_angle_min, m.glint_angle_max, strand_random);
    let half_cos = cos(0.5 * a.phi);
    let n_tt = sadeghi_gaussian(m.azimuthal_width_tt, PI - a.phi);
    let n_trt = half_cos + m.glint_intensity * sadeghi_gaussian(m.glint_width, glint_angle - a.phi);
    let m_r = sadeghi_gaussian(m.width.x, a.theta_h - m.shift.x);
    let m_tt = sadeghi_gaussian(m.width.y, a.theta_h - m.shift.y);
    let m_trt = sadeghi_gaussian(m.width.z, a.theta_h - m.shift.z);
    let r = m.color_r * (m.intensity_r * m_r * half_cos * inv);
    let tt = m.color_tt * base_color * (m.intensity_tt * m_tt * n_tt * inv);
    let trt = m.color_trt * base_color * (m.intensity_trt * m_trt * n_trt * inv);
    return (r + tt + trt + base_color * m.diffuse) * a.cos_theta_i;
}
