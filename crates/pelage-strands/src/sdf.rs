//! A signed distance field of the body the strands grow on, built on the GPU
//! (`wgsl/strands/sdf.wgsl`), which the simulation's collision step samples.

use glam::{UVec3, Vec3};
use pelage_gpu::{
    BindLayout, Gpu, GpuTimer, PassInfo, compute_pipeline_with_constants, dispatch_size,
    read_buffer, wgpu, zeroed_storage,
};
use pelage_scene::{Mesh, ParamError, SDF_BAND_CELLS, SdfGrid};

use crate::{MESH, MeshBuffers};

/// Workgroup size of `sdf.wgsl`.
const WORKGROUP: u32 = 64;

/// The timestamp label of the field's build (one compute pass of several dispatches).
pub const SDF_LABEL: &str = "strands: sdf";

/// The frame resource of the body's distance field (a 3D `r32float` texture).
pub const BODY_SDF: &str = "strands.sdf";

/// The grid one dispatch of the build runs on, as `sdf.wgsl`'s pipeline constants
/// (`SdfUniforms` there, built from them by `level()`).
#[derive(Clone, Copy, Debug, PartialEq)]
struct SdfLevel {
    /// Position of node (0, 0, 0).
    origin: Vec3,
    /// Edge of a cell.
    cell: f32,
    /// Nodes per axis.
    dims: UVec3,
    /// Triangles of the mesh.
    triangle_count: u32,
    /// Cells around each triangle's box it writes exactly ([`SDF_BAND_CELLS`]).
    band: u32,
    /// The distance written where no triangle reached (every triangle non-finite).
    far: f32,
    /// Fine nodes per coarse cell along each axis at the fine level
    /// ([`COARSE_FACTOR`]); 1 at the coarse level.
    coarse: u32,
    /// Texels per row of the buffer the finish writes the field to (a multiple of 64:
    /// 256-byte rows for the copy to the texture).
    pitch: u32,
    /// Bits of a coarse key that name a triangle ([`index_bits`]).
    index_bits: u32,
}

/// Which half of the coarse points a dispatch of the build reads and writes, and a
/// sweep's axis (pipeline constants of `sdf.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq)]
struct SdfPass {
    axis: u32,
    read_half: u32,
    write_half: u32,
}

/// `sdf.wgsl`'s pipeline constants for a dispatch on `level` (whose coarse level has
/// `coarse_dims` nodes) in `pass`. Every value is an f32 or a u32, exact as an f64.
fn constants(level: &SdfLevel, coarse_dims: UVec3, pass: SdfPass) -> Vec<(&'static str, f64)> {
    vec![
        ("ORIGIN_X", f64::from(level.origin.x)),
        ("ORIGIN_Y", f64::from(level.origin.y)),
        ("ORIGIN_Z", f64::from(level.origin.z)),
        ("CELL", f64::from(level.cell)),
        ("DIMS_X", f64::from(level.dims.x)),
        ("DIMS_Y", f64::from(level.dims.y)),
        ("DIMS_Z", f64::from(level.dims.z)),
        ("TRIANGLES", f64::from(level.triangle_count)),
        ("BAND", f64::from(level.band)),
        ("FAR", f64::from(level.far)),
        ("COARSE", f64::from(level.coarse)),
        ("PITCH", f64::from(level.pitch)),
        ("INDEX_BITS", f64::from(level.index_bits)),
        ("COARSE_DIMS_X", f64::from(coarse_dims.x)),
        ("COARSE_DIMS_Y", f64::from(coarse_dims.y)),
        ("COARSE_DIMS_Z", f64::from(coarse_dims.z)),
        ("READ_HALF", f64::from(pass.read_half)),
        ("WRITE_HALF", f64::from(pass.write_half)),
        ("AXIS", f64::from(pass.axis)),
    ]
}

