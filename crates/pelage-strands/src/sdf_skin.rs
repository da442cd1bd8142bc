//! A skinned body's distance field without a rebuild every frame: the field is built
//! once in the bind pose, and the simulation reads it through the inverse of the skin
//! (`wgsl/strands/sdf_skin.wgsl` blends the joint matrices at a lattice of points every
//! frame; `simulate.wgsl` inverts that blend at each vertex).

use encase::ShaderType;
use glam::{UVec3, UVec4, Vec3, Vec4};
use pelage_gpu::{
    BindLayout, Gpu, GpuTimer, PassInfo, compute_pipeline_with_constants, dispatch_size,
    storage_buffer, wgpu, zeroed_storage,
};
use pelage_scene::{Mesh, SdfGrid, Skin};

use crate::sdf::{copy_rows, extent, texture_3d};
use crate::simulate::closest_on_triangle;

/// Workgroup size of `sdf_skin.wgsl`.
const WORKGROUP: u32 = 64;

/// The timestamp label of the lattice's pass.
pub const SDF_SKIN_LABEL: &str = "strands: sdf skin";

/// The frame resource of the lattice of blended joint matrices (a 3D `rgba32float`
/// texture, three texels per point).
pub const SDF_SKIN: &str = "strands.sdf_skin";

/// Lattice cells around each triangle's box within which [`lattice_skin`] finds the
/// nearest triangle exactly.
pub(crate) const EXACT_CELLS: u32 = 2;

/// The least cell of the skin's lattice, in cells of the body's field.
pub const SKIN_LATTICE_MIN_CELLS: f32 = 2.0;

/// The mean edge of `triangles` of `mesh` (0 when none has finite corners).
fn mean_edge(mesh: &Mesh, triangles: &[u32]) -> f32 {
    let (mut sum, mut count) = (0.0f64, 0u32);
    for &t in triangles {
        let i = 3 * t as usize;
        let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[mesh.indices[i + k] as usize]);
        let edges = [a.distance(b), b.distance(c), c.distance(a)];
        if edges.iter().all(|e| e.is_finite()) {
            sum += edges.iter().map(|&e| f64::from(e)).sum::<f64>();
            count += 3;
        }
    }
    if count == 0 {
        0.0
    } else {
        (sum / f64::from(count)) as f32
    }
}

/// The skin's lattice over a field on `grid` of the body `triangles` of `bind`: the same
/// origin, its cell the larger of [`SKIN_LATTICE_MIN_CELLS`] field cells and the body's
/// mean edge, enough points to cover every node of the field. Skin weights belong to
/// vertices and are interpolated across each triangle, so they change on the scale of
/// an edge, and a much finer lattice buys little for its cost. Measured on the creature
/// (mean edge 0.080; `cargo test -p pelage-strands --test sdf skinned_creature`): with
/// the field at 128, a lattice of every 2nd node (107 250 points) leaves 0.24% of the
/// fur's vertices deeper than half a width, the mean edge's (9 240 points) 0.30%; at 64,
/// every 2nd node (cell 0.071) 1.32%, the mean edge's 1.35%, every 4th node (0.14)
/// 1.92% (all without the collision step's standoff, `DynamicsParams::sdf_standoff` 0).
pub(crate) fn skin_lattice(grid: &SdfGrid, bind: &Mesh, triangles: &[u32]) -> SdfGrid {
    let cell = (SKIN_LATTICE_MIN_CELLS * grid.cell).max(mean_edge(bind, triangles));
    let extent = (grid.dims - UVec3::ONE).as_vec3() * grid.cell;
    SdfGrid {
        origin: grid.origin,
        cell,
        dims: ((extent / cell).ceil().as_uvec3() + UVec3::ONE).max(UVec3::splat(2)),
    }
}

/// One lattice point's skin as `sdf_skin.wgsl` reads it (`PointSkin` there): the
/// joints and weights of the body's surface point nearest to it.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub(crate) struct PointSkin {
    /// Four joint indices (a slot of weight 0 may name any joint).
    joints: UVec4,
    /// Their weights, summing to 1.
    weights: Vec4,
}

