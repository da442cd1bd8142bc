// shade/volume.wgsl: the volume method's grid passes (multiple scattering after Moon,
// Walter and Marschner 2008), run every frame before the hair is drawn. The grid and the
// phase function are described in shade/models/volume_common.wgsl. CPU mirror:
// `pelage_reference::volume` (crates/pelage-reference/src/volume.rs).
//
// Reads:  u (VolumeUniforms), frame (Frame: the lights), the strand vertices and StrandRoot
//         attributes (width, colour), the mesh (positions, normals: f32 x3 each; a u32
//         triangle list), Chiang's model and tables at @group(2).
// Writes: bounds (6 x atomic<u32>, cleared to 0 before `fit`), accum (VOLUME_ACCUM u32 per
//         cell, cleared to 0 before `splat`), medium (3 vec4 per cell: mean tangent times
//         alignment and optical depth; A_iso and the march's extinction; g_iso and the
//         body's solid share: `describe`), state_in/state_out (6 vec4 per cell: the
//         light leaving the cell this step along x+, x-, y+, y-, z+, z-, rgb and an
//         unused w), fluence (header + 3 vec4 per cell, see volume_common.wgsl).
// Dispatch, in order:
//   `fit`: fit_invocations / 256 workgroups of 256 (grid-stride loop over the vertices);
//   `finalize`: one workgroup of 1;
//   `splat`: one invocation per segment, workgroups of 64, flattened as
//            gid.y * num_workgroups.x * 64 + gid.x (pelage_gpu::dispatch_size);
//   `splat_mesh`: one invocation per triangle, flattened the same way (none without one);
//   `occupy`: one invocation per cell, flattened the same way (none without a mesh: the
//             solid shares stay the cleared 0);
//   `describe`: one invocation per cell, workgroups of 64, flattened the same way;
//   `inject`: one invocation per cell, workgroups of 64, flattened the same way;
//   `propagate`: as `inject`, `iterations` times, state_in and state_out swapped each time;
//   `settle` then `settled`: as `inject`, state_in and state_out swapped between them
//             (neither without a mesh).
//
// Splat: a segment of length L and width w adds optical depth w L (pi/4) / cell^2 to the
// cells along it (pi/4: the mean of its projected width over isotropic directions; every
// crossing of a fibre counts, as in the path tracer), sampled at most half a cell apart;
// its tangent (sign chosen so the largest component is positive) and its colour weighted
// by that depth. Fixed point, u32 atomics only (saturating; the tangent as wrapping i32).
// Inject: per cell and light, the light reaching the cell unscattered, exp(-tau) with
// tau the optical depth from the cell's face toward the light (the cells crossed, each
// for the length of the ray in it: volume_clear_toward), times the share that meets the
// cell's fibres (volume_meet: kappa times the cell's mean transmittance from its face),
// scattered once: E = irradiance
// exp(-tau) meet A(theta_l), its flux E times the scattered mean direction; weighted by
// u.light_fibres (0 when dual scattering carries the lights' scattering, `dual_volume`).
// The sky (radiance frame.ambient / pi from every direction, the path tracer's `sky`)
// likewise, as VOLUME_SKY_DIRECTIONS directional lights marched to the grid's border;
// the sky's unscattered light (fluence and flux, times the cell's own mean transmittance
// along each direction and its clear share) is added to the cell's fluence: the hair
// reads its single scattering of the sky from the grid (orders: lights 1 explicit, >= 2
// grid; sky all grid). The mesh pass reads the grid too, for the body's sky
// (shade/body_sky_volume.wgsl).
// The mesh (the body under the hair, a Lambertian of albedo pi mesh_color, as the path
// tracer's): `splat_mesh` adds its area-weighted outward normal to the cells, `occupy`
// derives the share of each cell inside it; the march toward a light is stopped by the
// cells' solid share, the mesh's lit area in a cell (n.l, under the cell's fibres)
// injects its reflection (mean direction 2/3 of the normal), and in each step the
// solid share of what arrives at a cell is reflected the same way (inside the mesh,
// back the way it came).
// Propagate (discrete ordinates along the six axis directions): light moves one cell per
// step along its direction, so a beam crossing sparse hair leaves the grid in as many
// steps as it has cells to cross (a moment scheme that spreads each step's light over
// the six faces lets a beam wander: free-streaming light stayed 2.9x too long); each
// direction stands for the cone of directions nearest it, so VOLUME_SPREAD of it moves
// to each of the four diagonal neighbours ahead and it crosses VOLUME_STEP_PATH cell
// edges (volume_common.wgsl). Each cell takes, per direction, what the cells behind it
// sent along it; of the light arriving, the body's solid share reflects (Lambertian,
// toward its normal; inside the body, back the way it came), exp(-kappa
// VOLUME_STEP_PATH) of the rest crosses the cell unscattered, the rest the fibres scatter
// (energy A_iso, flux as volume_scatter_flux). Light born in a cell (scattered there,
// reflected, or injected) is born along it uniformly and may scatter again before it
// leaves: the share p = (1 - exp(-kappa)) / kappa leaves unscattered, the rest is born
// again times the albedo, so a cell lets out e p / (1 - r), r = A_iso (1 - p), and keeps
// p / (1 - r |f| / e) of the flux (each scattering in the cell keeps that share of its
// direction). What leaves is split over the six directions by `volume_directions`. The
// fluence adds the light's path in the cell: (1 - exp(-kappa VOLUME_STEP_PATH)) / kappa
// per unit arriving, (1 - p) / kappa per birth (1/2 as kappa -> 0). Checked against a
// Monte Carlo random walk in a homogeneous cube (scripts/volume_transport.py, which
// prints the figures). Then `settle`: the fluence over the clear share of cells the body
// partly fills (below).

