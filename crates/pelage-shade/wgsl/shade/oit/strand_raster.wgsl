// Stage 3, the strand rasterizer: hair drawn in compute, without the raster pipeline
// and without 64-bit atomics. StrandRaster in crates/pelage-shade/src/methods/
// strand_raster.rs records these entry points in this order each frame:
//
//   cs_shade        one thread per strand vertex: projects it (clip position) and shades
//                   it once with the hair model contract (hair_shade of shade/hair.wgsl,
//                   stage 2's per-vertex visibility), into `shaded`.
//   cs_bin          one thread per segment: clips it to the near and far planes, projects
//                   it into a RasterSegment (pixels, window depth, half width in pixels,
//                   colours), and counts it into every (screen tile, depth bin) cell its
//                   widened footprint touches (atomicAdd on u32).
//   cs_scan_reduce, cs_scan_top, cs_scan_apply
//                   exclusive prefix sum of the cell counts into `offsets` (blocks of
//                   SCAN_BLOCK cells, then one workgroup over the block sums); the total
//                   is the pool size this frame needs, recorded in `header`.
//   cs_scatter      one thread per segment again: the same cells, each gets the
//                   segment's index at offsets[cell] + atomicAdd(counts[cell]); indices
//                   past the pool's capacity are dropped and counted.
//   cs_fine         one workgroup per screen tile, one thread per pixel: the tile's
//                   segments, bin after bin in key order, drawn in runs: each thread
//                   puts one segment's fragments (analytic coverage, depth tested against
//                   the opaque depth) into per-pixel lists, each pixel sorts its list by
//                   view depth and composites it front to back; a pixel stops below 1/255
//                   transmittance (and takes no more fragments), the tile once all have.
//   vs_fullscreen + fs_resolve
//                   blends the result (premultiplied colour, 1 - transmittance) over the
//                   caller's colour target.
//
// Dispatches larger than 65535 workgroups are 2-D: linear ids come from
// workgroup_id.x + workgroup_id.y * num_workgroups.x.

#import shade/hair.wgsl

const SCAN_THREADS: u32 = 256u;
// Cells per scan block: SCAN_THREADS threads x 4.
const SCAN_BLOCK: u32 = 1024u;
// A pixel is finished once its transmittance drops below this.
const OPAQUE_ENOUGH: f32 = 0.00392156863;
// Tile edge in pixels (8 or 16): one workgroup of TILE x TILE threads per tile.
override TILE: u32 = 16u;

struct RasterParams {
    width: u32,
    height: u32,
    tile: u32,
    tiles_x: u32,
    tiles_y: u32,
    bins: u32,
    // Segment indices the pool holds.
    capacity: u32,
    // This frame's strands and segments per strand (stage 1's layout).
    strands: u32,
    segments: u32,
    // Scan blocks: ceil(tiles_x * tiles_y * bins / SCAN_BLOCK).
    scan_blocks: u32,
    // bin = clamp(floor((view depth - bin_near) * bin_scale), 0, bins - 1).
    bin_near: f32,
    bin_scale: f32,
    // Alpha of a strand covering a whole pixel.
    opacity: f32,
    // World units per pixel at view depth 1.
    pixel_scale: f32,
    // 1 when depth is reversed (nearer is larger), else 0.
    reverse_z: u32,
    _pad: u32,
}

// A strand vertex projected and shaded: clip position; linear RGB radiance toward the
// eye and, in w, the strand's true half width there (world units).
struct ShadedVertex {
    clip: vec4<f32>,
    color: vec4<f32>,
}

// A segment clipped and projected. a, b: x and y in pixels (y down), window depth, half
// width in pixels (negative: culled). color_a, color_b: radiance and view depth.
struct RasterSegment {
    a: vec4<f32>,
    b: vec4<f32>,
    color_a: vec4<f32>,
    color_b: vec4<f32>,
}

// Counters kept from frame to frame (zeroed when the method is built), read back by
// StrandRaster: index 0 the pool size the last frame needed, 1 the largest any frame
// needed, 2 frames whose pool overflowed, 3 segment indices dropped (saturating).
struct Header {
    needed: atomic<u32>,
    peak: atomic<u32>,
    overflowed_frames: atomic<u32>,
    dropped: atomic<u32>,
}

