//! Typed GPU buffers laid out by encase, so Rust and WGSL agree on every offset.

use std::marker::PhantomData;

use encase::ShaderType;
use encase::internal::WriteInto;

use crate::context::Gpu;
use crate::error::{GpuError, Result};

/// `value`'s bytes in WGSL storage layout, padded to a whole number of words
/// (at least one: zero-sized bindings are invalid).
fn storage_bytes<T: ShaderType + WriteInto + ?Sized>(label: &str, value: &T) -> Result<Vec<u8>> {
    let mut writer = encase::StorageBuffer::new(Vec::<u8>::new());
    writer
        .write(value)
        .map_err(|e| GpuError::Validation(format!("laying out `{label}` with encase: {e}")))?;
    let mut bytes = writer.into_inner();
    let padded = bytes.len().max(1).next_multiple_of(4);
    bytes.resize(padded, 0);
    Ok(bytes)
}

/// Create a buffer initialised with `value` in WGSL storage layout.
///
/// `usage` gets `COPY_SRC | COPY_DST` added (for readback and rewrites). When
/// it includes `STORAGE` the size is checked with [`Gpu::check_storage_size`].
/// Sizes are rounded up to a multiple of 4 bytes (at least 4).
pub fn storage_buffer<T: ShaderType + WriteInto + ?Sized>(
    gpu: &Gpu,
    label: &str,
    value: &T,
    usage: wgpu::BufferUsages,
) -> Result<wgpu::Buffer> {
    let bytes = storage_bytes(label, value)?;
    if usage.contains(wgpu::BufferUsages::STORAGE) {
        gpu.check_storage_size(label, bytes.len() as u64)?;
    }
    gpu.scoped(|device| {
        crate::counters::create_buffer_init(
            device,
            &wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: &bytes,
                usage: usage | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            },
        )
    })
}

/// Queues a rewrite of `buffer` from offset 0 with `value` in WGSL storage layout (takes
/// effect at the next submit), for a buffer made by [`storage_buffer`] or
/// [`zeroed_storage`] (both allow `COPY_DST`). Errors when `value` does not fit `buffer`.
pub fn write_storage<T: ShaderType + WriteInto + ?Sized>(
    queue: &wgpu::Queue,
    label: &str,
    buffer: &wgpu::Buffer,
    value: &T,
) -> Result<()> {
    let bytes = storage_bytes(label, value)?;
    if bytes.len() as u64 > buffer.size() {
        return Err(GpuError::Validation(format!(
            "`{label}`: {} bytes do not fit its {}-byte buffer",
            bytes.len(),
            buffer.size()
        )));
    }
    queue.write_buffer(buffer, 0, &bytes);
    Ok(())
}

/// A zero-filled buffer of `bytes` (rounded up to a multiple of 4, at least 4)
/// with `STORAGE | COPY_SRC | COPY_DST` added to `usage`; size checked with
/// [`Gpu::check_storage_size`].
pub fn zeroed_storage(
    gpu: &Gpu,
    label: &str,
    bytes: u64,
    usage: wgpu::BufferUsages,
) -> Result<wgpu::Buffer> {
    let size = bytes.max(1).next_multiple_of(4);
    gpu.check_storage_size(label, size)?;
    // wgpu zero-initialises every new buffer.
    gpu.scoped(|device| {
        crate::counters::create_buffer(
            device,
            &wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: usage
                    | wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            },
        )
    })
}

/// A uniform buffer holding one `T`, rewritten with [`UniformBuffer::write`].
#[derive(Debug)]
pub struct UniformBuffer<T> {
    /// The buffer (`UNIFORM | COPY_DST | COPY_SRC`), for bind groups.
    pub buffer: wgpu::Buffer,
    /// The bytes last queued: a write of the same value queues nothing.
    last: std::sync::Mutex<Vec<u8>>,
    _t: PhantomData<T>,
}

impl<T: ShaderType + WriteInto> UniformBuffer<T> {
    /// Create the buffer holding `value`.
    ///
    /// Errors with [`GpuError::Validation`] if `T` breaks WGSL's uniform
    /// layout rules (e.g. an array of `f32`, whose stride must be 16 there);
    /// encase reports this by panicking, which is caught here (its message
    /// still reaches stderr).
    pub fn new(gpu: &Gpu, label: &str, value: &T) -> Result<Self> {
        std::panic::catch_unwind(T::assert_uniform_compat).map_err(|panic| {
            let why = panic
                .downcast_ref::<String>()
                .map(String::as_str)
                .or_else(|| panic.downcast_ref::<&str>().copied())
                .unwrap_or("layout rules broken");
            GpuError::Validation(format!(
                "`{label}`: {} cannot live in a uniform buffer: {why}; add \
                 #[shader(align(16))]/#[shader(size(16))] or use a storage buffer",
                std::any::type_name::<T>()
            ))
        })?;
        let bytes = storage_bytes(label, value)?;
        let buffer = gpu.scoped(|device| {
            crate::counters::create_buffer_init(
                device,
                &wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents: &bytes,
                    usage: wgpu::BufferUsages::UNIFORM
                        | wgpu::BufferUsages::COPY_DST
                        | wgpu::BufferUsages::COPY_SRC,
                },
            )
        })?;
        Ok(UniformBuffer {
            buffer,
            last: std::sync::Mutex::new(bytes),
            _t: PhantomData,
        })
    }

    /// Queue a rewrite of the buffer with `value` (takes effect at the next submit);
    /// nothing is queued when `value` lays out to the bytes last written (a light or
    /// camera that did not move costs no staging copy).
    ///
    /// Uniform-compatible types have the same layout in storage and uniform
    /// space, so the storage writer is used (checked once in [`UniformBuffer::new`]).
    pub fn write(&self, queue: &wgpu::Queue, value: &T) -> Result<()> {
        let bytes = storage_bytes("uniform", value)?;
        if bytes.len() as u64 > self.buffer.size() {
            return Err(GpuError::Validation(format!(
                "uniform value of {} bytes does not fit its {}-byte buffer",
                bytes.len(),
                self.buffer.size()
            )));
        }
        let mut last = self
            .last
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        if *last != bytes {
            queue.write_buffer(&self.buffer, 0, &bytes);
            *last = bytes;
        }
        Ok(())
    }
}
