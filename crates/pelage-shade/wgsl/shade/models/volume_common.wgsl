// shade/models/volume_common.wgsl: what the volume method's passes (shade/volume.wgsl) and
// its shading (shade/models/chiang_volume_model.wgsl) share: the grid's uniform, its
// layout, and the fibre phase function built from Chiang's energy tables.
// Declares structs, constants and pure functions only (chiang_dual_at reads
// shade/models/chiang.wgsl's table at @group(2) @binding(2)).
//
// The grid: resolution^3 cubic cells over the hair's bounds. `fluence` holds a header
// (fluence[0] = origin.xyz, cell edge) and then, per cell and colour channel c, at
// 1 + 3 * cell + c, the vec4 (phi, Phi.xyz): the fluence phi = int L dw of the lights'
// light scattered at least once and of all the sky's light (unscattered too: the sky's
// single scattering is read from the grid, with its visibility), and its flux vector
// Phi = int L w dw (w the direction the light travels). That is order-1 spherical harmonics (4 coefficients) per channel in
// moment form: L(w) = (phi + 3 Phi . w) / (4 pi).
//
// The fibre phase function (azimuthally averaged): light travelling along p that a fibre
// of tangent t scatters leaves with the energy A = a_f + a_b (per channel, pbrt's
// int f |cos theta| dw at |theta| of p, from the dual-scattering tables), on the specular
// cone (the component along t kept) with its component across t kept times
// g = (2 / pi) (a_f - a_b) / A (forward energy uniform over the forward half circle of
// azimuths, backward over the backward one: the mean of cos over a half circle is 2 / pi).
// For fibres of mixed directions (alignment s = |sum of tangents| / count in [0, 1]) the
// unaligned share scatters with the mean over isotropic tangents: A_iso and
// (1 + 2 g_iso) / 3 times p.

#import shared/math.wgsl
#import shade/models/chiang.wgsl

// Mirrors `VolumeUniforms` in crates/pelage-shade/src/volume.rs.
struct VolumeUniforms {
    // Cells per side.
    resolution: u32,
    // Propagation steps.
    iterations: u32,
    // Strand vertices and segments stage 1 grew this frame.
    vertex_count: u32,
    segments: u32,
    strand_count: u32,
    // Invocations of the fit pass (a grid-stride loop covers every vertex).
    fit_invocations: u32,
    // Tip width as a fraction of the root width.
    tip_width: f32,
    // Fixed-point units per unit of optical depth in `accum`, and its inverse.
    fixed_scale: f32,
    inv_fixed_scale: f32,
    // Smallest cell edge, world units.
    min_cell: f32,
    // Triangles of the mesh (the body under the hair), 0 for none.
    triangle_count: u32,
    // The injection's weight of the light the fibres scatter of the lights: 1 (`volume`),
    // or 0 where dual scattering carries it (`dual_volume`).
    light_fibres: f32,
    // The mesh's Lambertian albedo per channel (pi times shade.mesh_color, as the path
    // tracer's, at most 1: a brighter body would make light every propagation step).
    mesh_albedo: vec3<f32>,
    _pad2: f32,
}

// u32 per cell in the splat accumulator: optical depth, tangent sum (x, y, z as i32),
// colour sum (r, g, b), unused, the mesh's area-weighted outward normal sum over the
// cell's face area (x, y, z as i32, at VOLUME_TANGENT_SCALE), the share of the cell
// inside the mesh (f32 bits, written by `occupy`).
const VOLUME_ACCUM: u32 = 12u;
const VOLUME_SURFACE: u32 = 8u;
const VOLUME_SOLID: u32 = 11u;
// The tangent sum is kept at a quarter of fixed_scale (it must fit an i32).
const VOLUME_TANGENT_SCALE: f32 = 0.25;
// Directions of the sky's injection (shade/volume.wgsl's volume_sky_direction); 15 and 32
// gave the same lab figures within 0.4 points.
const VOLUME_SKY_DIRECTIONS: u32 = 15u;
// The propagation's light along an axis direction stands for the directions nearer that
// axis than any other (a sixth of the sphere, the cube's face seen from its centre).
// Moving one cell along the axis, the light of that cone moves aside too: its mean
// |tangent| toward each other axis, weighted by the flux it carries along the axis, is
// 2 VOLUME_SPREAD, so a step sends VOLUME_SPREAD of it to each of the four diagonal
// neighbours; and it travels VOLUME_STEP_PATH cell edges (the flux-weighted mean secant),
// the path its fluence counts and its attenuation crosses. Over the face of the unit
// cube, r = (1, y, z) with y, z in [-1, 1]: VOLUME_SPREAD = int |y| / |r|^4 / (2 int 1 /
// |r|^4), VOLUME_STEP_PATH = int 1 / |r|^3 / int 1 / |r|^4 (pelage_reference::volume
// integrates both itself). Without the spread, light held to six directions leaves a
// cube's faces too slowly: a dense white furnace rose to 1.39x the sky.
const VOLUME_SPREAD: f32 = 0.20116;
const VOLUME_STEP_PATH: f32 = 1.20309;
// Samples of |theta| in [0, pi/2] for the isotropic averages.
const VOLUME_THETA_SAMPLES: u32 = 8u;