@group(3) @binding(0) var<uniform> raster: RasterParams;
@group(3) @binding(1) var<storage, read_write> shaded: array<ShadedVertex>;
@group(3) @binding(2) var<storage, read_write> raster_segments: array<RasterSegment>;
@group(3) @binding(3) var<storage, read_write> counts: array<atomic<u32>>;
@group(3) @binding(4) var<storage, read_write> offsets: array<u32>;
@group(3) @binding(5) var<storage, read_write> pool: array<u32>;
@group(3) @binding(6) var<storage, read_write> block_sums: array<u32>;
@group(3) @binding(7) var<storage, read_write> header: Header;
// The opaque depth, read as unfilterable float (GL has no textureLoad of a depth texture).
@group(3) @binding(8) var opaque_depth: texture_2d<f32>;
@group(3) @binding(9) var composite: texture_storage_2d<rgba16float, write>;
@group(3) @binding(10) var composite_read: texture_2d<f32>;

fn linear_id(wid: vec3<u32>, groups: vec3<u32>, size: u32, lid: u32) -> u32 {
    return (wid.x + wid.y * groups.x) * size + lid;
}

// ---- per vertex: project and shade -------------------------------------------------

@compute @workgroup_size(64)
fn cs_shade(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let i = linear_id(wid, groups, 64u, lid);
    let per_strand = raster.segments + 1u;
    if (i >= raster.strands * per_strand) {
        return;
    }
    let strand = i / per_strand;
    let k = i % per_strand;
    let base = strand * per_strand;
    let here = vertices[i];
    let prev = vertices[base + select(k - 1u, 0u, k == 0u)].xyz;
    let next = vertices[base + min(k + 1u, raster.segments)].xyz;
    let root = roots[strand];

    // The vertex as hair.wgsl's vertex stage hands it to hair_shade, on the centre line.
    var v: VertexOut;
    v.clip = frame.view_proj * vec4<f32>(here.xyz, 1.0);
    v.world = here.xyz;
    v.tangent = safe_normalize(next - prev, vec3<f32>(0.0, 1.0, 0.0));
    v.color = root.color;
    v.v = here.w;
    v.visibility = vec4<f32>(1.0);
    if (frame.visibility_stride > 0u) {
        for (var l = 0u; l < min(frame.light_count, MAX_LIGHTS); l += 1u) {
            v.visibility[l] = light_visibility_buffer[l * frame.visibility_stride + i];
        }
    }
    v.coverage = 1.0;
    v.view_depth = v.clip.w;
    v.strand = strand;
    v.strand_random = f32(pcg_hash(root.seed ^ 0x68bc21ebu) >> 8u) * (1.0 / 16777216.0);
    let half_width = 0.5 * root.width * mix(1.0, style.tip_width, here.w);
    shaded[i] = ShadedVertex(v.clip, vec4<f32>(hair_shade(v).rgb, half_width));
}

// ---- per segment: clip, project, walk the tiles ------------------------------------

// Signed distances of a clip position inside the near and the far plane.
fn plane_distances(c: vec4<f32>) -> vec2<f32> {
    if (raster.reverse_z != 0u) {
        return vec2<f32>(c.w - c.z, c.z);
    }
    return vec2<f32>(c.z, c.w - c.z);
}

// The part [t0, t1] of the segment from p to q inside both planes (t0 > t1: none).
fn clip_range(p: vec4<f32>, q: vec4<f32>) -> vec2<f32> {
    var range = vec2<f32>(0.0, 1.0);
    let dp = plane_distances(p);
    let dq = plane_distances(q);
    for (var i = 0u; i < 2u; i += 1u) {
        if (dp[i] < 0.0 && dq[i] < 0.0) {
            return vec2<f32>(1.0, 0.0);
        }
        if (dp[i] < 0.0) {
            range.x = max(range.x, dp[i] / (dp[i] - dq[i]));
        } else if (dq[i] < 0.0) {
            range.y = min(range.y, dp[i] / (dp[i] - dq[i]));
        }
    }
    return range;
}