/// The most triangles a body's distance field takes: the coarse keys hold a triangle's
/// index below at least 8 bits of its distance (2^24, past the triangles a default
/// 128 MiB storage binding of indices holds).
pub const MAX_SDF_TRIANGLES: u32 = 1 << 24;

/// Bits that name every one of `triangles` (at least 1).
fn index_bits(triangles: u32) -> u32 {
    (u32::BITS - triangles.saturating_sub(1).leading_zeros()).max(1)
}

/// Fine cells per cell of the coarse grid over which the sweeps carry the surface.
pub const COARSE_FACTOR: u32 = 4;

/// The coarse grid of `grid`: the same origin, [`COARSE_FACTOR`] times the cell, and
/// enough nodes to cover every fine node (coarse node `k` is fine node
/// `COARSE_FACTOR · k`).
pub fn coarse_grid(grid: &SdfGrid) -> SdfGrid {
    let dims =
        (grid.dims - UVec3::ONE + UVec3::splat(COARSE_FACTOR - 1)) / COARSE_FACTOR + UVec3::ONE;
    SdfGrid {
        origin: grid.origin,
        cell: grid.cell * COARSE_FACTOR as f32,
        dims,
    }
}

/// The axes the sweeps over the coarse grid run along, in order (0: x, 1: y, 2: z).
pub const SWEEP_AXES: [u32; 3] = [0, 1, 2];

/// Vertex-triangle pairs past which [`body_triangles`] does not look for buried
/// triangles (keeps them all).
pub const MAX_BURIED_CHECK: u64 = 200_000_000;

/// The triangles of `mesh` that bound the body (indices into its triangle list), for
/// [`BodySdf::of_body`]: all but those buried inside another of its parts. A part is a
/// set of triangles connected by shared vertex indices; a triangle is buried when each of
/// its corners is inside another part (that part's winding number at it at least ½,
/// Jacobson et al. 2013). A mesh of overlapping closed parts (the built-in creature)
/// has such surfaces running on inside the body, facing outward: a field that took them
/// as surface would say "outside" next to them, deep in the body. Triangles that cross
/// another part's surface are kept. One part, or more than [`MAX_BURIED_CHECK`] pairs of
/// a vertex and a triangle of another part whose box holds it: every triangle.
/// Corners that are not finite are never inside.
pub fn body_triangles(mesh: &Mesh) -> Vec<u32> {
    let triangles = mesh.indices.len() / 3;
    let all = || (0..triangles as u32).collect();
    let vertices = mesh.positions.len();
    // Parts: union-find over the vertices, joined along each triangle.
    let mut parent: Vec<usize> = (0..vertices).collect();
    fn root(parent: &mut [usize], mut v: usize) -> usize {
        while parent[v] != v {
            parent[v] = parent[parent[v]];
            v = parent[v];
        }
        v
    }
    for tri in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| tri[k] as usize);
        if a >= vertices || b >= vertices || c >= vertices {
            return all();
        }
        for (x, y) in [(a, b), (b, c)] {
            let (rx, ry) = (root(&mut parent, x), root(&mut parent, y));
            parent[rx] = ry;
        }
    }
    let mut part_of_root = vec![usize::MAX; vertices];
    let mut parts: Vec<(Vec<usize>, Vec3, Vec3)> = Vec::new();
    let mut triangle_part = Vec::with_capacity(triangles);
    for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
        let r = root(&mut parent, tri[0] as usize);
        if part_of_root[r] == usize::MAX {
            part_of_root[r] = parts.len();
            parts.push((Vec::new(), Vec3::INFINITY, Vec3::NEG_INFINITY));
        }
        let part = &mut parts[part_of_root[r]];
        part.0.push(t);
        for &i in tri {
            let p = mesh.positions[i as usize];
            part.1 = part.1.min(p);
            part.2 = part.2.max(p);
        }
        triangle_part.push(part_of_root[r]);
    }
    if parts.len() < 2 {
        return all();
    }
    let holds =
        |(_, lo, hi): &(Vec<usize>, Vec3, Vec3), p: Vec3| p.cmpge(*lo).all() && p.cmple(*hi).all();
    let mut vertex_part = vec![usize::MAX; vertices];
    for (tri, &part) in mesh.indices.chunks_exact(3).zip(&triangle_part) {
        for &i in tri {
            vertex_part[i as usize] = part;
        }
    }
    let work: u64 = (0..vertices)
        .filter(|&v| vertex_part[v] != usize::MAX)
        .map(|v| {
            let p = mesh.positions[v];
            (parts.iter().enumerate())
                .filter(|&(k, part)| k != vertex_part[v] && holds(part, p))
                .map(|(_, part)| part.0.len() as u64)
                .sum::<u64>()
        })
        .sum();
    if work > MAX_BURIED_CHECK {
        return all();
    }
    let inside_other: Vec<bool> = (0..vertices)
        .map(|v| {
            let p = mesh.positions[v];
            vertex_part[v] != usize::MAX
                && p.is_finite()
                && (parts.iter().enumerate()).any(|(k, part)| {
                    k != vertex_part[v] && holds(part, p) && winding(mesh, &part.0, p) >= 0.5
                })
        })
        .collect();
    (0..triangles as u32)
        .filter(|&t| {
            let tri = &mesh.indices[3 * t as usize..3 * t as usize + 3];
            !tri.iter().all(|&i| inside_other[i as usize])
        })
        .collect()
}

