//! The strand rasterizer: hair drawn in compute, without the raster pipeline and with
//! 32-bit atomics only (`shade/oit/strand_raster.wgsl`, which lists the passes).
//!
//! Per frame: every strand vertex is projected and shaded once; every segment is
//! clipped, projected and counted into the (screen tile, depth bin) cells its footprint
//! touches; a prefix sum turns the counts into offsets in a pool of segment indices the
//! caller sizes; the segments are scattered into it and each cell sorted by segment
//! index (so every run reads the same order); one workgroup per tile, one thread per
//! pixel, takes its segments bin after bin (front to back) in batches staged in
//! workgroup memory: each thread tests its own pixel against each segment (analytic
//! coverage: the pixel centre's distance to the centre line against the projected half
//! width), keeps the nearest few fragments of the bin in a window in registers and
//! composites front to back; a full-screen pass blends the result over the colour
//! target.
//!
//! What shading once per vertex loses against shading per fragment: the shading model
//! is evaluated at the strand's centre line at each vertex and interpolated along the
//! segment, so a highlight narrower than a segment is blurred along it, and the view
//! direction does not vary across the strand's width (it does not across a ribbon a
//! pixel wide either). The OIT lab measures the lit pictures against the per-fragment
//! exact composite, and the flat ones (no shading) against a true-width reference.
//!
//! Memory: 8 bytes per pixel (the composite, `rgba16float`), 8 bytes per (tile, bin)
//! cell (counts, offsets) and 4 per 1024 cells (block sums), 4 per tile (its opaque
//! depth), 32 bytes per strand
//! vertex, 64 per segment, 4 per pool entry.
//!
//! The pool follows vello's pattern: the scan records the size a frame needed in a
//! header; [`StrandRaster`] reads it back a frame later (a buffer mapped when the
//! caller's submission completes, never waited for) and grows the pool before the next
//! frame it records. A frame that overflows draws the references that fit and counts
//! the rest ([`HairPass::stats`]).

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::{Arc, Mutex};

use encase::ShaderType;
use glam::Vec3;
use pelage_contract::{StrandFrame, StrandLayout};
use pelage_gpu::{
    BindLayout, Gpu, GpuError, GpuTimer, PassInfo, UniformBuffer, wgpu, zeroed_storage,
};
use pelage_scene::{CameraMatrices, Light};

use super::{HairPass, OitStats};
use crate::draw::{
    Common, Draw, HairInputs, OIT_STORAGE, RasterDesc, TARGET_COLOR, TARGET_DEPTH, TargetViews,
    Vertices, over_target, raster_pipeline,
};

/// Cells per scan block (`SCAN_BLOCK` in the WGSL).
const SCAN_BLOCK: u64 = 1024;
/// Threads per workgroup of the per-vertex and per-segment passes.
const LINE_GROUP: u64 = 64;
/// Bytes of a shaded vertex (`ShadedVertex`).
const SHADED_BYTES: u64 = 32;
/// Bytes of a projected segment (`RasterSegment`).
const SEGMENT_BYTES: u64 = 64;
/// Bytes of the composite per pixel (`rgba16float`).
const COMPOSITE_BYTES: u64 = 8;
/// Bytes of the header (`Header`: five `u32`).
const HEADER_BYTES: u64 = 20;

/// The method's constants and this frame's layout (`RasterParams` in
/// `shade/oit/strand_raster.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, ShaderType)]
pub struct StrandRasterUniforms {
    /// Target width in pixels.
    pub width: u32,
    /// Target height in pixels.
    pub height: u32,
    /// Tile edge in pixels.
    pub tile: u32,
    /// Tiles across.
    pub tiles_x: u32,
    /// Tiles down.
    pub tiles_y: u32,
    /// Depth bins per tile.
    pub bins: u32,
    /// Segment indices the pool holds.
    pub capacity: u32,
    /// Strands grown this frame.
    pub strands: u32,
    /// Segments per strand this frame.
    pub segments: u32,
    /// Scan blocks over the cells.
    pub scan_blocks: u32,
    /// View depth where bin 0 starts.
    pub bin_near: f32,
    /// Bins per unit of view depth.
    pub bin_scale: f32,
    /// Alpha of a strand covering a whole pixel.
    pub opacity: f32,
    /// World units per pixel at view depth 1.
    pub pixel_scale: f32,
    /// 1 when depth is reversed.
    pub reverse_z: u32,
    /// Padding.
    pub _pad: u32,
}

