//! The A-buffer: per-pixel linked lists of every fragment in a pool the caller sizes
//! (`shade/oit/a_buffer.wgsl`, `shade/oit/ppll.wgsl`).

use pelage_gpu::{Gpu, read_buffer, wgpu, zeroed_storage};

use super::OitStats;
use super::sliced::{
    OitTile, PassContext, PassKind, Sliced, SlicedMethod, rows_per_slice, sliced_hair_pass,
};
use crate::draw::{Common, HairInputs};

/// Bytes of one linked-list node.
pub(crate) const NODE_BYTES: u64 = 16;

/// The A-buffer: 4 bytes of head per pixel plus 16 bytes per node.
#[derive(Debug)]
pub struct ABuffer(SlicedMethod);

/// The linked-list buffers (heads at 2, nodes at 3, counters at 4) for `nodes_per_pixel`
/// nodes on average; returns the slices with the buffers added.
pub(crate) fn list_buffers(
    gpu: &Gpu,
    what: &str,
    base: OitTile,
    nodes_per_pixel: f32,
    width: u32,
    height: u32,
) -> crate::Result<Sliced> {
    let pool_per_pixel = (f64::from(nodes_per_pixel) * NODE_BYTES as f64).ceil() as u64;
    let rows = rows_per_slice(gpu, what, width, height, pool_per_pixel)?;
    let pixels = u64::from(width) * u64::from(rows);
    let capacity = (f64::from(nodes_per_pixel) * pixels as f64).ceil() as u64;
    let capacity = u32::try_from(capacity.max(1)).unwrap_or(u32::MAX);
    let mut sliced = Sliced::new(gpu, OitTile { capacity, ..base }, height, rows)?;
    let usage = wgpu::BufferUsages::STORAGE;
    sliced.buffers = vec![
        (
            2,
            zeroed_storage(gpu, "pelage list heads", pixels * 4, usage)?,
        ),
        (
            3,
            zeroed_storage(
                gpu,
                "pelage list nodes",
                u64::from(capacity) * NODE_BYTES,
                usage,
            )?,
        ),
        (4, zeroed_storage(gpu, "pelage list counters", 16, usage)?),
    ];
    Ok(sliced)
}

/// Reads the list counters (`shade/oit/ppll.wgsl`).
pub(crate) fn list_stats(gpu: &Gpu, sliced: &Sliced) -> crate::Result<OitStats> {
    let Some(counters) = sliced.buffer(4) else {
        return Ok(OitStats::default());
    };
    let bytes = read_buffer(gpu, counters)?;
    let word = |i: usize| {
        bytes
            .get(4 * i..4 * i + 4)
            .and_then(|b| b.try_into().ok())
            .map_or(0, |b| u64::from(u32::from_le_bytes(b)))
    };
    Ok(OitStats {
        stored: word(3),
        dropped: word(1),
        peak_nodes: word(2),
        capacity: u64::from(sliced.capacity),
        overflowed_frames: 0,
    })
}

impl ABuffer {
    /// Builds the A-buffer for `width` x `height` targets with a pool of
    /// `nodes_per_pixel` nodes per pixel, sorting `resolve_k` per pixel at resolve.
    pub fn new(
        gpu: &Gpu,
        inputs: &HairInputs<'_>,
        nodes_per_pixel: f32,
        resolve_k: u32,
        width: u32,
        height: u32,
    ) -> crate::Result<Self> {
        super::refuse_reverse_z(inputs, "a_buffer")?;
        super::require_feature(gpu, "the A-buffer", wgpu::Features::empty())?;
        pelage_scene::Transparency::ABuffer {
            nodes_per_pixel,
            resolve_k,
        }
        .validate()?;
        let common = Common::new(gpu, inputs, 1, inputs.params.min_pixels.max(1.0))?;
        let base = OitTile {
            reverse_z: u32::from(inputs.target.reverse_z),
            width,
            k: resolve_k,
            ..Default::default()
        };
        let mut sliced = list_buffers(
            gpu,
            "A-buffer node pool",
            base,
            nodes_per_pixel,
            width,
            height,
        )?;
        let module = common.module(gpu, "shade/oit/a_buffer.wgsl")?;
        let ctx = PassContext {
            gpu,
            common: &common,
            inputs,
            module: &module,
        };
        sliced.add_hair_pass(
            &ctx,
            "shade: a-buffer fill",
            "fs_fill",
            PassKind::Storage,
            &[0, 1, 2, 3, 4],
        )?;
        sliced.add_resolve_pass(
            gpu,
            &inputs.target,
            &module,
            "shade: a-buffer resolve",
            "fs_resolve",
            &[0, 2, 3, 4],
        )?;
        Ok(Self(SlicedMethod {
            name: "a_buffer",
            common,
            sliced,
        }))
    }

    /// Nodes in the pool (per slice).
    pub fn capacity(&self) -> u32 {
        self.0.sliced.capacity
    }

