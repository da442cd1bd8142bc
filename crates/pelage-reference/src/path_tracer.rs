//! A path tracer of strands: the multiple-scattering ground truth for pelage's hair.
//!
//! Slow and obviously right, never shipped. Everything runs in `f64`.
//!
//! # Scene
//! - **Hair**: every strand segment is the cylinder of [`crate::transmittance`] (its real
//!   radius, so `segments_from_strands`' taper is kept), scattering light with one
//!   [`ChiangFibre`] (optionally with a σ_a per strand, indexed by [`Segment::strand`]). A
//!   ray hits a cylinder where it enters it ([`SegmentBvh::closest_hit`]); the fibre offset
//!   `h` of the ray is the one [`crate::chiang`] defines, from the exact geometry.
//! - **Mesh**: triangles as a two-sided Lambertian occluder of albedo `ρ` (BRDF `ρ/π`), with
//!   the geometric normal turned toward the incoming ray (no vertex normals). pelage's
//!   `wgsl/shade/mesh.wgsl` shades its mesh `style.color · Σ E max(n·l, 0)` (+ ambient), which
//!   is a Lambertian of albedo `ρ = π · style.color` lit directly; pass that albedo for a
//!   like-for-like direct term, at most 1 per channel (`pelage_scene::mesh_albedo`, as
//!   the volume grid takes it; an albedo above 1 is refused: it would make light at every
//!   bounce).
//! - **Lights** (`pelage_scene::Light`, as `wgsl/shade/frame.wgsl` delivers them): a
//!   directional light is a delta light of irradiance `color · intensity` (on a surface facing
//!   it) from `-direction`; a point light delivers `color · intensity / max(d², 1e-4)` at
//!   distance `d` (the same floor as `frame_irradiance`). Lights are not visible to rays.
//! - **Background and sky**: two constant radiances, as pelage's renderer means them.
//!   [`PathTracerSettings::background`] is what a *camera* ray that hits nothing sees (the
//!   renderer's `shade.background`, its clear colour: it lights nothing);
//!   [`PathTracerSettings::sky`] is the radiance an escaping ray sees after at least one
//!   scattering (the light of the environment). pelage's constant `ambient` lights an
//!   unoccluded Lambertian surface of albedo `ρ` with `ρ · ambient`, which is a sky of
//!   radiance `ambient/π` seen unoccluded: pass `sky = ambient/π` for a like-for-like scene.
//!
//! # Camera
//! Pixel `(x, y)`, `y` down, covers exactly the area pelage's raster of
//! `camera.view_projection(width / height)` gives it (wgpu clip space: NDC `y` up, depth in
//! [0, 1]): a primary ray unprojects the NDC point `(2(x + jx)/w - 1, 1 - 2(y + jy)/h)` at depth
//! 0 and 1 through the inverse view-projection (in `f64`), starts on the near plane and ends on
//! the far plane (then it sees the background); `(jx, jy)` is uniform in the pixel (box filter).
//!
//! # Integrator
//! Unidirectional path tracing. At every scattering vertex, next-event estimation to every
//! light with a shadow ray through hair and mesh (hair is opaque to shadow rays: light
//! reaches through fibres only by scattering, which is what makes this a multiple-scattering
//! reference), then a continuation sampled from the BSDF (Chiang: [`ChiangFibre::sample`];
//! Lambert: cosine-weighted). Scattering vertex `k` (1-based) adds its light-sampled term and,
//! if its continuation escapes, the sky; vertex `max_bounces` is the last, so
//! `max_bounces = 1` is direct light only (lights and sky seen after one scattering).
//! No MIS is needed: lights are delta lights and the sky is only reached by BSDF
//! sampling. Russian roulette from vertex `roulette_start` on, survival probability
//! `min(0.95, max component of the path throughput)`, the throughput divided by it (unbiased).
//!
//! # Self-intersection
//! A ray leaving a fibre (the continuation, or a shadow ray) starts on the surface of the
//! segment's cylinder where the outward normal is the part of the new direction perpendicular
//! to the axis, at `1.001 r` from the axis point of the hit: it leaves from the side it goes
//! to (for TT, the far side), so it cannot enter that cylinder again. At joints of a bent
//! strand that point may lie just outside the neighbouring segment's cylinder, so entries into
//! the same strand closer than `4 r` are ignored (a strand cannot really curl back onto itself
//! that close). Rays leaving the mesh start `1e-9 (1 + scene extent)` off the triangle along
//! its facing normal. The BSDF is evaluated with the `h` of the hit and the fibre's tangent at
//! the hit segment; as in pbrt, where on the cross-section light leaves is not modelled beyond
//! this.
//!
//! # Determinism
//! Every pixel has its own [`Pcg32`] seeded from `(seed, pixel index)`; rows are rendered in
//! parallel with rayon but no random number depends on scheduling, so a seed gives the same
//! image bit for bit on any number of threads ([`PathTracer::render_with_progress`] reports
//! each finished row, for a progress bar).

use std::f64::consts::{PI, TAU};
use std::path::Path;

use glam::{DVec3, DVec4, Vec3};
use pelage_scene::{Camera, Light, ParamError};
use rayon::prelude::*;