/// The compute passes in recording order: (label, entry point, `@group(3)` bindings).
const PASSES: [(&str, &str, &[u32]); 9] = [
    ("shade: strand raster shade", "cs_shade", &[0, 1]),
    (
        "shade: strand raster tile depth",
        "cs_tile_depth",
        &[0, 8, 11],
    ),
    // cs_bin and cs_scatter share walk_cells, which names offsets, the pool and the
    // tiles' depths.
    (
        "shade: strand raster bin",
        "cs_bin",
        &[0, 1, 2, 3, 4, 5, 11],
    ),
    (
        "shade: strand raster scan reduce",
        "cs_scan_reduce",
        &[0, 3, 6],
    ),
    ("shade: strand raster scan top", "cs_scan_top", &[0, 6, 7]),
    (
        "shade: strand raster scan apply",
        "cs_scan_apply",
        &[0, 3, 4, 6],
    ),
    (
        "shade: strand raster scatter",
        "cs_scatter",
        &[0, 2, 3, 4, 5, 11],
    ),
    ("shade: strand raster sort", "cs_sort", &[0, 3, 4, 5, 7]),
    (
        "shade: strand raster fine",
        "cs_fine",
        &[0, 2, 3, 4, 5, 8, 9],
    ),
];
const RESOLVE: &str = "shade: strand raster resolve";

/// How one pass is dispatched.
#[derive(Clone, Copy, Debug)]
enum Grid {
    /// One thread per strand vertex of this frame.
    Vertices,
    /// One thread per segment of this frame.
    Segments,
    /// One workgroup per scan block.
    Blocks,
    /// One workgroup.
    One,
    /// One thread per (tile, bin) cell.
    Cells,
    /// One thread per tile.
    TileThreads,
    /// One workgroup per tile.
    Tiles,
}

const GRIDS: [Grid; 9] = [
    Grid::Vertices,
    Grid::TileThreads,
    Grid::Segments,
    Grid::Blocks,
    Grid::One,
    Grid::Blocks,
    Grid::Segments,
    Grid::Cells,
    Grid::Tiles,
];

/// The `@group(3)` layout of a pass using `bindings` (see the WGSL's declarations).
fn raster_layout(label: &str, bindings: &[u32]) -> BindLayout {
    bindings.iter().fold(
        BindLayout::new(label, wgpu::ShaderStages::COMPUTE),
        |layout, &binding| match binding {
            0 => layout.uniform(0),
            8 => layout.texture_2d(8, wgpu::TextureSampleType::Float { filterable: false }),
            9 => layout.entry(
                9,
                wgpu::BindingType::StorageTexture {
                    access: wgpu::StorageTextureAccess::WriteOnly,
                    format: wgpu::TextureFormat::Rgba16Float,
                    view_dimension: wgpu::TextureViewDimension::D2,
                },
            ),
            _ => layout.storage_rw(binding),
        },
    )
}

/// Workgroups for `n` in a grid no side of which passes `max` (2-D past it).
fn grid(n: u64, max: u32) -> Option<(u32, u32)> {
    if n == 0 {
        return Some((0, 0));
    }
    let max = u64::from(max.max(1));
    let x = n.min(max);
    let y = n.div_ceil(x);
    (y <= max).then_some((x as u32, y as u32))
}

/// A readback of the header, mapped when the submission that copied it completes.
#[derive(Debug)]
struct Readback {
    buffer: wgpu::Buffer,
    /// [`IDLE`], [`PENDING`], [`READY`] or [`FAILED`].
    state: Arc<AtomicU8>,
}

const IDLE: u8 = 0;
const PENDING: u8 = 1;
const READY: u8 = 2;
const FAILED: u8 = 3;

/// The pool and the bind groups that name it (rebuilt when it grows or the caller's
/// depth view changes).
#[derive(Debug)]
struct PoolState {
    buffer: wgpu::Buffer,
    capacity: u32,
    /// The depth view the groups sample and the groups (one per compute pass).
    groups: Option<(wgpu::TextureView, Arc<Vec<wgpu::BindGroup>>)>,
    /// The largest size a frame needed, as read back.
    peak_seen: u32,
}

/// Buffers of fixed size.
#[derive(Debug)]
struct Storage {
    shaded: wgpu::Buffer,
    segments: wgpu::Buffer,
    counts: wgpu::Buffer,
    offsets: wgpu::Buffer,
    block_sums: wgpu::Buffer,
    header: wgpu::Buffer,
    tile_depth: wgpu::Buffer,
    composite: wgpu::Texture,
    composite_view: wgpu::TextureView,
}

impl Storage {
    /// Names every buffer and view the method's passes bind `oit.storage` for an audit
    /// (`pelage_gpu::audit`).
    fn name_for_audit(&self) {
        for buffer in [
            &self.shaded,
            &self.segments,
            &self.counts,
            &self.offsets,
            &self.block_sums,
            &self.header,
            &self.tile_depth,
        ] {
            pelage_gpu::audit::name_buffer(buffer, crate::OIT_STORAGE);
        }
        pelage_gpu::audit::name_view(&self.composite_view, crate::OIT_STORAGE);
    }
}