    /// Draws a frame into `targets` (as `encode` does) and reads back, between the fill
    /// and the resolve, every stored fragment and the opaque colour under the hair: the
    /// input of an exact, fully sorted composite (the lab's reference). Needs the whole
    /// screen in one slice; fragments beyond the pool are missing (check
    /// [`HairPass::stats`](crate::HairPass::stats)). Waits for the GPU.
    pub fn capture(&self, gpu: &Gpu, targets: &crate::Targets) -> crate::Result<FragmentCapture> {
        if self.0.sliced.count != 1 {
            return Err(crate::ShadeError::Unsupported(format!(
                "capturing fragments needs the screen in one slice, but this A-buffer uses {}; \
                 use a smaller image or fewer nodes per pixel",
                self.0.sliced.count
            )));
        }
        let (Some(heads), Some(nodes)) = (self.0.sliced.buffer(2), self.0.sliced.buffer(3)) else {
            return Err(crate::ShadeError::Unsupported(
                "the A-buffer has no lists".into(),
            ));
        };
        let copy = |label: &str, size: u64| {
            pelage_gpu::create_buffer(
                &gpu.device,
                &wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                },
            )
        };
        let (heads_copy, nodes_copy, background) = gpu.scoped(|device| {
            let background = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("pelage capture background"),
                size: targets.color.size(),
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: targets.color.format(),
                usage: wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            });
            (
                copy("pelage capture heads", heads.size()),
                copy("pelage capture nodes", nodes.size()),
                background,
            )
        })?;
        let (color, resolve) = targets.color_views();
        let depth = targets.depth_view();
        let views = targets.views(&color, resolve.as_ref(), &depth);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        self.0.common.encode_mesh(&mut encoder, &views, None, None);
        self.0
            .sliced
            .encode_with(&mut encoder, &views, None, &mut |encoder, pass| {
                if pass == 0 {
                    encoder.copy_buffer_to_buffer(heads, 0, &heads_copy, 0, heads.size());
                    encoder.copy_buffer_to_buffer(nodes, 0, &nodes_copy, 0, nodes.size());
                    encoder.copy_texture_to_texture(
                        targets.color.as_image_copy(),
                        background.as_image_copy(),
                        targets.color.size(),
                    );
                }
            })?;
        gpu.submit_and_wait([encoder.finish()])?;
        let heads = read_buffer(gpu, &heads_copy)?;
        let nodes = read_buffer(gpu, &nodes_copy)?;
        let background = pelage_gpu::read_texture(gpu, &background)?;
        let word = |bytes: &[u8], i: usize| {
            bytes
                .get(4 * i..4 * i + 4)
                .and_then(|b| b.try_into().ok())
                .map_or(0, u32::from_le_bytes)
        };
        let pixels = (targets.width as usize) * (targets.height as usize);
        let capacity = nodes.len() / 16;
        let mut lists = Vec::with_capacity(pixels);
        for p in 0..pixels {
            let mut list = Vec::new();
            let mut link = word(&heads, p) as usize;
            while link != 0 && link <= capacity && list.len() < capacity {
                let n = link - 1;
                let (rg, ba) = (word(&nodes, 4 * n), word(&nodes, 4 * n + 1));
                list.push(CapturedFragment {
                    depth: f32::from_bits(word(&nodes, 4 * n + 2)),
                    color: [
                        half_to_f32(rg as u16),
                        half_to_f32((rg >> 16) as u16),
                        half_to_f32(ba as u16),
                    ],
                    alpha: half_to_f32((ba >> 16) as u16),
                });
                link = word(&nodes, 4 * n + 3) as usize;
            }
            lists.push(list);
        }
        Ok(FragmentCapture {
            width: targets.width,
            height: targets.height,
            background: background.data,
            lists,
        })
    }
}

/// One hair fragment as the A-buffer stored it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CapturedFragment {
    /// View depth (scene units along the view axis).
    pub depth: f32,
    /// Linear RGB, not premultiplied.
    pub color: [f32; 3],
    /// Alpha.
    pub alpha: f32,
}

/// Every hair fragment of a frame, per pixel, and the opaque image under the hair.
#[derive(Clone, Debug)]
pub struct FragmentCapture {
    /// Image size.
    pub width: u32,
    /// Image size.
    pub height: u32,
    /// The opaque colour under the hair, RGBA8 sRGB, rows tightly packed.
    pub background: Vec<u8>,
    /// Fragments of each pixel (row-major), in list order (unsorted).
    pub lists: Vec<Vec<CapturedFragment>>,
}

/// IEEE half to f32 (the nodes store colour with WGSL's `pack2x16float`).
fn half_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exponent = i32::from((h >> 10) & 0x1f);
    let mantissa = f32::from(h & 0x3ff);
    match exponent {
        0 => sign * mantissa * 2f32.powi(-24),
        31 if mantissa == 0.0 => sign * f32::INFINITY,
        31 => f32::NAN,
        e => sign * (1.0 + mantissa / 1024.0) * 2f32.powi(e - 15),
    }
}

sliced_hair_pass!(ABuffer);