// End `t` of the clipped segment in pixels: x, y, window depth, half width in pixels;
// and its colour with 1 / view depth.
fn project_end(p: ShadedVertex, q: ShadedVertex, t: f32) -> array<vec4<f32>, 2> {
    let c = mix(p.clip, q.clip, t);
    let w = max(c.w, 1e-20);
    let ndc = c.xyz / w;
    let x = (ndc.x * 0.5 + 0.5) * f32(raster.width);
    let y = (0.5 - ndc.y * 0.5) * f32(raster.height);
    let half_width = mix(p.color.w, q.color.w, t) / (raster.pixel_scale * w);
    return array<vec4<f32>, 2>(
        vec4<f32>(x, y, ndc.z, half_width),
        vec4<f32>(mix(p.color.rgb, q.color.rgb, t), w),
    );
}

fn segment_vertex(s: u32) -> u32 {
    return s / raster.segments * (raster.segments + 1u) + s % raster.segments;
}

// The sort key of a projected segment: view depth at its midpoint.
fn segment_key(seg: RasterSegment) -> f32 {
    return 0.5 * (seg.color_a.w + seg.color_b.w);
}

fn segment_bin(seg: RasterSegment) -> u32 {
    let b = floor((segment_key(seg) - raster.bin_near) * raster.bin_scale);
    return u32(clamp(b, 0.0, f32(raster.bins - 1u)));
}

// Reach of a segment's coverage beyond its centre line, in pixels: its widest half
// width plus half a pixel (a pixel centre farther than this gets no coverage).
fn segment_reach(seg: RasterSegment) -> f32 {
    return max(seg.a.w, seg.b.w) + 0.5;
}

// Tile columns [x0, x1] of tile row `row` that the segment widened by `r` touches.
fn row_columns(seg: RasterSegment, r: f32, row: u32) -> vec2<i32> {
    let y_lo = f32(row * raster.tile) - r;
    let y_hi = f32((row + 1u) * raster.tile) + r;
    let dy = seg.b.y - seg.a.y;
    var t = vec2<f32>(0.0, 1.0);
    if (abs(dy) > 1e-6) {
        let t_lo = (y_lo - seg.a.y) / dy;
        let t_hi = (y_hi - seg.a.y) / dy;
        t = vec2<f32>(max(0.0, min(t_lo, t_hi)), min(1.0, max(t_lo, t_hi)));
    }
    if (t.x > t.y) {
        return vec2<i32>(1, 0);
    }
    let xa = mix(seg.a.x, seg.b.x, t.x);
    let xb = mix(seg.a.x, seg.b.x, t.y);
    let tile = f32(raster.tile);
    let x0 = i32(floor((min(xa, xb) - r) / tile));
    let x1 = i32(floor((max(xa, xb) + r) / tile));
    return vec2<i32>(max(x0, 0), min(x1, i32(raster.tiles_x) - 1));
}

// Tile rows [y0, y1] the segment widened by `r` touches (y0 > y1: none).
fn segment_rows(seg: RasterSegment, r: f32) -> vec2<i32> {
    let tile = f32(raster.tile);
    let y0 = i32(floor((min(seg.a.y, seg.b.y) - r) / tile));
    let y1 = i32(floor((max(seg.a.y, seg.b.y) + r) / tile));
    return vec2<i32>(max(y0, 0), min(y1, i32(raster.tiles_y) - 1));
}

// Every (tile, bin) cell segment `s` (projected as `seg`) touches: counted into `counts`
// (cs_bin), or, with `scatter`, its index written at the cell's offset plus the count so
// far (cs_scatter). One walk, so both passes visit the same cells.
fn walk_cells(seg: RasterSegment, s: u32, scatter: bool) {
    let bin = segment_bin(seg);
    let r = segment_reach(seg);
    let rows = segment_rows(seg, r);
    for (var row = rows.x; row <= rows.y; row += 1) {
        let cols = row_columns(seg, r, u32(row));
        for (var col = cols.x; col <= cols.y; col += 1) {
            let cell = (u32(row) * raster.tiles_x + u32(col)) * raster.bins + bin;
            let before = atomicAdd(&counts[cell], 1u);
            if (scatter) {
                let slot = offsets[cell] + before;
                if (slot < raster.capacity) {
                    pool[slot] = s;
                }
            }
        }
    }
}