#import shared/math.wgsl
#import shared/bounds.wgsl
#import shared/strand.wgsl
#import shade/frame.wgsl
#import shade/models/chiang.wgsl
#import shade/models/volume_common.wgsl

@group(0) @binding(0) var<uniform> u: VolumeUniforms;
@group(0) @binding(1) var<uniform> frame: Frame;
@group(0) @binding(2) var<storage, read> vertices: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> roots: array<StrandRoot>;
@group(0) @binding(4) var<storage, read_write> bounds: array<atomic<u32>, 6>;
@group(0) @binding(5) var<storage, read_write> accum: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> medium: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> state_in: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> state_out: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read_write> fluence: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read> mesh_positions: array<f32>;
@group(0) @binding(11) var<storage, read> mesh_indices: array<u32>;
@group(0) @binding(12) var<storage, read> mesh_normals: array<f32>;

@compute @workgroup_size(256)
fn fit(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    var keys = bounds_empty();
    for (var i = gid.x; i < u.vertex_count; i += u.fit_invocations) {
        keys = bounds_add(keys, vertices[i].xyz);
    }
    let all_keys = bounds_reduce(lid, keys);
    if lid == 0u {
        atomicMax(&bounds[0], all_keys.hi.x);
        atomicMax(&bounds[1], all_keys.hi.y);
        atomicMax(&bounds[2], all_keys.hi.z);
        atomicMax(&bounds[3], all_keys.lo.x);
        atomicMax(&bounds[4], all_keys.lo.y);
        atomicMax(&bounds[5], all_keys.lo.z);
    }
}

// The grid: a cube of resolution cells on its longest side of the bounds, half a cell of
// margin, centred on the hair.
@compute @workgroup_size(1)
fn finalize() {
    let hi = bounds_hi(vec3<u32>(atomicLoad(&bounds[0]), atomicLoad(&bounds[1]), atomicLoad(&bounds[2])));
    let lo = bounds_lo(vec3<u32>(atomicLoad(&bounds[3]), atomicLoad(&bounds[4]), atomicLoad(&bounds[5])));
    var centre = 0.5 * (lo + hi);
    var extent = max(hi.x - lo.x, max(hi.y - lo.y, hi.z - lo.z));
    // No vertices (or non-finite ones): a harmless unit grid at the origin.
    if u.vertex_count == 0u || !(extent >= 0.0 && extent < 1e30 && all(abs(centre) < vec3<f32>(1e30))) {
        centre = vec3<f32>(0.0);
        extent = 1.0;
    }
    let n = f32(u.resolution);
    // extent + cell = n cell: half a cell of margin on each side.
    let cell = max(extent / (n - 1.0), u.min_cell);
    fluence[0] = vec4<f32>(centre - vec3<f32>(0.5 * n * cell), cell);
}

fn add_saturating(index: u32, amount: u32) {
    if amount == 0u {
        return;
    }
    let old = atomicAdd(&accum[index], amount);
    if old > 0xffffffffu - amount {
        atomicMax(&accum[index], 0xffffffffu);
    }
}

fn cell_of(p: vec3<f32>, origin: vec3<f32>, cell: f32) -> vec3<i32> {
    let n = i32(u.resolution);
    return clamp(vec3<i32>(floor((p - origin) / cell)), vec3<i32>(0), vec3<i32>(n - 1));
}

fn cell_index(c: vec3<i32>) -> u32 {
    let n = u.resolution;
    return (u32(c.z) * n + u32(c.y)) * n + u32(c.x);
}

@compute @workgroup_size(64)
fn splat(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let segment = gid.y * groups.x * 64u + gid.x;
    if segment >= u.strand_count * u.segments {
        return;
    }
    let strand = segment / u.segments;
    let k = segment % u.segments;
    let base = strand * (u.segments + 1u);
    let a = vertices[base + k];
    let b = vertices[base + k + 1u];
    let root = roots[strand];
    let width = root.width * mix(1.0, u.tip_width, 0.5 * (a.w + b.w));
    let header = fluence[0];
    let origin = header.xyz;
    let cell = header.w;
    let d = b.xyz - a.xyz;
    let len = length(d);
    if !(len > 0.0) || !(width > 0.0) || !(len < 1e30) {
        return;
    }
    var t = d / len;
    let at = abs(t);
    var major = t.z;
    if at.x >= at.y && at.x >= at.z {
        major = t.x;
    } else if at.y >= at.z {
        major = t.y;
    }
    t = select(t, -t, major < 0.0);
    let n = u32(clamp(ceil(2.0 * len / cell), 1.0, 4096.0));
    let depth = width * len * (0.25 * PI) / (cell * cell) / f32(n);
    let amount = depth * u.fixed_scale;
    if !(amount >= 0.5) {
        return;
    }
    let fixed = u32(min(round(amount), 4294967295.0));
    let tangent = vec3<i32>(round(t * (amount * VOLUME_TANGENT_SCALE)));
    let color = vec3<u32>(round(clamp(root.color, vec3<f32>(0.0), vec3<f32>(1.0)) * amount));
    for (var i = 0u; i < n; i++) {
        let p = mix(a.xyz, b.xyz, (f32(i) + 0.5) / f32(n));
        let at_cell = VOLUME_ACCUM * cell_index(cell_of(p, origin, cell));
        add_saturating(at_cell, fixed);
        atomicAdd(&accum[at_cell + 1u], bitcast<u32>(tangent.x));
        atomicAdd(&accum[at_cell + 2u], bitcast<u32>(tangent.y));
        atomicAdd(&accum[at_cell + 3u], bitcast<u32>(tangent.z));
        add_saturating(at_cell + 4u, color.x);
        add_saturating(at_cell + 5u, color.y);
        add_saturating(at_cell + 6u, color.z);
    }
}

