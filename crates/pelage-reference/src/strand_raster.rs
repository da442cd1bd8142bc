//! Mirror of the strand rasterizer's binning and compositing
//! (`wgsl/shade/oit/strand_raster.wgsl`: `cs_bin` and `cs_scatter`, `cs_fine`).
//!
//! It starts from the segments the GPU projected (`RasterSegment`, what `cs_bin` writes;
//! `StrandRaster::capture` in pelage-shade reads them back): projection and shading are
//! checked elsewhere. [`bin`] walks every segment's footprint over the screen tiles as
//! `cs_bin` and `cs_scatter` do and lists, per (tile, depth bin) cell, the segments that
//! touch it; [`composite`] runs `cs_fine` pixel by pixel: the tile's cells bin after
//! bin, each pixel keeping the [`WINDOW`] nearest fragments of a bin in order and
//! compositing front to back with analytic coverage, the depth test against the opaque
//! depth, until the transmittance drops below [`OPAQUE_ENOUGH`].
//!
//! Every function follows its WGSL twin in plain `f32` with the same operation order, so
//! the tile lists equal the GPU's exactly and the composite matches within float noise
//! (the GPU stores it as `rgba16float`, and may fuse multiply-adds). The GPU sorts each
//! cell by segment index (`cs_sort`), as [`bin`] lists it, so the mirror's cells and
//! the GPU's give the same picture; the row and column masks `cs_fine` stages with a
//! batch only prune, so the mirror tests every segment at every pixel of the tile.
//!
//! The tile-level early exit of `cs_fine` (a workgroup stops once every pixel of its
//! tile is finished) and its batches skip only pixels that are already finished, so
//! they do not change any pixel.

/// A pixel is finished once its transmittance drops below this (`OPAQUE_ENOUGH`).
pub const OPAQUE_ENOUGH: f32 = 0.003_921_568_6;

/// The most cells [`bin`] and [`composite`] accept: what `StrandRaster::new` allows
/// (`tiles_x * tiles_y * bins <= u32::MAX / 2`).
pub const MAX_CELLS: u64 = u32::MAX as u64 / 2;

/// What [`bin`] and [`composite`] refuse instead of panicking.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum StrandRasterError {
    /// `tiles_x * tiles_y * bins` passes [`MAX_CELLS`] or cannot be allocated.
    #[error("{tiles_x} x {tiles_y} tiles x {bins} bins: too many cells for the mirror")]
    TooManyCells {
        /// Tiles across.
        tiles_x: u32,
        /// Tiles down.
        tiles_y: u32,
        /// Depth bins per tile.
        bins: u32,
    },
    /// `width * height` pixels cannot be allocated.
    #[error("a {width}x{height} composite is too large for the mirror")]
    TooManyPixels {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
    },
    /// [`composite`] was given a number of cells other than `tiles_x * tiles_y * bins`.
    #[error("{given} cells given where the parameters have {expected}")]
    CellCount {
        /// `tiles_x * tiles_y * bins`.
        expected: usize,
        /// The length of the cell lists given.
        given: usize,
    },
    /// [`composite`] was given an opaque depth other than one value per pixel.
    #[error("{given} opaque depths given for {expected} pixels")]
    DepthCount {
        /// `width * height`.
        expected: usize,
        /// The length of the opaque depth given.
        given: usize,
    },
    /// A cell names a segment past the end of the segments.
    #[error("cell {cell} names segment {segment} of {segments}")]
    SegmentIndex {
        /// The cell.
        cell: usize,
        /// The index it holds.
        segment: u32,
        /// The number of segments.
        segments: usize,
    },
}