/// The winding number at `p` of the triangles `triangles` of `mesh` (the solid angles
/// they subtend over 4π, Van Oosterom and Strackee's formula).
fn winding(mesh: &Mesh, triangles: &[usize], p: Vec3) -> f64 {
    let p = p.as_dvec3();
    let mut total = 0.0;
    for &t in triangles {
        let tri = &mesh.indices[3 * t..3 * t + 3];
        let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[tri[k] as usize].as_dvec3() - p);
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let det = a.dot(b.cross(c));
        let div = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
        if det.is_finite() && div.is_finite() {
            total += 2.0 * det.atan2(div);
        }
    }
    total / (4.0 * std::f64::consts::PI)
}

/// A signed distance field of a mesh on a grid ([`SdfGrid`]: the mesh's box plus a
/// margin, `resolution` nodes along its longest axis), negative inside, built on the GPU
/// from [`MeshBuffers`] in one compute pass ([`SDF_LABEL`]) and a copy, and held in a 3D
/// `r32float` texture ([`BodySdf::view`]) that the simulation reads with `textureLoad`
/// and trilinear interpolation (`r32float` is not filterable without a device feature,
/// and the simulation's pass already binds WebGPU's 8 storage buffers, so a texture it
/// is).
///
/// **Build.** Each triangle writes its exact distance into the nodes of its box grown by
/// [`SDF_BAND_CELLS`] cells that lie within that band of its plane, together with the
/// side of the mesh's normal the node is on (one atomic on a key: the distance's bits
/// above, the side below, so the nearest triangle's side comes with its distance). The
/// same on a coarse grid ([`coarse_grid`]: every [`COARSE_FACTOR`]-th node, one coarse
/// cell around each triangle, the key the distance in fixed point above the triangle's
/// index, so that the least names the nearest triangle; hence [`MAX_SDF_TRIANGLES`])
/// seeds each coarse node near the surface with its nearest surface point; sweeps along
/// each line of the coarse grid ([`SWEEP_AXES`], both ways: each node hands on
/// whichever of its point and the one it was handed is nearer the next node) carry the
/// points to the rest. A last pass, one invocation per coarse cell, writes each fine
/// node's signed distance to a buffer, which is copied into the texture (on lavapipe,
/// storing a 3D texture node by node cost more than the rest of the build). The arrays
/// the splats take extremes in are cleared with buffer fills, and every buffer the
/// passes write is bound read-write in all of them (on lavapipe a dispatch that changes
/// how a buffer is used costs a barrier of about 0.8 ms). The grids and passes are
/// pipeline constants, one pipeline per dispatch, made once here: lavapipe (Mesa 22)
/// compiled a shader again at every dispatch whose loops were bounded by uniforms (it
/// inlines their values), about 0.9 ms each.
///
/// **What the field holds.** Every node within the band ([`SdfGrid::band`]) of the
/// surface holds its exact signed distance (to float rounding): what the collision step
/// reads near the surface, where a vertex's cell has all its corners in the band. A
/// farther node holds the distance to the nearest of the surface points that the 8
/// coarse nodes around it hold, signed by the side of that point's normal: never nearer
/// than the surface is (each is a point of it), farther by up to about 2 cells (measured
/// against the CPU mirror `pelage_reference::sdf`: 1.6 cells on a sphere, 1.6 on the
/// creature), and of the right sign outside the body; inside a mesh of overlapping
/// closed parts, where a buried part's surface faces outward, a node about as far from
/// it as from the body's surface may take either side (as with the exact nearest-normal
/// sign itself).
///
/// **Holes, NaN.** The sign is the side of the nearest surface point's normal: an open
/// mesh is "inside" only behind its surface near a node, never flooded from a hole, and
/// a hole's rim is a surface like any other. Triangles with a non-finite corner are
/// skipped; if none is left, every node reads far outside (no collision) rather than a
/// wrong inside.
#[derive(Debug)]
pub struct BodySdf {
    grid: SdfGrid,
    coarse: SdfGrid,
    /// The finish's output, rows of `pitch` texels, copied into `texture`.
    field: wgpu::Buffer,
    pitch: u32,
    /// The splats' keys (fine and coarse), cleared to 0 before each build.
    cleared: [wgpu::Buffer; 2],
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    /// One pipeline per dispatch, each specialised to its level and pass: the fine
    /// splat; the coarse splat and seed; the sweeps along x, y and z; the finish.
    pipelines: [wgpu::ComputePipeline; 7],
    /// The fine level's group (its keys) and the coarse level's.
    groups: [wgpu::BindGroup; 2],
    triangle_count: u32,
    limits: wgpu::Limits,
}