/// The skin of every point of `lattice` (in [`SdfGrid::index`] order): the weights of
/// the point of `triangles` (of the bind pose `bind`) nearest to it, the barycentric
/// blend of its corners' normalised weights, the four heaviest joints kept and
/// renormalised. Triangles with a non-finite corner are skipped; with none left, every
/// point takes joint 0.
///
/// The nearest triangle is exact for the points within [`EXACT_CELLS`] lattice cells of
/// a triangle's box (each triangle offers itself to those: every corner of a cell that a
/// point near the surface lies in); sweeps along each axis of the lattice,
/// both ways, hand every other point its neighbour's nearest triangle when that one is
/// nearer (vector propagation, as the field's far nodes are found): about the points
/// times six distance tests, and what is far from the body, where a weight moves no
/// surface, may take a triangle slightly farther than the nearest.
pub(crate) fn lattice_skin(
    bind: &Mesh,
    skin: &Skin,
    triangles: &[u32],
    lattice: &SdfGrid,
) -> Vec<PointSkin> {
    let weights = skin.normalized_weights();
    let corners = |t: u32| {
        let i = 3 * t as usize;
        [0, 1, 2].map(|k| bind.indices[i + k] as usize)
    };
    let positions = |t: u32| corners(t).map(|v| bind.positions[v]);
    let fallback = PointSkin {
        joints: UVec4::ZERO,
        weights: Vec4::X,
    };
    let dims = lattice.dims;
    let distance = |i: UVec3, t: u32| {
        let p = lattice.node(i);
        let [a, b, c] = positions(t);
        let (u, v, w) = closest_on_triangle(p, a, b, c);
        p.distance(a * u + b * v + c * w)
    };
    // The nearest triangle of each point so far and its distance.
    let mut best: Vec<(u32, f32)> = vec![(u32::MAX, f32::INFINITY); lattice.nodes()];
    let top = (dims - UVec3::ONE).as_vec3();
    for &t in triangles {
        let [a, b, c] = positions(t);
        if !(a.is_finite() && b.is_finite() && c.is_finite()) {
            continue;
        }
        let cell = |p: Vec3| ((p - lattice.origin) / lattice.cell).clamp(Vec3::ZERO, top);
        let margin = Vec3::splat(EXACT_CELLS as f32);
        let lo = (cell(a.min(b).min(c)).floor() - margin)
            .max(Vec3::ZERO)
            .as_uvec3();
        let hi = (cell(a.max(b).max(c)).ceil() + margin).min(top).as_uvec3();
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    let i = UVec3::new(x, y, z);
                    let d = distance(i, t);
                    let slot = &mut best[lattice.index(i)];
                    if d < slot.1 {
                        *slot = (t, d);
                    }
                }
            }
        }
    }
    // Sweeps: along x, y and z, each forward then back, a point takes the triangle its
    // neighbour behind it holds when that is nearer to it.
    for axis in 0..3 {
        let step = UVec3::AXES[axis];
        let n = dims[axis];
        for backward in [false, true] {
            for i in 0..lattice.nodes() {
                let at = lattice.node_of(i);
                if at[axis] == 0 {
                    // Walk the line from this end.
                    for k in 1..n {
                        let (from, to) = if backward {
                            (at + step * (n - k), at + step * (n - 1 - k))
                        } else {
                            (at + step * (k - 1), at + step * k)
                        };
                        let (t, _) = best[lattice.index(from)];
                        if t == u32::MAX {
                            continue;
                        }
                        let d = distance(to, t);
                        let slot = &mut best[lattice.index(to)];
                        if d < slot.1 {
                            *slot = (t, d);
                        }
                    }
                }
            }
        }
    }
    best.iter()
        .enumerate()
        .map(|(i, &(t, _))| {
            if t == u32::MAX {
                return fallback;
            }
            let [a, b, c] = positions(t);
            let (u, v, w) = closest_on_triangle(lattice.node(lattice.node_of(i)), a, b, c);
            let mut blend: Vec<(u32, f32)> = Vec::with_capacity(12);
            for (&vertex, share) in corners(t).iter().zip([u, v, w]) {
                for (&j, &wj) in skin.joints[vertex].iter().zip(&weights[vertex]) {
                    let add = share * wj;
                    if add <= 0.0 {
                        continue;
                    }
                    match blend.iter_mut().find(|(k, _)| *k == j) {
                        Some((_, total)) => *total += add,
                        None => blend.push((j, add)),
                    }
                }
            }
            // The four heaviest (ties: the lower joint), renormalised.
            blend.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            blend.truncate(4);
            let sum: f32 = blend.iter().map(|(_, w)| w).sum();
            if sum <= 0.0 {
                return fallback;
            }
            let mut out = PointSkin {
                joints: UVec4::ZERO,
                weights: Vec4::ZERO,
            };
            for (k, (j, w)) in blend.into_iter().enumerate() {
                out.joints[k] = j;
                out.weights[k] = w / sum;
            }
            out
        })
        .collect()
}