/// The rasterizer's parameters (`RasterParams` in `strand_raster.wgsl`), less what only
/// the projection and the dispatches use (strands, segments per strand, scan blocks,
/// pixel scale).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterParams {
    /// Target width in pixels.
    pub width: u32,
    /// Target height in pixels.
    pub height: u32,
    /// Tile edge in pixels (`TILE`, 8 or 16 on the GPU).
    pub tile: u32,
    /// Tiles across (`ceil(width / tile)` on the GPU).
    pub tiles_x: u32,
    /// Tiles down (`ceil(height / tile)` on the GPU).
    pub tiles_y: u32,
    /// Depth bins per tile.
    pub bins: u32,
    /// Segment indices the pool holds. [`bin`] lists every reference as a pool large
    /// enough would; which references an overflowing pool keeps depends on the GPU's
    /// atomic order, so the mirror leaves the capacity to the cells it is given.
    pub capacity: u32,
    /// View depth where bin 0 starts.
    pub bin_near: f32,
    /// Bins per unit of view depth.
    pub bin_scale: f32,
    /// Alpha of a strand covering a whole pixel.
    pub opacity: f32,
    /// Depth reversed: nearer is larger, the test is `>` and the far plane is 0.
    pub reverse_z: bool,
}

impl RasterParams {
    /// Cells: `tiles_x * tiles_y * bins`, or an error past [`MAX_CELLS`].
    pub fn cell_count(&self) -> Result<usize, StrandRasterError> {
        let cells = u128::from(self.tiles_x) * u128::from(self.tiles_y) * u128::from(self.bins);
        if cells > u128::from(MAX_CELLS) {
            return Err(self.too_many_cells());
        }
        usize::try_from(cells).map_err(|_| self.too_many_cells())
    }

    /// The cell of tile (`tile_x`, `tile_y`) and `bin`: `(tile_y * tiles_x + tile_x) *
    /// bins + bin`, in wrapping `u32` arithmetic as the WGSL computes it (no wrap for
    /// parameters within [`MAX_CELLS`]).
    pub fn cell(&self, tile_x: u32, tile_y: u32, bin: u32) -> usize {
        tile_y
            .wrapping_mul(self.tiles_x)
            .wrapping_add(tile_x)
            .wrapping_mul(self.bins)
            .wrapping_add(bin) as usize
    }

    fn too_many_cells(&self) -> StrandRasterError {
        StrandRasterError::TooManyCells {
            tiles_x: self.tiles_x,
            tiles_y: self.tiles_y,
            bins: self.bins,
        }
    }
}

/// A projected segment (`RasterSegment` in `strand_raster.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterSegment {
    /// First end: x and y in pixels (y down), window depth, half width in pixels
    /// (negative: culled).
    pub a: [f32; 4],
    /// Second end, as `a`.
    pub b: [f32; 4],
    /// First end's linear RGB radiance and 1 / view depth.
    pub color_a: [f32; 4],
    /// Second end's, as `color_a`.
    pub color_b: [f32; 4],
}

impl From<[f32; 16]> for RasterSegment {
    /// From the 16 floats the GPU stores: `a`, `b`, `color_a`, `color_b`.
    fn from(v: [f32; 16]) -> Self {
        let part = |i: usize| [v[i], v[i + 1], v[i + 2], v[i + 3]];
        Self {
            a: part(0),
            b: part(4),
            color_a: part(8),
            color_b: part(12),
        }
    }
}

impl RasterSegment {
    /// Whether `cs_bin` culled it (clipped away entirely): `a[3] < 0`. `cs_scatter`
    /// skips it, so it is in no cell.
    pub fn culled(&self) -> bool {
        self.a[3] < 0.0
    }
}

/// WGSL `mix`: `a * (1 - t) + b * t`.
fn mix(a: f32, b: f32, t: f32) -> f32 {
    crate::noise::mix(a, b, t)
}

/// WGSL `clamp(v, lo, hi)`: `min(max(v, lo), hi)`.
fn clamp(v: f32, lo: f32, hi: f32) -> f32 {
    v.max(lo).min(hi)
}

/// WGSL `f32` to `i32`: toward zero, saturating (NaN to 0, as Rust's `as`).
fn to_i32(v: f32) -> i32 {
    v as i32
}

/// `segment_key`: the view depth at the segment's midpoint, the sort key.
pub fn segment_key(seg: &RasterSegment) -> f32 {
    0.5 * (seg.color_a[3] + seg.color_b[3])
}