fn mesh_vec3(buffer: u32, vertex: u32) -> vec3<f32> {
    let k = 3u * vertex;
    if buffer == 0u {
        return vec3<f32>(mesh_positions[k], mesh_positions[k + 1u], mesh_positions[k + 2u]);
    }
    return vec3<f32>(mesh_normals[k], mesh_normals[k + 1u], mesh_normals[k + 2u]);
}

// The mesh's area-weighted outward normal per cell: each triangle sampled at the
// centroids of its m^2 sub-triangles (m: its longest edge over half a cell), each adding
// its share of the area times the normal (oriented as the vertex normals) over the cell's
// face area. Samples outside the grid are dropped (the mesh may reach beyond the hair).
@compute @workgroup_size(64)
fn splat_mesh(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let tri = gid.y * groups.x * 64u + gid.x;
    if tri >= u.triangle_count {
        return;
    }
    let ia = mesh_indices[3u * tri];
    let ib = mesh_indices[3u * tri + 1u];
    let ic = mesh_indices[3u * tri + 2u];
    let a = mesh_vec3(0u, ia);
    let e1 = mesh_vec3(0u, ib) - a;
    let e2 = mesh_vec3(0u, ic) - a;
    var an = 0.5 * cross(e1, e2);
    let outward = mesh_vec3(1u, ia) + mesh_vec3(1u, ib) + mesh_vec3(1u, ic);
    an = select(an, -an, dot(an, outward) < 0.0);
    let header = fluence[0];
    let origin = header.xyz;
    let cell = header.w;
    let longest = max(length(e1), max(length(e2), length(e2 - e1)));
    if !(longest < 1e30) || !(length(an) > 0.0) {
        return;
    }
    let m = u32(clamp(ceil(2.0 * longest / cell), 1.0, 64.0));
    let per = an / (cell * cell * f32(m * m)) * (u.fixed_scale * VOLUME_TANGENT_SCALE);
    let fixed = vec3<i32>(round(per));
    if all(fixed == vec3<i32>(0)) {
        return;
    }
    let n = f32(u.resolution);
    for (var i = 0u; i < m; i += 1u) {
        for (var j = 0u; j + i < m; j += 1u) {
            for (var flip = 0u; flip < 2u; flip += 1u) {
                if flip == 1u && i + j + 1u >= m {
                    continue;
                }
                let off = select(1.0 / 3.0, 2.0 / 3.0, flip == 1u);
                let p = a + e1 * ((f32(i) + off) / f32(m)) + e2 * ((f32(j) + off) / f32(m));
                let q = (p - origin) / cell;
                if any(q < vec3<f32>(0.0)) || any(q >= vec3<f32>(n)) {
                    continue;
                }
                let at = VOLUME_ACCUM * cell_index(vec3<i32>(floor(q))) + VOLUME_SURFACE;
                atomicAdd(&accum[at], bitcast<u32>(fixed.x));
                atomicAdd(&accum[at + 1u], bitcast<u32>(fixed.y));
                atomicAdd(&accum[at + 2u], bitcast<u32>(fixed.z));
            }
        }
    }
}

fn surface_at(index: u32) -> vec3<f32> {
    return vec3<f32>(
        surface_component(index, 0u),
        surface_component(index, 1u),
        surface_component(index, 2u),
    );
}

// Component `axis` of `surface_at(index)`, one atomic load.
fn surface_component(index: u32, axis: u32) -> f32 {
    let at = VOLUME_ACCUM * index + VOLUME_SURFACE + axis;
    return f32(bitcast<i32>(atomicLoad(&accum[at]))) * (u.inv_fixed_scale / VOLUME_TANGENT_SCALE);
}

fn solid_at(index: u32) -> f32 {
    return bitcast<f32>(atomicLoad(&accum[VOLUME_ACCUM * index + VOLUME_SOLID]));
}

// The share of each cell inside the mesh, from its normals alone (the divergence
// theorem: along a row of cells, the inside indicator rises by the surface's -n.x per
// cell face area): per axis, the sum of -n over the cells before this one plus half of
// its own, from the low end, and of +n from the high end (a row whose one end lies
// inside a mesh that leaves the grid is right from the other end), the larger of the two
// clamped to [0, 1]; the median of the three axes.
@compute @workgroup_size(64)
fn occupy(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let n = u.resolution;
    let i = gid.y * groups.x * 64u + gid.x;
    if i >= n * n * n {
        return;
    }
    let c = vec3<i32>(i32(i % n), i32((i / n) % n), i32(i / (n * n)));
    let own = surface_at(i);
    var axes = vec3<f32>(0.0);
    for (var axis = 0u; axis < 3u; axis += 1u) {
        var low = -0.5 * own[axis];
        var high = 0.5 * own[axis];
        for (var k = 0; k < i32(n); k += 1) {
            if k == c[axis] {
                continue;
            }
            var y = c;
            y[axis] = k;
            let s = surface_component(cell_index(y), axis);
            if k < c[axis] {
                low -= s;
            } else {
                high += s;
            }
        }
        axes[axis] = clamp(max(low, high), 0.0, 1.0);
    }
    let solid = max(min(axes.x, axes.y), min(max(axes.x, axes.y), axes.z));
    atomicStore(&accum[VOLUME_ACCUM * i + VOLUME_SOLID], bitcast<u32>(solid));
}