impl BodySdf {
    /// The field of `mesh` over the box `bounds` (where the mesh stays in every pose it
    /// will be built in) with `resolution` nodes along the box's longest axis. Nothing
    /// is computed until [`BodySdf::encode`] (or [`BodySdf::build`]) runs. Refuses a
    /// resolution outside `[MIN_SDF_RESOLUTION, MAX_SDF_RESOLUTION]` or past the device's
    /// `max_texture_dimension_3d` (named `dynamics.sdf_resolution`), a mesh without
    /// triangles or with more than [`MAX_SDF_TRIANGLES`] (`mesh.indices`), and a grid
    /// whose buffers the device cannot bind.
    pub fn new(
        gpu: &Gpu,
        mesh: &MeshBuffers,
        bounds: (Vec3, Vec3),
        resolution: u32,
    ) -> crate::Result<Self> {
        Self::with_triangles(gpu, mesh, None, bounds, resolution)
    }

    /// The field of the body `mesh` (the mesh `buffers` hold; refused, naming `mesh`,
    /// when they do not match): as [`BodySdf::new`] over [`body_triangles`] only, the
    /// surfaces buried inside another of its parts left out, so that next to them deep
    /// in the body the field says "inside". Which triangles are buried is decided once,
    /// in the pose `mesh` is in (a skinned mesh's bind pose): a part the rig later
    /// pushes into another keeps its triangles.
    pub fn of_body(
        gpu: &Gpu,
        buffers: &MeshBuffers,
        mesh: &Mesh,
        bounds: (Vec3, Vec3),
        resolution: u32,
    ) -> crate::Result<Self> {
        buffers.check_matches(mesh)?;
        Self::of_triangles(
            gpu,
            buffers,
            mesh,
            &body_triangles(mesh),
            bounds,
            resolution,
        )
    }