/// `segment_bin`: `clamp(floor((key - bin_near) * bin_scale), 0, bins - 1)`.
pub fn segment_bin(params: &RasterParams, seg: &RasterSegment) -> u32 {
    let b = ((segment_key(seg) - params.bin_near) * params.bin_scale).floor();
    // `bins - 1u` wraps at 0 bins on the GPU; the mirror has no cells then anyway.
    let last = params.bins.wrapping_sub(1) as f32;
    // f32 to u32: toward zero, saturating (NaN to 0).
    clamp(b, 0.0, last) as u32
}

/// `segment_reach`: the widest half width plus half a pixel, in pixels.
pub fn segment_reach(seg: &RasterSegment) -> f32 {
    seg.a[3].max(seg.b[3]) + 0.5
}

/// `segment_rows`: the tile rows `[y0, y1]` the segment widened by `r` touches (`y0 >
/// y1`: none).
pub fn segment_rows(params: &RasterParams, seg: &RasterSegment, r: f32) -> [i32; 2] {
    let tile = params.tile as f32;
    let y0 = to_i32(((seg.a[1].min(seg.b[1]) - r) / tile).floor());
    let y1 = to_i32(((seg.a[1].max(seg.b[1]) + r) / tile).floor());
    [y0.max(0), y1.min((params.tiles_y as i32).wrapping_sub(1))]
}

/// `row_columns`: the tile columns `[x0, x1]` of tile row `row` that the segment
/// widened by `r` touches (`x0 > x1`: none).
pub fn row_columns(params: &RasterParams, seg: &RasterSegment, r: f32, row: u32) -> [i32; 2] {
    let y_lo = row.wrapping_mul(params.tile) as f32 - r;
    let y_hi = row.wrapping_add(1).wrapping_mul(params.tile) as f32 + r;
    let dy = seg.b[1] - seg.a[1];
    let mut t = [0.0f32, 1.0];
    if dy.abs() > 1e-6 {
        let t_lo = (y_lo - seg.a[1]) / dy;
        let t_hi = (y_hi - seg.a[1]) / dy;
        t = [0.0f32.max(t_lo.min(t_hi)), 1.0f32.min(t_lo.max(t_hi))];
    }
    if t[0] > t[1] {
        return [1, 0];
    }
    let xa = mix(seg.a[0], seg.b[0], t[0]);
    let xb = mix(seg.a[0], seg.b[0], t[1]);
    let tile = params.tile as f32;
    let x0 = to_i32(((xa.min(xb) - r) / tile).floor());
    let x1 = to_i32(((xa.max(xb) + r) / tile).floor());
    [x0.max(0), x1.min((params.tiles_x as i32).wrapping_sub(1))]
}

/// `cs_tile_depth`: per screen tile (row-major), the farthest opaque depth over its
/// pixels inside the target (`opaque_depth`, row-major, one value per pixel).
///
/// Errors when `opaque_depth` is not one value per pixel or the tiles cannot be
/// allocated.
pub fn tile_depths(
    params: &RasterParams,
    opaque_depth: &[f32],
) -> Result<Vec<f32>, StrandRasterError> {
    let pixels = u64::from(params.width) * u64::from(params.height);
    if opaque_depth.len() as u64 != pixels {
        return Err(StrandRasterError::DepthCount {
            expected: usize::try_from(pixels).unwrap_or(usize::MAX),
            given: opaque_depth.len(),
        });
    }
    let tiles = u64::from(params.tiles_x) * u64::from(params.tiles_y);
    let tiles = usize::try_from(tiles)
        .ok()
        .filter(|&t| t as u64 <= MAX_CELLS)
        .ok_or_else(|| params.too_many_cells())?;
    let mut out: Vec<f32> = Vec::new();
    out.try_reserve_exact(tiles)
        .map_err(|_| params.too_many_cells())?;
    let farther = |a: f32, b: f32| if params.reverse_z { a < b } else { a > b };
    for t in 0..tiles {
        let (tx, ty) = (
            t as u64 % u64::from(params.tiles_x.max(1)),
            t as u64 / u64::from(params.tiles_x.max(1)),
        );
        let tile = u64::from(params.tile);
        let (x0, y0) = (tx * tile, ty * tile);
        let x1 = (x0 + tile).min(u64::from(params.width));
        let y1 = (y0 + tile).min(u64::from(params.height));
        let mut deepest = if params.reverse_z { 2.0 } else { -1.0 };
        for y in y0..y1 {
            for x in x0..x1 {
                let z = opaque_depth[(y * u64::from(params.width) + x) as usize];
                if farther(z, deepest) {
                    deepest = z;
                }
            }
        }
        out.push(deepest);
    }
    Ok(out)
}

