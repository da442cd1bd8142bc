//! CPU mirror of the volume method's grid passes (`crates/pelage-shade/wgsl/shade/volume.wgsl`,
//! after Moon, Walter and Marschner 2008), in `f64`, computing everything from the strands,
//! the lights and the Chiang parameters: the grid's fit, the splat (in floating point, not
//! the GPU's fixed point), the injection and the propagation, with the fibre energies from
//! [`ChiangFibre::lobe_energies`] (integrated here, not read from the GPU's tables) sampled
//! at the GPU table's `|θ|` texels and interpolated as it interpolates them.
//!
//! The method, its phase function and its approximations are stated in
//! `crates/pelage-shade/wgsl/shade/models/volume_common.wgsl`; this file follows it step
//! for step so that a test can hold the GPU to it.

use std::collections::HashMap;
use std::f64::consts::{FRAC_PI_2, PI};

use glam::{DVec3, DVec4, IVec3, Vec3, Vec4};
use pelage_scene::{Absorption, ChiangParams, Light};

use crate::chiang::{ChiangFibre, sigma_a_from_reflectance};

/// Texels of `|θ|` in the GPU's energy table (`CHIANG_THETA`).
const THETA_TEXELS: usize = 32;
/// Samples of `|θ|` of the isotropic averages (`VOLUME_THETA_SAMPLES`).
const THETA_SAMPLES: usize = 8;
/// Directions of the sky's injection (`VOLUME_SKY_DIRECTIONS`).
pub const SKY_DIRECTIONS: usize = 15;

/// `volume_sky_direction`: the `k`-th of [`SKY_DIRECTIONS`] directions of a Fibonacci
/// lattice on the sphere (z uniform, azimuth stepped by the golden angle).
pub fn sky_direction(k: usize) -> DVec3 {
    lattice_direction(k, SKY_DIRECTIONS, 0.0)
}

/// The `k`-th of `n` directions of a Fibonacci lattice on the sphere, its azimuths turned
/// by `turn` radians: z at the middle of the `k`-th of `n` equal bands, the azimuth
/// stepped by the golden angle.
pub fn lattice_direction(k: usize, n: usize, turn: f64) -> DVec3 {
    let z = 1.0 - (2.0 * k as f64 + 1.0) / n.max(1) as f64;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = turn + PI * (3.0 - 5f64.sqrt()) * k as f64;
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// The strands as stage 1 hands them over, and what lights and shades them.
#[derive(Clone, Copy, Debug)]
pub struct VolumeInput<'a> {
    /// `strands × (segments + 1)` vertices: xyz position, w the strand parameter in [0, 1].
    pub vertices: &'a [Vec4],
    /// Segments per strand.
    pub segments: u32,
    /// Root width of each strand.
    pub widths: &'a [f32],
    /// Colour of each strand (linear RGB; the absorption when the parameters take it from
    /// the colour).
    pub colors: &'a [Vec3],
    /// Tip width as a fraction of the root width.
    pub tip_width: f32,
    /// The lights (as the scene gives them).
    pub lights: &'a [Light],
    /// `shade.ambient`: a sky of uniform radiance `ambient / π` from every direction (the
    /// path tracer's `sky`).
    pub ambient: f32,
    /// The fibre, the grid's size and its steps.
    pub params: &'a ChiangParams,
    /// The body under the hair, if any.
    pub mesh: Option<VolumeMesh<'a>>,
}

/// The body under the hair: it shadows the light and reflects it as a Lambertian of
/// albedo `π · color` (the path tracer's mesh), at most 1 per channel.
#[derive(Clone, Copy, Debug)]
pub struct VolumeMesh<'a> {
    /// Vertex positions.
    pub positions: &'a [Vec3],
    /// Vertex normals (they orient the triangles outward).
    pub normals: &'a [Vec3],
    /// Triangle list, three indices per triangle.
    pub indices: &'a [u32],
    /// `shade.mesh_color`.
    pub color: Vec3,
}

/// The grid the passes leave: what the shading reads, and the per-cell medium.
#[derive(Clone, Debug)]
pub struct VolumeGridCpu {
    /// Cells per side.
    pub resolution: u32,
    /// The grid's lowest corner.
    pub origin: DVec3,
    /// Cell edge.
    pub cell: f64,
    /// Optical depth of each cell (over a cell edge, isotropic mean).
    pub depth: Vec<f64>,
    /// The share of each cell inside the mesh.
    pub solid: Vec<f64>,
    /// Per cell and channel: fluence and flux vector `(φ, Φ)` of the lights' light
    /// scattered at least once and of all the sky's (its unscattered light included),
    /// over the clear share where the body fills part of a cell (`settle`).
    pub fluence: Vec<[DVec4; 3]>,
    /// Per cell: the part of `fluence` that is the sky's unscattered light (the same in
    /// every channel), settled the same way: the sky the grid lets reach the cell's fibres.
    pub sky: Vec<DVec4>,
    /// Total energy leaving the cells at each step (index 0: the injection), channels
    /// summed: the energy test watches it.
    pub step_energy: Vec<f64>,
    /// Total energy arriving at the cells at each propagation step (one fewer than
    /// `step_energy`): step `k`'s arrivals are step `k`'s departures less what left the
    /// grid, and its departures are its arrivals less what the fibres absorbed.
    pub step_arrivals: Vec<f64>,
}

impl VolumeGridCpu {
    /// The fluence and flux of the three channels at `p`, as the shading reads them
    /// (`volume_sample` in `chiang_volume_common_model.wgsl`): trilinear between cell centres,
    /// clamped at the grid's border.
    pub fn sample(&self, p: DVec3) -> [DVec4; 3] {
        let mut out = [DVec4::ZERO; 3];
        self.trilinear(p, |i, w| {
            if let Some(cell) = self.fluence.get(i) {
                for (ch, v) in out.iter_mut().enumerate() {
                    *v += w * cell[ch];
                }
            }
        });
        out
    }