// Energy and forward bias of each channel for light at |theta| to the fibre.
struct VolumeFibre {
    albedo: vec3<f32>,
    g: vec3<f32>,
}

fn volume_fibre_channel(theta: f32, x: f32) -> vec2<f32> {
    let e = chiang_dual_at(theta, x);
    let af = dot(e.forward, vec4<f32>(1.0));
    let ab = dot(e.backward, vec4<f32>(1.0));
    let a = af + ab;
    return vec2<f32>(a, select(0.0, (2.0 / PI) * (af - ab) / a, a > 1e-8));
}

// The phase function's energy and bias at |theta| for absorption coordinates x (per channel).
fn volume_fibre_at(theta: f32, x: vec3<f32>) -> VolumeFibre {
    let r = volume_fibre_channel(theta, x.x);
    let g = volume_fibre_channel(theta, x.y);
    let b = volume_fibre_channel(theta, x.z);
    return VolumeFibre(vec3<f32>(r.x, g.x, b.x), vec3<f32>(r.y, g.y, b.y));
}

// The mean over light of isotropic directions that meets the fibre: |theta| weighted by
// cos^2 (cos for the directions' density, cos for the fibre's projected width), at
// VOLUME_THETA_SAMPLES midpoints; g weighted by energy.
fn volume_fibre_isotropic(x: vec3<f32>) -> VolumeFibre {
    var w_sum = 0.0;
    var a = vec3<f32>(0.0);
    var ag = vec3<f32>(0.0);
    for (var j = 0u; j < VOLUME_THETA_SAMPLES; j += 1u) {
        let theta = (f32(j) + 0.5) * (0.5 * PI / f32(VOLUME_THETA_SAMPLES));
        let c = cos(theta);
        let w = c * c;
        let f = volume_fibre_at(theta, x);
        w_sum += w;
        a += w * f.albedo;
        ag += w * f.albedo * f.g;
    }
    let albedo = a / w_sum;
    return VolumeFibre(albedo, select(vec3<f32>(0.0), ag / (w_sum * albedo), albedo > vec3<f32>(1e-8)));
}

// The flux of light of the three channels after one scattering by fibres of mean tangent
// t with alignment s, channel bias g (aligned) and g_iso (unaligned): `f` and the result
// hold one flux vector per channel (columns r, g, b); per channel
//   s (t (t.p) + g (p - t (t.p))) + (1 - s) (1 + 2 g_iso) / 3 p.
fn volume_scatter_flux(f: mat3x3<f32>, t: vec3<f32>, s: f32, g: vec3<f32>, g_iso: vec3<f32>) -> mat3x3<f32> {
    let tp = t * f;
    let iso = (1.0 - s) * (vec3<f32>(1.0) + 2.0 * g_iso) / 3.0;
    let a0 = t * tp.x;
    let a1 = t * tp.y;
    let a2 = t * tp.z;
    return mat3x3<f32>(
        s * (a0 + g.x * (f[0] - a0)) + iso.x * f[0],
        s * (a1 + g.y * (f[1] - a1)) + iso.y * f[1],
        s * (a2 + g.z * (f[2] - a2)) + iso.z * f[2],
    );
}

// Column c of `f` times k[c]: per channel scaling of a flux matrix.
fn volume_columns(f: mat3x3<f32>, k: vec3<f32>) -> mat3x3<f32> {
    return mat3x3<f32>(f[0] * k.x, f[1] * k.y, f[2] * k.z);
}

fn volume_sigma_coordinates(sigma: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(
        chiang_sigma_coordinate(sigma.x),
        chiang_sigma_coordinate(sigma.y),
        chiang_sigma_coordinate(sigma.z),
    );
}