    /// [`BodySdf::new`] over `kept`, triangles of `mesh` (which `buffers` hold): every
    /// one of them, or the subset [`body_triangles`] chose.
    pub(crate) fn of_triangles(
        gpu: &Gpu,
        buffers: &MeshBuffers,
        mesh: &Mesh,
        kept: &[u32],
        bounds: (Vec3, Vec3),
        resolution: u32,
    ) -> crate::Result<Self> {
        if kept.len() == mesh.indices.len() / 3 {
            return Self::new(gpu, buffers, bounds, resolution);
        }
        let indices: Vec<u32> = kept
            .iter()
            .flat_map(|&t| {
                mesh.indices[3 * t as usize..3 * t as usize + 3]
                    .iter()
                    .copied()
            })
            .collect();
        let buffer = pelage_gpu::create_buffer_init(
            &gpu.device,
            &wgpu::util::BufferInitDescriptor {
                label: Some("pelage sdf body triangles"),
                contents: bytemuck::cast_slice(&indices),
                usage: wgpu::BufferUsages::STORAGE,
            },
        );
        // A subset of the mesh's triangle list: the frame plan's `mesh`.
        pelage_gpu::audit::name_buffer(&buffer, MESH);
        Self::with_triangles(
            gpu,
            buffers,
            Some((buffer, kept.len() as u32)),
            bounds,
            resolution,
        )
    }