    /// The sky's unscattered fluence and flux at `p` ([`Self::sky`]), read as
    /// [`Self::sample`] reads the fluence.
    pub fn sample_sky(&self, p: DVec3) -> DVec4 {
        let mut out = DVec4::ZERO;
        self.trilinear(p, |i, w| {
            out += w * self.sky.get(i).copied().unwrap_or_default()
        });
        out
    }

    /// The fibres' optical depth (`depth`, the body not counted) along the ray from `p`
    /// in the unit direction `d` to the grid's border: each cell's depth per edge times
    /// the ray's length in it (cell edges), the cells by the mirror's `ray_cells` from `p`
    /// itself. 0 from outside.
    pub fn optical_depth_toward(&self, p: DVec3, d: DVec3) -> f64 {
        let n = self.resolution.max(1) as usize;
        let from = (p - self.origin) / self.cell;
        if !(from.is_finite() && d.is_finite())
            || from.min_element() < 0.0
            || from.max_element() >= n as f64
        {
            return 0.0;
        }
        // Every ray leaves the cube within its diagonal, under 2n cell edges.
        ray_cells(from, d, 2.0 * n as f64, n, true)
            .into_iter()
            .map(|(c, length)| self.depth[cell_index(c, n)] * length)
            .sum()
    }

    /// Calls `f(cell index, weight)` for the 8 cells around `p` (trilinear between cell
    /// centres, clamped at the grid's border).
    fn trilinear(&self, p: DVec3, mut f: impl FnMut(usize, f64)) {
        let n = i64::from(self.resolution.max(1));
        let q = (p - self.origin) / self.cell - DVec3::splat(0.5);
        let base = q.floor();
        let frac = (q - base).clamp(DVec3::ZERO, DVec3::ONE);
        for corner in 0..8i64 {
            let o = [corner & 1, (corner >> 1) & 1, (corner >> 2) & 1];
            let mut w = 1.0;
            let mut c = [0i64; 3];
            for a in 0..3 {
                w *= if o[a] == 1 { frac[a] } else { 1.0 - frac[a] };
                c[a] = (base[a] as i64 + o[a]).clamp(0, n - 1);
            }
            f(((c[2] * n + c[1]) * n + c[0]) as usize, w);
        }
    }
}

/// The volume method's reading of its grid at a fibre (`hair_scattered` in
/// `chiang_volume_common_model.wgsl`), with the fibre's energies integrated here
/// ([`ChiangFibre::lobe_energies`] at the table's texels): the radiance toward `v` is
/// `A(θ_v) / (4π) (φ + 3 Φ' · q)` per channel, `q = t (t·v) + g(θ_v) (v − t (t·v))`, `Φ'`
/// the flux shortened to at most `φ / 3`.
#[derive(Clone, Debug)]
pub struct FibreResponse {
    table: EnergyTable,
}

impl FibreResponse {
    /// The response of fibres like `fibre` (its σ_a included).
    pub fn new(fibre: &ChiangFibre) -> Self {
        Self {
            table: EnergyTable::new(fibre),
        }
    }

    /// The radiance toward unit `v` of a fibre of unit tangent `t` in the light `field`
    /// (per channel `(φ, Φ)`, as [`VolumeGridCpu::sample`] gives it).
    pub fn radiance(&self, t: DVec3, v: DVec3, field: &[DVec4; 3]) -> DVec3 {
        let sin_o = t.dot(v).clamp(-1.0, 1.0);
        let phase = self.table.at(sin_o.abs().asin());
        let along = t * sin_o;
        let across = v - along;
        let mut out = DVec3::ZERO;
        for (c, value) in field.iter().enumerate() {
            let q = along + phase.g[c] * across;
            let phi = value.x.max(0.0);
            let flux = DVec3::new(value.y, value.z, value.w);
            let len = flux.length();
            let flux = if 3.0 * len > phi {
                flux * (phi / (3.0 * len))
            } else {
                flux
            };
            out[c] = phase.albedo[c] * (phi + 3.0 * flux.dot(q)).max(0.0) / (4.0 * PI);
        }
        out
    }
}

/// Energy `A` and forward bias `g` per channel, as `volume_fibre_at`.
#[derive(Clone, Copy, Debug)]
struct Phase {
    albedo: DVec3,
    g: DVec3,
}

/// `(a_f, a_b)` per channel at the table's `|θ|` texels, for one σ_a.
#[derive(Clone, Debug)]
struct EnergyTable {
    af: Vec<DVec3>,
    ab: Vec<DVec3>,
}

impl EnergyTable {
    fn new(fibre: &ChiangFibre) -> Self {
        let (mut af, mut ab) = (Vec::new(), Vec::new());
        for j in 0..THETA_TEXELS {
            let theta = FRAC_PI_2 * j as f64 / (THETA_TEXELS - 1) as f64;
            let e = fibre.lobe_energies(theta);
            af.push(e.a_f());
            ab.push(e.a_b());
        }
        Self { af, ab }
    }

    /// Linear in `|θ|` between texels, as `chiang_dual_at`.
    fn at(&self, theta: f64) -> Phase {
        let last = (THETA_TEXELS - 1) as f64;
        let u = (theta / FRAC_PI_2).clamp(0.0, 1.0) * last;
        let i = u.floor().min(last - 1.0);
        let f = u - i;
        let i = i as usize;
        let af = self.af[i] * (1.0 - f) + self.af[i + 1] * f;
        let ab = self.ab[i] * (1.0 - f) + self.ab[i + 1] * f;
        let a = af + ab;
        let g = DVec3::new(
            bias(af.x, ab.x, a.x),
            bias(af.y, ab.y, a.y),
            bias(af.z, ab.z, a.z),
        );
        Phase { albedo: a, g }
    }

    /// `volume_fibre_isotropic`.
    fn isotropic(&self) -> Phase {
        let (mut w_sum, mut a, mut ag) = (0.0, DVec3::ZERO, DVec3::ZERO);
        for j in 0..THETA_SAMPLES {
            let theta = (j as f64 + 0.5) * FRAC_PI_2 / THETA_SAMPLES as f64;
            let w = theta.cos().powi(2);
            let p = self.at(theta);
            w_sum += w;
            a += w * p.albedo;
            ag += w * p.albedo * p.g;
        }
        let albedo = a / w_sum;
        let g = DVec3::new(
            ratio(ag.x, w_sum * albedo.x),
            ratio(ag.y, w_sum * albedo.y),
            ratio(ag.z, w_sum * albedo.z),
        );
        Phase { albedo, g }
    }
}

