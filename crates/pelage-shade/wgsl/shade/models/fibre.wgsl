// shade/models/fibre.wgsl: the angles of a hair fibre (Marschner et al. 2003 conventions),
// shared by the shading models. Twin of `fibre_angles` in crates/pelage-reference/src/shading.rs.
// Reads nothing, writes nothing: pure functions and structs, no bindings, no entry point.
//
// t: unit tangent (root to tip); l: unit direction to the light; v: unit direction to the
// eye (both pointing away from the fibre). Longitudinal angles are measured from the normal
// plane: sin(theta_i) = t.l, sin(theta_r) = t.v, theta_h = (theta_i + theta_r)/2,
// theta_d = (theta_r - theta_i)/2. Azimuths are measured in the normal plane from the
// fibre's major axis a1: e1 = normalize(t x z) (t x x within ~0.06 degrees of +-z, Dusek's
// eq. 3.4), e2 = t x e1, turned about t by the strand's azimuth. phi = |phi_r - phi_i| in
// [0, pi]; cos_2phi_h = cos(phi_i + phi_r). When l or v lies along t the azimuth is
// undefined and phi = 0, cos_2phi_h = 1.

#import shared/math.wgsl

// Smallest cos(theta_d): 1/cos^2(theta_d) is singular where l = -t and v = t.
const FIBRE_MIN_COS_THETA_D: f32 = 1e-4;
// Below this length a projection onto the normal plane counts as zero.
const FIBRE_MIN_PROJECTION: f32 = 1e-5;

struct FibreAngles {
    sin_theta_i: f32,
    sin_theta_r: f32,
    // sqrt(1 - sin^2(theta_i)): the factor that turns the scattering function into radiance.
    cos_theta_i: f32,
    theta_h: f32,
    sin_theta_d: f32,
    // Clamped to at least FIBRE_MIN_COS_THETA_D.
    cos_theta_d: f32,
    // |phi_r - phi_i| in [0, pi].
    phi: f32,
    cos_phi: f32,
    // cos(phi_i + phi_r), for the eccentric TRT index.
    cos_2phi_h: f32,
}

struct FibreFrame {
    a1: vec3<f32>,
    a2: vec3<f32>,
}

// The fibre's cross-section axes, turned by `azimuth` (radians) about t.
fn fibre_frame(t: vec3<f32>, azimuth: f32) -> FibreFrame {
    var e1 = cross(t, vec3<f32>(0.0, 0.0, 1.0));
    if (length(e1) < 1e-3) {
        e1 = cross(t, vec3<f32>(1.0, 0.0, 0.0));
    }
    e1 = safe_normalize(e1, vec3<f32>(1.0, 0.0, 0.0));
    let e2 = cross(t, e1);
    let s = sin(azimuth);
    let c = cos(azimuth);
    return FibreFrame(c * e1 + s * e2, -s * e1 + c * e2);
}

// (phi, cos phi, cos 2phi_h) of l and v about t in the frame turned by `azimuth`.
// phi is the angle of the 2-D (dot, |cross|): full precision near 0 and pi.
fn fibre_azimuths(t: vec3<f32>, l: vec3<f32>, v: vec3<f32>, azimuth: f32) -> vec3<f32> {
    let f = fibre_frame(t, azimuth);
    let l1 = dot(l, f.a1);
    let l2 = dot(l, f.a2);
    let r1 = dot(v, f.a1);
    let r2 = dot(v, f.a2);
    let nl = length(vec2<f32>(l1, l2));
    let nr = length(vec2<f32>(r1, r2));
    if (nl < FIBRE_MIN_PROJECTION || nr < FIBRE_MIN_PROJECTION) {
        return vec3<f32>(0.0, 1.0, 1.0);
    }
    let c = l1 * r2 - l2 * r1;
    let d = l1 * r1 + l2 * r2;
    let phi = fibre_angle(abs(c), d);
    let n = nl * nr;
    return vec3<f32>(phi, clamp(d / n, -1.0, 1.0), clamp((l1 * r1 - l2 * r2) / n, -1.0, 1.0));
}

// sqrt(1 - x^2) without the cancellation of 1 - x*x near |x| = 1.
fn fibre_cos_from_sin(x: f32) -> f32 {
    return sqrt(max((1.0 - x) * (1.0 + x), 0.0));
}

// The angle of the vector (x, y): atan2 refined by one Newton step on the unit vector,
// a + sin(angle - a) with sin(angle - a) = (y cos a - x sin a) / |(x, y)|. Vulkan allows
// inverse trigonometry errors of thousands of ulp (lavapipe's asin is off by up to 2e-4);
// sin and cos are far more accurate, so this is good to about 1e-7. 0 for (0, 0).
fn fibre_angle(y: f32, x: f32) -> f32 {
    let n = length(vec2<f32>(x, y));
    if (n < 1e-30) {
        return 0.0;
    }
    let a = atan2(y, x);
    return a + (y * cos(a) - x * sin(a)) / n;
}

// asin(x) for x in [-1, 1], accurate (see fibre_angle).
fn fibre_asin(x: f32) -> f32 {
    return fibre_angle(x, fibre_cos_from_sin(x));
}

// acos(x) for x in [-1, 1], accurate (see fibre_angle).
fn fibre_acos(x: f32) -> f32 {
    return fibre_angle(fibre_cos_from_sin(x), x);
}

// The angles of the module comment. sin(theta) = t.l and cos(theta) = |t x l| (no
// cancellation at grazing angles), theta = their angle.
fn fibre_angles(t: vec3<f32>, l: vec3<f32>, v: vec3<f32>, azimuth: f32) -> FibreAngles {
    let si = clamp(dot(t, l), -1.0, 1.0);
    let sr = clamp(dot(t, v), -1.0, 1.0);
    let ci = min(length(cross(t, l)), 1.0);
    let cr = min(length(cross(t, v)), 1.0);
    let theta_i = fibre_angle(si, ci);
    let theta_r = fibre_angle(sr, cr);
    let theta_d = 0.5 * (theta_r - theta_i);
    let az = fibre_azimuths(t, l, v, azimuth);
    return FibreAngles(
        si,
        sr,
        ci,
        0.5 * (theta_i + theta_r),
        sin(theta_d),
        max(cos(theta_d), FIBRE_MIN_COS_THETA_D),
        az.x,
        az.y,
        az.z,
    );
}