/// What [`StrandRaster::capture`] reads back.
#[derive(Clone, Debug, PartialEq)]
pub struct RasterCapture {
    /// The uniforms of the frame.
    pub uniforms: StrandRasterUniforms,
    /// Every segment of the frame as `cs_bin` projected it (`RasterSegment`: `a`, `b`,
    /// `color_a`, `color_b`, four floats each; `a[3] < 0` for a culled segment).
    pub segments: Vec<[f32; 16]>,
    /// Per cell (`(tile_y * tiles_x + tile_x) * bins + bin`), the segment indices the
    /// pool holds, in the order `cs_scatter` wrote them (atomic order: not sorted).
    pub cells: Vec<Vec<u32>>,
    /// Per pixel, row-major: premultiplied linear colour and 1 - transmittance.
    pub composite: Vec<[f32; 4]>,
}

/// The strand rasterizer (see the module documentation).
#[derive(Debug)]
pub struct StrandRaster {
    common: Common,
    uniforms_value: StrandRasterUniforms,
    uniforms: UniformBuffer<StrandRasterUniforms>,
    storage: Storage,
    pool: Mutex<PoolState>,
    /// Compute pipelines in the order of [`PASSES`], with their `@group(3)` layouts.
    pipelines: Vec<(wgpu::ComputePipeline, wgpu::BindGroupLayout)>,
    /// Groups 0 (strands, frame, visibility) and 2 (the shading model) of `cs_shade`.
    shade_groups: [Option<wgpu::BindGroup>; 3],
    resolve: Draw,
    resolve_group: wgpu::BindGroup,
    readbacks: [Readback; 2],
    /// The uniforms `prepare` last wrote (the pool's growth rewrites their capacity).
    prepared: Mutex<StrandRasterUniforms>,
    /// The strands' box, for the depth range of the bins.
    reach: (Vec3, Vec3),
    width: u32,
    height: u32,
    max_pool: u32,
    /// The device the compute passes' bind groups are built on (the first frame, a new
    /// depth view, a grown pool): recording takes no device.
    gpu: Gpu,
}

impl StrandRaster {
    /// Builds the rasterizer for `width` x `height` targets (single-sampled) with tiles
    /// of `tile` pixels, `bins` depth bins and a pool of `pool` references per segment.
    pub fn new(
        gpu: &Gpu,
        inputs: &HairInputs<'_>,
        tile: u32,
        bins: u32,
        pool: f32,
        width: u32,
        height: u32,
    ) -> crate::Result<Self> {
        pelage_scene::Transparency::StrandRaster { tile, bins, pool }.validate()?;
        if width == 0 || height == 0 {
            return Err(pelage_scene::ParamError::new(
                "target size",
                (width, height),
                "both sides must be at least 1 pixel",
            )
            .into());
        }
        let common = Common::new(gpu, inputs, 1, inputs.params.min_pixels)?;
        let limits = gpu.limits();
        let strands = inputs.strands;
        let full = strands.full_layout();
        let tiles_x = width.div_ceil(tile);
        let tiles_y = height.div_ceil(tile);
        let cells = u64::from(tiles_x) * u64::from(tiles_y) * u64::from(bins);
        let scan_blocks = cells.div_ceil(SCAN_BLOCK);
        let max_dim = limits.max_compute_workgroups_per_dimension;
        let too_many = |what: &str, n: u64| {
            crate::ShadeError::from(pelage_scene::ParamError::new(
                what,
                n,
                &format!(
                    "needs more workgroups than a {max_dim} x {max_dim} dispatch holds; use fewer strands, bigger tiles, fewer bins or a smaller target"
                ),
            ))
        };
        for (what, n) in [
            ("strand vertices", full.vertices().div_ceil(LINE_GROUP)),
            ("segments", full.segment_count().div_ceil(LINE_GROUP)),
            ("tiles", u64::from(tiles_x) * u64::from(tiles_y)),
            ("cells", cells.div_ceil(LINE_GROUP)),
            ("scan blocks", scan_blocks),
        ] {
            grid(n, max_dim).ok_or_else(|| too_many(what, n))?;
        }
        if scan_blocks > u64::from(u32::MAX) || cells > u64::from(u32::MAX) / 2 {
            return Err(too_many("cells", cells));
        }
        if u64::from(width) > u64::from(limits.max_texture_dimension_2d)
            || u64::from(height) > u64::from(limits.max_texture_dimension_2d)
        {
            return Err(GpuError::TooLarge {
                what: format!("strand raster composite of {width}x{height}"),
                bytes: u64::from(width) * u64::from(height) * COMPOSITE_BYTES,
                limit: u64::from(limits.max_texture_dimension_2d),
            }
            .into());
        }
        let binding_limit = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let max_pool = (binding_limit / 4).min(u64::from(u32::MAX)) as u32;
        let wanted = (full.segment_count() as f64 * f64::from(pool)).ceil();
        let capacity = (wanted.max(1024.0).min(f64::from(max_pool))) as u32;

        let usage = wgpu::BufferUsages::STORAGE;
        let storage_buffer =
            |label: &str, bytes: u64| zeroed_storage(gpu, label, bytes.max(16), usage);
        let composite = gpu.scoped(|device| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some("pelage strand raster composite"),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba16Float,
                usage: wgpu::TextureUsages::STORAGE_BINDING
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        })?;
        let composite_view = composite.create_view(&Default::default());
        let storage = Storage {
            shaded: storage_buffer(
                "pelage strand raster vertices",
                full.vertices() * SHADED_BYTES,
            )?,
            segments: storage_buffer(
                "pelage strand raster segments",
                full.segment_count() * SEGMENT_BYTES,
            )?,
            counts: storage_buffer("pelage strand raster counts", cells * 4)?,
            offsets: storage_buffer("pelage strand raster offsets", cells * 4)?,
            block_sums: storage_buffer("pelage strand raster block sums", scan_blocks * 4)?,
            header: zeroed_storage(
                gpu,
                "pelage strand raster header",
                HEADER_BYTES,
                usage | wgpu::BufferUsages::COPY_SRC,
            )?,
            tile_depth: storage_buffer(
                "pelage strand raster tile depths",
                u64::from(tiles_x) * u64::from(tiles_y) * 4,
            )?,
            composite,
            composite_view,
        };
        let pool_buffer = storage_buffer("pelage strand raster pool", u64::from(capacity) * 4)?;
        storage.name_for_audit();
        pelage_gpu::audit::name_buffer(&pool_buffer, crate::OIT_STORAGE);