fn bias(af: f64, ab: f64, a: f64) -> f64 {
    if a > 1e-8 {
        (2.0 / PI) * (af - ab) / a
    } else {
        0.0
    }
}

fn ratio(x: f64, y: f64) -> f64 {
    if y > 1e-8 { x / y } else { 0.0 }
}

/// One channel of `volume_scatter_flux`: the flux of light travelling with flux `p` after
/// one scattering.
fn scatter_direction(p: DVec3, t: DVec3, s: f64, g: f64, g_iso: f64) -> DVec3 {
    let along = t * t.dot(p);
    s * (along + g * (p - along)) + (1.0 - s) * ((1.0 + 2.0 * g_iso) / 3.0) * p
}

/// `volume_escape`: the share of light crossing a cell edge of optical depth `kappa`
/// unscattered, averaged over where it starts, and the mean path (cell edges) before it
/// scatters or leaves.
fn escape(kappa: f64) -> (f64, f64) {
    if kappa < 1e-4 {
        return (
            1.0 - kappa / 2.0 + kappa * kappa / 6.0,
            0.5 - kappa / 6.0 + kappa * kappa / 24.0,
        );
    }
    let p = -(-kappa).exp_m1() / kappa;
    (p, (1.0 - p) / kappa)
}

/// `volume_cell_transmittance`: the mean over a cell (the unit cube, optical depth `kappa`
/// per edge) of `exp(−κ s)`, `s` the way from a point to the cell's face along `l`. With
/// `P(s > t) = Q(t) = Π_a (1 − |l_a| t)` up to `T = 1 / max_a |l_a|`, it is
/// `1 − κ ∫₀ᵀ e^(−κt) Q(t) dt`: by parts where `κT > 4`, else 6-point Gauss-Legendre.
pub(crate) fn cell_transmittance(kappa: f64, l: DVec3) -> f64 {
    let a = l.abs();
    let t_end = 1.0 / a.max_element().max(1e-6);
    let s1 = a.x + a.y + a.z;
    let s2 = a.x * a.y + a.y * a.z + a.z * a.x;
    let s3 = a.x * a.y * a.z;
    if kappa * t_end > 4.0 {
        let ik = 1.0 / kappa;
        let d1 = -s1 + t_end * (2.0 * s2 - 3.0 * s3 * t_end);
        let d2 = 2.0 * s2 - 6.0 * s3 * t_end;
        let d3 = -6.0 * s3;
        let at_zero = ik * (s1 + ik * (-2.0 * s2 + ik * 6.0 * s3));
        return at_zero + (-kappa * t_end).exp() * ik * (d1 + ik * (d2 + ik * d3));
    }
    const X: [f64; 3] = [0.238_619_186_1, 0.661_209_386_5, 0.932_469_514_2];
    const W: [f64; 3] = [0.467_913_934_6, 0.360_761_573_0, 0.171_324_492_4];
    let mut integral = 0.0;
    for (x, w) in X.iter().zip(W) {
        for side in [-1.0, 1.0] {
            let t = 0.5 * t_end * (1.0 + side * x);
            let q = 1.0 - t * (s1 - t * (s2 - t * s3));
            integral += w * (-kappa * t).exp() * q;
        }
    }
    1.0 - kappa * (0.5 * t_end) * integral
}

/// One channel of `volume_born`: energy `e` and flux `f` born in a cell scatter there
/// until they leave; returns what leaves and the fluence left in the cell per unit leaving.
fn born(e: f64, f: DVec3, kappa: f64, albedo: f64) -> (f64, DVec3, f64) {
    let (p, path) = escape(kappa);
    let r = albedo.min(1.0) * (1.0 - p);
    let bias = if e > 0.0 {
        (f.length() / e).min(1.0)
    } else {
        0.0
    };
    (e * p / (1.0 - r), f * (p / (1.0 - r * bias)), path / p)
}

/// One channel of `volume_directions`: energy `e` and flux `f` as the light along the six
/// directions of [`FACES`].
fn directions(e: f64, f: DVec3) -> [f64; 6] {
    let l1 = f.x.abs() + f.y.abs() + f.z.abs();
    let c = if l1 > e { e / l1 } else { 1.0 };
    let even = (e - c * l1).max(0.0) / 6.0;
    let mut out = [even; 6];
    for (k, d) in FACES.iter().enumerate() {
        out[k] += (c * f.dot(d.as_dvec3())).max(0.0);
    }
    out
}

/// The propagation's spread and step path (`VOLUME_SPREAD`, `VOLUME_STEP_PATH`),
/// integrated here: over the directions nearest +x, the face of the unit cube seen from
/// its centre, r = (1, y, z) with y, z in [-1, 1] (solid angle dy dz / |r|³, flux along x
/// 1 / |r|), the flux-weighted mean of |y| (the tangent toward y) halved and the
/// flux-weighted mean secant.
fn cone_moments() -> (f64, f64) {
    let m = 512;
    let (mut flux, mut aside, mut solid) = (0.0, 0.0, 0.0);
    for i in 0..m {
        for j in 0..m {
            let y = -1.0 + 2.0 * (i as f64 + 0.5) / m as f64;
            let z = -1.0 + 2.0 * (j as f64 + 0.5) / m as f64;
            let r = (1.0 + y * y + z * z).sqrt();
            let w = 1.0 / (r * r * r);
            solid += w;
            flux += w / r;
            aside += w / r * y.abs();
        }
    }
    (0.5 * aside / flux, solid / flux)
}

/// Index of cell `c` (inside the grid) of an `n`-cell grid, x fastest.
fn cell_index(c: IVec3, n: usize) -> usize {
    (c.z as usize * n + c.y as usize) * n + c.x as usize
}