@compute @workgroup_size(64)
fn cs_bin(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let s = linear_id(wid, groups, 64u, lid);
    if (s >= raster.strands * raster.segments) {
        return;
    }
    let v = segment_vertex(s);
    let p = shaded[v];
    let q = shaded[v + 1u];
    let range = clip_range(p.clip, q.clip);
    var seg: RasterSegment;
    if (range.x > range.y) {
        seg.a = vec4<f32>(0.0, 0.0, 0.0, -1.0);
        seg.b = seg.a;
        seg.color_a = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        seg.color_b = seg.color_a;
        raster_segments[s] = seg;
        return;
    }
    let a = project_end(p, q, range.x);
    let b = project_end(p, q, range.y);
    seg.a = a[0];
    seg.b = b[0];
    seg.color_a = a[1];
    seg.color_b = b[1];
    raster_segments[s] = seg;
    walk_cells(seg, s, false);
}

@compute @workgroup_size(64)
fn cs_scatter(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let s = linear_id(wid, groups, 64u, lid);
    if (s >= raster.strands * raster.segments) {
        return;
    }
    let seg = raster_segments[s];
    if (seg.a.w < 0.0) {
        return;
    }
    walk_cells(seg, s, true);
}

// ---- exclusive prefix sum of the cell counts ----------------------------------------

var<workgroup> scan_shared: array<u32, SCAN_THREADS>;

// Inclusive scan of scan_shared in place (Hillis-Steele); returns element `lid`.
fn scan_workgroup(lid: u32, value: u32) -> u32 {
    scan_shared[lid] = value;
    workgroupBarrier();
    for (var step = 1u; step < SCAN_THREADS; step <<= 1u) {
        var add = 0u;
        if (lid >= step) {
            add = scan_shared[lid - step];
        }
        workgroupBarrier();
        scan_shared[lid] += add;
        workgroupBarrier();
    }
    return scan_shared[lid];
}

fn cell_count(cell: u32) -> u32 {
    if (cell >= raster.tiles_x * raster.tiles_y * raster.bins) {
        return 0u;
    }
    return atomicLoad(&counts[cell]);
}

// Block sums: block b sums cells [b * SCAN_BLOCK, (b + 1) * SCAN_BLOCK).
@compute @workgroup_size(256)
fn cs_scan_reduce(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let block = wid.x + wid.y * groups.x;
    let first = block * SCAN_BLOCK + lid * 4u;
    var sum = 0u;
    for (var i = 0u; i < 4u; i += 1u) {
        sum += cell_count(first + i);
    }
    let total = scan_workgroup(lid, sum);
    if (lid == SCAN_THREADS - 1u && block < raster.scan_blocks) {
        block_sums[block] = total;
    }
}

// The block sums scanned exclusively in place by one workgroup; the total is this
// frame's pool size, recorded in the header with the overflow when it passes capacity.
@compute @workgroup_size(256)
fn cs_scan_top(@builtin(local_invocation_index) lid: u32) {
    let n = raster.scan_blocks;
    let per = (n + SCAN_THREADS - 1u) / SCAN_THREADS;
    let first = lid * per;
    var sum = 0u;
    for (var i = 0u; i < per; i += 1u) {
        if (first + i < n) {
            sum += block_sums[first + i];
        }
    }
    let inclusive = scan_workgroup(lid, sum);
    var running = inclusive - sum;
    for (var i = 0u; i < per; i += 1u) {
        if (first + i < n) {
            let value = block_sums[first + i];
            block_sums[first + i] = running;
            running += value;
        }
    }
    if (lid == SCAN_THREADS - 1u) {
        let total = inclusive;
        atomicStore(&header.needed, total);
        atomicMax(&header.peak, total);
        if (total > raster.capacity) {
            atomicAdd(&header.overflowed_frames, 1u);
            let lost = total - raster.capacity;
            let before = atomicLoad(&header.dropped);
            atomicStore(&header.dropped, select(before + lost, 0xffffffffu, before + lost < before));
        }
    }
}