fn depth_at(index: u32) -> f32 {
    return f32(atomicLoad(&accum[VOLUME_ACCUM * index])) * u.inv_fixed_scale;
}

fn flat_cell(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.y * groups.x * 64u + gid.x;
}

// A cell's fibres from the splat: optical depth, unit mean tangent and alignment, and the
// isotropic phase function's A and g.
struct CellFibres {
    kappa: f32,
    t: vec3<f32>,
    s: f32,
    iso: VolumeFibre,
}

fn cell_fibres(i: u32) -> CellFibres {
    let at = VOLUME_ACCUM * i;
    let kappa = depth_at(i);
    let tangent_sum = vec3<f32>(
        f32(bitcast<i32>(atomicLoad(&accum[at + 1u]))),
        f32(bitcast<i32>(atomicLoad(&accum[at + 2u]))),
        f32(bitcast<i32>(atomicLoad(&accum[at + 3u]))),
    ) * (u.inv_fixed_scale / VOLUME_TANGENT_SCALE);
    var t = vec3<f32>(0.0, 1.0, 0.0);
    var s = 0.0;
    let tl = length(tangent_sum);
    if kappa > 0.0 {
        s = clamp(tl / kappa, 0.0, 1.0);
    }
    if tl > 0.0 {
        t = tangent_sum / tl;
    }
    // A cell without fibres scatters nothing: its phase function is never read.
    var iso = VolumeFibre(vec3<f32>(0.0), vec3<f32>(0.0));
    if kappa > 0.0 {
        iso = volume_fibre_isotropic(cell_coordinates(i, kappa));
    }
    return CellFibres(kappa, t, s, iso);
}

// The absorption coordinates (volume_sigma_coordinates) of the mean colour of cell i's
// fibres (white where it has none), of optical depth kappa.
fn cell_coordinates(i: u32, kappa: f32) -> vec3<f32> {
    let at = VOLUME_ACCUM * i;
    let color_sum = vec3<f32>(
        f32(atomicLoad(&accum[at + 4u])),
        f32(atomicLoad(&accum[at + 5u])),
        f32(atomicLoad(&accum[at + 6u])),
    ) * u.inv_fixed_scale;
    var color = vec3<f32>(1.0);
    if kappa > 0.0 {
        color = clamp(color_sum / kappa, vec3<f32>(0.0), vec3<f32>(1.0));
    }
    return volume_sigma_coordinates(chiang_sigma_a(chiang, color));
}

// Per cell, after `occupy`: the medium the later passes read with plain loads (the
// march toward a light one load per cell crossed, not two atomics): the mean tangent times the
// alignment and the optical depth; A_iso and the extinction a march toward a light
// crosses in the cell (the optical depth plus -ln of the body's clear share, so that
// exp(-sum) is exp(-tau) times the product of the clear shares); g_iso and the solid share.
@compute @workgroup_size(64)
fn describe(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let n = u.resolution;
    let i = flat_cell(gid, groups);
    if i >= n * n * n {
        return;
    }
    let fibres = cell_fibres(i);
    let solid = solid_at(i);
    let extinction = fibres.kappa - log(max(1.0 - solid, 1e-30));
    medium[3u * i] = vec4<f32>(fibres.t * fibres.s, fibres.kappa);
    medium[3u * i + 1u] = vec4<f32>(fibres.iso.albedo, extinction);
    medium[3u * i + 2u] = vec4<f32>(fibres.iso.g, solid);
}