/// The cells a ray from `from` (in cell units) along unit `l` crosses, with the length of
/// the ray in each (cell units), from where it leaves its first cell (or, `from_start`,
/// from `from` itself, its first cell included) up to `limit` or the border of an
/// `n`-cell grid: every crossing of a cell face found per axis, sorted, each stretch
/// between two crossings in the cell holding its middle.
fn ray_cells(from: DVec3, l: DVec3, limit: f64, n: usize, from_start: bool) -> Vec<(IVec3, f64)> {
    let mut cuts = Vec::new();
    for a in 0..3 {
        if l[a].abs() < 1e-20 {
            continue;
        }
        let mut k = if l[a] > 0.0 {
            from[a].floor() + 1.0
        } else {
            from[a].ceil() - 1.0
        };
        loop {
            let t = (k - from[a]) / l[a];
            if t >= limit || !(-1.0..=n as f64 + 1.0).contains(&k) {
                break;
            }
            cuts.push(t);
            k += l[a].signum();
        }
    }
    cuts.push(limit);
    if from_start {
        cuts.push(0.0);
    }
    cuts.sort_by(f64::total_cmp);
    let mut out = Vec::new();
    let start = cuts[0];
    let mut t = start;
    for &cut in &cuts[1..] {
        let cut = cut.min(limit);
        if cut > t {
            let q = (from + l * (0.5 * (t + cut))).floor();
            if q.min_element() < 0.0 || q.max_element() >= n as f64 {
                break;
            }
            out.push((q.as_ivec3(), cut - t));
            t = cut;
        }
    }
    out
}

const FACES: [IVec3; 6] = [
    IVec3::new(1, 0, 0),
    IVec3::new(-1, 0, 0),
    IVec3::new(0, 1, 0),
    IVec3::new(0, -1, 0),
    IVec3::new(0, 0, 1),
    IVec3::new(0, 0, -1),
];

