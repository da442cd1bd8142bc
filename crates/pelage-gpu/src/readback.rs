//! Copy GPU buffers and textures back to the CPU (tests, tools; never in the frame loop).

use std::ops::Range;

use crate::context::Gpu;
use crate::error::{GpuError, Result};

/// Copy all of `buffer` (which needs `COPY_SRC`) to the CPU. Waits for the GPU.
pub fn read_buffer(gpu: &Gpu, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
    read_buffer_range(gpu, buffer, 0, buffer.size())
}

/// Copy `size` bytes of `buffer` from `offset` to the CPU. Waits for the GPU.
///
/// Any offset and size inside the buffer work; the copy is widened to 4-byte
/// boundaries internally (which must lie inside the buffer).
pub fn read_buffer_range(
    gpu: &Gpu,
    buffer: &wgpu::Buffer,
    offset: u64,
    size: u64,
) -> Result<Vec<u8>> {
    let end = offset
        .checked_add(size)
        .filter(|&end| end <= buffer.size())
        .ok_or_else(|| {
            GpuError::Map(format!(
                "bytes {offset}..{offset}+{size} lie outside the {}-byte buffer",
                buffer.size()
            ))
        })?;
    if !buffer.usage().contains(wgpu::BufferUsages::COPY_SRC) {
        return Err(GpuError::Map(format!(
            "the buffer lacks COPY_SRC usage ({:?}); add wgpu::BufferUsages::COPY_SRC where it is created",
            buffer.usage()
        )));
    }
    if size == 0 {
        return Ok(Vec::new());
    }
    // Buffer copies start and end on 4-byte boundaries.
    let start = offset - offset % wgpu::COPY_BUFFER_ALIGNMENT;
    let stop = end.next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
    if stop > buffer.size() {
        return Err(GpuError::Map(format!(
            "cannot read up to byte {end} of a {}-byte buffer: copies end on 4-byte \
             boundaries; make the buffer's size a multiple of 4",
            buffer.size()
        )));
    }
    let staging = staging_buffer(gpu, stop - start)?;
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("pelage read_buffer"),
        });
    encoder.copy_buffer_to_buffer(buffer, start, &staging, 0, stop - start);
    gpu.submit_and_wait([encoder.finish()])?;
    let bytes = map_read(gpu, &staging, 0..stop - start)?;
    let skip = (offset - start) as usize;
    Ok(bytes
        .get(skip..skip + size as usize)
        .map(<[u8]>::to_vec)
        .unwrap_or_default())
}

/// A 2-D image read back from a texture: rows tightly packed, top row first.
#[derive(Debug, Clone, PartialEq)]
pub struct TextureData {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// The texture's format.
    pub format: wgpu::TextureFormat,
    /// Bytes per texel of `format`.
    pub bytes_per_texel: u32,
    /// `height` rows of `width * bytes_per_texel` bytes.
    pub data: Vec<u8>,
}

