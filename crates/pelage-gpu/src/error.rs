//! The error type of every fallible call in this crate.

use crate::shaders::ShaderError;

/// Everything that can go wrong between pelage and the GPU.
///
/// wgpu reports most of its errors asynchronously; [`crate::Gpu`] captures them
/// with error scopes (and, for devices it created itself, an uncaptured-error
/// handler) and hands them back as one of these variants instead of panicking.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter could be created for any enabled backend.
    #[error(
        "no GPU adapter found ({tried}). On Debian without a GPU install lavapipe: \
         `apt-get install -y mesa-vulkan-drivers`; the WGPU_BACKEND environment \
         variable selects the backend (vulkan or gl)"
    )]
    NoAdapter {
        /// What was tried and what each attempt answered.
        tried: String,
    },
    /// `WGPU_BACKEND` names no backend wgpu knows.
    #[error(
        "WGPU_BACKEND={value:?} names no backend; use one or more of vulkan, gl, metal, dx12 \
         (comma-separated), or unset it to try every backend"
    )]
    BadBackend {
        /// The variable's value.
        value: String,
    },
    /// The adapter refused to create a device.
    #[error("the adapter refused to create a device: {0}")]
    RequestDevice(String),
    /// A wgpu validation error captured by an error scope or the uncaptured-error
    /// handler, or a request this crate refused before wgpu saw it.
    #[error("validation error: {0}")]
    Validation(String),
    /// The device ran out of memory.
    #[error("the GPU ran out of memory: {0}; use fewer strands/segments or a smaller image")]
    OutOfMemory(String),
    /// The device was lost (driver reset, or destroyed); it cannot be used again.
    #[error("the GPU device was lost: {0}; create a new Gpu")]
    DeviceLost(String),
    /// Mapping a buffer for reading failed.
    #[error("mapping a buffer for reading failed: {0}")]
    Map(String),
    /// A shader could not be found, composed, parsed or validated.
    #[error(transparent)]
    Shader(#[from] ShaderError),
    /// A buffer would exceed the adapter's limits.
    #[error(
        "{what} needs {bytes} bytes but the adapter's max_storage_buffer_binding_size is \
         {limit} ({over} over); use fewer strands/segments or split the scene",
        over = .bytes.saturating_sub(*.limit)
    )]
    TooLarge {
        /// What the buffer holds, e.g. "strand vertices".
        what: String,
        /// Bytes it needs.
        bytes: u64,
        /// The limit it exceeds.
        limit: u64,
    },
    /// Waiting for the GPU (`Device::poll`) failed.
    #[error("waiting for the GPU failed: {0}")]
    Poll(String),
}

/// `Result` with [`GpuError`] as the default error.
pub type Result<T, E = GpuError> = std::result::Result<T, E>;