    /// [`BodySdf::new`] over `triangles` (its own triangle list and count) instead of
    /// the mesh's when given.
    fn with_triangles(
        gpu: &Gpu,
        mesh: &MeshBuffers,
        triangles: Option<(wgpu::Buffer, u32)>,
        bounds: (Vec3, Vec3),
        resolution: u32,
    ) -> crate::Result<Self> {
        let (indices, triangle_count) = match triangles {
            Some((buffer, count)) => (buffer, count),
            None => (mesh.indices.clone(), mesh.triangle_count),
        };
        let device_max = gpu.limits().max_texture_dimension_3d;
        if resolution > device_max {
            return Err(ParamError::new(
                "dynamics.sdf_resolution",
                resolution,
                &format!("must be at most {device_max} on this device (max_texture_dimension_3d)"),
            )
            .into());
        }
        if triangle_count == 0 {
            return Err(ParamError::new(
                "mesh.indices",
                0,
                "a body's distance field needs at least one triangle",
            )
            .into());
        }
        if triangle_count > MAX_SDF_TRIANGLES {
            return Err(ParamError::new(
                "mesh.indices",
                triangle_count,
                &format!("a body's distance field takes at most {MAX_SDF_TRIANGLES} triangles"),
            )
            .into());
        }
        let grid = SdfGrid::new(bounds, resolution)?;
        let coarse = coarse_grid(&grid);
        let nodes = grid.nodes() as u64;
        let coarse_nodes = coarse.nodes() as u64;
        // Rows of 256 bytes for the copy into the texture.
        let pitch = grid.dims.x.next_multiple_of(64);
        let field_bytes = u64::from(pitch) * u64::from(grid.dims.y) * u64::from(grid.dims.z) * 4;
        let storage = wgpu::BufferUsages::STORAGE;
        // Cleared before every build (the splats' keys and nearest triangles start at 0).
        let cleared = storage | wgpu::BufferUsages::COPY_DST;
        let keys = zeroed_storage(gpu, "pelage sdf keys", nodes * 4, cleared)?;
        let field = zeroed_storage(
            gpu,
            "pelage sdf field",
            field_bytes,
            storage | wgpu::BufferUsages::COPY_SRC,
        )?;
        let coarse_keys = zeroed_storage(gpu, "pelage sdf coarse keys", coarse_nodes * 4, cleared)?;
        // The coarse points, two halves (A, B) the passes read one of and write the other.
        let points = zeroed_storage(gpu, "pelage sdf coarse points", coarse_nodes * 32, storage)?;
        // Scratch of the build: written and read inside its one pass.
        for b in [&keys, &field, &coarse_keys, &points] {
            pelage_gpu::audit::name_buffer(b, BODY_SDF);
        }
        let diagonal = (grid.dims - UVec3::ONE).as_vec3().length() * grid.cell;
        let level = |g: &SdfGrid, band: u32, factor: u32| SdfLevel {
            origin: g.origin,
            cell: g.cell,
            dims: g.dims,
            triangle_count,
            band,
            far: 2.0 * diagonal,
            coarse: factor,
            pitch,
            index_bits: index_bits(triangle_count),
        };
        let fine_level = level(&grid, SDF_BAND_CELLS, COARSE_FACTOR);
        // The coarse level's splats reach every node within one coarse cell of a triangle.
        let coarse_level = level(&coarse, 1, 1);
        // Which half of `points` each pass reads and writes: the seed writes A, the
        // sweeps along x, y and z go A to B, B to A, A to B, and the finish reads B.
        let half = u32::try_from(coarse_nodes).map_err(|_| {
            ParamError::new(
                "dynamics.sdf_resolution",
                resolution,
                "makes a coarse grid past 2^32 nodes",
            )
        })?;
        let (a, b) = (0, half);
        let pass = |axis, read_half, write_half| SdfPass {
            axis,
            read_half,
            write_half,
        };
        let none = pass(0, a, a);
        // (entry point, level, pass) of each dispatch, in order.
        let dispatches = [
            ("splat", &fine_level, none),
            ("splat_coarse", &coarse_level, none),
            ("seed", &coarse_level, none),
            ("sweep", &coarse_level, pass(SWEEP_AXES[0], a, b)),
            ("sweep", &coarse_level, pass(SWEEP_AXES[1], b, a)),
            ("sweep", &coarse_level, pass(SWEEP_AXES[2], a, b)),
            ("finish", &fine_level, pass(0, b, b)),
        ];
        let module = crate::SHADERS.library().module(gpu, "strands/sdf.wgsl")?;
        let built = gpu.scoped(|device| {
            let (texture, view) = texture_3d(
                device,
                "pelage body sdf",
                extent(grid.dims),
                wgpu::TextureFormat::R32Float,
            );
            pelage_gpu::audit::name_view(&view, BODY_SDF);
            let layout = BindLayout::new(SDF_LABEL, wgpu::ShaderStages::COMPUTE)
                .storage(0)
                .storage(1)
                .storage(2)
                .storage_rw(3)
                .storage_rw(4)
                .storage_rw(5)
                .build(device);
            let pipelines = dispatches.map(|(entry, level, pass)| {
                compute_pipeline_with_constants(
                    device,
                    SDF_LABEL,
                    &module,
                    entry,
                    &[Some(&layout)],
                    &constants(level, coarse.dims, pass),
                )
            });
            // A level's keys; the mesh, the field and the coarse points are the same in
            // both groups.
            let group = |keys: &wgpu::Buffer| {
                pelage_gpu::bind_buffers(
                    device,
                    SDF_LABEL,
                    &layout,
                    &[
                        &mesh.positions,
                        &mesh.normals,
                        &indices,
                        keys,
                        &field,
                        &points,
                    ],
                )
            };
            let groups = [group(&keys), group(&coarse_keys)];
            (texture, view, pipelines, groups)
        })?;
        let (texture, view, pipelines, groups) = built;
        Ok(Self {
            grid,
            coarse,
            field,
            pitch,
            cleared: [keys, coarse_keys],
            texture,
            view,
            pipelines,
            groups,
            triangle_count,
            limits: gpu.limits().clone(),
        })
    }

