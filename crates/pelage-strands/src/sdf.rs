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

/// Vertex-triangle pairs past which [`burial`] does not look for buried surfaces (says
/// none is).
pub const MAX_BURIED_CHECK: u64 = 200_000_000;

/// How deep each vertex of `mesh` lies inside another of its parts (positive inside,
/// negative outside every other part): the distance to the nearest triangle of that part,
/// signed by the part's winding number there (inside at ½ or more, Jacobson et al.
/// 2013), the largest over the other parts. A part is a set of triangles connected by
/// shared vertex indices. A mesh of overlapping closed parts (the built-in creature) has
/// surfaces running on inside the body, facing outward: [`BodySdf::of_body`]
/// interpolates these depths over each triangle (linearly, with the barycentric
/// coordinates of a triangle's point nearest a node) to know which of its points are
/// buried, and lets a buried point vote "outside" for no node (see [`BodySdf`]).
///
/// Only parts whose box, grown by the mesh's longest edge, holds the vertex are measured;
/// a vertex that no such box holds, a vertex that is not finite, and every vertex of a mesh
/// of one part read minus the longest edge (outside, at least that far for a triangle's
/// points, since no triangle then reaches the part). More than [`MAX_BURIED_CHECK`] pairs
/// of a vertex and a triangle of another part to measure: every vertex reads so (nothing
/// buried), as does a mesh with an index past its vertices.
pub fn burial(mesh: &Mesh) -> Vec<f32> {
    let vertices = mesh.positions.len();
    let longest = mesh
        .indices
        .chunks_exact(3)
        .filter(|tri| tri.iter().all(|&i| (i as usize) < vertices))
        .flat_map(|tri| {
            let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[tri[k] as usize]);
            [a.distance(b), b.distance(c), c.distance(a)]
        })
        .filter(|d| d.is_finite())
        .fold(0.0f32, f32::max);
    // "Outside, farther than any triangle reaches": minus the longest edge (at least a
    // little below 0 for a degenerate mesh).
    let outside = -longest.max(f32::MIN_POSITIVE);
    let none = || vec![outside; vertices];
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
            return none();
        }
        for (x, y) in [(a, b), (b, c)] {
            let (rx, ry) = (root(&mut parent, x), root(&mut parent, y));
            parent[rx] = ry;
        }
    }
    let mut part_of_root = vec![usize::MAX; vertices];
    // Each part: its triangles and its box, grown by the longest edge.
    let mut parts: Vec<(Vec<usize>, Vec3, Vec3)> = Vec::new();
    let mut vertex_part = vec![usize::MAX; vertices];
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
            part.1 = part.1.min(p - longest);
            part.2 = part.2.max(p + longest);
            vertex_part[i as usize] = part_of_root[r];
        }
    }
    if parts.len() < 2 {
        return none();
    }
    let holds =
        |(_, lo, hi): &(Vec<usize>, Vec3, Vec3), p: Vec3| p.cmpge(*lo).all() && p.cmple(*hi).all();
    // The parts each vertex is measured against.
    let own = &vertex_part;
    let near = |v: usize| {
        let p = mesh.positions[v];
        (parts.iter().enumerate()).filter(move |&(k, part)| {
            own[v] != usize::MAX && k != own[v] && p.is_finite() && holds(part, p)
        })
    };
    let work: u64 = (0..vertices)
        .map(|v| near(v).map(|(_, part)| part.0.len() as u64).sum::<u64>())
        .sum();
    if work > MAX_BURIED_CHECK {
        return none();
    }
    (0..vertices)
        .map(|v| {
            let p = mesh.positions[v];
            near(v)
                .map(|(_, part)| {
                    let d = nearest_distance(mesh, &part.0, p);
                    if winding(mesh, &part.0, p) >= 0.5 {
                        d
                    } else {
                        -d
                    }
                })
                .fold(outside, f32::max)
        })
        .collect()
}

/// The triangles of `mesh` that bound the body (indices into its triangle list): all but
/// those with every corner buried inside another part ([`burial`] above 0). The
/// surface the skin's lattice ([`SdfSkin`](crate::SdfSkin)) takes each point's nearest
/// triangle from.
pub fn body_triangles(mesh: &Mesh) -> Vec<u32> {
    kept_triangles(mesh, &burial(mesh))
}

/// [`body_triangles`] from the vertices' [`burial`].
pub(crate) fn kept_triangles(mesh: &Mesh, burial: &[f32]) -> Vec<u32> {
    (0..(mesh.indices.len() / 3) as u32)
        .filter(|&t| {
            let tri = &mesh.indices[3 * t as usize..3 * t as usize + 3];
            !tri.iter()
                .all(|&i| burial.get(i as usize).is_some_and(|&b| b > 0.0))
        })
        .collect()
}