/// The skin of a body's distance field built once in the bind pose: every frame one
/// compute pass ([`SDF_SKIN_LABEL`]) blends the frame's joint matrices with the weights
/// of each point of a lattice over the field's box (its cell the larger of
/// [`SKIN_LATTICE_MIN_CELLS`] field cells and the body's mean edge; the weights of the
/// body's surface point nearest each point, exact within two lattice cells of the
/// surface, handed on by sweeps along the lattice's lines beyond), and a copy puts the
/// blended matrices in a 3D `rgba32float` texture (three texels a point: the rows of the
/// 3x4 affine map).
///
/// The simulation (`simulate.wgsl`, `SDF_SKIN` on) interpolates them trilinearly at a
/// bind-pose point `q` into `A(q)` and solves `A(q) q = p` for a vertex at `p` by Newton
/// steps, once per vertex and substep before its collision rounds (a strand's first
/// vertex from where it settled the substep before, or from `p` itself; each later one
/// from where the vertex before it settled, moved to first order); the rounds take that
/// answer to first order and read the bind-pose field at `q`. The skinned surface is
/// where the bind surface's points go, so the field's zero is the skinned surface's, to
/// the lattice's interpolation of the weights (and to the bend of a skinned triangle,
/// which the mesh draws flat), and no field is rebuilt per frame. Gradients come back through the
/// inverse of the map's Jacobian, transposed, and distances scale by how the map
/// stretches lengths along the gradient (1 where the rig is rigid).
///
/// Where the Newton steps do not settle (a blend folded over itself, past what linear
/// blend skinning keeps one-to-one), the sample reads "far outside": that vertex does
/// not collide with the field in that step.
#[derive(Debug)]
pub struct SdfSkin {
    lattice: SdfGrid,
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    /// The pass's output, rows of `pitch` texels, copied into `texture`.
    rows: wgpu::Buffer,
    pitch: u32,
    /// The texture the simulation reads (held: `view` is of it).
    _texture: wgpu::Texture,
    view: wgpu::TextureView,
    limits: wgpu::Limits,
}

impl SdfSkin {
    /// The lattice over `field` (a field of `bind`, built in that pose), the weights of
    /// its points from `skin` over `triangles` of `bind` (those the field was built
    /// from), blending the matrices `joint_matrices` holds when it runs
    /// ([`crate::MeshSkin::joint_matrices`]). Refused: a bind pose that is not a valid
    /// mesh, a skin that does not fit it (naming `skin.*`), a triangle index past it
    /// (`triangles`), a lattice wider than the device's `max_texture_dimension_3d`
    /// allows (three texels a point; `dynamics.sdf_resolution`).
    pub fn new(
        gpu: &Gpu,
        bind: &Mesh,
        skin: &Skin,
        triangles: &[u32],
        field: &SdfGrid,
        joint_matrices: &wgpu::Buffer,
    ) -> crate::Result<Self> {
        bind.validate()?;
        skin.validate(bind.positions.len())?;
        let triangle_count = bind.indices.len() / 3;
        if let Some(&t) = triangles.iter().find(|&&t| t as usize >= triangle_count) {
            return Err(pelage_scene::ParamError::new(
                "triangles",
                t,
                &format!("must name triangles of the bind pose (it has {triangle_count})"),
            )
            .into());
        }
        let lattice = skin_lattice(field, bind, triangles);
        let max = gpu.limits().max_texture_dimension_3d;
        if 3 * lattice.dims.x > max || lattice.dims.max_element() > max {
            return Err(pelage_scene::ParamError::new(
                "dynamics.sdf_resolution",
                field.dims.max_element(),
                &format!(
                    "makes a skin lattice of {} points, three texels each, past this \
                     device's max_texture_dimension_3d ({max})",
                    lattice.dims
                ),
            )
            .into());
        }
        let points = lattice_skin(bind, skin, triangles, &lattice);
        let storage = wgpu::BufferUsages::STORAGE;
        let point_skins = storage_buffer(gpu, "pelage sdf skin points", &points, storage)?;
        pelage_gpu::audit::constant(&[&point_skins]);
        // Rows of 256 bytes (16 texels) for the copy into the texture.
        let pitch = (3 * lattice.dims.x).next_multiple_of(16);
        let bytes = u64::from(pitch) * u64::from(lattice.dims.y) * u64::from(lattice.dims.z) * 16;
        let rows = zeroed_storage(
            gpu,
            "pelage sdf skin rows",
            bytes,
            storage | wgpu::BufferUsages::COPY_SRC,
        )?;
        pelage_gpu::audit::name_buffer(&rows, SDF_SKIN);
        let module = crate::SHADERS
            .library()
            .module(gpu, "strands/sdf_skin.wgsl")?;
        let constants = [
            ("DIMS_X", f64::from(lattice.dims.x)),
            ("DIMS_Y", f64::from(lattice.dims.y)),
            ("DIMS_Z", f64::from(lattice.dims.z)),
            ("PITCH", f64::from(pitch)),
            ("JOINTS", f64::from(skin.joint_count)),
        ];
        let (texture, view, pipeline, bind_group) = gpu.scoped(|device| {
            let (texture, view) = texture_3d(
                device,
                "pelage sdf skin lattice",
                extent(UVec3::new(
                    3 * lattice.dims.x,
                    lattice.dims.y,
                    lattice.dims.z,
                )),
                wgpu::TextureFormat::Rgba32Float,
            );
            pelage_gpu::audit::name_view(&view, SDF_SKIN);
            let layout = BindLayout::new(SDF_SKIN_LABEL, wgpu::ShaderStages::COMPUTE)
                .storage(0)
                .storage(1)
                .storage_rw(2)
                .build(device);
            let pipeline = compute_pipeline_with_constants(
                device,
                SDF_SKIN_LABEL,
                &module,
                "main",
                &[Some(&layout)],
                &constants,
            );
            let bind_group = pelage_gpu::bind_buffers(
                device,
                SDF_SKIN_LABEL,
                &layout,
                &[&point_skins, joint_matrices, &rows],
            );
            (texture, view, pipeline, bind_group)
        })?;
        Ok(Self {
            lattice,
            pipeline,
            bind_group,
            rows,
            pitch,
            _texture: texture,
            view,
            limits: gpu.limits().clone(),
        })
    }