use crate::chiang::{ChiangError, ChiangFibre, FibreFrame, PreparedFibre};
use crate::flip::{FlipError, LinearImage};
use crate::transmittance::{Segment, SegmentBvh, SegmentHit};

/// Most bounces a render may ask for.
pub const MAX_BOUNCES_LIMIT: u32 = 1024;

/// Most samples per pixel a render may ask for (65 536: beyond it the `f64` mean of a
/// pixel still converges, but a render of any useful size would take days).
pub const MAX_SPP: u32 = 65_536;

/// Largest image side accepted (8192² pixels of radiance and mask take 1 GiB).
pub const MAX_IMAGE_SIDE: u32 = 8192;

/// A fibre's continuation and shadow rays start this fraction of the radius outside it.
pub const SPAWN_OFFSET: f64 = 1.0e-3;

/// `(√5 − 1) / 2`: the azimuth step of [`PathTracer::field_at`]'s Fibonacci lattice.
const GOLDEN_RATIO_CONJUGATE: f64 = 0.618_033_988_749_894_9;

/// Entries into the strand a ray leaves, closer than this many radii, are ignored.
pub const SELF_SKIP_RADII: f64 = 4.0;

/// PCG32 (O'Neill's `pcg32_random_r`, XSH RR 64/32): a small, fast, reproducible generator.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    /// A generator on stream `stream` (any value) seeded with `seed` (pcg32's `srandom_r`).
    pub fn new(seed: u64, stream: u64) -> Pcg32 {
        let mut r = Pcg32 {
            state: 0,
            inc: (stream << 1) | 1,
        };
        r.next_u32();
        r.state = r
            .state
            .wrapping_add(splitmix64(seed ^ stream.rotate_left(32)));
        r.next_u32();
        r
    }

    /// The next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// A uniform `f64` in [0, 1) with 53 random bits.
    pub fn next_f64(&mut self) -> f64 {
        let hi = u64::from(self.next_u32() >> 5);
        let lo = u64::from(self.next_u32() >> 6);
        ((hi << 26) | lo) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// SplitMix64's finaliser: spreads nearby seeds over the state space.
fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// What is wrong with a path-tracing request.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PathTraceError {
    /// `spp` is 0 or above [`MAX_SPP`].
    #[error("spp = {0}: must be in 1..={MAX_SPP} samples per pixel")]
    Spp(u32),
    /// `max_bounces` is 0 or above [`MAX_BOUNCES_LIMIT`].
    #[error("max_bounces = {0}: must be in 1..={MAX_BOUNCES_LIMIT} (1 = direct light only)")]
    Bounces(u32),
    /// Width or height is 0 or above [`MAX_IMAGE_SIDE`].
    #[error("image size {width}x{height}: each side must be in 1..={MAX_IMAGE_SIDE}")]
    Size {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
    },
    /// An input holds a NaN or infinity.
    #[error("{what} is not finite")]
    NonFinite {
        /// Which input, e.g. `segments[3]`.
        what: String,
    },
    /// An input is out of range.
    #[error("{what}: {reason}")]
    Invalid {
        /// Which input.
        what: String,
        /// What is wrong.
        reason: String,
    },
    /// The fibre parameters are out of range.
    #[error(transparent)]
    Fibre(#[from] ChiangError),
    /// A camera or light parameter is out of range.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// Writing an image failed.
    #[error("writing the image failed: {0}")]
    Image(String),
}

/// Render settings.
#[derive(Clone, Debug, PartialEq)]
pub struct PathTracerSettings {
    /// Samples (paths) per pixel, in 1..=[`MAX_SPP`]. Default 64.
    pub spp: u32,
    /// Most scattering vertices per path, in 1..=1024; 1 = direct light only. Default 16.
    pub max_bounces: u32,
    /// Seed of every pixel's random numbers. Default 0.
    pub seed: u64,
    /// Linear RGB radiance a camera ray that hits nothing sees (pelage's
    /// `shade.background`: it lights nothing), finite and >= 0. Default black.
    pub background: DVec3,
    /// Linear RGB radiance an escaping ray sees after at least one scattering: the light
    /// of the environment (pelage's `shade.ambient / π`, see the module docs), finite and
    /// >= 0. Default black.
    pub sky: DVec3,
    /// First scattering vertex (1-based) whose continuation faces Russian roulette; values
    /// above `max_bounces` turn it off. Default 4.
    pub roulette_start: u32,
}

impl Default for PathTracerSettings {
    fn default() -> Self {
        Self {
            spp: 64,
            max_bounces: 16,
            seed: 0,
            background: DVec3::ZERO,
            sky: DVec3::ZERO,
            roulette_start: 4,
        }
    }
}

impl PathTracerSettings {
    /// Checks the settings (see the field docs).
    pub fn validate(&self) -> Result<(), PathTraceError> {
        if self.spp == 0 || self.spp > MAX_SPP {
            return Err(PathTraceError::Spp(self.spp));
        }
        if self.max_bounces == 0 || self.max_bounces > MAX_BOUNCES_LIMIT {
            return Err(PathTraceError::Bounces(self.max_bounces));
        }
        for (what, v) in [("background", self.background), ("sky", self.sky)] {
            if !v.is_finite() {
                return Err(PathTraceError::NonFinite { what: what.into() });
            }
            if v.min_element() < 0.0 {
                return Err(PathTraceError::Invalid {
                    what: what.into(),
                    reason: format!("{v:?} must be >= 0"),
                });
            }
        }
        Ok(())
    }
}

/// The scene handed to [`PathTracer::new`].
#[derive(Clone, Debug)]
pub struct HairScene<'a> {
    /// Strand segments (e.g. from `segments_from_strands`); `opacity` is ignored (fibres are
    /// opaque surfaces here). Degenerate ones (zero length or radius) are skipped.
    pub segments: &'a [Segment],
    /// The hair's BSDF.
    pub fibre: ChiangFibre,
    /// Optional σ_a per strand (indexed by [`Segment::strand`]), replacing `fibre.sigma_a`;
    /// must cover every strand id used.
    pub strand_sigma_a: Option<&'a [DVec3]>,
    /// Mesh vertex positions (may be empty).
    pub mesh_positions: &'a [Vec3],
    /// Mesh triangles as indices into `mesh_positions`; zero-area ones are skipped.
    pub mesh_triangles: &'a [[u32; 3]],
    /// Lambertian albedo of the mesh, linear RGB, finite and >= 0 (see the module docs for
    /// pelage's `π · style.color`).
    pub mesh_albedo: DVec3,
    /// Lights (any number, including none).
    pub lights: &'a [Light],
}