/// The distance from `p` to the nearest of `triangles` of `mesh`.
fn nearest_distance(mesh: &Mesh, triangles: &[usize], p: Vec3) -> f32 {
    triangles
        .iter()
        .map(|&t| crate::guides::distance_to_triangle(mesh, t, p))
        .fold(f32::INFINITY, f32::min)
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
/// storing a 3D texture node by node cost more than the rest of the build).
///
/// **Overlapping parts.** A mesh of closed parts that overlap unwelded (the built-in
/// creature) has surfaces running on inside the body: a part's surface inside another
/// part faces outward, and its nearest point's side says "outside" of its own part for
/// a node that is inside the other. [`BodySdf::of_body`] gives each vertex its depth in
/// the other parts ([`burial`]) and the splat interpolates it at each nearest point: a
/// buried point that says "outside" decides no side (its distance is kept, in a second
/// key of the node, for a node outside), and a node nearer a buried point than the point
/// is deep is inside the other part (a distance changes no faster than the point moves)
/// and says "inside". Buried points seed no coarse node. (Before, the triangles wholly
/// inside another part were left out and those crossing its surface kept whole: on the
/// creature at 64 about 5% of the nodes within the band, by the mirror, took the wrong
/// side of the body where parts meet; `the_field_is_inside_where_the_body_is` measures
/// what is left against the winding number.)
///
/// The arrays
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
/// creature), and of the right sign outside the body. Where parts meet, a node inside
/// one part whose nearest surface is the other's, beyond the junction, and whose own
/// part's surface is past the band, may still read outside (the winding number's count
/// on the creature: 0.4% of the band's nodes at 64, 0.24% at 128).
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
    /// Each vertex's [`burial`] (the splats read it).
    burial: wgpu::Buffer,
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
        Self::with_burial(gpu, mesh, None, bounds, resolution)
    }

    /// The field of the body `mesh` (the mesh `buffers` hold; refused, naming `mesh`,
    /// when they do not match): as [`BodySdf::new`], with the surfaces buried inside
    /// another of its parts voting "outside" for no node ([`burial`]), so that next to
    /// them, in the body, the field says "inside". Which points are buried is decided
    /// once, in the pose `mesh` is in (a skinned mesh's bind pose): a field rebuilt every
    /// frame of a moving mesh keeps that pose's junctions.
    pub fn of_body(
        gpu: &Gpu,
        buffers: &MeshBuffers,
        mesh: &Mesh,
        bounds: (Vec3, Vec3),
        resolution: u32,
    ) -> crate::Result<Self> {
        buffers.check_matches(mesh)?;
        Self::with_burial(gpu, buffers, Some(&burial(mesh)), bounds, resolution)
    }

    /// [`BodySdf::new`] with each vertex's [`burial`] (one per vertex of the mesh `mesh`
    /// holds; `None`: nothing buried).
    pub(crate) fn with_burial(
        gpu: &Gpu,
        mesh: &MeshBuffers,
        burial: Option<&[f32]>,
        bounds: (Vec3, Vec3),
        resolution: u32,
    ) -> crate::Result<Self> {
        let triangle_count = mesh.triangle_count;
        let depths = match burial {
            Some(b) if b.len() == mesh.vertex_count as usize => b.to_vec(),
            Some(b) => {
                return Err(ParamError::new(
                    "mesh.positions",
                    b.len(),
                    &format!("a burial per vertex of the mesh ({})", mesh.vertex_count),
                )
                .into());
            }
            // Outside every other part everywhere.
            None => vec![-1.0; mesh.vertex_count as usize],
        };
        // A storage binding of at least one element.
        let depths = if depths.is_empty() {
            vec![-1.0]
        } else {
            depths
        };
        let burial = pelage_gpu::create_buffer_init(
            &gpu.device,
            &wgpu::util::BufferInitDescriptor {
                label: Some("pelage sdf burial"),
                contents: bytemuck::cast_slice(&depths),
                usage: wgpu::BufferUsages::STORAGE,
            },
        );
        pelage_gpu::audit::name_buffer(&burial, BODY_SDF);
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
        // The fine splat's keys, two halves: the votes that decide a node's side, and
        // the "outside" votes of buried points (their distance only).
        let keys = zeroed_storage(gpu, "pelage sdf keys", nodes * 8, cleared)?;
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
                .storage(6)
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
                        &mesh.indices,
                        keys,
                        &field,
                        &points,
                        &burial,
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
            burial,
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
    /// and two keys (4 bytes each), the finish's buffer, per coarse node a key and two
    /// points (4 + 2 x 16 bytes), and per mesh vertex its [`burial`] (4 bytes).
    pub fn bytes(&self) -> u64 {
        self.grid.nodes() as u64 * 12
            + self.field.size()
            + self.coarse.nodes() as u64 * 36
            + self.burial.size()
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