    /// Records the pass (the joint matrices as they are when it runs) and the copy into
    /// the texture. Record it after the joint matrices are written and before the
    /// simulation.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        let timestamp_writes = timer.and_then(|t| t.compute_pass(SDF_SKIN_LABEL));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(SDF_SKIN_LABEL),
            timestamp_writes,
        });
        pass.set_pipeline(&self.pipeline);
        pelage_gpu::set_bind_group(&mut pass, 0, &self.bind_group);
        let groups = dispatch_size(&self.limits, self.lattice.nodes() as u64, WORKGROUP);
        pass.dispatch_workgroups(groups.0, groups.1, 1);
        drop(pass);
        let dims = self.lattice.dims;
        copy_rows(
            encoder,
            &self.rows,
            self.pitch * 16,
            &self._texture,
            extent(UVec3::new(3 * dims.x, dims.y, dims.z)),
        );
    }

    /// The pass [`SdfSkin::encode`] records: it writes [`SDF_SKIN`] (the joint matrices
    /// it reads are the caller's, written outside the frame's passes).
    pub fn pass(&self) -> PassInfo {
        PassInfo::new(SDF_SKIN_LABEL).writes([SDF_SKIN])
    }

    /// The lattice.
    pub fn lattice(&self) -> &SdfGrid {
        &self.lattice
    }

    /// The blended matrices (`texture_3d<f32>`, `rgba32float`; point `(i, j, k)`'s rows
    /// at texels `(3i, j, k)` to `(3i + 2, j, k)`).
    pub fn view(&self) -> &wgpu::TextureView {
        &self.view
    }

    /// The blended matrices of the last frame run, three rows a point in
    /// [`SdfGrid::index`] order. Waits for the GPU: for tests and tools.
    pub fn read(&self, gpu: &Gpu) -> crate::Result<Vec<[Vec4; 3]>> {
        let bytes = pelage_gpu::read_buffer(gpu, &self.rows)?;
        let floats: Vec<f32> = bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        let texel = |x: u32, y: u32, z: u32| {
            let i = 4 * ((z * self.lattice.dims.y + y) * self.pitch + x) as usize;
            Vec4::from_slice(&floats[i..i + 4])
        };
        Ok((0..self.lattice.nodes())
            .map(|i| {
                let n = self.lattice.node_of(i);
                [0, 1, 2].map(|r| texel(3 * n.x + r, n.y, n.z))
            })
            .collect())
    }

    /// Bytes on the GPU: per lattice point its skin (32), its rows in the buffer and in
    /// the texture (48 each, the buffer's rows padded).
    pub fn bytes(&self) -> u64 {
        self.lattice.nodes() as u64 * (32 + 48) + self.rows.size()
    }
}