/// A light ready to sample.
#[derive(Clone, Copy, Debug)]
enum PreparedLight {
    Directional { to_light: DVec3, irradiance: DVec3 },
    Point { position: DVec3, intensity: DVec3 },
}

/// A BVH node over triangles (as the segment BVH: children at `first`, `first + 1` when
/// `count == 0`, else a leaf of `count` triangles from `first`).
#[derive(Clone, Copy, Debug)]
struct TriNode {
    min: DVec3,
    max: DVec3,
    first: u32,
    count: u32,
}

/// One triangle in `f64` with its unit geometric normal.
#[derive(Clone, Copy, Debug)]
struct Triangle {
    a: DVec3,
    e1: DVec3,
    e2: DVec3,
    normal: DVec3,
}

/// Median-split BVH over triangles.
#[derive(Clone, Debug, Default)]
struct TriangleBvh {
    nodes: Vec<TriNode>,
    tris: Vec<Triangle>,
}

impl TriangleBvh {
    fn build(tris: Vec<Triangle>) -> TriangleBvh {
        let boxes: Vec<(DVec3, DVec3)> = tris
            .iter()
            .map(|t| {
                let (b, c) = (t.a + t.e1, t.a + t.e2);
                let lo = t.a.min(b).min(c);
                let hi = t.a.max(b).max(c);
                let pad = 1e-9 * (1.0 + lo.abs().max(hi.abs()).max_element());
                (lo - pad, hi + pad)
            })
            .collect();
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        let mut nodes = Vec::new();
        if !tris.is_empty() {
            let blank = TriNode {
                min: DVec3::ZERO,
                max: DVec3::ZERO,
                first: 0,
                count: 0,
            };
            nodes.push(blank);
            let mut stack = vec![(0usize, 0usize, tris.len())];
            while let Some((node, start, end)) = stack.pop() {
                let mut min = DVec3::INFINITY;
                let mut max = DVec3::NEG_INFINITY;
                let mut cmin = DVec3::INFINITY;
                let mut cmax = DVec3::NEG_INFINITY;
                for &i in &order[start..end] {
                    let (lo, hi) = boxes[i as usize];
                    min = min.min(lo);
                    max = max.max(hi);
                    cmin = cmin.min(0.5 * (lo + hi));
                    cmax = cmax.max(0.5 * (lo + hi));
                }
                nodes[node].min = min;
                nodes[node].max = max;
                if end - start <= 4 {
                    nodes[node].first = start as u32;
                    nodes[node].count = (end - start) as u32;
                    continue;
                }
                let ext = cmax - cmin;
                let axis = if ext.x >= ext.y && ext.x >= ext.z {
                    0
                } else if ext.y >= ext.z {
                    1
                } else {
                    2
                };
                let mid = start + (end - start) / 2;
                let key = |i: &u32| {
                    let (lo, hi) = boxes[*i as usize];
                    lo[axis] + hi[axis]
                };
                order[start..end]
                    .select_nth_unstable_by(mid - start, |x, y| key(x).total_cmp(&key(y)));
                let left = nodes.len();
                nodes.push(blank);
                nodes.push(blank);
                nodes[node].first = left as u32;
                nodes[node].count = 0;
                stack.push((left, start, mid));
                stack.push((left + 1, mid, end));
            }
        }
        let tris = order.iter().map(|&i| tris[i as usize]).collect();
        TriangleBvh { nodes, tris }
    }