/// Runs the grid passes on the CPU. Strands or lights that give nothing leave a grid of
/// zeros; nothing here can produce NaN from finite input (empty cells, zero-length
/// segments and cells without light are skipped as the GPU skips them).
pub fn volume_grid(input: &VolumeInput<'_>) -> VolumeGridCpu {
    let p = input.params;
    let n = p.volume_grid.max(1) as usize;
    let segments = input.segments as usize;
    let strands = input.widths.len().min(input.colors.len());
    let per = segments + 1;
    let vertices: &[Vec4] = if segments > 0 {
        &input.vertices[..(strands * per).min(input.vertices.len())]
    } else {
        &[]
    };
    // Fit: a cube of n cells on the longest side, half a cell of margin.
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for v in vertices {
        let q = v.truncate().as_dvec3();
        lo = lo.min(q);
        hi = hi.max(q);
    }
    let mut centre = 0.5 * (lo + hi);
    let mut extent = (hi - lo).max_element();
    if vertices.is_empty() || !((0.0..1e30).contains(&extent) && centre.abs().max_element() < 1e30)
    {
        centre = DVec3::ZERO;
        extent = 1.0;
    }
    let cell = (extent / (n as f64 - 1.0)).max(1e-6);
    let origin = centre - DVec3::splat(0.5 * n as f64 * cell);
    let cells = n * n * n;
    let index = |c: IVec3| cell_index(c, n);
    let clamp_cell = |q: DVec3| {
        let c = ((q - origin) / cell).floor();
        IVec3::new(
            (c.x as i32).clamp(0, n as i32 - 1),
            (c.y as i32).clamp(0, n as i32 - 1),
            (c.z as i32).clamp(0, n as i32 - 1),
        )
    };
    // Splat.
    let mut depth = vec![0.0f64; cells];
    let mut tangent = vec![DVec3::ZERO; cells];
    let mut color = vec![DVec3::ZERO; cells];
    for s in 0..strands {
        let width = f64::from(input.widths[s]);
        let col = input.colors[s].as_dvec3().clamp(DVec3::ZERO, DVec3::ONE);
        for k in 0..segments {
            let a = vertices[s * per + k];
            let b = vertices[s * per + k + 1];
            let w = width * (1.0 + (f64::from(input.tip_width) - 1.0) * 0.5 * f64::from(a.w + b.w));
            let d = (b - a).truncate().as_dvec3();
            let len = d.length();
            if !(len > 0.0 && len < 1e30 && w > 0.0) {
                continue;
            }
            let mut t = d / len;
            let at = t.abs();
            let major = if at.x >= at.y && at.x >= at.z {
                t.x
            } else if at.y >= at.z {
                t.y
            } else {
                t.z
            };
            if major < 0.0 {
                t = -t;
            }
            let samples = (2.0 * len / cell).ceil().clamp(1.0, 4096.0) as usize;
            let amount = w * len * 0.25 * PI / (cell * cell) / samples as f64;
            for i in 0..samples {
                let f = (i as f64 + 0.5) / samples as f64;
                let q = a.truncate().as_dvec3() * (1.0 - f) + b.truncate().as_dvec3() * f;
                let c = index(clamp_cell(q));
                depth[c] += amount;
                tangent[c] += t * amount;
                color[c] += col * amount;
            }
        }
    }
    // The mesh: the area-weighted outward normal per cell over the cell's face area
    // (`splat_mesh`), and the share of each cell inside it (`occupy`).
    let mut surface = vec![DVec3::ZERO; cells];
    let mut mesh_albedo = DVec3::ZERO;
    if let Some(mesh) = input.mesh {
        // At most 1 (`pelage_scene::mesh_albedo`): a brighter body would make light
        // every step.
        mesh_albedo = pelage_scene::mesh_albedo(mesh.color).as_dvec3();
        splat_mesh(&mesh, origin, cell, n, &mut surface);
    }
    let solid = occupancy(&surface, n);
    // The fibre's energies, one table per absorption met.
    let fibre_of = |sigma_a: DVec3| ChiangFibre {
        sigma_a,
        beta_m: f64::from(p.beta_m),
        beta_n: f64::from(p.beta_n),
        alpha: f64::from(p.alpha_deg).to_radians(),
        eta: f64::from(p.eta),
    };
    let mut tables: HashMap<[u64; 3], EnergyTable> = HashMap::new();
    let mut sigma_key = |c: DVec3| -> [u64; 3] {
        let sigma = match p.absorption() {
            Absorption::Fixed(s) => s.as_dvec3(),
            Absorption::FromColor => sigma_a_from_reflectance(c, f64::from(p.beta_n)),
        };
        // The GPU computes sigma in f32.
        let sigma = sigma.as_vec3().as_dvec3();
        let key = [sigma.x.to_bits(), sigma.y.to_bits(), sigma.z.to_bits()];
        tables
            .entry(key)
            .or_insert_with(|| EnergyTable::new(&fibre_of(sigma)));
        key
    };
    // Medium.
    let mut medium_t = vec![DVec3::ZERO; cells];
    let mut medium_s = vec![0.0; cells];
    let mut keys = Vec::with_capacity(cells);
    for c in 0..cells {
        let (mut t, mut s, mut col) = (DVec3::Y, 0.0, DVec3::ONE);
        let tl = tangent[c].length();
        if depth[c] > 0.0 {
            s = (tl / depth[c]).clamp(0.0, 1.0);
            col = (color[c] / depth[c]).clamp(DVec3::ZERO, DVec3::ONE);
        }
        if tl > 0.0 {
            t = tangent[c] / tl;
        }
        medium_t[c] = t;
        medium_s[c] = s;
        keys.push(sigma_key(col));
    }
    let iso: Vec<Phase> = keys.iter().map(|k| tables[k].isotropic()).collect();
    // Inject: per cell and channel the energy born there and its flux (`state` until the
    // light born settles), and the sky's unscattered fluence.
    let mut state = vec![[DVec4::ZERO; 3]; cells];
    let mut sky_fluence = vec![DVec4::ZERO; cells];
    // `volume_clear_toward`: exp(-τ) times the body's clear share from where the ray
    // from `pos` toward `l` leaves its cell up to `reach` or the grid's border, each cell
    // crossed for the length of the ray in it (its clear share to that power).
    let clear_toward = |pos: DVec3, l: DVec3, reach: f64| {
        let mut tau = 0.0;
        let mut clear = 1.0;
        for (c, length) in ray_cells((pos - origin) / cell, l, reach / cell, n, false) {
            let j = index(c);
            tau += depth[j] * length;
            clear *= (1.0 - solid[j]).max(1e-30).powf(length);
        }
        (-tau).exp() * clear
    };
    // `volume_meet`: of light along `l` falling on a cell of optical depth `kappa`, the
    // share its fibres meet per unit irradiance (κ times the mean transmittance) and the
    // cell's mean transmittance from its face.
    let meet_of = |kappa: f64, l: DVec3| {
        let mean = cell_transmittance(kappa, l);
        (kappa * mean, mean)
    };
    let ambient = f64::from(input.ambient);
    // `u.light_fibres`: 0 where dual scattering carries the lights' scattering.
    let light_fibres = if p.multiple_scattering.grid_carries_lights() {
        1.0
    } else {
        0.0
    };
    for c in 0..cells {
        let kappa = depth[c];
        let lit_mesh = surface[c].length();
        let xyz = IVec3::new((c % n) as i32, ((c / n) % n) as i32, (c / (n * n)) as i32);
        // The marches start from the centroid of the cell's clear part: half the solid
        // share of a cell edge from the centre, away from the body (`inject`).
        let away = if lit_mesh > 0.0 {
            surface[c] / lit_mesh
        } else {
            DVec3::ZERO
        };
        let pos = origin + (xyz.as_dvec3() + 0.5 + away * (0.5 * solid[c])) * cell;
        let (t, s) = (medium_t[c], medium_s[c]);
        let table = &tables[&keys[c]];
        // The sky (`inject`'s second half): SKY_DIRECTIONS directional lights of
        // irradiance 4 ambient / SKY_DIRECTIONS (radiance ambient / π over 4π / K sr
        // each); what arrives unscattered the fibres meet and scatter (A_iso, g_iso) and
        // the body reflects, and, times the cell's mean transmittance along each
        // direction, it is the cell's fluence.
        let mut sky = DVec4::ZERO;
        if ambient > 0.0 {
            let irradiance = ambient * 4.0 / SKY_DIRECTIONS as f64;
            let mut lit = 0.0;
            let (mut met, mut met_flux) = (0.0, DVec3::ZERO);
            for k in 0..SKY_DIRECTIONS {
                let l = sky_direction(k);
                let seen = irradiance * clear_toward(pos, l, 4.0 * n as f64 * cell);
                let (meet, mean) = meet_of(kappa, l);
                met += seen * meet;
                met_flux -= seen * meet * l;
                let f = -seen * mean * l;
                sky += DVec4::new(seen * mean, f.x, f.y, f.z);
                lit += seen * surface[c].dot(l).max(0.0);
            }
            // Scattered by the cell's fibres as `propagate` scatters what arrives.
            for (ch, out) in state[c].iter_mut().enumerate() {
                let a = iso[c].albedo[ch];
                let f = a * scatter_direction(met_flux, t, s, iso[c].g[ch], iso[c].g[ch]);
                *out += DVec4::new(a * met, f.x, f.y, f.z);
            }
            if lit_mesh > 0.0 {
                let bounce = lit * (-kappa).exp() * mesh_albedo;
                let d = (2.0 / 3.0) * surface[c] / lit_mesh;
                for ch in 0..3 {
                    let f = bounce[ch] * d;
                    state[c][ch] += DVec4::new(bounce[ch], f.x, f.y, f.z);
                }
            }
        }
        // The fluence is the mean over the whole cell (`settle` divides by the clear
        // share): the sky's light is only in the clear share.
        sky_fluence[c] = sky * (1.0 - solid[c]);
        if (kappa <= 0.0 || light_fibres == 0.0) && lit_mesh <= 0.0 {
            continue;
        }
        for light in input.lights.iter().take(pelage_scene::MAX_LIGHTS) {
            let (l, irradiance, reach) = match light {
                Light::Directional(d) => (
                    (-d.direction.as_dvec3()).normalize(),
                    (d.color * d.intensity).as_dvec3(),
                    f64::INFINITY,
                ),
                Light::Point(pt) => {
                    let to = pt.position.as_dvec3() - pos;
                    let len = to.length();
                    let l = if len < 1e-6 { DVec3::Y } else { to / len };
                    (
                        l,
                        (pt.color * pt.intensity).as_dvec3() / to.length_squared().max(1e-4),
                        len,
                    )
                }
            };
            let seen = clear_toward(pos, l, reach.min(4.0 * n as f64 * cell));
            let theta = t.dot(l).abs().min(1.0).asin();
            let aligned = table.at(theta);
            let albedo = s * aligned.albedo + (1.0 - s) * iso[c].albedo;
            let scattered = irradiance * (seen * meet_of(kappa, l).0 * light_fibres) * albedo;
            for ch in 0..3 {
                let dir = scatter_direction(-l, t, s, aligned.g[ch], iso[c].g[ch]);
                let f = scattered[ch] * dir;
                state[c][ch] += DVec4::new(scattered[ch], f.x, f.y, f.z);
            }
            if lit_mesh > 0.0 {
                let bounce =
                    irradiance * (seen * (-kappa).exp() * surface[c].dot(l).max(0.0)) * mesh_albedo;
                let d = (2.0 / 3.0) * surface[c] / lit_mesh;
                for ch in 0..3 {
                    let f = bounce[ch] * d;
                    state[c][ch] += DVec4::new(bounce[ch], f.x, f.y, f.z);
                }
            }
        }
    }
    // The light born settles in its cell and leaves along the six directions.
    let mut fluence = vec![[DVec4::ZERO; 3]; cells];
    let mut leaving = vec![[[0.0f64; 6]; 3]; cells];
    for c in 0..cells {
        for ch in 0..3 {
            let b = state[c][ch];
            let (e, f, path) = born(b.x, DVec3::new(b.y, b.z, b.w), depth[c], iso[c].albedo[ch]);
            leaving[c][ch] = directions(e, f);
            fluence[c][ch] = path * DVec4::new(e, f.x, f.y, f.z) + sky_fluence[c];
        }
    }
    let mut state = leaving;
    let energy = |st: &[[[f64; 6]; 3]]| st.iter().flatten().flatten().sum::<f64>();
    let mut step_energy = vec![energy(&state)];
    let mut step_arrivals = Vec::new();
    // Propagate: light moves one cell per step along its direction, `spread` of it to
    // each diagonal neighbour ahead, crossing `step_path` cell edges.
    let (spread, step_path) = cone_moments();
    let sent = |state: &[[[f64; 6]; 3]], y: IVec3, ch: usize, k: usize| {
        if y.min_element() < 0 || y.max_element() >= n as i32 {
            0.0
        } else {
            state[index(y)][ch][k]
        }
    };
    for _ in 0..p.volume_iterations {
        let mut next = vec![[[0.0f64; 6]; 3]; cells];
        let mut arrived_total = 0.0;
        for c in 0..cells {
            let xyz = IVec3::new((c % n) as i32, ((c / n) % n) as i32, (c / (n * n)) as i32);
            // Per channel, what arrives along each direction from the neighbour behind
            // and, `spread` each, the four beside that one.
            let mut arrive = [[0.0f64; 6]; 3];
            for (k, d) in FACES.iter().enumerate() {
                let behind = xyz - *d;
                for (ch, a) in arrive.iter_mut().enumerate() {
                    let mut aside = 0.0;
                    for e in FACES.iter().filter(|e| e.dot(*d) == 0) {
                        aside += sent(&state, behind + *e, ch, k);
                    }
                    a[k] = (1.0 - 4.0 * spread) * sent(&state, behind, ch, k) + spread * aside;
                }
            }
            let kappa = depth[c];
            let keep = (-kappa * step_path).exp();
            let clear = 1.0 - solid[c];
            let (t, s) = (medium_t[c], medium_s[c]);
            // The mean path in the cell of the light arriving, (1 - keep) / κ.
            let p_cross = if kappa > 0.0 {
                -(-kappa * step_path).exp_m1() / kappa
            } else {
                step_path
            };
            let flows: [DVec3; 3] = std::array::from_fn(|ch| {
                FACES
                    .iter()
                    .zip(arrive[ch])
                    .map(|(d, a)| a * d.as_dvec3())
                    .sum()
            });
            // The body reflects toward its normal, or (inside it) back the way the light
            // came, all channels together.
            let sl = surface[c].length();
            let back: DVec3 = flows.iter().sum();
            let normal = if sl > 0.0 {
                surface[c] / sl
            } else if back.length() > 0.0 {
                -back / back.length()
            } else {
                DVec3::ZERO
            };
            for ch in 0..3 {
                let arrived: f64 = arrive[ch].iter().sum();
                arrived_total += arrived;
                let flow = flows[ch];
                let scatter = (1.0 - keep) * clear * iso[c].albedo[ch];
                let mut e = scatter * arrived;
                let mut f = scatter * scatter_direction(flow, t, s, iso[c].g[ch], iso[c].g[ch]);
                if solid[c] > 0.0 {
                    let bounce = solid[c] * arrived * mesh_albedo[ch];
                    e += bounce;
                    f += bounce * (2.0 / 3.0) * normal;
                }
                let (e, f, path) = born(e, f, kappa, iso[c].albedo[ch]);
                let out = directions(e, f);
                for k in 0..6 {
                    next[c][ch][k] = out[k] + keep * clear * arrive[ch][k];
                }
                fluence[c][ch] += p_cross * clear * DVec4::new(arrived, flow.x, flow.y, flow.z)
                    + path * DVec4::new(e, f.x, f.y, f.z);
            }
        }
        state = next;
        step_energy.push(energy(&state));
        step_arrivals.push(arrived_total);
    }
    let fluence = settle(&fluence, &solid, n);
    let sky = settle(
        &sky_fluence.iter().map(|&v| [v; 3]).collect::<Vec<_>>(),
        &solid,
        n,
    )
    .into_iter()
    .map(|v| v[0])
    .collect();
    VolumeGridCpu {
        resolution: n as u32,
        origin,
        cell,
        depth,
        solid,
        fluence,
        sky,
        step_energy,
        step_arrivals,
    }
}