@compute @workgroup_size(64)
fn inject(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let n = u.resolution;
    let i = flat_cell(gid, groups);
    if i >= n * n * n {
        return;
    }
    let c = vec3<i32>(i32(i % n), i32((i / n) % n), i32(i / (n * n)));
    let header = fluence[0];
    let origin = header.xyz;
    let cell = header.w;
    // The cell's fibres as `describe` wrote them (the isotropic phase function is not
    // integrated twice); their absorption coordinates for the lights' angles.
    let med = medium[3u * i];
    let kappa = med.w;
    let s = length(med.xyz);
    let t = select(vec3<f32>(0.0, 1.0, 0.0), med.xyz / s, s > 0.0);
    let x = cell_coordinates(i, kappa);
    let iso = VolumeFibre(medium[3u * i + 1u].xyz, medium[3u * i + 2u].xyz);
    let surface = surface_at(i);
    let lit_mesh = length(surface);
    // The marches toward the lights and the sky start from the centroid of the cell's
    // clear part (where its fibres are), not its centre: half the solid share of a cell
    // edge away from the body, along the body's outward normal in the cell (exact for a
    // flat surface parallel to a face). From the centre, a cell beside the body saw a
    // sixth too little of the sky (volume_sky_beside_a_body_is_what_the_body_leaves).
    let away = select(vec3<f32>(0.0), surface / lit_mesh, lit_mesh > 0.0);
    let p = origin + (vec3<f32>(c) + vec3<f32>(0.5) + away * (0.5 * medium[3u * i + 2u].w)) * cell;
    // The energy born in the cell and its flux (a column per channel).
    var e = vec3<f32>(0.0);
    var f = mat3x3<f32>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    // The body's reflection leaves along 2/3 of its normal.
    let lambert = select(vec3<f32>(0.0), (2.0 / 3.0) * surface / lit_mesh, lit_mesh > 0.0);
    // The march toward each light serves the fibres' part and the body's reflection.
    if (kappa > 0.0 && u.light_fibres > 0.0) || lit_mesh > 0.0 {
        for (var li = 0u; li < min(frame.light_count, MAX_LIGHTS); li += 1u) {
            let light = frame.lights[li];
            let l = frame_to_light(light, p);
            let irradiance = frame_irradiance(light, p);
            // March toward the light from the cell's face, up to the light itself when
            // it is a point inside the grid.
            var reach = 4.0 * f32(n) * cell;
            if light.position.w != 0.0 {
                reach = min(reach, length(light.position.xyz - p));
            }
            let seen = volume_clear_toward(c, p, l, origin, cell, reach);
            // A uniform branch: `dual_volume` leaves the fibres' part to dual scattering.
            if u.light_fibres > 0.0 {
                let cos_i = length(cross(t, l));
                let theta = fibre_angle(abs(dot(t, l)), min(cos_i, 1.0));
                let aligned = volume_fibre_at(theta, x);
                let albedo = s * aligned.albedo + (1.0 - s) * iso.albedo;
                let scattered = irradiance * (seen * volume_meet(kappa, l).x * u.light_fibres) * albedo;
                let travel = mat3x3<f32>(-l * scattered.x, -l * scattered.y, -l * scattered.z);
                e += scattered;
                f += volume_scatter_flux(travel, t, s, aligned.g, iso.g);
            }
            if lit_mesh > 0.0 {
                // The mesh's lit area in the cell, under the cell's own fibres, reflected
                // as a Lambertian (mean direction 2/3 of its normal).
                let bounce = irradiance * (seen * exp(-kappa) * max(0.0, dot(surface, l))) * u.mesh_albedo;
                e += bounce;
                f += mat3x3<f32>(lambert * bounce.x, lambert * bounce.y, lambert * bounce.z);
            }
        }
    }
    // The sky: uniform radiance frame.ambient / pi from every direction (the path
    // tracer's `sky`), as VOLUME_SKY_DIRECTIONS directional lights of irradiance
    // 4 ambient / VOLUME_SKY_DIRECTIONS each, marched to the grid's border like a light.
    // What reaches the cell unscattered the cell's fibres scatter as `propagate` scatters
    // what arrives (A_iso and g_iso, the share volume_meet of each direction), and the
    // body's lit area reflects: that joins the injection (orders >= 2 of the sky once it
    // propagates); times the cell's own mean transmittance along each direction it is the
    // cell's fluence (order 1: what hair_scattered makes of it is the fibre's single
    // scattering of the sky, with the grid's visibility).
    var sky = vec4<f32>(0.0);
    if frame.ambient > 0.0 {
        let irradiance = frame.ambient * 4.0 / f32(VOLUME_SKY_DIRECTIONS);
        var lit = 0.0;
        var met = vec4<f32>(0.0);
        for (var k = 0u; k < VOLUME_SKY_DIRECTIONS; k += 1u) {
            let l = volume_sky_direction(k);
            let seen = irradiance * volume_clear_toward(c, p, l, origin, cell, 4.0 * f32(n) * cell);
            let share = volume_meet(kappa, l);
            met += seen * share.x * vec4<f32>(1.0, -l);
            sky += seen * share.y * vec4<f32>(1.0, -l);
            lit += seen * max(0.0, dot(surface, l));
        }
        e += met.x * iso.albedo;
        let travel = mat3x3<f32>(met.yzw, met.yzw, met.yzw);
        f += volume_columns(volume_scatter_flux(travel, t, s, iso.g, iso.g), iso.albedo);
        if lit_mesh > 0.0 {
            let bounce = lit * exp(-kappa) * u.mesh_albedo;
            e += bounce;
            f += mat3x3<f32>(lambert * bounce.x, lambert * bounce.y, lambert * bounce.z);
        }
    }
    // The fluence is the mean over the whole cell (`settle` divides by the clear share):
    // the sky's light is only in the clear share.
    sky *= 1.0 - medium[3u * i + 2u].w;
    let born = volume_born(e, f, kappa, iso.albedo);
    let none = vec3<f32>(0.0);
    write_state(i, born.e, born.f, 0.0, VolumeDirections(none, none, none, none, none, none));
    fluence[1u + 3u * i] = born.path * vec4<f32>(born.e.x, born.f[0]) + sky;
    fluence[2u + 3u * i] = born.path * vec4<f32>(born.e.y, born.f[1]) + sky;
    fluence[3u + 3u * i] = born.path * vec4<f32>(born.e.z, born.f[2]) + sky;
}

// The k-th of VOLUME_SKY_DIRECTIONS directions spread evenly over the sphere (a
// Fibonacci lattice: z uniform, azimuth stepped by the golden angle).
fn volume_sky_direction(k: u32) -> vec3<f32> {
    let z = 1.0 - (2.0 * f32(k) + 1.0) / f32(VOLUME_SKY_DIRECTIONS);
    let r = sqrt(max(0.0, 1.0 - z * z));
    let phi = 2.399963229728653 * f32(k);
    return vec3<f32>(r * cos(phi), r * sin(phi), z);
}