    /// Nearest triangle hit in `(0, max_t]` (`d` unit): `(t, triangle index)`.
    fn closest_hit(&self, o: DVec3, d: DVec3, max_t: f64, any: bool) -> Option<(f64, usize)> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut best = None;
        let mut t_max = max_t;
        let mut stack = [0u32; 64];
        let mut sp = 1usize;
        while sp > 0 {
            sp -= 1;
            let node = &self.nodes[stack[sp] as usize];
            if !box_hit(o, d, t_max, node.min, node.max) {
                continue;
            }
            if node.count == 0 {
                for n in [node.first, node.first + 1] {
                    if let Some(slot) = stack.get_mut(sp) {
                        *slot = n;
                        sp += 1;
                    }
                }
                continue;
            }
            let first = node.first as usize;
            for (k, tri) in self.tris[first..first + node.count as usize]
                .iter()
                .enumerate()
            {
                if let Some(t) = ray_triangle(tri, o, d, t_max) {
                    t_max = t;
                    best = Some((t, first + k));
                    if any {
                        return best;
                    }
                }
            }
        }
        best
    }
}

/// Slab test: whether the ray meets the closed box for some `t` in `[0, max_t]`.
fn box_hit(o: DVec3, d: DVec3, max_t: f64, min: DVec3, max: DVec3) -> bool {
    let mut near = 0.0f64;
    let mut far = max_t;
    for i in 0..3 {
        if d[i] == 0.0 {
            if o[i] < min[i] || o[i] > max[i] {
                return false;
            }
            continue;
        }
        let inv = 1.0 / d[i];
        let t1 = (min[i] - o[i]) * inv;
        let t2 = (max[i] - o[i]) * inv;
        near = near.max(t1.min(t2));
        far = far.min(t1.max(t2));
        if near > far {
            return false;
        }
    }
    true
}

/// Möller-Trumbore, two-sided: the hit distance in `(0, max_t]`.
fn ray_triangle(tri: &Triangle, o: DVec3, d: DVec3, max_t: f64) -> Option<f64> {
    let p = d.cross(tri.e2);
    let det = tri.e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - tri.a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(tri.e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = tri.e2.dot(q) * inv;
    (t > 0.0 && t <= max_t).then_some(t)
}

/// What a scattering vertex on a fibre needs of its segment.
struct FibreVertex {
    /// The hit's projection onto the segment's axis.
    axis_point: DVec3,
    /// The fibre's frame (x along the axis).
    frame: FibreFrame,
    /// The fibre with the strand's σ_a.
    fibre: PreparedFibre,
    /// Radius at the hit.
    radius: f64,
    /// The strand's entries to ignore for rays leaving it.
    skip: Option<(u32, f64)>,
}

impl FibreVertex {
    /// Where a ray along `w` leaves the fibre: on its surface, on the side `w` goes to (see
    /// the module docs); `p` (the hit) for a `w` along the axis.
    fn spawn(&self, w: DVec3, p: DVec3) -> DVec3 {
        let perp = w - self.frame.x * self.frame.x.dot(w);
        let len = perp.length();
        let u = if len > 1.0e-9 {
            perp / len
        } else {
            (p - self.axis_point).normalize_or(self.frame.y)
        };
        self.axis_point + u * (self.radius * (1.0 + SPAWN_OFFSET))
    }
}

/// The light arriving at a visible fibre that has scattered at least once on the way (off
/// other fibres or the mesh), or comes from the sky: what a volume method's grid stands for
/// at that fibre (`pelage_reference::volume`), measured by [`PathTracer::field_at`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldSample {
    /// The hit's point on the fibre's axis (where pelage's shading reads its grid).
    pub point: DVec3,
    /// Unit tangent of the fibre.
    pub tangent: DVec3,
    /// Unit direction toward the camera.
    pub view: DVec3,
    /// The fibre's σ_a.
    pub sigma_a: DVec3,
    /// Fluence per channel, `φ = ∫ L(ω) dω` over the sphere of directions `ω` the light
    /// comes from.
    pub fluence: DVec3,
    /// Flux vector per channel, `Φ = ∫ L(ω) (−ω) dω` (the direction the light travels).
    pub flux: [DVec3; 3],
    /// The fibre's response to that light, `∫ f(v, ω) cos θ_ω L(ω) dω` with Chiang's BSDF at
    /// the hit's offset `h`: the radiance toward the camera of every order the field
    /// carries (orders ≥ 2 of the lights, all of the sky's).
    pub response: DVec3,
}

/// A path's next ray after a scattering vertex.
#[derive(Clone, Copy, Debug)]
struct Continuation {
    origin: DVec3,
    dir: DVec3,
    /// `f cos θ / pdf`.
    weight: DVec3,
    /// Entries to ignore (see [`SegmentBvh::closest_hit`]).
    skip: Option<(u32, f64)>,
}

/// What a ray hit.
#[derive(Clone, Copy, Debug)]
enum Surface {
    Hair(SegmentHit),
    Mesh(usize),
}

/// A path-traced image.
#[derive(Clone, Debug, PartialEq)]
pub struct PathTracedImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear radiance, row-major, top row first.
    pub pixels: Vec<[f32; 3]>,
    /// Per pixel, the fraction of primary samples whose first hit is hair.
    pub hair_mask: Vec<f32>,
    /// Samples per pixel.
    pub spp: u32,
}

impl PathTracedImage {
    /// The radiance as a [`LinearImage`] (fails only if the image holds a non-finite value or
    /// its fields were edited out of shape).
    pub fn to_linear_image(&self) -> Result<LinearImage, FlipError> {
        LinearImage::new(self.width, self.height, self.pixels.clone())
    }