/// `cs_bin` and `cs_scatter`: per cell (`(tile_y * tiles_x + tile_x) * bins + bin`), the
/// indices of the segments whose widened footprint touches it, less the tiles whose
/// opaque surface (the farthest of `opaque_depth` over the tile, [`tile_depths`]) is in
/// front of the whole segment, in ascending order (the GPU's pool holds them so after
/// `cs_sort`). Culled segments are in no cell; every reference is listed, whatever
/// `params.capacity` (see [`RasterParams::capacity`]).
///
/// Errors when the cells pass [`MAX_CELLS`] or cannot be allocated, or `opaque_depth`
/// is not one value per pixel.
pub fn bin(
    params: &RasterParams,
    segments: &[RasterSegment],
    opaque_depth: &[f32],
) -> Result<Vec<Vec<u32>>, StrandRasterError> {
    let count = params.cell_count()?;
    let depths = tile_depths(params, opaque_depth)?;
    let mut cells: Vec<Vec<u32>> = Vec::new();
    cells
        .try_reserve_exact(count)
        .map_err(|_| params.too_many_cells())?;
    cells.resize_with(count, Vec::new);
    if count == 0 {
        return Ok(cells);
    }
    for (s, seg) in segments.iter().enumerate() {
        if seg.culled() {
            continue;
        }
        // Indices past u32 cannot come from the GPU; the mirror stops there.
        let Ok(index) = u32::try_from(s) else { break };
        let bin = segment_bin(params, seg);
        let r = segment_reach(seg);
        let rows = segment_rows(params, seg, r);
        let nearest = if params.reverse_z {
            seg.a[2].max(seg.b[2])
        } else {
            seg.a[2].min(seg.b[2])
        };
        for row in rows[0]..=rows[1] {
            let cols = row_columns(params, seg, r, row as u32);
            for col in cols[0]..=cols[1] {
                let t = (row as u32)
                    .wrapping_mul(params.tiles_x)
                    .wrapping_add(col as u32) as usize;
                let hidden = depths.get(t).is_some_and(|&opaque| {
                    if params.reverse_z {
                        nearest <= opaque
                    } else {
                        nearest >= opaque
                    }
                });
                if hidden {
                    continue;
                }
                let cell = params.cell(col as u32, row as u32, bin);
                if let Some(list) = cells.get_mut(cell) {
                    list.push(index);
                }
            }
        }
    }
    Ok(cells)
}

/// `segment_coverage`: the coverage of the pixel centred at `p` by the segment, its
/// window depth there and the perspective-correct parameter: `[coverage, depth, t]`,
/// coverage 0 outside it (half open along the segment: `u` in `[0, 1)`).
pub fn segment_coverage(seg: &RasterSegment, p: [f32; 2]) -> [f32; 3] {
    let d = [seg.b[0] - seg.a[0], seg.b[1] - seg.a[1]];
    let len2 = d[0] * d[0] + d[1] * d[1];
    let mut u = 0.0f32;
    if len2 > 1e-12 {
        let pa = [p[0] - seg.a[0], p[1] - seg.a[1]];
        u = (pa[0] * d[0] + pa[1] * d[1]) / len2;
        // Half open, so consecutive segments share no pixel at their joint. Not
        // `!(0.0..1.0).contains(&u)`: a NaN `u` goes on, as in the WGSL.
        #[allow(clippy::manual_range_contains)]
        if u < 0.0 || u >= 1.0 {
            return [0.0; 3];
        }
    }
    let e = [p[0] - (seg.a[0] + u * d[0]), p[1] - (seg.a[1] + u * d[1])];
    let dist = (e[0] * e[0] + e[1] * e[1]).sqrt();
    let half_width = mix(seg.a[3], seg.b[3], u);
    let coverage = clamp(
        (dist + half_width).min(0.5) - (dist - half_width).max(-0.5),
        0.0,
        1.0,
    );
    let inv_b = 1.0 / seg.color_b[3];
    let inv_w = mix(1.0 / seg.color_a[3], inv_b, u);
    let t = if inv_w > 0.0 { u * inv_b / inv_w } else { 0.0 };
    [coverage, mix(seg.a[2], seg.b[2], u), t]
}