    /// Records the build: buffer fills, one compute pass ([`SDF_LABEL`], every dispatch
    /// reading the mesh buffers as they are when it runs) and a copy into the texture.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        self.clear(encoder);
        let timestamp_writes = timer.and_then(|t| t.compute_pass(SDF_LABEL));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(SDF_LABEL),
            timestamp_writes,
        });
        for (_, dispatches) in self.stages() {
            record(&mut pass, &dispatches);
        }
        drop(pass);
        self.copy_field(encoder);
    }

    /// Clears the arrays the splats take their extremes in (a fill: on lavapipe the
    /// clearing dispatch it replaces took 1.1 ms at 64³).
    fn clear(&self, encoder: &mut wgpu::CommandEncoder) {
        for buffer in &self.cleared {
            encoder.clear_buffer(buffer, 0, None);
        }
    }

    /// Copies the finish's output into the texture.
    fn copy_field(&self, encoder: &mut wgpu::CommandEncoder) {
        copy_rows(
            encoder,
            &self.field,
            self.pitch * 4,
            &self.texture,
            extent(self.grid.dims),
        );
    }

    /// Records the same build as [`BodySdf::encode`], each stage in a compute pass of
    /// its own labelled `"{SDF_LABEL} / {stage}"` ([`BodySdf::STAGES`]), so a timer
    /// gives each stage's GPU time (the bench's breakdown; slightly slower than
    /// [`BodySdf::encode`] by the passes' own cost).
    pub fn encode_stages(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        mut timer: Option<&mut GpuTimer>,
    ) {
        self.clear(encoder);
        for (stage, dispatches) in self.stages() {
            let label = format!("{SDF_LABEL} / {stage}");
            let timestamp_writes = timer.as_deref_mut().and_then(|t| t.compute_pass(&label));
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&label),
                timestamp_writes,
            });
            record(&mut pass, &dispatches);
        }
        self.copy_field(encoder);
    }

    /// The names of the build's stages, in order ([`BodySdf::encode_stages`]).
    pub const STAGES: [&str; 4] = ["splat", "coarse", "sweeps", "finish"];

    /// The build's dispatches, by stage.
    fn stages(&self) -> Vec<(&'static str, Vec<Dispatch<'_>>)> {
        let size = |n: u64| dispatch_size(&self.limits, n, WORKGROUP);
        let coarse_nodes = size(self.coarse.nodes() as u64);
        let triangles = size(u64::from(self.triangle_count));
        let [fine, coarse] = &self.groups;
        let [splat, coarse_splat, seed, x, y, z, finish] = &self.pipelines;
        // A sweep runs one invocation per line of the coarse grid along its axis: as
        // many as the nodes of the plane across it.
        let d = self.coarse.dims.to_array();
        let lines = |k: usize| {
            let a = SWEEP_AXES[k] as usize;
            size(u64::from(d[(a + 1) % 3]) * u64::from(d[(a + 2) % 3]))
        };
        vec![
            ("splat", vec![(splat, fine, triangles)]),
            (
                "coarse",
                vec![
                    (coarse_splat, coarse, triangles),
                    (seed, coarse, coarse_nodes),
                ],
            ),
            (
                "sweeps",
                vec![
                    (x, coarse, lines(0)),
                    (y, coarse, lines(1)),
                    (z, coarse, lines(2)),
                ],
            ),
            ("finish", vec![(finish, fine, coarse_nodes)]),
        ]
    }

    /// Records the build and submits it (a field built once: a still or rigid mesh).
    pub fn build(&self, gpu: &Gpu) -> crate::Result<()> {
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some(SDF_LABEL),
            });
        self.encode(&mut encoder, None);
        gpu.queue.submit([encoder.finish()]);
        Ok(())
    }

    /// The pass [`BodySdf::encode`] records: it reads [`MESH`] and writes [`BODY_SDF`].
    pub fn pass(&self) -> PassInfo {
        PassInfo::new(SDF_LABEL).reads([MESH]).writes([BODY_SDF])
    }

    /// The grid.
    pub fn grid(&self) -> &SdfGrid {
        &self.grid
    }

    /// The field (`texture_3d<f32>`, `r32float`, one texel per node).
    pub fn view(&self) -> &wgpu::TextureView {
        &self.view
    }

    /// Bytes the field and its build buffers take on the GPU: per fine node the texture
    /// and the key (4 bytes each), the finish's buffer, and per coarse node a key and two
    /// points (4 + 2 x 16 bytes).
    pub fn bytes(&self) -> u64 {
        self.grid.nodes() as u64 * 8 + self.field.size() + self.coarse.nodes() as u64 * 36
    }

    /// The coarse grid the sweeps run over ([`coarse_grid`]).
    pub fn coarse_grid(&self) -> &SdfGrid {
        &self.coarse
    }

    /// Reads the field back, one value per node in [`SdfGrid::index`] order. Waits for
    /// the GPU: for tests and tools.
    pub fn read(&self, gpu: &Gpu) -> crate::Result<Vec<f32>> {
        let dims = self.grid.dims;
        let row = u64::from(dims.x) * 4;
        let padded = row.next_multiple_of(u64::from(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT));
        let size = padded * u64::from(dims.y) * u64::from(dims.z);
        let staging = gpu.scoped(|device| {
            pelage_gpu::create_buffer(
                device,
                &wgpu::BufferDescriptor {
                    label: Some("pelage sdf readback"),
                    size,
                    usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                },
            )
        })?;
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("pelage sdf readback"),
            });
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &staging,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded as u32),
                    rows_per_image: Some(dims.y),
                },
            },
            extent(dims),
        );
        gpu.queue.submit([encoder.finish()]);
        let bytes = read_buffer(gpu, &staging)?;
        let mut out = Vec::with_capacity(self.grid.nodes());
        for r in bytes.chunks(padded as usize) {
            out.extend(
                r[..row as usize]
                    .chunks_exact(4)
                    .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            );
        }
        Ok(out)
    }
}

