// Voxel shadows, pass 2: splat every strand segment into the light-space density grid.
//
// Reads:  LightGridUniforms, LightGrid (fitted this frame), the strand vertices and
//         StrandRoot attributes (width).
// Writes: `volume`, (resolution_z + 1) layers of atomic<u32> fixed-point optical
//         depth, cleared to 0 before the pass; additions saturate at 0xffffffff.
// Dispatch: one invocation per segment, workgroup_size(64); x = min(groups, limit),
//         y = ceil(groups / x).
//
// A segment of length L and width w whose direction makes angle theta with the light
// casts a shadow of area w * L * sin(theta); spread over a cell cross-section A it
// blocks w * L * sin(theta) / A of the light on average. With strands placed at random,
// the number of crossings on a ray is Poisson, and E[(1 - opacity)^N] = exp(-opacity * E[N]):
// so the segment adds optical depth opacity * w * L * sin(theta) / A, sampled along its
// length at most half a voxel apart so long segments leave no gaps.

#import shared/strand.wgsl
#import shadow/light_common.wgsl

@group(0) @binding(0) var<uniform> u: LightGridUniforms;
@group(0) @binding(1) var<storage, read> grid: LightGrid;
@group(0) @binding(2) var<storage, read> vertices: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> roots: array<StrandRoot>;
@group(0) @binding(4) var<storage, read_write> volume: array<atomic<u32>>;

// Adds `amount`, saturating instead of wrapping: an addition that wrapped is followed
// by atomicMax to the ceiling, so once any addition overflowed the cell ends at the ceiling.
fn add_saturating(index: u32, amount: u32) {
    if amount == 0u {
        return;
    }
    let old = atomicAdd(&volume[index], amount);
    if old > 0xffffffffu - amount {
        atomicMax(&volume[index], 0xffffffffu);
    }
}

fn splat_nearest(g: vec3<f32>, amount: f32) {
    let res = vec3<i32>(i32(u.resolution_x), i32(u.resolution_y), i32(u.resolution_z));
    let c = clamp(vec3<i32>(floor(g)), vec3<i32>(0), res - 1);
    add_saturating(voxel_index(u, u32(c.x), u32(c.y), u32(c.z)), u32(round(amount)));
}

fn splat_trilinear(g: vec3<f32>, amount: f32) {
    let res = vec3<i32>(i32(u.resolution_x), i32(u.resolution_y), i32(u.resolution_z));
    // Cell centres sit at integer + 0.5.
    let c = g - 0.5;
    let base = vec3<i32>(floor(c));
    let f = c - floor(c);
    for (var corner = 0u; corner < 8u; corner++) {
        let o = vec3<i32>(i32(corner & 1u), i32((corner >> 1u) & 1u), i32((corner >> 2u) & 1u));
        let w = select(1.0 - f.x, f.x, o.x == 1) * select(1.0 - f.y, f.y, o.y == 1) * select(1.0 - f.z, f.z, o.z == 1);
        // Weight that falls outside the grid is kept at the border (the grid is padded,
        // so this only happens for the outermost half voxel).
        let v = clamp(base + o, vec3<i32>(0), res - 1);
        add_saturating(voxel_index(u, u32(v.x), u32(v.y), u32(v.z)), u32(round(amount * w)));
    }
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let segment = gid.y * groups.x * 64u + gid.x;
    if segment >= u.strand_count * u.segments {
        return;
    }
    let strand = segment / u.segments;
    let k = segment % u.segments;
    let base = strand * (u.segments + 1u);
    let a = vertices[base + k];
    let b = vertices[base + k + 1u];
    let width = roots[strand].width * mix(1.0, u.tip_width, 0.5 * (a.w + b.w));

    let la = to_light_space(u, a.xyz);
    let lb = to_light_space(u, b.xyz);
    let projected = length(lb.xy - la.xy);
    let tau = u.opacity * width * projected / (grid.cell.x * grid.cell.y);
    let ga = (la - grid.origin) * grid.inv_cell;
    let gb = (lb - grid.origin) * grid.inv_cell;
    let span = abs(gb - ga);
    let n = u32(clamp(ceil(2.0 * max(span.x, max(span.y, span.z))), 1.0, 4096.0));
    let amount = tau * u.fixed_scale / f32(n);
    if !(amount > 0.0) {
        return;
    }
    for (var i = 0u; i < n; i++) {
        let g = mix(ga, gb, (f32(i) + 0.5) / f32(n));
        if u.splat == 1u {
            splat_trilinear(g, amount);
        } else {
            splat_nearest(g, amount);
        }
    }
}