// Offsets of every cell (its block's offset plus the scan within the block); counts
// are zeroed for cs_scatter to count again.
@compute @workgroup_size(256)
fn cs_scan_apply(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let block = wid.x + wid.y * groups.x;
    let first = block * SCAN_BLOCK + lid * 4u;
    var values: array<u32, 4>;
    var sum = 0u;
    for (var i = 0u; i < 4u; i += 1u) {
        values[i] = cell_count(first + i);
        sum += values[i];
    }
    let inclusive = scan_workgroup(lid, sum);
    if (block >= raster.scan_blocks) {
        return;
    }
    var running = block_sums[block] + inclusive - sum;
    let cells = raster.tiles_x * raster.tiles_y * raster.bins;
    for (var i = 0u; i < 4u; i += 1u) {
        if (first + i < cells) {
            offsets[first + i] = running;
            atomicStore(&counts[first + i], 0u);
        }
        running += values[i];
    }
}

// ---- per tile: composite ------------------------------------------------------------
//
// A tile's cells are consecutive in the pool, bin after bin (within a bin, in the order
// cs_scatter's atomics gave): the tile's segments in depth order to the bins' resolution.
// They are drawn in runs of up to one segment per thread:
// each thread walks its segment's pixels in the tile (phase A) and appends a fragment
// (view depth there, the segment's place in the run) to the pixel's list in workgroup
// memory, skipping pixels already opaque; each thread then sorts its own pixel's list by
// depth and composites it (phase B). A run whose fragments overflow a pixel's list is
// drawn again as runs of half the length (for the rest of the tile), so no fragment is
// lost. The order is exact per pixel within a run (window depth), and by depth bin
// between runs: only fragments of the same bin drawn in different runs can be out of order.

// Fragment slots of a tile's lists: FRAG_SLOTS / (TILE x TILE) per pixel.
const FRAG_SLOTS: u32 = 2048u;
// Bits of a fragment key holding its entry in the run (runs are at most 512 long).
const ENTRY_MASK: u32 = 511u;
const MAX_TILE_PIXELS: u32 = 256u;

// Segments per thread in a run (before halving on overflow).
const RUN_PER_THREAD: u32 = 2u;
var<workgroup> run_ids: array<u32, 512>;
var<workgroup> frag_key: array<u32, FRAG_SLOTS>;
var<workgroup> frag_count: array<atomic<u32>, MAX_TILE_PIXELS>;
var<workgroup> tile_opaque: array<f32, MAX_TILE_PIXELS>;
// 1 while the pixel is inside the target and not yet opaque.
var<workgroup> tile_open: array<u32, MAX_TILE_PIXELS>;
var<workgroup> overflowed: atomic<u32>;
var<workgroup> pixels_done: atomic<u32>;
var<workgroup> tile_range: vec2<u32>;
var<workgroup> shared_word: u32;

// Coverage of the pixel centred at `p` by the segment, its window depth and the
// perspective-correct parameter along it: (coverage, depth, t); coverage 0 outside it.
fn segment_coverage(seg: RasterSegment, p: vec2<f32>) -> vec3<f32> {
    let d = seg.b.xy - seg.a.xy;
    let len2 = dot(d, d);
    var u = 0.0;
    if (len2 > 1e-12) {
        u = dot(p - seg.a.xy, d) / len2;
        // Half open, so consecutive segments share no pixel at their joint.
        if (u < 0.0 || u >= 1.0) {
            return vec3<f32>(0.0);
        }
    }
    let dist = length(p - (seg.a.xy + u * d));
    let half_width = mix(seg.a.w, seg.b.w, u);
    // Overlap of the strand's cross-section [dist - w, dist + w] with the pixel's [-1/2, 1/2].
    let coverage = clamp(min(dist + half_width, 0.5) - max(dist - half_width, -0.5), 0.0, 1.0);
    // Perspective correct: 1 / view depth is linear on the screen.
    let inv_b = 1.0 / seg.color_b.w;
    let inv_w = mix(1.0 / seg.color_a.w, inv_b, u);
    let t = select(0.0, u * inv_b / inv_w, inv_w > 0.0);
    return vec3<f32>(coverage, mix(seg.a.z, seg.b.z, u), t);
}