        let uniforms_value = StrandRasterUniforms {
            width,
            height,
            tile,
            tiles_x,
            tiles_y,
            bins,
            capacity,
            strands: full.strands,
            segments: full.segments,
            scan_blocks: scan_blocks as u32,
            bin_near: 0.0,
            bin_scale: 1.0,
            opacity: strands.style.opacity,
            pixel_scale: 1.0,
            reverse_z: u32::from(inputs.target.reverse_z),
            _pad: 0,
        };
        let uniforms = UniformBuffer::new(gpu, "pelage strand raster", &uniforms_value)?;

        let module = common.module(gpu, "shade/oit/strand_raster.wgsl")?;
        let model = common.model.binding();
        let (pipelines, shade_groups) = gpu.scoped(|device| {
            // Group 0 of cs_shade: hair.wgsl's frame, strands, style and visibility.
            let hair_layout =
                BindLayout::new("pelage strand raster shade", wgpu::ShaderStages::COMPUTE)
                    .uniform(0)
                    .storage(1)
                    .storage(2)
                    .uniform(3)
                    .storage(4)
                    .build(device);
            let model_layout = model.layout(
                device,
                "pelage strand raster model",
                wgpu::ShaderStages::COMPUTE,
            );
            let constants = [("TILE", f64::from(tile))];
            let pipelines: Vec<_> = PASSES
                .iter()
                .map(|&(label, entry, bindings)| {
                    let own = raster_layout(label, bindings).build(device);
                    let mut layouts: Vec<Option<&wgpu::BindGroupLayout>> = vec![None; 4];
                    if entry == "cs_shade" {
                        layouts[0] = Some(&hair_layout);
                        model.place(&mut layouts, model_layout.as_ref());
                        layouts.resize(4, None);
                    }
                    layouts[3] = Some(&own);
                    let pipeline = pelage_gpu::compute_pipeline_with_constants(
                        device, label, &module, entry, &layouts, &constants,
                    );
                    (pipeline, own)
                })
                .collect();
            let group0 = pelage_gpu::bind_buffers(
                device,
                "pelage strand raster shade",
                &hair_layout,
                &[
                    &common.frame.buffer,
                    &strands.vertices,
                    &strands.roots,
                    &common.style.buffer,
                    &common.visibility,
                ],
            );
            let model_group = model_layout
                .as_ref()
                .and_then(|l| model.bind_group(device, "pelage strand raster model", l));
            (pipelines, [Some(group0), None, model_group])
        })?;