/// `settle`: per cell, `values` over the clear share where the body fills part of it; a
/// cell at least half solid takes its clear neighbours' (weighted by their shares).
fn settle(values: &[[DVec4; 3]], solid: &[f64], n: usize) -> Vec<[DVec4; 3]> {
    let index = |c: IVec3| cell_index(c, n);
    let mut out = values.to_vec();
    for (c, value) in out.iter_mut().enumerate() {
        let s = solid[c];
        if s >= 0.5 {
            let xyz = IVec3::new((c % n) as i32, ((c / n) % n) as i32, (c / (n * n)) as i32);
            let mut w = 0.0;
            let mut sum = [DVec4::ZERO; 3];
            for d in FACES {
                let y = xyz + d;
                if y.min_element() < 0 || y.max_element() >= n as i32 {
                    continue;
                }
                let j = index(y);
                let clear = 1.0 - solid[j];
                if clear > 0.5 {
                    w += clear;
                    for ch in 0..3 {
                        sum[ch] += values[j][ch];
                    }
                }
            }
            let k = if w > 0.0 { 1.0 / w } else { 0.0 };
            *value = sum.map(|v| v * k);
        } else if s > 0.0 {
            *value = values[c].map(|v| v / (1.0 - s));
        }
    }
    out
}

/// `splat_mesh`: each triangle sampled at the centroids of its `m²` sub-triangles (`m`:
/// its longest edge over half a cell, at most 64), each adding its share of the area
/// times the outward normal (oriented as the vertex normals) over the cell's face area;
/// samples outside the grid are dropped.
fn splat_mesh(mesh: &VolumeMesh<'_>, origin: DVec3, cell: f64, n: usize, surface: &mut [DVec3]) {
    let vertex = |k: u32, of: &[Vec3]| of.get(k as usize).map(|v| v.as_dvec3());
    for tri in mesh.indices.chunks_exact(3) {
        let (Some(a), Some(b), Some(c)) = (
            vertex(tri[0], mesh.positions),
            vertex(tri[1], mesh.positions),
            vertex(tri[2], mesh.positions),
        ) else {
            continue;
        };
        let outward = [tri[0], tri[1], tri[2]]
            .iter()
            .filter_map(|&k| vertex(k, mesh.normals))
            .sum::<DVec3>();
        let (e1, e2) = (b - a, c - a);
        let mut an = 0.5 * e1.cross(e2);
        if an.dot(outward) < 0.0 {
            an = -an;
        }
        let longest = e1.length().max(e2.length()).max((e2 - e1).length());
        if !(longest < 1e30 && an.length() > 0.0) {
            continue;
        }
        let m = (2.0 * longest / cell).ceil().clamp(1.0, 64.0) as usize;
        let per = an / (cell * cell * (m * m) as f64);
        for i in 0..m {
            for j in 0..m - i {
                for (flip, off) in [(false, 1.0 / 3.0), (true, 2.0 / 3.0)] {
                    if flip && i + j + 1 >= m {
                        continue;
                    }
                    let p =
                        a + e1 * ((i as f64 + off) / m as f64) + e2 * ((j as f64 + off) / m as f64);
                    let q = (p - origin) / cell;
                    if q.min_element() < 0.0 || q.max_element() >= n as f64 {
                        continue;
                    }
                    let c = q.floor().as_ivec3();
                    surface[cell_index(c, n)] += per;
                }
            }
        }
    }
}