// Whether window depth `z` is in front of the opaque depth `opaque`.
fn in_front(z: f32, opaque: f32) -> bool {
    if (raster.reverse_z != 0u) {
        return z > opaque;
    }
    return z < opaque;
}

// Phase A for one segment: a fragment in every open pixel of the tile it covers.
fn emit_fragments(seg: RasterSegment, entry: u32, origin: vec2<u32>, slots: u32) {
    let r = segment_reach(seg);
    let d = seg.b.xy - seg.a.xy;
    // Walk the segment's major axis; across it, only the pixels within `r` of the line
    // (r / cos of the angle to the axis) can be covered.
    let major = select(1u, 0u, abs(d.x) >= abs(d.y));
    let minor = 1u - major;
    let first = vec2<i32>(origin);
    let last = first + vec2<i32>(i32(TILE) - 1);
    let lo = max(i32(clamp(floor(min(seg.a[major], seg.b[major]) - r), -1.0, 1.0e9)), first[major]);
    let hi = min(i32(clamp(floor(max(seg.a[major], seg.b[major]) + r), -1.0, 1.0e9)), last[major]);
    let along = d[major];
    let len2 = dot(d, d);
    let inv_len2 = select(0.0, 1.0 / len2, len2 > 1e-12);
    let span = select(r, r * length(d) / abs(along), abs(along) > 1e-6);
    for (var m = lo; m <= hi; m += 1) {
        // The infinite line's centre at this step (not clamped to the segment: every
        // pixel within `r` of the segment is within `span` of it).
        var centre_line = seg.a[minor];
        if (abs(along) > 1e-6) {
            centre_line = seg.a[minor] + (f32(m) + 0.5 - seg.a[major]) / along * d[minor];
        }
        let n0 = max(i32(clamp(floor(centre_line - span), -1.0, 1.0e9)), first[minor]);
        let n1 = min(i32(clamp(floor(centre_line + span), -1.0, 1.0e9)), last[minor]);
        for (var n = n0; n <= n1; n += 1) {
            var pixel = vec2<i32>(m, n);
            if (major == 1u) {
                pixel = vec2<i32>(n, m);
            }
            let p = u32(pixel.y - first.y) * TILE + u32(pixel.x - first.x);
            if (tile_open[p] == 0u) {
                continue;
            }
            // Covered (as segment_coverage decides, without its square root) and in
            // front of the opaque surface.
            let q = vec2<f32>(pixel) + vec2<f32>(0.5) - seg.a.xy;
            var u = 0.0;
            if (len2 > 1e-12) {
                u = dot(q, d) * inv_len2;
                if (u < 0.0 || u >= 1.0) {
                    continue;
                }
            }
            // Squared distance to the line from the cross product (well conditioned
            // however long the segment; |q|^2 - u^2 |d|^2 is not).
            let cross = q.x * d.y - q.y * d.x;
            let reach = mix(seg.a.w, seg.b.w, u) + 0.5;
            if (cross * cross * inv_len2 >= reach * reach) {
                continue;
            }
            let z = mix(seg.a.z, seg.b.z, u);
            if (!in_front(z, tile_opaque[p])) {
                continue;
            }
            let slot = atomicAdd(&frag_count[p], 1u);
            if (slot < slots) {
                // The window depth's bits (nearer first; non-negative floats order as
                // integers) with the low bits replaced by the entry: one word sorts by
                // depth, then run order.
                let near_first = select(z, 1.0 - z, raster.reverse_z != 0u);
                frag_key[p * slots + slot] = (bitcast<u32>(max(near_first, 0.0)) & ~ENTRY_MASK) | entry;
            } else {
                atomicStore(&overflowed, 1u);
            }
        }
    }
}