/// `cs_fine` for every pixel: per pixel (row-major) the premultiplied linear colour
/// and 1 - transmittance, what the GPU stores in its `rgba16float` composite.
///
/// `cells` holds every cell's segment indices in the order the pool does (the GPU's
/// lists from `StrandRaster::capture`, sorted by `cs_sort`, or [`bin`]'s, also
/// ascending): a tile's cells read bin after bin are its sequence of segments. Each
/// pixel walks the sequence; a segment puts a fragment into it when
/// [`fragment_depth`] says so (projection onto the segment in `[0, 1)`, distance below
/// the half width plus half a pixel, in front of the opaque depth), with the colour
/// and alpha of [`segment_coverage`]. The pixel keeps the [`WINDOW`] nearest fragments
/// of the current bin, ordered by (depth, segment index); a fragment arriving when the
/// window is full pushes the nearest of the window and itself out and that one is
/// composited front to back; when the bin changes and at the end the window is
/// composited nearest first. The pixel takes nothing more once its transmittance drops
/// below [`OPAQUE_ENOUGH`]. `opaque_depth` is the window depth of the opaque scene per
/// pixel, row-major. Pixels outside the tiles stay zero, as the GPU leaves them
/// unwritten.
///
/// Errors when `cells` is not one list per cell, `opaque_depth` not one value per
/// pixel, a cell names a segment past `segments`, or the sizes cannot be allocated.
pub fn composite(
    params: &RasterParams,
    segments: &[RasterSegment],
    cells: &[Vec<u32>],
    opaque_depth: &[f32],
) -> Result<Vec<[f32; 4]>, StrandRasterError> {
    let cell_count = params.cell_count()?;
    if cells.len() != cell_count {
        return Err(StrandRasterError::CellCount {
            expected: cell_count,
            given: cells.len(),
        });
    }
    let too_many_pixels = StrandRasterError::TooManyPixels {
        width: params.width,
        height: params.height,
    };
    let pixels = usize::try_from(u64::from(params.width) * u64::from(params.height))
        .map_err(|_| too_many_pixels.clone())?;
    if opaque_depth.len() != pixels {
        return Err(StrandRasterError::DepthCount {
            expected: pixels,
            given: opaque_depth.len(),
        });
    }
    for (c, list) in cells.iter().enumerate() {
        if let Some(&s) = list.iter().find(|&&s| s as usize >= segments.len()) {
            return Err(StrandRasterError::SegmentIndex {
                cell: c,
                segment: s,
                segments: segments.len(),
            });
        }
    }
    let mut out: Vec<[f32; 4]> = Vec::new();
    out.try_reserve_exact(pixels)
        .map_err(|_| too_many_pixels.clone())?;
    out.resize(pixels, [0.0; 4]);
    if params.tile == 0 || params.tile > 16 {
        return Ok(out);
    }
    for tile_y in 0..params.tiles_y {
        for tile_x in 0..params.tiles_x {
            let sequence: Vec<(u32, &RasterSegment)> = (0..params.bins)
                .flat_map(|bin| cells[params.cell(tile_x, tile_y, bin)].iter())
                .map(|&s| (s, &segments[s as usize]))
                .collect();
            for y in 0..params.tile {
                for x in 0..params.tile {
                    let (px, py) = (tile_x * params.tile + x, tile_y * params.tile + y);
                    if px < params.width && py < params.height {
                        let index = py as usize * params.width as usize + px as usize;
                        let centre = [px as f32 + 0.5, py as f32 + 0.5];
                        out[index] =
                            composite_pixel(params, &sequence, centre, opaque_depth[index]);
                    }
                }
            }
        }
    }
    Ok(out)
}