        let (resolve, resolve_group) = gpu.scoped(|device| {
            let layout = BindLayout::new(RESOLVE, wgpu::ShaderStages::FRAGMENT)
                .texture_2d(10, wgpu::TextureSampleType::Float { filterable: false })
                .build(device);
            let layouts = [None, None, None, Some(&layout)];
            let pipeline = raster_pipeline(
                device,
                &RasterDesc {
                    label: RESOLVE,
                    layouts: &layouts,
                    module: &module,
                    vertex: "vs_fullscreen",
                    fragment: Some("fs_resolve"),
                    targets: &[Some(over_target(&inputs.target))],
                    depth: None,
                    samples: 1,
                    cull: None,
                },
            );
            let group = pelage_gpu::create_bind_group(
                device,
                &wgpu::BindGroupDescriptor {
                    label: Some(RESOLVE),
                    layout: &layout,
                    entries: &[wgpu::BindGroupEntry {
                        binding: 10,
                        resource: wgpu::BindingResource::TextureView(&storage.composite_view),
                    }],
                },
            );
            let draw = Draw {
                label: RESOLVE,
                pipeline,
                groups: Vec::new(),
                vertices: Vertices::Fixed(3),
            };
            (draw, group)
        })?;

        let readback = |label: &str| -> crate::Result<Readback> {
            let buffer = gpu.scoped(|device| {
                pelage_gpu::create_buffer(
                    device,
                    &wgpu::BufferDescriptor {
                        label: Some(label),
                        size: HEADER_BYTES,
                        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                        mapped_at_creation: false,
                    },
                )
            })?;
            Ok(Readback {
                buffer,
                state: Arc::new(AtomicU8::new(IDLE)),
            })
        };
        let readbacks = [
            readback("pelage strand raster readback 0")?,
            readback("pelage strand raster readback 1")?,
        ];
        Ok(Self {
            uniforms_value,
            uniforms,
            storage,
            pool: Mutex::new(PoolState {
                buffer: pool_buffer,
                capacity,
                groups: None,
                peak_seen: 0,
            }),
            pipelines,
            shade_groups,
            resolve,
            resolve_group,
            readbacks,
            prepared: Mutex::new(uniforms_value),
            reach: strands.reach,
            width,
            height,
            max_pool,
            common,
            gpu: gpu.clone(),
        })
    }

    /// Segment references the pool holds now (it grows after a frame that needed more).
    pub fn capacity(&self) -> u32 {
        self.pool.lock().map_or(0, |p| p.capacity)
    }

    /// Cells, summed over every frame drawn (saturating), longer than the sort takes
    /// (`SORT_MAX` in the WGSL, 1024 references; lavapipe's loop limit): they are
    /// composited in the order the scatter's atomics gave, so their tiles may differ
    /// from run to run. Reads the GPU's counters (waits for the GPU).
    pub fn unsorted_cells(&self, gpu: &Gpu) -> crate::Result<u64> {
        let bytes = pelage_gpu::read_buffer(gpu, &self.storage.header)?;
        Ok(bytes
            .get(16..20)
            .and_then(|b| b.try_into().ok())
            .map_or(0, |b| u64::from(u32::from_le_bytes(b))))
    }

    /// What the last recorded frame left on the GPU (waits for it): the uniforms, every
    /// projected segment, each cell's segment indices as the pool holds them, and the
    /// composite. For tests and the CPU mirror (`pelage_reference::strand_raster`).
    pub fn capture(&self, gpu: &Gpu) -> crate::Result<RasterCapture> {
        let uniforms = *self.prepared.lock().map_err(|_| {
            GpuError::Validation("a thread panicked while recording this method".into())
        })?;
        let words = |buffer: &wgpu::Buffer| -> crate::Result<Vec<u32>> {
            Ok(pelage_gpu::read_buffer(gpu, buffer)?
                .chunks_exact(4)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect())
        };
        let s = &self.storage;
        let segment_count = uniforms.strands as usize * uniforms.segments as usize;
        let segments = words(&s.segments)?
            .chunks_exact(16)
            .take(segment_count)
            .map(|c| std::array::from_fn(|i| f32::from_bits(c[i])))
            .collect();
        let offsets = words(&s.offsets)?;
        let counts = words(&s.counts)?;
        let pool = {
            let pool = self.pool.lock().map_err(|_| {
                GpuError::Validation("a thread panicked while recording this method".into())
            })?;
            words(&pool.buffer)?
        };
        let cell_count =
            uniforms.tiles_x as usize * uniforms.tiles_y as usize * uniforms.bins as usize;
        let cells = (0..cell_count)
            .map(|c| {
                let start = offsets.get(c).copied().unwrap_or(0) as usize;
                let end = (start + counts.get(c).copied().unwrap_or(0) as usize)
                    .min(uniforms.capacity as usize)
                    .max(start);
                pool.get(start..end).map_or_else(Vec::new, <[u32]>::to_vec)
            })
            .collect();
        let texture = pelage_gpu::read_texture(gpu, &s.composite)?;
        let composite = texture
            .data
            .chunks_exact(8)
            .map(|p| {
                std::array::from_fn(|i| {
                    pelage_gpu::f16_to_f32(u16::from_le_bytes([p[2 * i], p[2 * i + 1]]))
                })
            })
            .collect();
        Ok(RasterCapture {
            uniforms,
            segments,
            cells,
            composite,
        })
    }

    /// The `@group(3)` bind groups of the compute passes, sampling `depth`.
    fn bind_groups(
        &self,
        gpu: &Gpu,
        pool: &wgpu::Buffer,
        depth: &wgpu::TextureView,
    ) -> crate::Result<Vec<wgpu::BindGroup>> {
        let s = &self.storage;
        Ok(gpu.scoped(|device| {
            PASSES
                .iter()
                .zip(&self.pipelines)
                .map(|(&(label, _, bindings), (_, layout))| {
                    let entries: Vec<wgpu::BindGroupEntry<'_>> = bindings
                        .iter()
                        .map(|&binding| {
                            let resource = match binding {
                                0 => self.uniforms.buffer.as_entire_binding(),
                                1 => s.shaded.as_entire_binding(),
                                2 => s.segments.as_entire_binding(),
                                3 => s.counts.as_entire_binding(),
                                4 => s.offsets.as_entire_binding(),
                                5 => pool.as_entire_binding(),
                                6 => s.block_sums.as_entire_binding(),
                                7 => s.header.as_entire_binding(),
                                8 => wgpu::BindingResource::TextureView(depth),
                                11 => s.tile_depth.as_entire_binding(),
                                _ => wgpu::BindingResource::TextureView(&s.composite_view),
                            };
                            wgpu::BindGroupEntry { binding, resource }
                        })
                        .collect();
                    pelage_gpu::create_bind_group(
                        device,
                        &wgpu::BindGroupDescriptor {
                            label: Some(label),
                            layout,
                            entries: &entries,
                        },
                    )
                })
                .collect()
        })?)
    }

    /// The compute passes' bind groups for `target`'s depth (built again only after the
    /// pool grew in [`HairPass::after_submit`] or for another depth view).
    fn groups(&self, target: &TargetViews<'_>) -> crate::Result<Arc<Vec<wgpu::BindGroup>>> {
        let mut pool = self.pool.lock().map_err(|_| {
            GpuError::Validation("a thread panicked while recording this method".into())
        })?;
        let depth = target.depth_to_sample();
        if let Some((view, groups)) = &pool.groups {
            if view == depth {
                return Ok(groups.clone());
            }
        }
        let groups = Arc::new(self.bind_groups(&self.gpu, &pool.buffer, depth)?);
        pool.groups = Some((depth.clone(), groups.clone()));
        Ok(groups)
    }

    /// Records the first `count` compute passes (after clearing the cell counts).
    fn record_compute(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        groups: &[wgpu::BindGroup],
        count: usize,
        mut timer: Option<&mut GpuTimer>,
    ) {
        // This frame's strands and segments, as `prepare` wrote them.
        let u = self.prepared.lock().map_or(self.uniforms_value, |p| *p);
        let layout = StrandLayout {
            strands: u.strands,
            segments: u.segments,
        };
        let max_dim = self.gpu.limits().max_compute_workgroups_per_dimension;
        encoder.clear_buffer(&self.storage.counts, 0, None);
        for (((label, _, _), (pipeline, _)), (group, grid_kind)) in PASSES
            .iter()
            .zip(&self.pipelines)
            .zip(groups.iter().zip(GRIDS))
            .take(count)
        {
            let n = match grid_kind {
                Grid::Vertices => layout.vertices().div_ceil(LINE_GROUP),
                Grid::Segments => layout.segment_count().div_ceil(LINE_GROUP),
                Grid::Blocks => u64::from(u.scan_blocks),
                Grid::One => 1,
                Grid::Cells => (u64::from(u.tiles_x) * u64::from(u.tiles_y) * u64::from(u.bins))
                    .div_ceil(LINE_GROUP),
                Grid::TileThreads => {
                    (u64::from(u.tiles_x) * u64::from(u.tiles_y)).div_ceil(LINE_GROUP)
                }
                Grid::Tiles => u64::from(u.tiles_x) * u64::from(u.tiles_y),
            };
            let (x, y) = grid(n, max_dim).unwrap_or((0, 0));
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(label),
                timestamp_writes: timer.as_deref_mut().and_then(|t| t.compute_pass(label)),
            });
            pass.set_pipeline(pipeline);
            if *label == PASSES[0].0 {
                for (index, g) in self.shade_groups.iter().enumerate() {
                    if let Some(g) = g {
                        pelage_gpu::set_bind_group(&mut pass, index as u32, g);
                    }
                }
            }
            pelage_gpu::set_bind_group(&mut pass, 3, group);
            if x > 0 && y > 0 {
                pass.dispatch_workgroups(x, y, 1);
            }
        }
    }

    /// Records the resolve: the composite blended over `target.color`.
    fn record_resolve(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &TargetViews<'_>,
        timer: Option<&mut GpuTimer>,
    ) {
        {
            let mut pass = pelage_gpu::audit::begin_render_pass(
                &mut *encoder,
                &wgpu::RenderPassDescriptor {
                    label: Some(RESOLVE),
                    color_attachments: &[Some(crate::draw::over_color(target.color))],
                    depth_stencil_attachment: None,
                    timestamp_writes: timer.and_then(|t| t.render_pass(RESOLVE)),
                    occlusion_query_set: None,
                    multiview_mask: None,
                },
            );
            self.resolve
                .record(&mut pass, Some((3, &self.resolve_group)));
        }
    }

    /// Takes what the header readbacks hold: the largest size a frame needed.
    fn collect_readbacks(&self, gpu: &Gpu) -> Option<u32> {
        // Runs the map callbacks of submissions that have completed; never waits.
        let _ = gpu.device.poll(wgpu::PollType::Poll);
        let mut peak = None;
        for r in &self.readbacks {
            match r.state.load(Ordering::Acquire) {
                READY => {
                    let words: Vec<u32> = match r.buffer.slice(..).get_mapped_range() {
                        Ok(view) => view
                            .chunks_exact(4)
                            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                            .collect(),
                        Err(_) => Vec::new(),
                    };
                    r.buffer.unmap();
                    r.state.store(IDLE, Ordering::Release);
                    peak = peak.max(words.get(1).copied());
                }
                FAILED => r.state.store(IDLE, Ordering::Release),
                _ => {}
            }
        }
        peak
    }

    /// Grows the pool when a frame needed more than it holds (up to the binding limit).
    fn grow(&self, gpu: &Gpu, pool: &mut PoolState, needed: u32) -> crate::Result<()> {
        pool.peak_seen = pool.peak_seen.max(needed);
        if needed <= pool.capacity || pool.capacity >= self.max_pool {
            return Ok(());
        }
        let capacity = (u64::from(needed) * 5 / 4).min(u64::from(self.max_pool)) as u32;
        pool.buffer = zeroed_storage(
            gpu,
            "pelage strand raster pool",
            u64::from(capacity) * 4,
            wgpu::BufferUsages::STORAGE,
        )?;
        pelage_gpu::audit::name_buffer(&pool.buffer, crate::OIT_STORAGE);
        pool.capacity = capacity;
        pool.groups = None;
        let mut prepared = self.prepared.lock().map_err(|_| {
            GpuError::Validation("a thread panicked while recording this method".into())
        })?;
        prepared.capacity = capacity;
        self.uniforms.write(&gpu.queue, &prepared)?;
        Ok(())
    }
}