    /// 8-bit sRGB RGBA bytes (alpha 255), row-major, values clamped to [0, 1] first.
    pub fn to_srgb8_rgba(&self) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|p| {
                [
                    crate::oit::linear_to_srgb8(p[0]),
                    crate::oit::linear_to_srgb8(p[1]),
                    crate::oit::linear_to_srgb8(p[2]),
                    255,
                ]
            })
            .collect()
    }

    /// Writes the linear radiance as a Radiance `.hdr` file.
    pub fn write_hdr(&self, path: &Path) -> Result<(), PathTraceError> {
        let file = std::fs::File::create(path)
            .map_err(|e| PathTraceError::Image(format!("{}: {e}", path.display())))?;
        let rgb: Vec<image::Rgb<f32>> = self.pixels.iter().map(|p| image::Rgb(*p)).collect();
        image::codecs::hdr::HdrEncoder::new(std::io::BufWriter::new(file))
            .encode(&rgb, self.width as usize, self.height as usize)
            .map_err(|e| PathTraceError::Image(format!("{}: {e}", path.display())))
    }

    /// Writes the image as an 8-bit sRGB PNG ([`Self::to_srgb8_rgba`]).
    pub fn write_png(&self, path: &Path) -> Result<(), PathTraceError> {
        image::save_buffer(
            path,
            &self.to_srgb8_rgba(),
            self.width,
            self.height,
            image::ExtendedColorType::Rgba8,
        )
        .map_err(|e| PathTraceError::Image(format!("{}: {e}", path.display())))
    }
}

/// A scene ready to path trace (BVHs built, inputs checked).
#[derive(Clone, Debug)]
pub struct PathTracer {
    hair: SegmentBvh,
    mesh: TriangleBvh,
    fibre: PreparedFibre,
    strand_sigma_a: Vec<DVec3>,
    mesh_albedo: DVec3,
    lights: Vec<PreparedLight>,
    /// Offset of rays leaving the mesh.
    mesh_eps: f64,
}

fn non_finite(what: String) -> PathTraceError {
    PathTraceError::NonFinite { what }
}

impl PathTracer {
    /// Checks the scene and builds its BVHs. Errors: a non-finite segment, position, σ_a,
    /// albedo or light; a negative σ_a or albedo; a triangle index out of range; a strand id
    /// not covered by `strand_sigma_a`; fibre parameters out of range.
    pub fn new(scene: &HairScene<'_>) -> Result<PathTracer, PathTraceError> {
        scene.fibre.validate()?;
        let mut extent = 0.0f64;
        let mut max_strand = None::<u32>;
        for (i, s) in scene.segments.iter().enumerate() {
            if !s.a.is_finite() || !s.b.is_finite() || !s.radius.is_finite() {
                return Err(non_finite(format!("segments[{i}]")));
            }
            extent = extent.max(s.a.abs().max_element() as f64);
            extent = extent.max(s.b.abs().max_element() as f64);
            max_strand = Some(max_strand.map_or(s.strand, |m: u32| m.max(s.strand)));
        }
        let strand_sigma_a = match scene.strand_sigma_a {
            None => Vec::new(),
            Some(sig) => {
                for (i, s) in sig.iter().enumerate() {
                    if !s.is_finite() {
                        return Err(non_finite(format!("strand_sigma_a[{i}]")));
                    }
                    if s.min_element() < 0.0 {
                        return Err(PathTraceError::Invalid {
                            what: format!("strand_sigma_a[{i}]"),
                            reason: format!("{s:?} must be >= 0"),
                        });
                    }
                }
                if let Some(m) = max_strand {
                    if m as usize >= sig.len() {
                        return Err(PathTraceError::Invalid {
                            what: "strand_sigma_a".into(),
                            reason: format!(
                                "has {} entries but a segment belongs to strand {m}",
                                sig.len()
                            ),
                        });
                    }
                }
                sig.to_vec()
            }
        };
        if !scene.mesh_albedo.is_finite() {
            return Err(non_finite("mesh_albedo".into()));
        }
        if scene.mesh_albedo.min_element() < 0.0 || scene.mesh_albedo.max_element() > 1.0 {
            return Err(PathTraceError::Invalid {
                what: "mesh_albedo".into(),
                reason: format!(
                    "{:?}: every channel must be in [0, 1] (a Lambertian above 1 makes light \
                     at every bounce; pelage's `shade.mesh_color` gives `pelage_scene::mesh_albedo`)",
                    scene.mesh_albedo
                ),
            });
        }
        for (i, p) in scene.mesh_positions.iter().enumerate() {
            if !p.is_finite() {
                return Err(non_finite(format!("mesh_positions[{i}]")));
            }
            extent = extent.max(p.abs().max_element() as f64);
        }
        let mut tris = Vec::with_capacity(scene.mesh_triangles.len());
        for (i, t) in scene.mesh_triangles.iter().enumerate() {
            let mut v = [DVec3::ZERO; 3];
            for (c, &idx) in t.iter().enumerate() {
                let p = scene.mesh_positions.get(idx as usize).ok_or_else(|| {
                    PathTraceError::Invalid {
                        what: format!("mesh_triangles[{i}]"),
                        reason: format!(
                            "index {idx} but there are {} positions",
                            scene.mesh_positions.len()
                        ),
                    }
                })?;
                v[c] = p.as_dvec3();
            }
            let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
            if let Some(normal) = e1.cross(e2).try_normalize() {
                tris.push(Triangle {
                    a: v[0],
                    e1,
                    e2,
                    normal,
                });
            }
        }
        let mut lights = Vec::with_capacity(scene.lights.len());
        for (i, light) in scene.lights.iter().enumerate() {
            light.validate(i)?;
            lights.push(match light {
                Light::Directional(d) => PreparedLight::Directional {
                    to_light: (-d.direction.as_dvec3()).normalize_or_zero(),
                    irradiance: d.color.as_dvec3() * f64::from(d.intensity),
                },
                Light::Point(p) => PreparedLight::Point {
                    position: p.position.as_dvec3(),
                    intensity: p.color.as_dvec3() * f64::from(p.intensity),
                },
            });
        }
        Ok(PathTracer {
            hair: SegmentBvh::build(scene.segments.to_vec()),
            mesh: TriangleBvh::build(tris),
            fibre: scene.fibre.prepare(),
            strand_sigma_a,
            mesh_albedo: scene.mesh_albedo,
            lights,
            mesh_eps: 1.0e-9 * (1.0 + extent),
        })
    }