// The transmittance toward l up to `reach` (world units from p, a point in cell c), from
// where the ray from p leaves cell c: exp(-tau) times the clear share of the body, tau
// the cells' extinction (per cell edge) times the length of the ray in each cell (cell
// edges), the cells found by a 3D DDA (Amanatides and Woo) until the border.
fn volume_clear_toward(c: vec3<i32>, p: vec3<f32>, l: vec3<f32>, origin: vec3<f32>, cell: f32, reach: f32) -> f32 {
    let n = i32(u.resolution);
    let limit = reach / cell;
    let step = select(vec3<i32>(-1), vec3<i32>(1), l >= vec3<f32>(0.0));
    let al = abs(l);
    let inv = select(vec3<f32>(1e30), 1.0 / al, al > vec3<f32>(1e-20));
    // Ray length (cell edges) to the next face along each axis: from p's place in its
    // cell, then one cell each.
    let q = clamp((p - origin) / cell - vec3<f32>(c), vec3<f32>(0.0), vec3<f32>(1.0));
    var next = select(q, vec3<f32>(1.0) - q, l >= vec3<f32>(0.0)) * inv;
    var at = c;
    var t = 0.0;
    var tau = 0.0;
    for (var k = 0; k < 3 * n + 3; k += 1) {
        let exit = min(next.x, min(next.y, next.z));
        if k > 0 {
            tau += medium[3u * cell_index(at) + 1u].w * (min(exit, limit) - t);
        }
        t = exit;
        if t >= limit {
            break;
        }
        if next.x <= exit {
            at.x += step.x;
            next.x += inv.x;
        } else if next.y <= exit {
            at.y += step.y;
            next.y += inv.y;
        } else {
            at.z += step.z;
            next.z += inv.z;
        }
        if any(at < vec3<i32>(0)) || any(at >= vec3<i32>(n)) {
            break;
        }
    }
    return exp(-tau);
}

// Of light along l (unit) falling on a cell of optical depth kappa per edge: x, the share
// its fibres meet, per unit irradiance; y, its mean fluence in the cell per unit
// irradiance: the mean over the cell's points of the transmittance from where the light
// enters to the point, volume_cell_transmittance (the light a cell's fibres meet is kappa
// times the path it travels in the cell, so x = kappa y).
fn volume_meet(kappa: f32, l: vec3<f32>) -> vec2<f32> {
    let y = volume_cell_transmittance(kappa, l);
    return vec2<f32>(kappa * y, y);
}

// The mean over a cell (the unit cube, optical depth kappa per edge) of exp(-kappa s), s
// the way from a point to the cell's face along l (by reciprocity, from the face the
// light along -l enters by). With the point's distances u_a to the exit faces uniform in
// [0, 1], s = min_a u_a / |l_a|, so P(s > t) = Q(t) = prod_a (1 - |l_a| t) up to
// T = 1 / max_a |l_a| (where Q is 0) and the mean is 1 - kappa int_0^T exp(-kappa t) Q dt:
// by parts (Q cubic) where kappa T > 4, else 6-point Gauss-Legendre (Q smooth, the
// exponential at most e^-4 across). The mean chord 1 / |l|_1 in place of the chords'
// spread overestimates it by up to 15 % at the sky's directions (Jensen: 1 - exp(-kappa
// c) is concave in the chord c); `cell_transmittance_is_the_cube_mean` in
// pelage-reference's volume tests checks it against Monte Carlo points.
fn volume_cell_transmittance(kappa: f32, l: vec3<f32>) -> f32 {
    let a = abs(l);
    let t_end = 1.0 / max(max(a.x, a.y), max(a.z, 1e-6));
    let s1 = a.x + a.y + a.z;
    let s2 = a.x * a.y + a.y * a.z + a.z * a.x;
    let s3 = a.x * a.y * a.z;
    if kappa * t_end > 4.0 {
        // By parts: the integral of e^(-kt) Q is -e^(-kt) (Q / k + Q' / k^2 + Q'' / k^3 +
        // Q'''/ k^4), with Q(0) = 1 and Q(T) = 0.
        let ik = 1.0 / kappa;
        let d1 = -s1 + t_end * (2.0 * s2 - 3.0 * s3 * t_end);
        let d2 = 2.0 * s2 - 6.0 * s3 * t_end;
        let d3 = -6.0 * s3;
        let at_zero = ik * (s1 + ik * (-2.0 * s2 + ik * 6.0 * s3));
        return at_zero + exp(-kappa * t_end) * ik * (d1 + ik * (d2 + ik * d3));
    }
    let x = array<f32, 3>(0.2386191861, 0.6612093865, 0.9324695142);
    let w = array<f32, 3>(0.4679139346, 0.3607615730, 0.1713244924);
    var integral = 0.0;
    for (var i = 0u; i < 3u; i += 1u) {
        for (var side = 0u; side < 2u; side += 1u) {
            let t = 0.5 * t_end * (1.0 + select(-x[i], x[i], side == 1u));
            let q = 1.0 - t * (s1 - t * (s2 - t * s3));
            integral += w[i] * exp(-kappa * t) * q;
        }
    }
    return 1.0 - kappa * (0.5 * t_end) * integral;
}

// The share of light crossing a cell edge of optical depth kappa unscattered, averaged
// over where along the edge it starts, p = (1 - exp(-kappa)) / kappa, and the mean path
// before it scatters or leaves, (1 - p) / kappa, in cell edges (a series below 1e-2,
// where f32 would cancel).
fn volume_escape(kappa: f32) -> vec2<f32> {
    if kappa < 1e-2 {
        return vec2<f32>(1.0 - kappa * (0.5 - kappa / 6.0), 0.5 - kappa * (1.0 / 6.0 - kappa / 24.0));
    }
    let p = (1.0 - exp(-kappa)) / kappa;
    return vec2<f32>(p, (1.0 - p) / kappa);
}