@compute @workgroup_size(TILE, TILE)
fn cs_fine(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let threads = TILE * TILE;
    let slots = FRAG_SLOTS / threads;
    let tile_index = wid.x + wid.y * groups.x;
    let tiles = raster.tiles_x * raster.tiles_y;
    let origin = vec2<u32>(tile_index % raster.tiles_x, tile_index / raster.tiles_x) * TILE;
    let px = origin.x + local.x;
    let py = origin.y + local.y;
    let inside = tile_index < tiles && px < raster.width && py < raster.height;
    let centre = vec2<f32>(f32(px) + 0.5, f32(py) + 0.5);
    var opaque = select(1.0, 0.0, raster.reverse_z != 0u);
    if (inside) {
        opaque = textureLoad(opaque_depth, vec2<i32>(i32(px), i32(py)), 0).r;
    }
    tile_opaque[lid] = opaque;
    tile_open[lid] = select(0u, 1u, inside);
    atomicStore(&frag_count[lid], 0u);
    if (lid == 0u) {
        atomicStore(&pixels_done, 0u);
        atomicStore(&overflowed, 0u);
    }
    var color = vec3<f32>(0.0);
    var transmittance = 1.0;
    workgroupBarrier();
    if (!inside) {
        atomicAdd(&pixels_done, 1u);
    }
    // The tile's cells are consecutive in the pool, bin after bin: one range.
    if (lid == 0u) {
        var range = vec2<u32>(0u, 0u);
        if (tile_index < tiles) {
            let first_cell = tile_index * raster.bins;
            let last_cell = first_cell + raster.bins - 1u;
            let start = min(offsets[first_cell], raster.capacity);
            let end = min(offsets[last_cell] + atomicLoad(&counts[last_cell]), raster.capacity);
            range = vec2<u32>(start, max(start, end));
        }
        tile_range = range;
    }
    let range = workgroupUniformLoad(&tile_range);
    var done = range.x;
    let longest_run = threads * RUN_PER_THREAD;
    var run = longest_run;
    loop {
        if (done >= range.y) {
            break;
        }
        let count = min(run, range.y - done);
        for (var entry = lid; entry < count; entry += threads) {
            let s = pool[done + entry];
            run_ids[entry] = s;
            emit_fragments(raster_segments[s], entry, origin, slots);
        }
        workgroupBarrier();
        if (lid == 0u) {
            shared_word = atomicLoad(&overflowed);
        }
        let overflow = workgroupUniformLoad(&shared_word) != 0u;
        if (overflow && run > 1u) {
            atomicStore(&frag_count[lid], 0u);
            if (lid == 0u) {
                atomicStore(&overflowed, 0u);
            }
            run = max(run >> 1u, 1u);
            workgroupBarrier();
            continue;
        }
        // Phase B: this pixel's fragments, sorted by view depth, front to back.
        let base = lid * slots;
        let fragments = min(atomicLoad(&frag_count[lid]), slots);
        for (var i = 1u; i < fragments; i += 1u) {
            let key = frag_key[base + i];
            var at = i;
            while (at > 0u && frag_key[base + at - 1u] > key) {
                frag_key[base + at] = frag_key[base + at - 1u];
                at -= 1u;
            }
            frag_key[base + at] = key;
        }
        for (var i = 0u; i < fragments; i += 1u) {
            let seg = raster_segments[run_ids[frag_key[base + i] & ENTRY_MASK]];
            let c = segment_coverage(seg, centre);
            let alpha = raster.opacity * c.x;
            color += transmittance * alpha * mix(seg.color_a.rgb, seg.color_b.rgb, c.z);
            transmittance *= 1.0 - alpha;
            if (transmittance < OPAQUE_ENOUGH) {
                tile_open[lid] = 0u;
                atomicAdd(&pixels_done, 1u);
                break;
            }
        }
        atomicStore(&frag_count[lid], 0u);
        done += count;
        workgroupBarrier();
        if (lid == 0u) {
            shared_word = atomicLoad(&pixels_done);
        }
        if (workgroupUniformLoad(&shared_word) >= threads) {
            break;
        }
    }
    if (inside) {
        textureStore(composite, vec2<i32>(i32(px), i32(py)), vec4<f32>(color, 1.0 - transmittance));
    }
}

// ---- resolve: blend over the caller's colour -----------------------------------------

@vertex
fn vs_fullscreen(@builtin(vertex_index) vi: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

// Premultiplied: the target's blend adds transmittance x what is there.
@fragment
fn fs_resolve(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    return textureLoad(composite_read, vec2<i32>(frag.xy), 0);
}