impl HairPass for StrandRaster {
    fn name(&self) -> &'static str {
        "strand_raster"
    }

    fn prepare(
        &self,
        queue: &wgpu::Queue,
        strands: &StrandFrame,
        camera: &CameraMatrices,
        lights: &[Light],
        width: u32,
        height: u32,
    ) -> crate::Result<()> {
        self.common
            .prepare(queue, strands, camera, lights, width, height)?;
        let layout = strands.layout;
        // Bins span the view depths of the strands' box (clamped in front of the eye).
        let view_proj = camera.view_projection();
        let (lo, hi) = self.reach;
        let mut near = f32::INFINITY;
        let mut far = f32::NEG_INFINITY;
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            let w = (view_proj * corner.extend(1.0)).w;
            near = near.min(w);
            far = far.max(w);
        }
        let near = near.max(0.0);
        let span = (far - near).max(1e-6);
        let capacity = self.pool.lock().map_or(0, |p| p.capacity);
        let u = StrandRasterUniforms {
            strands: layout.strands,
            segments: layout.segments,
            bin_near: near,
            bin_scale: self.uniforms_value.bins as f32 / span,
            pixel_scale: camera.pixel_scale(height),
            capacity,
            ..self.uniforms_value
        };
        if !(u.bin_scale.is_finite() && u.bin_near.is_finite() && u.pixel_scale.is_finite()) {
            return Err(pelage_scene::ParamError::new(
                "camera",
                u.pixel_scale,
                "gives a non-finite pixel size or depth range for the strands; check the projection",
            )
            .into());
        }
        self.uniforms.write(queue, &u)?;
        if let Ok(mut prepared) = self.prepared.lock() {
            *prepared = u;
        }
        Ok(())
    }

    fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        strands: &StrandFrame,
        target: &TargetViews<'_>,
        mut timer: Option<&mut GpuTimer>,
    ) -> crate::Result<()> {
        self.common.check(self.name(), strands)?;
        if (target.width, target.height) != (self.width, self.height) {
            return Err(crate::ShadeError::TargetSize {
                built: (self.width, self.height),
                given: (target.width, target.height),
            });
        }
        let groups = self.groups(target)?;
        self.common.encode_volume(encoder, timer.as_deref_mut());
        self.common
            .encode_mesh(encoder, target, None, timer.as_deref_mut());
        self.record_compute(encoder, &groups, PASSES.len(), timer.as_deref_mut());
        self.record_resolve(encoder, target, timer);
        // The header goes to an idle readback, mapped once the caller's submission of
        // this encoder completes; `after_submit` takes it once the GPU is done.
        if let Some(r) = self
            .readbacks
            .iter()
            .find(|r| r.state.load(Ordering::Acquire) == IDLE)
        {
            encoder.copy_buffer_to_buffer(&self.storage.header, 0, &r.buffer, 0, HEADER_BYTES);
            r.state.store(PENDING, Ordering::Release);
            let state = r.state.clone();
            encoder.map_buffer_on_submit(&r.buffer, wgpu::MapMode::Read, .., move |result| {
                state.store(
                    if result.is_ok() { READY } else { FAILED },
                    Ordering::Release,
                );
            });
        }
        Ok(())
    }

    fn after_submit(&self, gpu: &Gpu) -> crate::Result<()> {
        // Never waits: takes the readbacks of frames the GPU has finished and grows the
        // pool for the next frame when one of them needed more.
        let Some(needed) = self.collect_readbacks(gpu) else {
            return Ok(());
        };
        let mut pool = self.pool.lock().map_err(|_| {
            GpuError::Validation("a thread panicked while recording this method".into())
        })?;
        self.grow(gpu, &mut pool, needed)
    }

    fn passes(&self, lookup: &[String]) -> Vec<PassInfo> {
        let shade = self
            .common
            .hair_shading(PASSES[0].0, true)
            .writes([OIT_STORAGE]);
        let tile_depth = PassInfo::new(PASSES[1].0)
            .reads([OIT_STORAGE, TARGET_DEPTH])
            .writes([OIT_STORAGE]);
        let middle = PASSES[2..8].iter().map(|(label, _, _)| {
            PassInfo::new(*label)
                .reads([OIT_STORAGE])
                .writes([OIT_STORAGE])
        });
        let fine = PassInfo::new(PASSES[8].0)
            .reads([OIT_STORAGE, TARGET_DEPTH])
            .writes([OIT_STORAGE]);
        let resolve = PassInfo::new(RESOLVE)
            .reads([OIT_STORAGE, TARGET_COLOR])
            .writes([TARGET_COLOR]);
        self.common
            .volume_pass()
            .into_iter()
            .chain(self.common.mesh_pass(lookup))
            .chain([shade, tile_depth])
            .chain(middle)
            .chain([fine, resolve])
            .collect()
    }

    fn grid(&self) -> Option<&crate::VolumeGrid> {
        self.common.grid()
    }

    fn body_sky_binding(&self) -> Option<pelage_gpu::ShaderBinding> {
        self.common.body_sky_binding()
    }

    fn memory_bytes(&self) -> u64 {
        let s = &self.storage;
        let pool = self.pool.lock().map_or(0, |p| p.buffer.size());
        [
            &s.shaded,
            &s.segments,
            &s.counts,
            &s.offsets,
            &s.block_sums,
            &s.header,
            &s.tile_depth,
            &self.uniforms.buffer,
        ]
        .iter()
        .map(|b| b.size())
        .sum::<u64>()
            + pool
            + u64::from(self.width) * u64::from(self.height) * COMPOSITE_BYTES
    }

    fn set_params(&mut self, gpu: &Gpu, params: &pelage_scene::ShadeParams) -> crate::Result<()> {
        self.common.set_params(gpu, params)
    }

    fn stats(&self, gpu: &Gpu) -> crate::Result<OitStats> {
        let bytes = pelage_gpu::read_buffer(gpu, &self.storage.header)?;
        let word = |i: usize| {
            bytes
                .get(4 * i..4 * i + 4)
                .and_then(|b| b.try_into().ok())
                .map_or(0, |b| u64::from(u32::from_le_bytes(b)))
        };
        let capacity = u64::from(self.capacity());
        Ok(OitStats {
            stored: word(0).min(capacity),
            dropped: word(3),
            peak_nodes: word(1),
            capacity,
            overflowed_frames: word(2),
        })
    }
}