    /// The light arriving at the first fibre a camera ray from `o` along unit `d` hits (see
    /// [`FieldSample`]), from `directions` rays leaving the fibre, a Fibonacci lattice on the
    /// sphere turned at random (each ray uniform, jittered in `cos` of the polar angle about
    /// the world's z). Each ray's radiance is a path of up to `settings.max_bounces`
    /// vertices (Russian roulette as in [`Self::render`]) that sees `settings.sky` when it
    /// escapes; its first vertex's light is included (light scattered once reaching the
    /// fibre), the lights' unscattered light is not (pelage shades it apart). `None` when
    /// the ray hits nothing or the mesh first. Errors for bad settings or `directions` 0.
    pub fn field_at(
        &self,
        o: DVec3,
        d: DVec3,
        directions: u32,
        settings: &PathTracerSettings,
        rng: &mut Pcg32,
    ) -> Result<Option<FieldSample>, PathTraceError> {
        settings.validate()?;
        if directions == 0 {
            return Err(PathTraceError::Invalid {
                what: "directions".into(),
                reason: "must be at least 1".into(),
            });
        }
        let Some((t_hit, Surface::Hair(sh))) = self.intersect(o, d, f64::INFINITY, None) else {
            return Ok(None);
        };
        let Some(vertex) = self.fibre_vertex(&sh) else {
            return Ok(None);
        };
        let p = o + d * t_hit;
        let view = -d;
        let wo_l = vertex.frame.to_local(view);
        let weight = 4.0 * PI / f64::from(directions);
        let mut fluence = DVec3::ZERO;
        let mut flux = [DVec3::ZERO; 3];
        let mut response = DVec3::ZERO;
        // A Fibonacci lattice turned at random: each direction uniform on the sphere, the
        // set of them evenly spread.
        let turn = rng.next_f64();
        for k in 0..directions {
            let z = 1.0 - 2.0 * (f64::from(k) + rng.next_f64()) / f64::from(directions);
            let r = (1.0 - z * z).max(0.0).sqrt();
            let azimuth = TAU * (turn + f64::from(k) * GOLDEN_RATIO_CONJUGATE).fract();
            let w = DVec3::new(r * azimuth.cos(), r * azimuth.sin(), z);
            let (l, _) = self.trace_from(
                vertex.spawn(w, p),
                w,
                f64::INFINITY,
                vertex.skip,
                settings.sky,
                settings,
                rng,
            );
            fluence += l * weight;
            for (c, f) in flux.iter_mut().enumerate() {
                *f -= w * (l[c] * weight);
            }
            let f = vertex
                .fibre
                .eval_projected(wo_l, vertex.frame.to_local(w), sh.h);
            response += f * l * weight;
        }
        Ok(Some(FieldSample {
            point: vertex.axis_point,
            tangent: vertex.frame.x,
            view,
            sigma_a: vertex.fibre.fibre().sigma_a,
            fluence,
            flux,
            response,
        }))
    }

    /// The fibre a ray hit, as a scattering vertex sees it; `None` for a degenerate segment.
    fn fibre_vertex(&self, sh: &SegmentHit) -> Option<FibreVertex> {
        let seg = &sh.segment;
        let a = seg.a.as_dvec3();
        let e = seg.b.as_dvec3() - a;
        let radius = f64::from(seg.radius);
        Some(FibreVertex {
            axis_point: a + e * sh.s,
            frame: FibreFrame::from_tangent(e)?,
            fibre: match self.strand_sigma_a.get(seg.strand as usize) {
                Some(s) => self.fibre.with_sigma_a(*s),
                None => self.fibre,
            },
            radius,
            skip: Some((seg.strand, SELF_SKIP_RADII * radius)),
        })
    }

    /// The strand BVH (for queries of the same geometry the tracer sees).
    pub fn hair_bvh(&self) -> &SegmentBvh {
        &self.hair
    }