// Light born in a cell, after its scatterings there: what leaves (energy and flux per
// channel) and `path`, the fluence it leaves in the cell per unit leaving.
struct VolumeBorn {
    e: vec3<f32>,
    f: mat3x3<f32>,
    path: f32,
}

// Energy `e` and flux `f` (a column per channel) born in a cell of optical depth `kappa`
// and fibre albedo `albedo` (the header's scheme: leaving e p / (1 - r), r = albedo
// (1 - p), flux p / (1 - r |f| / e); the albedo capped at 1 so that 1 - r >= p > 0).
fn volume_born(e: vec3<f32>, f: mat3x3<f32>, kappa: f32, albedo: vec3<f32>) -> VolumeBorn {
    let esc = volume_escape(kappa);
    let r = min(albedo, vec3<f32>(1.0)) * (1.0 - esc.x);
    let spread = vec3<f32>(length(f[0]), length(f[1]), length(f[2]));
    let bias = select(vec3<f32>(0.0), min(spread / e, vec3<f32>(1.0)), e > vec3<f32>(0.0));
    let ke = esc.x / (vec3<f32>(1.0) - r);
    let kf = esc.x / (vec3<f32>(1.0) - r * bias);
    return VolumeBorn(e * ke, volume_columns(f, kf), esc.y / esc.x);
}

// Light along the six axis directions, rgb each: what arrives at a cell, or what leaves.
struct VolumeDirections {
    xp: vec3<f32>,
    xn: vec3<f32>,
    yp: vec3<f32>,
    yn: vec3<f32>,
    zp: vec3<f32>,
    zn: vec3<f32>,
}

// Energy `e` and flux `f` (a column per channel) as light along the six directions: per
// channel and axis the flux's component goes along its sign, and what the flux's L1 norm
// leaves of the energy is spread evenly over the six. A flux longer (L1) than the energy
// is shortened to it: six directions hold no beam narrower than their own off the axes.
fn volume_directions(e: vec3<f32>, f: mat3x3<f32>) -> VolumeDirections {
    let axes = transpose(f);
    let l1 = abs(axes[0]) + abs(axes[1]) + abs(axes[2]);
    let c = select(vec3<f32>(1.0), e / l1, l1 > e);
    let even = max(vec3<f32>(0.0), e - c * l1) / 6.0;
    let x = c * axes[0];
    let y = c * axes[1];
    let z = c * axes[2];
    let zero = vec3<f32>(0.0);
    return VolumeDirections(
        max(x, zero) + even,
        max(-x, zero) + even,
        max(y, zero) + even,
        max(-y, zero) + even,
        max(z, zero) + even,
        max(-z, zero) + even,
    );
}

// Writes cell `i`'s six states: the light born there leaving (`e`, `f`) plus `kept` times
// the light that arrived along each direction and crossed unscattered.
fn write_state(i: u32, e: vec3<f32>, f: mat3x3<f32>, kept: f32, a: VolumeDirections) {
    let out = volume_directions(e, f);
    let j = 6u * i;
    state_out[j] = vec4<f32>(out.xp + kept * a.xp, 0.0);
    state_out[j + 1u] = vec4<f32>(out.xn + kept * a.xn, 0.0);
    state_out[j + 2u] = vec4<f32>(out.yp + kept * a.yp, 0.0);
    state_out[j + 3u] = vec4<f32>(out.yn + kept * a.yn, 0.0);
    state_out[j + 4u] = vec4<f32>(out.zp + kept * a.zp, 0.0);
    state_out[j + 5u] = vec4<f32>(out.zn + kept * a.zn, 0.0);
}

// What cell `j` sent along direction `k` in the last step, if `inside` (none from
// outside the grid).
fn sent(inside: bool, j: u32, k: u32) -> vec3<f32> {
    if !inside {
        return vec3<f32>(0.0);
    }
    return state_in[6u * j + k].xyz;
}

// The light arriving at cell `c` along direction `k` (the k-th of x+, x-, y+, y-, z+, z-,
// which is `d`): 1 - 4 VOLUME_SPREAD of what the neighbour behind, b = c - d, sent along
// d, and VOLUME_SPREAD of what each of the four beside b, b -+ e for e either other axis,
// sent (volume_common.wgsl); `axis` and `sign` give d.
fn arrival(c: vec3<i32>, axis: u32, sign: i32, k: u32) -> vec3<f32> {
    let n = i32(u.resolution);
    var b = c;
    b[axis] -= sign;
    if b[axis] < 0 || b[axis] >= n {
        return vec3<f32>(0.0);
    }
    let j = cell_index(b);
    // The other two axes and their strides in the cell index.
    let e1 = select(0u, 1u, axis == 0u);
    let e2 = select(2u, 1u, axis == 2u);
    let s1 = select(1u, u32(n), e1 == 1u);
    let s2 = select(u32(n * n), u32(n), e2 == 1u);
    let aside = sent(b[e1] + 1 < n, j + s1, k) + sent(b[e1] > 0, j - s1, k)
        + sent(b[e2] + 1 < n, j + s2, k) + sent(b[e2] > 0, j - s2, k);
    return (1.0 - 4.0 * VOLUME_SPREAD) * state_in[6u * j + k].xyz + VOLUME_SPREAD * aside;
}