/// Fragments a pixel's window holds (`WINDOW`): the order within a bin is exact
/// wherever a pixel gets at most this many fragments from it.
pub const WINDOW: usize = 8;

/// A fragment in a pixel's window: sort depth (nearer is smaller; negative: an empty
/// slot), segment index, linear colour and alpha.
#[derive(Clone, Copy)]
struct Fragment {
    depth: f32,
    id: u32,
    color: [f32; 4],
}

const EMPTY: Fragment = Fragment {
    depth: -1.0,
    id: 0,
    color: [0.0; 4],
};

/// The front-to-back state of one pixel.
struct Blend {
    color: [f32; 3],
    transmittance: f32,
    open: bool,
}

impl Blend {
    /// Composites `f` behind what the pixel holds, unless the pixel is finished or `f`
    /// is an empty slot.
    fn take(&mut self, f: &Fragment) {
        if self.open && f.depth >= 0.0 {
            let weight = self.transmittance * f.color[3];
            for (k, channel) in self.color.iter_mut().enumerate() {
                *channel += weight * f.color[k];
            }
            self.transmittance *= 1.0 - f.color[3];
            self.open = self.transmittance >= OPAQUE_ENOUGH;
        }
    }
}

/// `fragment_depth`: the sort depth of the fragment `seg` puts into the pixel centred
/// at `centre` in front of `opaque` (nearer is smaller, never negative), or `None`.
pub fn fragment_depth(
    params: &RasterParams,
    seg: &RasterSegment,
    centre: [f32; 2],
    opaque: f32,
) -> Option<f32> {
    let d = [seg.b[0] - seg.a[0], seg.b[1] - seg.a[1]];
    let len2 = d[0] * d[0] + d[1] * d[1];
    let inv_len2 = if len2 > 1e-12 { 1.0 / len2 } else { 0.0 };
    let q = [centre[0] - seg.a[0], centre[1] - seg.a[1]];
    let mut u = 0.0f32;
    if len2 > 1e-12 {
        u = (q[0] * d[0] + q[1] * d[1]) * inv_len2;
        #[allow(clippy::manual_range_contains)]
        if u < 0.0 || u >= 1.0 {
            return None;
        }
    }
    let cross = q[0] * d[1] - q[1] * d[0];
    let reach = mix(seg.a[3], seg.b[3], u) + 0.5;
    if cross * cross * inv_len2 >= reach * reach {
        return None;
    }
    let z = mix(seg.a[2], seg.b[2], u);
    let in_front = if params.reverse_z {
        z > opaque
    } else {
        z < opaque
    };
    if !in_front {
        return None;
    }
    let near_first = if params.reverse_z { 1.0 - z } else { z };
    Some(near_first.max(0.0))
}