/// Read mip 0, layer 0 of `texture` (which needs `COPY_SRC`), removing wgpu's
/// 256-byte row padding. Waits for the GPU.
///
/// Compressed, multisampled and combined depth-stencil formats (and
/// `Depth24Plus`) are refused with an error.
pub fn read_texture(gpu: &Gpu, texture: &wgpu::Texture) -> Result<TextureData> {
    let format = texture.format();
    let refuse = |why: &str| {
        Err(GpuError::Validation(format!(
            "read_texture cannot read a {format:?} texture: {why}"
        )))
    };
    if !texture.usage().contains(wgpu::TextureUsages::COPY_SRC) {
        return refuse(
            "it lacks COPY_SRC usage; add wgpu::TextureUsages::COPY_SRC where it is created",
        );
    }
    if format.is_compressed() {
        return refuse("compressed formats are not supported");
    }
    if texture.sample_count() != 1 {
        return refuse("multisampled textures cannot be copied; resolve it first");
    }
    let Some(bytes_per_texel) = format.block_copy_size(None) else {
        return refuse("the format has no single copyable aspect (depth-stencil or Depth24Plus)");
    };
    let (width, height) = (texture.width(), texture.height());
    let row = u64::from(width) * u64::from(bytes_per_texel);
    let padded_row = row.next_multiple_of(u64::from(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT));
    let Ok(padded_row_u32) = u32::try_from(padded_row) else {
        return refuse("a row is wider than 4 GiB");
    };
    let total = padded_row * u64::from(height);
    if total == 0 {
        return Ok(TextureData {
            width,
            height,
            format,
            bytes_per_texel,
            data: Vec::new(),
        });
    }

    let staging = staging_buffer(gpu, total)?;
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("pelage read_texture"),
        });
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &staging,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded_row_u32),
                rows_per_image: Some(height),
            },
        },
        wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
    );
    gpu.submit_and_wait([encoder.finish()])?;
    let padded = map_read(gpu, &staging, 0..total)?;

    // Drop the padding at the end of each row.
    let data = padded
        .chunks_exact(padded_row as usize)
        .flat_map(|r| r.get(..row as usize).unwrap_or_default())
        .copied()
        .collect();
    Ok(TextureData {
        width,
        height,
        format,
        bytes_per_texel,
        data,
    })
}

/// A `MAP_READ | COPY_DST` buffer of `size` bytes.
fn staging_buffer(gpu: &Gpu, size: u64) -> Result<wgpu::Buffer> {
    gpu.scoped(|device| {
        crate::counters::create_buffer(
            device,
            &wgpu::BufferDescriptor {
                label: Some("pelage readback staging"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            },
        )
    })
}

/// On the web (`wasm32`) a map answers only after control returns to the browser's
/// event loop, so a blocking read can never finish: every readback is
/// [`GpuError::Map`] there (draw the frame to a canvas instead).
#[cfg(target_arch = "wasm32")]
pub(crate) fn map_read(_gpu: &Gpu, _buffer: &wgpu::Buffer, _range: Range<u64>) -> Result<Vec<u8>> {
    Err(GpuError::Map(
        "reading a buffer back waits for the GPU, which a web page cannot do (the map \
         answers only after control returns to the browser's event loop); draw the frame \
         to a canvas instead"
            .into(),
    ))
}

/// Map `range` of a `MAP_READ` buffer, copy it out and unmap. Waits for the GPU.
/// `range` must lie inside the buffer, start on 8 bytes and span a multiple of 4.
#[cfg(not(target_arch = "wasm32"))]
pub(crate) fn map_read(gpu: &Gpu, buffer: &wgpu::Buffer, range: Range<u64>) -> Result<Vec<u8>> {
    let (sender, receiver) = std::sync::mpsc::channel();
    gpu.scoped(|_| {
        buffer.map_async(wgpu::MapMode::Read, range.clone(), move |result| {
            // The receiver outlives the wait below; if not, nobody needs the answer.
            let _ = sender.send(result);
        })
    })?;
    crate::wait(&gpu.device, None)?;
    match receiver.try_recv() {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return Err(GpuError::Map(e.to_string())),
        Err(_) => {
            return Err(GpuError::Map(
                "the map callback had not run after waiting for the GPU".into(),
            ));
        }
    }
    let bytes = buffer
        .get_mapped_range(range)
        .map(|view| view.to_vec())
        .map_err(|e| GpuError::Map(e.to_string()));
    buffer.unmap();
    gpu.check()?;
    bytes
}

/// The value of an IEEE 754 half float (the texels of an `Rgba16Float` readback).
pub fn f16_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exponent = i32::from((h >> 10) & 0x1f);
    let mantissa = f32::from(h & 0x3ff);
    sign * match exponent {
        0 => mantissa * 2f32.powi(-24),
        31 if mantissa == 0.0 => f32::INFINITY,
        31 => f32::NAN,
        e => (1.0 + mantissa / 1024.0) * 2f32.powi(e - 15),
    }
}