/// `occupy`: the share of each cell inside the mesh from the normals alone (the inside
/// indicator rises by `-n` per cell face area along a row): per axis the sum of `-n`
/// over the cells before plus half of the cell's own from the low end, of `+n` from the
/// high end, the larger clamped to [0, 1]; the median of the three axes.
fn occupancy(surface: &[DVec3], n: usize) -> Vec<f64> {
    let index = |c: [usize; 3]| (c[2] * n + c[1]) * n + c[0];
    (0..surface.len())
        .map(|i| {
            let c = [i % n, (i / n) % n, i / (n * n)];
            let own = surface[i];
            let mut axes = [0.0; 3];
            for (axis, out) in axes.iter_mut().enumerate() {
                let (mut low, mut high) = (-0.5 * own[axis], 0.5 * own[axis]);
                for k in 0..n {
                    if k == c[axis] {
                        continue;
                    }
                    let mut y = c;
                    y[axis] = k;
                    let s = surface[index(y)][axis];
                    if k < c[axis] {
                        low -= s;
                    } else {
                        high += s;
                    }
                }
                *out = low.max(high).clamp(0.0, 1.0);
            }
            let [x, y, z] = axes;
            x.min(y).max(x.max(y).min(z))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid's optical depth along a ray is the depth per edge times the way to the
    /// border, in cells: along an axis, a diagonal and an oblique direction through a
    /// uniform grid (against the distance to the cube's border, worked out apart), with
    /// one cell emptied on the axis's way; 0 from outside.
    #[test]
    fn optical_depth_toward_is_the_depth_times_the_way_out() {
        let n = 8u32;
        let mut grid = VolumeGridCpu {
            resolution: n,
            origin: DVec3::splat(-1.0),
            cell: 0.25,
            depth: vec![0.5; (n * n * n) as usize],
            solid: Vec::new(),
            fluence: Vec::new(),
            sky: Vec::new(),
            step_energy: Vec::new(),
            step_arrivals: Vec::new(),
        };
        let p = DVec3::new(0.1, -0.05, 0.2);
        for d in [
            DVec3::X,
            DVec3::NEG_Y,
            DVec3::ONE.normalize(),
            DVec3::new(0.3, -0.8, 0.52).normalize(),
        ] {
            // The way to the cube [-1, 1]^3's border, by the slab method.
            let way = (0..3)
                .map(|a| {
                    if d[a] > 0.0 {
                        (1.0 - p[a]) / d[a]
                    } else if d[a] < 0.0 {
                        (-1.0 - p[a]) / d[a]
                    } else {
                        f64::INFINITY
                    }
                })
                .fold(f64::INFINITY, f64::min);
            let tau = grid.optical_depth_toward(p, d);
            assert!(
                (tau - 0.5 * way / 0.25).abs() < 1e-9,
                "{d}: {tau} against {}",
                0.5 * way / 0.25
            );
        }
        // Emptying the cell next along +x takes one cell edge's depth off.
        let before = grid.optical_depth_toward(p, DVec3::X);
        grid.depth[((4 * n + 3) * n + 5) as usize] = 0.0;
        let after = grid.optical_depth_toward(p, DVec3::X);
        assert!((before - after - 0.5).abs() < 1e-9, "{before} {after}");
        assert_eq!(grid.optical_depth_toward(DVec3::splat(2.0), DVec3::X), 0.0);
    }

    /// The cell's mean transmittance from its face against the mean over random points of
    /// the cube (each point's own way out along `l`, no formula shared), for axis,
    /// diagonal, the sky's and random directions and optical depths on both sides of the
    /// closed form's branch; the mean chord it replaced is off by more than the Monte
    /// Carlo's error on the diagonal, so the comparison can tell them apart.
    #[test]
    fn cell_transmittance_is_the_cube_mean() {
        let mut rng = crate::path_tracer::Pcg32::new(7, 1);
        let mut dirs = vec![DVec3::X, DVec3::NEG_Y, DVec3::ONE.normalize()];
        dirs.extend((0..SKY_DIRECTIONS).map(sky_direction));
        for _ in 0..4 {
            let v = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) - 0.5;
            dirs.push(v.normalize());
        }
        let points: Vec<DVec3> = (0..100_000)
            .map(|_| DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()))
            .collect();
        let mut worst: f64 = 0.0;
        for l in &dirs {
            for kappa in [0.0, 0.01, 0.5, 2.0, 3.9, 4.1, 8.0, 30.0] {
                let mc = points
                    .iter()
                    .map(|u| {
                        // The way to the face each axis leaves by, the nearest of the three.
                        let s = (0..3)
                            .filter(|&a| l[a].abs() > 1e-12)
                            .map(|a| {
                                let to_face = if l[a] > 0.0 { 1.0 - u[a] } else { u[a] };
                                to_face / l[a].abs()
                            })
                            .fold(f64::INFINITY, f64::min);
                        (-kappa * s).exp()
                    })
                    .sum::<f64>()
                    / points.len() as f64;
                let mean = cell_transmittance(kappa, *l);
                worst = worst.max((mean - mc).abs());
                assert!(
                    (mean - mc).abs() < 3e-3,
                    "kappa {kappa}, l {l}: {mean} against the points' {mc}"
                );
            }
        }
        println!("cell transmittance: largest difference from 100 000 points {worst:.2e}");
        // Along an axis every chord is one edge: the edge's own mean.
        for kappa in [0.3, 2.0, 9.0] {
            assert!((cell_transmittance(kappa, DVec3::Z) - escape(kappa).0).abs() < 1e-9);
        }
        // The mean chord 1 / |l|₁ on the diagonal at κ = 2 (what volume_meet used before).
        let diagonal = DVec3::ONE.normalize();
        let chord = escape(2.0 / 3f64.sqrt()).0;
        assert!(chord / cell_transmittance(2.0, diagonal) > 1.08);
        // The two branches meet at κT = 4.
        let t = 1.0 / diagonal.max_element();
        let (below, above) = (4.0 / t - 1e-9, 4.0 / t + 1e-9);
        assert!(
            (cell_transmittance(below, diagonal) - cell_transmittance(above, diagonal)).abs()
                < 1e-7
        );
    }

    /// The value of `const NAME: f32 = value;` in the volume method's WGSL.
    fn wgsl_constant(name: &str) -> f64 {
        let source = include_str!("../../pelage-shade/wgsl/shade/models/volume_common.wgsl");
        let line = source
            .lines()
            .find(|l| l.starts_with(&format!("const {name}: f32 = ")))
            .unwrap_or_else(|| panic!("{name} not in volume_common.wgsl"));
        line.split('=')
            .nth(1)
            .unwrap()
            .trim()
            .trim_end_matches(';')
            .parse()
            .unwrap()
    }

    /// The spread and step path the GPU is compiled with are the cone's, as integrated
    /// here (a change to either side shows).
    #[test]
    fn cone_moments_are_the_shaders_constants() {
        let (spread, path) = cone_moments();
        println!("cone: spread {spread:.5}, step path {path:.5}");
        assert!(
            (spread - wgsl_constant("VOLUME_SPREAD")).abs() < 5e-5,
            "{spread}"
        );
        assert!(
            (path - wgsl_constant("VOLUME_STEP_PATH")).abs() < 5e-5,
            "{path}"
        );
    }

    /// A ray's cells: along an axis from a cell centre, every cell ahead once for a whole
    /// edge; along a diagonal, lengths that sum to the distance from the first cell's
    /// corner to the limit.
    #[test]
    fn ray_cells_cross_whole_cells() {
        let along = ray_cells(DVec3::new(1.5, 1.5, 1.5), DVec3::X, 100.0, 5, false);
        assert_eq!(along.len(), 3);
        assert!(
            along
                .iter()
                .all(|&(c, l)| c.y == 1 && c.z == 1 && (l - 1.0).abs() < 1e-12)
        );
        let d = DVec3::ONE.normalize();
        let diagonal = ray_cells(DVec3::splat(0.5), d, 3.0, 8, false);
        let total: f64 = diagonal.iter().map(|&(_, l)| l).sum();
        assert!((total - (3.0 - 0.5 * 3f64.sqrt())).abs() < 1e-12, "{total}");
        assert!(ray_cells(DVec3::splat(0.5), d, 0.5, 8, false).is_empty());
    }
}