/// `dims` as a texture's size.
pub(crate) fn extent(dims: UVec3) -> wgpu::Extent3d {
    wgpu::Extent3d {
        width: dims.x,
        height: dims.y,
        depth_or_array_layers: dims.z,
    }
}

/// A 3D texture of `format` that a pass's buffer is copied into and the simulation reads
/// (`COPY_DST | TEXTURE_BINDING | COPY_SRC`: read back by tests), and its view. (On
/// lavapipe, storing a 3D texture texel by texel cost more than the body field's whole
/// build: the passes write buffers, [`copy_rows`] moves them.)
pub(crate) fn texture_3d(
    device: &wgpu::Device,
    label: &str,
    size: wgpu::Extent3d,
    format: wgpu::TextureFormat,
) -> (wgpu::Texture, wgpu::TextureView) {
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D3,
        format,
        usage: wgpu::TextureUsages::COPY_DST
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
    (texture, view)
}

/// Records the copy of `buffer` (rows of `bytes_per_row`, a multiple of 256, `size.height`
/// rows an image) into the whole of `texture`.
pub(crate) fn copy_rows(
    encoder: &mut wgpu::CommandEncoder,
    buffer: &wgpu::Buffer,
    bytes_per_row: u32,
    texture: &wgpu::Texture,
    size: wgpu::Extent3d,
) {
    encoder.copy_buffer_to_texture(
        wgpu::TexelCopyBufferInfo {
            buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(bytes_per_row),
                rows_per_image: Some(size.height),
            },
        },
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        size,
    );
}

/// One dispatch of the build: its pipeline, bind group and workgroup counts.
type Dispatch<'a> = (&'a wgpu::ComputePipeline, &'a wgpu::BindGroup, (u32, u32));

/// Records `dispatches` into `pass`.
fn record(pass: &mut wgpu::ComputePass<'_>, dispatches: &[Dispatch<'_>]) {
    for (pipeline, group, size) in dispatches {
        pass.set_pipeline(pipeline);
        pelage_gpu::set_bind_group(pass, 0, group);
        pass.dispatch_workgroups(size.0, size.1, 1);
    }
}
