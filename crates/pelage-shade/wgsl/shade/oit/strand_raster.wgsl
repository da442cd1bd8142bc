// Stage 3, the strand rasterizer: hair drawn in compute, without the raster pipeline
// and without 64-bit atomics. StrandRaster in crates/pelage-shade/src/methods/
// strand_raster.rs records these entry points in this order each frame:
//
//   cs_shade        one thread per strand vertex: projects it (clip position) and shades
//                   it once with the hair model contract (hair_shade of shade/hair.wgsl,
//                   stage 2's per-vertex visibility), into `shaded`.
//   cs_tile_depth   one thread per screen tile: the farthest opaque depth over its pixels.
//   cs_bin          one thread per segment: clips it to the near and far planes, projects
//                   it into a RasterSegment (pixels, window depth, half width in pixels,
//                   colours), and counts it into every (screen tile, depth bin) cell its
//                   widened footprint touches and the tile's opaque surface does not
//                   hide (atomicAdd on u32).
//   cs_scan_reduce, cs_scan_top, cs_scan_apply
//                   exclusive prefix sum of the cell counts into `offsets` (blocks of
//                   SCAN_BLOCK cells, then one workgroup over the block sums); the total
//                   is the pool size this frame needs, recorded in `header`.
//   cs_scatter      one thread per segment again: the same cells, each gets the
//                   segment's index at offsets[cell] + atomicAdd(counts[cell]); indices
//                   past the pool's capacity are dropped and counted.
//   cs_sort         one thread per (tile, bin) cell: sorts the cell's references by
//                   segment index, so the order cs_fine reads is the same every run.
//   cs_fine         one workgroup per screen tile, one thread per pixel: the tile's
//                   segments, bin after bin, staged in batches in workgroup memory;
//                   each thread tests its own pixel against every segment of the batch
//                   (analytic coverage, depth tested against the opaque depth), keeps a
//                   small window of the nearest fragments of the bin in registers and
//                   composites front to back; a pixel stops below 1/255 transmittance,
//                   the tile once all have (one vote per batch).
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
// needed, 2 frames whose pool overflowed, 3 segment indices dropped (saturating), 4
// cells longer than SORT_MAX left in the scatter's order (saturating).
struct Header {
    needed: atomic<u32>,
    peak: atomic<u32>,
    overflowed_frames: atomic<u32>,
    dropped: atomic<u32>,
    unsorted: atomic<u32>,
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
// Per screen tile, the farthest opaque depth over its pixels (cs_tile_depth).
@group(3) @binding(11) var<storage, read_write> tile_depth: array<f32>;

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

// ---- per tile: the farthest opaque depth ----------------------------------------------

// The depth of an empty pixel: the far plane.
fn far_depth() -> f32 {
    return select(1.0, 0.0, raster.reverse_z != 0u);
}

// Whether window depth `a` is farther than `b`.
fn farther(a: f32, b: f32) -> bool {
    if (raster.reverse_z != 0u) {
        return a < b;
    }
    return a > b;
}

// One thread per tile: the farthest opaque depth over the tile's pixels in the target
// (a segment nowhere in front of it puts no fragment into the tile).
@compute @workgroup_size(64)
fn cs_tile_depth(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let t = linear_id(wid, groups, 64u, lid);
    if (t >= raster.tiles_x * raster.tiles_y) {
        return;
    }
    let origin = vec2<u32>(t % raster.tiles_x, t / raster.tiles_x) * raster.tile;
    let end = min(origin + vec2<u32>(raster.tile), vec2<u32>(raster.width, raster.height));
    // Nearer than anything: the first pixel replaces it.
    var deepest = select(-1.0, 2.0, raster.reverse_z != 0u);
    for (var y = origin.y; y < end.y; y += 1u) {
        for (var x = origin.x; x < end.x; x += 1u) {
            let z = textureLoad(opaque_depth, vec2<i32>(i32(x), i32(y)), 0).r;
            deepest = select(deepest, z, farther(z, deepest));
        }
    }
    tile_depth[t] = deepest;
}

// Whether the segment, nearest at window depth `nearest`, lies wholly behind the
// opaque surface of tile `t`: it then puts no fragment there (cs_fine's depth test).
fn behind_tile(nearest: f32, t: u32) -> bool {
    let opaque = tile_depth[t];
    if (raster.reverse_z != 0u) {
        return nearest <= opaque;
    }
    return nearest >= opaque;
}

// Every (tile, bin) cell segment `s` (projected as `seg`) touches, less the tiles whose
// opaque surface hides it: counted into `counts` (cs_bin), or, with `scatter`, its index
// written at the cell's offset plus the count so far (cs_scatter). One walk, so both
// passes visit the same cells.
fn walk_cells(seg: RasterSegment, s: u32, scatter: bool) {
    let bin = segment_bin(seg);
    let r = segment_reach(seg);
    let rows = segment_rows(seg, r);
    let nearest = select(min(seg.a.z, seg.b.z), max(seg.a.z, seg.b.z), raster.reverse_z != 0u);
    for (var row = rows.x; row <= rows.y; row += 1) {
        let cols = row_columns(seg, r, u32(row));
        for (var col = cols.x; col <= cols.y; col += 1) {
            let t = u32(row) * raster.tiles_x + u32(col);
            if (behind_tile(nearest, t)) {
                continue;
            }
            let cell = t * raster.bins + bin;
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

// ---- per cell: sort the references by segment index ------------------------------------
//
// cs_scatter's atomics put a cell's references in whatever order the threads reached
// them; sorting each cell by segment index makes the order cs_fine reads (and so every
// composite) the same run after run. One thread per cell, a Shell sort in the pool
// (Ciura's gaps): no barrier, and close to linear on the nearly sorted lists a
// scatter leaves. Lavapipe stops every loop of an invocation once its loops have taken
// 65 535 iterations in all (gallivm's loop limiter, per 8-lane vector), which a Shell
// sort of a few thousand references passes: cells longer than SORT_MAX stay in the
// scatter's order (their tiles may differ from run to run) and are counted in the
// header.

const SORT_MAX: u32 = 1024u;

// Ciura's gaps, largest first.
const SORT_GAPS: array<u32, 8> = array<u32, 8>(701u, 301u, 132u, 57u, 23u, 10u, 4u, 1u);

// The pool range [start, end) of `cell` (clipped to the pool's capacity).
fn cell_range(cell: u32) -> vec2<u32> {
    let start = min(offsets[cell], raster.capacity);
    let end = min(offsets[cell] + atomicLoad(&counts[cell]), raster.capacity);
    return vec2<u32>(start, max(start, end));
}

@compute @workgroup_size(64)
fn cs_sort(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let cell = linear_id(wid, groups, 64u, lid);
    if (cell >= raster.tiles_x * raster.tiles_y * raster.bins) {
        return;
    }
    let range = cell_range(cell);
    let n = range.y - range.x;
    if (n > SORT_MAX) {
        let before = atomicAdd(&header.unsorted, 1u);
        if (before == 0xffffffffu) {
            atomicStore(&header.unsorted, before);
        }
        return;
    }
    var gaps = SORT_GAPS;
    for (var g = 0u; g < 8u; g += 1u) {
        let gap = gaps[g];
        if (gap >= n) {
            continue;
        }
        for (var i = range.x + gap; i < range.y; i += 1u) {
            let v = pool[i];
            var j = i;
            loop {
                if (j < range.x + gap) {
                    break;
                }
                let w = pool[j - gap];
                if (w <= v) {
                    break;
                }
                pool[j] = w;
                j -= gap;
            }
            pool[j] = v;
        }
    }
}

// ---- per tile: composite ------------------------------------------------------------
//
// One workgroup per tile, one thread per pixel. The tile's cells are consecutive in the
// pool, bin after bin, each sorted by segment index (cs_sort): the tile's segments in
// depth order to the bins' resolution. They are staged in batches of BATCH segments in
// workgroup memory (each with a mask of the tile rows and columns its widened bounding
// box touches); every thread walks the batch and tests its own pixel against each
// segment (analytic coverage, depth tested against the opaque depth). A pixel keeps a
// window of the WINDOW nearest fragments of the current bin in registers, sorted by
// (window depth, segment index): a fragment arriving when the window is full pushes
// the nearest of the window and itself out, and that one is composited front to back;
// the window is flushed, nearest first, when the bin changes and at the end. The order
// is exact within a bin wherever a pixel gets at most WINDOW fragments from it, and by
// bin between bins. A pixel stops below 1/255 transmittance; the tile stops when all
// its pixels have (one vote per batch). No per-pixel lists, no atomics, nothing capped.

// Segments staged per batch.
const BATCH: u32 = 64u;
// Fragments a pixel's window holds (the order within a bin is exact up to this many).
const WINDOW: u32 = 8u;

var<workgroup> batch_segments: array<RasterSegment, BATCH>;
// Segment index and bin of each staged segment.
var<workgroup> batch_ids: array<u32, BATCH>;
var<workgroup> batch_bins: array<u32, BATCH>;
// Bits 0..15: tile rows the segment's widened box touches; bits 16..31: columns.
var<workgroup> batch_masks: array<u32, BATCH>;
var<workgroup> tile_range: vec2<u32>;
// The vote: ping-pong flags, set by every pixel still open.
var<workgroup> tile_busy: array<u32, 2>;

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

// Whether the segment puts a fragment into the pixel centred at `centre` in front of
// `opaque`: its projection onto the segment in [0, 1), its squared distance to the
// centre line (from the cross product: well conditioned however long the segment) below
// the half width plus half a pixel. Returns the fragment's sort depth (nearer is
// smaller, never negative), or -1 for none.
fn fragment_depth(seg: RasterSegment, centre: vec2<f32>, opaque: f32) -> f32 {
    let d = seg.b.xy - seg.a.xy;
    let len2 = dot(d, d);
    let inv_len2 = select(0.0, 1.0 / len2, len2 > 1e-12);
    let q = centre - seg.a.xy;
    var u = 0.0;
    if (len2 > 1e-12) {
        u = dot(q, d) * inv_len2;
        if (u < 0.0 || u >= 1.0) {
            return -1.0;
        }
    }
    let cross = q.x * d.y - q.y * d.x;
    let reach = mix(seg.a.w, seg.b.w, u) + 0.5;
    if (cross * cross * inv_len2 >= reach * reach) {
        return -1.0;
    }
    let z = mix(seg.a.z, seg.b.z, u);
    if (!in_front(z, opaque)) {
        return -1.0;
    }
    return max(select(z, 1.0 - z, raster.reverse_z != 0u), 0.0);
}

// Bits of the tile rows (0..15) and columns (16..31) whose pixel centres lie in the
// segment's bounding box widened by its reach.
fn tile_mask(seg: RasterSegment, origin: vec2<u32>) -> u32 {
    let r = segment_reach(seg);
    let lo = min(seg.a.xy, seg.b.xy) - vec2<f32>(r) - vec2<f32>(origin) - vec2<f32>(0.5);
    let hi = max(seg.a.xy, seg.b.xy) + vec2<f32>(r) - vec2<f32>(origin) - vec2<f32>(0.5);
    // Pixel k (centre k + 0.5 in tile coordinates) is inside when lo <= k <= hi: bits
    // [first, last + 1) (none when last < first).
    let first = vec2<u32>(clamp(ceil(lo), vec2<f32>(0.0), vec2<f32>(f32(TILE))));
    let end = vec2<u32>(clamp(floor(hi) + 1.0, vec2<f32>(0.0), vec2<f32>(f32(TILE))));
    let below_end = (vec2<u32>(1u) << end) - vec2<u32>(1u);
    let below_first = (vec2<u32>(1u) << first) - vec2<u32>(1u);
    let bits = below_end & ~below_first;
    return (bits.y & 0xffffu) | ((bits.x & 0xffffu) << 16u);
}

// One pixel's state in cs_fine: its place, front-to-back blend and window. Private so
// that the helpers below, called with constant slots, keep the window in registers
// (and so that no loop runs per fragment: lavapipe stops every loop of an invocation
// once its loops have taken 65 535 iterations in all).
var<private> px_centre: vec2<f32>;
var<private> px_opaque: f32;
var<private> px_row_bit: u32;
var<private> px_column_bit: u32;
var<private> px_color: vec3<f32>;
var<private> px_transmittance: f32;
// Still taking fragments: inside the target and above 1/255 transmittance.
var<private> px_open: bool;
// The bin the window holds fragments of.
var<private> px_bin: u32;
// The window, farthest first; an empty slot has depth -1 (nearer than any fragment,
// so an insertion stops there and pushes nothing out).
var<private> w_depth: array<f32, WINDOW>;
var<private> w_id: array<u32, WINDOW>;
var<private> w_color: array<vec4<f32>, WINDOW>;
// The fragment being inserted, then the one pushed out.
var<private> carry_depth: f32;
var<private> carry_id: u32;
var<private> carry_color: vec4<f32>;

// Composites a fragment (colour, alpha) of sort depth `depth` behind what the pixel
// holds, unless the pixel is finished or the fragment an empty slot (depth < 0).
fn blend(depth: f32, f: vec4<f32>) {
    if (px_open && depth >= 0.0) {
        px_color += px_transmittance * f.w * f.rgb;
        px_transmittance *= 1.0 - f.w;
        px_open = px_transmittance >= OPAQUE_ENOUGH;
    }
}

// Composites window slot `k` and empties it.
fn flush_slot(k: u32) {
    blend(w_depth[k], w_color[k]);
    w_depth[k] = -1.0;
}

// The window composited nearest first, and emptied.
fn flush_window() {
    flush_slot(7u);
    flush_slot(6u);
    flush_slot(5u);
    flush_slot(4u);
    flush_slot(3u);
    flush_slot(2u);
    flush_slot(1u);
    flush_slot(0u);
}

// One compare-exchange of the insertion: slot `k` keeps the farther of itself and the
// carry (by depth, then segment index), the nearer goes on.
fn exchange(k: u32) {
    let nearer = carry_depth < w_depth[k] || (carry_depth == w_depth[k] && carry_id < w_id[k]);
    let keep_depth = select(carry_depth, w_depth[k], nearer);
    let keep_id = select(carry_id, w_id[k], nearer);
    let keep_color = select(carry_color, w_color[k], nearer);
    carry_depth = select(w_depth[k], carry_depth, nearer);
    carry_id = select(w_id[k], carry_id, nearer);
    carry_color = select(w_color[k], carry_color, nearer);
    w_depth[k] = keep_depth;
    w_id[k] = keep_id;
    w_color[k] = keep_color;
}

// Entry `e` of the staged batch (of `count`) at this pixel: a new bin flushes the
// window; a fragment goes into the window, and what the window pushes out (the nearest
// of it and the fragment, once it is full) is composited.
fn take_entry(e: u32, count: u32) {
    if (e >= count || !px_open) {
        return;
    }
    let seg_bin = batch_bins[e];
    if (seg_bin != px_bin) {
        flush_window();
        px_bin = seg_bin;
    }
    let mask = batch_masks[e];
    if ((mask & px_row_bit) == 0u || (mask & px_column_bit) == 0u || !px_open) {
        return;
    }
    let seg = batch_segments[e];
    let depth = fragment_depth(seg, px_centre, px_opaque);
    if (depth < 0.0) {
        return;
    }
    let c = segment_coverage(seg, px_centre);
    carry_depth = depth;
    carry_id = batch_ids[e];
    carry_color = vec4<f32>(mix(seg.color_a.rgb, seg.color_b.rgb, c.z), raster.opacity * c.x);
    exchange(0u);
    exchange(1u);
    exchange(2u);
    exchange(3u);
    exchange(4u);
    exchange(5u);
    exchange(6u);
    exchange(7u);
    blend(carry_depth, carry_color);
}

@compute @workgroup_size(TILE, TILE)
fn cs_fine(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let tile_index = wid.x + wid.y * groups.x;
    let tiles = raster.tiles_x * raster.tiles_y;
    let origin = vec2<u32>(tile_index % raster.tiles_x, tile_index / raster.tiles_x) * TILE;
    let px = origin.x + local.x;
    let py = origin.y + local.y;
    let inside = tile_index < tiles && px < raster.width && py < raster.height;
    px_centre = vec2<f32>(f32(px) + 0.5, f32(py) + 0.5);
    px_opaque = far_depth();
    if (inside) {
        px_opaque = textureLoad(opaque_depth, vec2<i32>(i32(px), i32(py)), 0).r;
    }
    px_row_bit = 1u << local.y;
    px_column_bit = 1u << (16u + local.x);
    px_color = vec3<f32>(0.0);
    px_transmittance = 1.0;
    px_open = inside;
    px_bin = 0u;
    w_depth = array<f32, WINDOW>(-1.0, -1.0, -1.0, -1.0, -1.0, -1.0, -1.0, -1.0);
    // The tile's cells are consecutive in the pool, bin after bin: one range.
    if (lid == 0u) {
        var range = vec2<u32>(0u, 0u);
        if (tile_index < tiles) {
            let first = cell_range(tile_index * raster.bins);
            let last = cell_range(tile_index * raster.bins + raster.bins - 1u);
            range = vec2<u32>(first.x, max(first.x, last.y));
        }
        tile_range = range;
        tile_busy = array<u32, 2>(0u, 0u);
    }
    let range = workgroupUniformLoad(&tile_range);
    var parity = 0u;
    for (var done = range.x; done < range.y; done += BATCH) {
        if (px_open) {
            tile_busy[parity] = 1u;
        }
        if (lid == 0u) {
            tile_busy[1u - parity] = 0u;
        }
        let count = min(BATCH, range.y - done);
        if (lid < count) {
            let s = pool[done + lid];
            let seg = raster_segments[s];
            batch_segments[lid] = seg;
            batch_ids[lid] = s;
            batch_bins[lid] = segment_bin(seg);
            batch_masks[lid] = tile_mask(seg, origin);
        }
        if (workgroupUniformLoad(&tile_busy[parity]) == 0u) {
            break;
        }
        parity = 1u - parity;
        // Eight entries per iteration (see px_open's note on lavapipe's loop limit).
        for (var e = 0u; e < count && px_open; e += 8u) {
            take_entry(e, count);
            take_entry(e + 1u, count);
            take_entry(e + 2u, count);
            take_entry(e + 3u, count);
            take_entry(e + 4u, count);
            take_entry(e + 5u, count);
            take_entry(e + 6u, count);
            take_entry(e + 7u, count);
        }
        workgroupBarrier();
    }
    // The last bin's window, nearest first.
    flush_window();
    if (inside) {
        textureStore(composite, vec2<i32>(i32(px), i32(py)), vec4<f32>(px_color, 1.0 - px_transmittance));
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