// One propagation step (the header's scheme): every cell takes the light arriving along
// the six directions; the body's solid share reflects it, the fibres keep or scatter
// the rest; the light born in the cell leaves after its scatterings there.
@compute @workgroup_size(64)
fn propagate(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let n = u.resolution;
    let i = flat_cell(gid, groups);
    if i >= n * n * n {
        return;
    }
    let c = vec3<i32>(i32(i % n), i32((i / n) % n), i32(i / (n * n)));
    let a = VolumeDirections(
        arrival(c, 0u, 1, 0u),
        arrival(c, 0u, -1, 1u),
        arrival(c, 1u, 1, 2u),
        arrival(c, 1u, -1, 3u),
        arrival(c, 2u, 1, 4u),
        arrival(c, 2u, -1, 5u),
    );
    let arrived = a.xp + a.xn + a.yp + a.yn + a.zp + a.zn;
    // The arriving flux, a column per channel.
    let flow = transpose(mat3x3<f32>(a.xp - a.xn, a.yp - a.yn, a.zp - a.zn));
    let med = medium[3u * i];
    let s = length(med.xyz);
    let t = select(vec3<f32>(0.0, 1.0, 0.0), med.xyz / s, s > 0.0);
    let kappa = med.w;
    let albedo = medium[3u * i + 1u].xyz;
    let phase = medium[3u * i + 2u];
    let solid = phase.w;
    let clear = 1.0 - solid;
    // The light arriving crosses VOLUME_STEP_PATH cell edges of the cell.
    let keep = exp(-kappa * VOLUME_STEP_PATH);
    // Scattered by the fibres.
    let scatter = (1.0 - keep) * clear * albedo;
    var e = scatter * arrived;
    var f = volume_columns(volume_scatter_flux(flow, t, s, phase.xyz, phase.xyz), scatter);
    // Reflected by the body (only where it has a solid share).
    if solid > 0.0 {
        let surface = surface_at(i);
        let sl = length(surface);
        var normal = surface / sl;
        if !(sl > 0.0) {
            let back = flow * vec3<f32>(1.0);
            let bl = length(back);
            normal = select(vec3<f32>(0.0), -back / bl, bl > 0.0);
        }
        let bounce = solid * arrived * u.mesh_albedo;
        e += bounce;
        f += mat3x3<f32>(normal * bounce.x, normal * bounce.y, normal * bounce.z) * (2.0 / 3.0);
    }
    let born = volume_born(e, f, kappa, albedo);
    write_state(i, born.e, born.f, keep * clear, a);
    // Its mean path in the cell, (1 - keep) / kappa (VOLUME_STEP_PATH as kappa -> 0).
    let p = VOLUME_STEP_PATH * volume_escape(kappa * VOLUME_STEP_PATH).x * clear;
    let bp = born.path;
    fluence[1u + 3u * i] += p * vec4<f32>(arrived.x, flow[0]) + bp * vec4<f32>(born.e.x, born.f[0]);
    fluence[2u + 3u * i] += p * vec4<f32>(arrived.y, flow[1]) + bp * vec4<f32>(born.e.y, born.f[1]);
    fluence[3u + 3u * i] += p * vec4<f32>(arrived.z, flow[2]) + bp * vec4<f32>(born.e.z, born.f[2]);
}

// After the last step: the fluence of the hair in cells the body partly fills. The grid's
// fluence is the mean over a whole cell, and light does not enter the body: where a cell
// is partly solid its hair (all in the clear share) sees the fluence divided by the clear
// share; a cell at least half solid takes instead its clear neighbours' fluence (weighted
// by their clear shares), so that hair just above the skin is not read half from inside
// the body. Written to `state_out` (free after the propagation), copied back by `settled`.
@compute @workgroup_size(64)
fn settle(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let n = u.resolution;
    let i = flat_cell(gid, groups);
    if i >= n * n * n {
        return;
    }
    let solid = medium[3u * i + 2u].w;
    var r = fluence[1u + 3u * i];
    var g = fluence[2u + 3u * i];
    var b = fluence[3u + 3u * i];
    if solid >= 0.5 {
        let c = vec3<i32>(i32(i % n), i32((i / n) % n), i32(i / (n * n)));
        var w = 0.0;
        r = vec4<f32>(0.0);
        g = vec4<f32>(0.0);
        b = vec4<f32>(0.0);
        for (var k = 0u; k < 6u; k += 1u) {
            let axis = k / 2u;
            var d = vec3<i32>(0);
            d[axis] = select(1, -1, (k & 1u) == 1u);
            let y = c + d;
            if any(y < vec3<i32>(0)) || any(y >= vec3<i32>(i32(n))) {
                continue;
            }
            let j = cell_index(y);
            let clear = 1.0 - medium[3u * j + 2u].w;
            if clear > 0.5 {
                // The neighbour's fluence over its clear share, weighted by that share.
                w += clear;
                r += fluence[1u + 3u * j];
                g += fluence[2u + 3u * j];
                b += fluence[3u + 3u * j];
            }
        }
        let k = select(0.0, 1.0 / w, w > 0.0);
        r *= k;
        g *= k;
        b *= k;
    } else if solid > 0.0 {
        let k = 1.0 / (1.0 - solid);
        r *= k;
        g *= k;
        b *= k;
    }
    state_out[6u * i] = r;
    state_out[6u * i + 1u] = g;
    state_out[6u * i + 2u] = b;
}

// Copies `settle`'s fluence back.
@compute @workgroup_size(64)
fn settled(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let n = u.resolution;
    let i = flat_cell(gid, groups);
    if i >= n * n * n {
        return;
    }
    fluence[1u + 3u * i] = state_in[6u * i];
    fluence[2u + 3u * i] = state_in[6u * i + 1u];
    fluence[3u + 3u * i] = state_in[6u * i + 2u];
}