/// `cs_fine` for one pixel: the tile's `sequence` of (segment index, segment) in pool
/// order, as [`composite`] describes.
fn composite_pixel(
    params: &RasterParams,
    sequence: &[(u32, &RasterSegment)],
    centre: [f32; 2],
    opaque: f32,
) -> [f32; 4] {
    let mut blend = Blend {
        color: [0.0; 3],
        transmittance: 1.0,
        open: true,
    };
    // Farthest first; empty slots (depth -1) are nearer than any fragment.
    let mut window = [EMPTY; WINDOW];
    let mut bin = 0u32;
    for &(id, seg) in sequence {
        if !blend.open {
            break;
        }
        let seg_bin = segment_bin(params, seg);
        if seg_bin != bin {
            for f in window.iter_mut().rev() {
                blend.take(f);
                *f = EMPTY;
            }
            bin = seg_bin;
        }
        if !blend.open {
            continue;
        }
        let Some(depth) = fragment_depth(params, seg, centre, opaque) else {
            continue;
        };
        let c = segment_coverage(seg, centre);
        let mut carry = Fragment {
            depth,
            id,
            color: [
                mix(seg.color_a[0], seg.color_b[0], c[2]),
                mix(seg.color_a[1], seg.color_b[1], c[2]),
                mix(seg.color_a[2], seg.color_b[2], c[2]),
                params.opacity * c[0],
            ],
        };
        for slot in window.iter_mut() {
            let nearer =
                carry.depth < slot.depth || (carry.depth == slot.depth && carry.id < slot.id);
            if !nearer {
                std::mem::swap(&mut carry, slot);
            }
        }
        blend.take(&carry);
    }
    for f in window.iter().rev() {
        blend.take(f);
    }
    [
        blend.color[0],
        blend.color[1],
        blend.color[2],
        1.0 - blend.transmittance,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(tile: u32, bins: u32) -> RasterParams {
        RasterParams {
            width: 32,
            height: 24,
            tile,
            tiles_x: 32u32.div_ceil(tile),
            tiles_y: 24u32.div_ceil(tile),
            bins,
            capacity: 1 << 16,
            bin_near: 1.0,
            bin_scale: 1.0,
            opacity: 0.5,
            reverse_z: false,
        }
    }

    /// A segment from (x0, y0) to (x1, y1) at view depth `w`, half width `hw` pixels.
    fn segment(
        x0: f32,
        y0: f32,
        x1: f32,
        y1: f32,
        w: f32,
        hw: f32,
        rgb: [f32; 3],
    ) -> RasterSegment {
        // Window depth increasing with the view depth w, as a perspective projection's.
        let z = 1.0 - 1.0 / w;
        RasterSegment {
            a: [x0, y0, z, hw],
            b: [x1, y1, z, hw],
            color_a: [rgb[0], rgb[1], rgb[2], w],
            color_b: [rgb[0], rgb[1], rgb[2], w],
        }
    }

    #[test]
    fn a_horizontal_segment_touches_the_tiles_it_crosses() {
        let p = params(8, 2);
        // From x = 2 to 20 on y = 4, half width 1: reach 1.5, so x in [0.5, 21.5] and
        // y in [2.5, 5.5]: tile row 0, columns 0..=2. View depth 2.5: bin 1.
        let seg = segment(2.0, 4.0, 20.0, 4.0, 2.5, 1.0, [1.0; 3]);
        let culled = RasterSegment {
            a: [0.0, 0.0, 0.0, -1.0],
            ..seg
        };
        let cells = bin(&p, &[seg, culled], &[1.0; 32 * 24]).unwrap();
        let touched: Vec<usize> = (0..cells.len()).filter(|&c| !cells[c].is_empty()).collect();
        assert_eq!(
            touched,
            vec![p.cell(0, 0, 1), p.cell(1, 0, 1), p.cell(2, 0, 1)]
        );
        assert!(touched.iter().all(|&c| cells[c] == vec![0]));
        // The segment is at window depth 0.6: an opaque surface at 0.5 over tile 1
        // (pixels 8..16 of rows 0..8) hides it there, unless one pixel of the tile is
        // open to the far plane.
        let mut depth = vec![1.0; 32 * 24];
        for x in 8..16 {
            for y in 0..8 {
                if (x, y) != (15, 7) {
                    depth[y * 32 + x] = 0.5;
                }
            }
        }
        let cells = bin(&p, &[seg], &depth).unwrap();
        assert_eq!(cells[p.cell(1, 0, 1)], vec![0], "one pixel is behind it");
        depth[7 * 32 + 15] = 0.5;
        let cells = bin(&p, &[seg], &depth).unwrap();
        assert!(cells[p.cell(1, 0, 1)].is_empty(), "hidden in tile 1");
        assert_eq!(cells[p.cell(0, 0, 1)], vec![0]);
        assert_eq!(cells[p.cell(2, 0, 1)], vec![0]);
    }

    #[test]
    fn nearer_segments_composite_first_and_depth_tests_apply() {
        let p = params(16, 1);
        let red = segment(0.0, 8.5, 32.0, 8.5, 2.0, 2.0, [1.0, 0.0, 0.0]);
        let blue = segment(0.0, 8.5, 32.0, 8.5, 3.0, 2.0, [0.0, 0.0, 1.0]);
        let segments = [blue, red];
        let cells = bin(&p, &segments, &[1.0; 32 * 24]).unwrap();
        let depth = vec![1.0; 32 * 24];
        let image = composite(&p, &segments, &cells, &depth).unwrap();
        // Pixel (5, 8): fully covered by both; red in front: 0.5 red, 0.25 blue.
        assert_eq!(image[8 * 32 + 5], [0.5, 0.0, 0.25, 0.75]);
        // Far from the line: nothing.
        assert_eq!(image[20 * 32 + 5], [0.0; 4]);
        // Everything behind an opaque depth of 0.25 (the segments are at 0.5 and 0.67).
        let near = vec![0.25; 32 * 24];
        let hidden = composite(&p, &segments, &cells, &near).unwrap();
        assert!(hidden.iter().all(|px| *px == [0.0; 4]));
        // Reverse-Z: nearer is larger, the test flips.
        let reversed = RasterParams {
            reverse_z: true,
            ..p
        };
        let flip = |mut s: RasterSegment| {
            s.a[2] = 1.0 - s.a[2];
            s.b[2] = 1.0 - s.b[2];
            s
        };
        let flipped = [flip(blue), flip(red)];
        let far = vec![0.0; 32 * 24];
        assert_eq!(
            composite(&reversed, &flipped, &cells, &far).unwrap()[8 * 32 + 5],
            [0.5, 0.0, 0.25, 0.75]
        );
        // Behind an opaque depth of 0.75 (the flipped segments are at 0.5 and 0.33).
        let near_reversed = vec![0.75; 32 * 24];
        assert!(
            composite(&reversed, &flipped, &cells, &near_reversed)
                .unwrap()
                .iter()
                .all(|px| *px == [0.0; 4])
        );
    }

    #[test]
    fn malformed_inputs_are_errors_not_panics() {
        let p = params(8, 4);
        let seg = segment(0.0, 0.0, 10.0, 10.0, 2.0, 1.0, [1.0; 3]);
        let depth = vec![1.0; 32 * 24];
        let cells = bin(&p, &[seg], &depth).unwrap();
        assert!(matches!(
            composite(&p, &[seg], &cells[1..], &depth),
            Err(StrandRasterError::CellCount { .. })
        ));
        assert!(matches!(
            composite(&p, &[seg], &cells, &depth[1..]),
            Err(StrandRasterError::DepthCount { .. })
        ));
        assert!(matches!(
            composite(&p, &[], &cells, &depth),
            Err(StrandRasterError::SegmentIndex { .. })
        ));
        let huge = RasterParams {
            tiles_x: u32::MAX,
            tiles_y: u32::MAX,
            ..p
        };
        assert!(bin(&huge, &[seg], &depth).is_err());
        assert!(matches!(
            bin(&p, &[seg], &depth[1..]),
            Err(StrandRasterError::DepthCount { .. })
        ));
        // Degenerate parameters and segments: no panic.
        for q in [
            RasterParams { tile: 0, ..p },
            RasterParams { bins: 0, ..p },
            RasterParams {
                tiles_x: 0,
                tiles_y: 0,
                ..p
            },
            RasterParams {
                bin_scale: f32::NAN,
                ..p
            },
        ] {
            let nan = segment(f32::NAN, 0.0, f32::INFINITY, 1e30, 0.0, f32::NAN, [1.0; 3]);
            let cells = bin(&q, &[seg, nan], &depth).unwrap();
            let _ = composite(&q, &[seg, nan], &cells, &depth).unwrap();
        }
    }
}