    /// Renders `width x height` pixels of `camera` (see the module docs). Errors for bad
    /// settings, a zero or too large size, or an invalid camera.
    pub fn render(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        settings: &PathTracerSettings,
    ) -> Result<PathTracedImage, PathTraceError> {
        self.render_with_progress(camera, width, height, settings, &|| {})
    }

    /// [`PathTracer::render`], calling `row_done` once per finished row (from rayon's
    /// threads, in any order; `height` calls in all when the render succeeds): what a
    /// progress bar counts. The image does not depend on it.
    pub fn render_with_progress(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        settings: &PathTracerSettings,
        row_done: &(dyn Fn() + Sync),
    ) -> Result<PathTracedImage, PathTraceError> {
        settings.validate()?;
        if width == 0 || height == 0 || width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
            return Err(PathTraceError::Size { width, height });
        }
        camera.validate()?;
        let vp = camera
            .view_projection(width as f32 / height as f32)
            .as_dmat4();
        let inv = vp.inverse();
        if !inv.is_finite() {
            return Err(PathTraceError::Invalid {
                what: "camera".into(),
                reason: "view-projection is not invertible".into(),
            });
        }
        let (w, h) = (width as usize, height as usize);
        let rows: Vec<Vec<([f32; 3], f32)>> = (0..h)
            .into_par_iter()
            .map(|y| {
                let row = (0..w)
                    .map(|x| {
                        let index = (y * w + x) as u64;
                        let mut rng = Pcg32::new(settings.seed, index);
                        let mut sum = DVec3::ZERO;
                        let mut hair = 0u32;
                        for _ in 0..settings.spp {
                            let nx = 2.0 * (x as f64 + rng.next_f64()) / w as f64 - 1.0;
                            let ny = 1.0 - 2.0 * (y as f64 + rng.next_f64()) / h as f64;
                            let near = inv * DVec4::new(nx, ny, 0.0, 1.0);
                            let far = inv * DVec4::new(nx, ny, 1.0, 1.0);
                            let near = near.truncate() / near.w;
                            let far = far.truncate() / far.w;
                            let span = far - near;
                            let len = span.length();
                            if !len.is_finite() || len <= 0.0 {
                                continue;
                            }
                            let (l, first_hair) =
                                self.trace(near, span / len, len, settings, &mut rng);
                            sum += l;
                            hair += u32::from(first_hair);
                        }
                        let n = f64::from(settings.spp);
                        let m = sum / n;
                        (
                            [m.x as f32, m.y as f32, m.z as f32],
                            (f64::from(hair) / n) as f32,
                        )
                    })
                    .collect();
                row_done();
                row
            })
            .collect();
        let (pixels, hair_mask) = rows.into_iter().flatten().unzip();
        Ok(PathTracedImage {
            width,
            height,
            pixels,
            hair_mask,
            spp: settings.spp,
        })
    }

    /// Nearest hit of hair or mesh in `(0, max_t]`.
    fn intersect(
        &self,
        o: DVec3,
        d: DVec3,
        max_t: f64,
        skip: Option<(u32, f64)>,
    ) -> Option<(f64, Surface)> {
        let hair = self.hair.closest_hit(o, d, max_t, skip);
        let limit = hair.map_or(max_t, |h| h.t);
        if let Some((t, tri)) = self.mesh.closest_hit(o, d, limit, false) {
            return Some((t, Surface::Mesh(tri)));
        }
        hair.map(|h| (h.t, Surface::Hair(h)))
    }

    fn occluded(&self, o: DVec3, d: DVec3, max_t: f64, skip: Option<(u32, f64)>) -> bool {
        self.mesh.closest_hit(o, d, max_t, true).is_some() || self.hair.occluded(o, d, max_t, skip)
    }

    /// Direction to the light, its irradiance at `p`, and its position (point lights).
    fn light_at(light: &PreparedLight, p: DVec3) -> Option<(DVec3, DVec3, Option<DVec3>)> {
        match *light {
            PreparedLight::Directional {
                to_light,
                irradiance,
            } => Some((to_light, irradiance, None)),
            PreparedLight::Point {
                position,
                intensity,
            } => {
                let v = position - p;
                let d2 = v.length_squared();
                let dir = v.try_normalize()?;
                Some((dir, intensity / d2.max(1.0e-4), Some(position)))
            }
        }
    }

    /// The shadow ray from `origin` toward the light: direction and length.
    fn shadow_ray(origin: DVec3, dir: DVec3, position: Option<DVec3>) -> Option<(DVec3, f64)> {
        match position {
            None => Some((dir, f64::INFINITY)),
            Some(q) => {
                let v = q - origin;
                let len = v.length();
                (len > 0.0).then(|| (v / len, len))
            }
        }
    }

    /// One path from `o` along unit `d` (primary ray up to `max_t`): its radiance and whether
    /// its first hit is hair.
    fn trace(
        &self,
        o: DVec3,
        d: DVec3,
        max_t: f64,
        settings: &PathTracerSettings,
        rng: &mut Pcg32,
    ) -> (DVec3, bool) {
        self.trace_from(o, d, max_t, None, settings.background, settings, rng)
    }

    /// [`Self::trace`] from a ray that may leave a fibre (`skip`, as a continuation's), seeing
    /// `miss` if it hits nothing: the background for a camera ray, the sky for a ray that
    /// stands for light arriving at a scattering vertex.
    #[allow(clippy::too_many_arguments)]
    fn trace_from(
        &self,
        o: DVec3,
        d: DVec3,
        max_t: f64,
        skip: Option<(u32, f64)>,
        miss: DVec3,
        settings: &PathTracerSettings,
        rng: &mut Pcg32,
    ) -> (DVec3, bool) {
        let Some(mut hit) = self.intersect(o, d, max_t, skip) else {
            return (miss, false);
        };
        let first_hair = matches!(hit.1, Surface::Hair(_));
        let mut origin = o;
        let mut dir = d;
        let mut throughput = DVec3::ONE;
        let mut radiance = DVec3::ZERO;
        for k in 1..=settings.max_bounces {
            let p = origin + dir * hit.0;
            let wo = -dir;
            let next = match hit.1 {
                Surface::Hair(sh) => self.scatter_hair(&sh, p, wo, throughput, &mut radiance, rng),
                Surface::Mesh(tri) => self.scatter_mesh(tri, p, wo, throughput, &mut radiance, rng),
            };
            let Some(Continuation {
                origin: next_o,
                dir: next_d,
                weight,
                skip,
            }) = next
            else {
                break;
            };
            throughput *= weight;
            if !throughput.is_finite() || throughput.max_element() <= 0.0 {
                break;
            }
            if k >= settings.roulette_start {
                let q = throughput.max_element().min(0.95);
                if rng.next_f64() >= q {
                    break;
                }
                throughput /= q;
            }
            match self.intersect(next_o, next_d, f64::INFINITY, skip) {
                None => {
                    radiance += throughput * settings.sky;
                    break;
                }
                Some(h) => {
                    if k == settings.max_bounces {
                        break;
                    }
                    hit = h;
                    origin = next_o;
                    dir = next_d;
                }
            }
        }
        (radiance, first_hair)
    }

    /// Next-event estimation at a fibre hit, then the sampled continuation.
    fn scatter_hair(
        &self,
        sh: &SegmentHit,
        p: DVec3,
        wo: DVec3,
        throughput: DVec3,
        radiance: &mut DVec3,
        rng: &mut Pcg32,
    ) -> Option<Continuation> {
        let vertex = self.fibre_vertex(sh)?;
        let (frame, fibre, skip) = (vertex.frame, vertex.fibre, vertex.skip);
        let wo_l = frame.to_local(wo);
        let spawn = |w: DVec3| vertex.spawn(w, p);
        for light in &self.lights {
            let Some((wi, irradiance, position)) = Self::light_at(light, p) else {
                continue;
            };
            let fc = fibre.eval_projected(wo_l, frame.to_local(wi), sh.h);
            if !fc.is_finite() || fc.max_element() <= 0.0 {
                continue;
            }
            let so = spawn(wi);
            let Some((sd, len)) = Self::shadow_ray(so, wi, position) else {
                continue;
            };
            if !self.occluded(so, sd, len, skip) {
                *radiance += throughput * fc * irradiance;
            }
        }
        let u = [
            rng.next_f64(),
            rng.next_f64(),
            rng.next_f64(),
            rng.next_f64(),
        ];
        let (wi_l, f, pdf) = fibre.sample(wo_l, sh.h, u)?;
        let cos_i = (1.0 - wi_l.x * wi_l.x).max(0.0).sqrt();
        let wi = frame.to_world(wi_l).try_normalize()?;
        Some(Continuation {
            origin: spawn(wi),
            dir: wi,
            weight: f * (cos_i / pdf),
            skip,
        })
    }

    /// Next-event estimation at a mesh hit, then a cosine-weighted continuation.
    fn scatter_mesh(
        &self,
        tri: usize,
        p: DVec3,
        wo: DVec3,
        throughput: DVec3,
        radiance: &mut DVec3,
        rng: &mut Pcg32,
    ) -> Option<Continuation> {
        let ng = self.mesh.tris.get(tri)?.normal;
        let n = if ng.dot(wo) >= 0.0 { ng } else { -ng };
        let so = p + n * self.mesh_eps;
        let brdf = self.mesh_albedo / PI;
        for light in &self.lights {
            let Some((wi, irradiance, position)) = Self::light_at(light, p) else {
                continue;
            };
            let cos = n.dot(wi);
            if cos <= 0.0 {
                continue;
            }
            let Some((sd, len)) = Self::shadow_ray(so, wi, position) else {
                continue;
            };
            if !self.occluded(so, sd, len, None) {
                *radiance += throughput * brdf * cos * irradiance;
            }
        }
        // Cosine-weighted hemisphere about n: f cos / pdf = albedo.
        let (u1, u2) = (rng.next_f64(), rng.next_f64());
        let rad = u1.sqrt();
        let phi = TAU * u2;
        let (t1, t2) = n.any_orthonormal_pair();
        let local_z = (1.0 - u1).max(0.0).sqrt();
        let wi = (t1 * (rad * phi.cos()) + t2 * (rad * phi.sin()) + n * local_z).try_normalize()?;
        Some(Continuation {
            origin: so,
            dir: wi,
            weight: self.mesh_albedo,
            skip: None,
        })
    }
}
