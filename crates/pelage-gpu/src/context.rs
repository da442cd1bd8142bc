//! [`Gpu`]: the device and queue every pelage stage works on, either created
//! here (headless) or brought by the caller (an engine's).

use std::sync::{Arc, Mutex, MutexGuard};

use crate::error::{GpuError, Result};

/// Optional features pelage uses when the adapter has them: timestamps, blending into
/// 32-bit float targets (deep opacity maps in float32) and 64-bit atomics (the k-buffer
/// and random subsets). [`Gpu::headless`] requests those its adapter offers; an engine
/// creating its own device for pelage should request
/// `adapter.features() & WANTED_FEATURES`.
pub const WANTED_FEATURES: wgpu::Features = wgpu::Features::TIMESTAMP_QUERY
    .union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS)
    .union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES)
    .union(wgpu::Features::FLOAT32_BLENDABLE)
    .union(wgpu::Features::SHADER_INT64)
    .union(wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX)
    .union(wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS);

/// Errors that wgpu reported outside any error scope, recorded by the
/// handlers [`Gpu::headless`] installs.
#[derive(Debug, Default)]
struct Recorded {
    /// Why the device was lost; sticky, a lost device stays lost.
    lost: Option<String>,
    /// Uncaptured errors not yet handed to a caller, oldest first.
    errors: Vec<GpuError>,
}

/// A wgpu device and queue, plus what pelage needs to know about them.
///
/// Cloning is cheap (wgpu handles are reference counted) and clones share the
/// recorded-error state.
#[derive(Debug, Clone)]
pub struct Gpu {
    /// The device every resource is created on.
    pub device: wgpu::Device,
    /// The queue work is submitted to.
    pub queue: wgpu::Queue,
    /// The adapter the device came from, when known.
    pub adapter_info: Option<wgpu::AdapterInfo>,
    features: wgpu::Features,
    limits: wgpu::Limits,
    downlevel: wgpu::DownlevelFlags,
    recorded: Arc<Mutex<Recorded>>,
}

impl Gpu {
    /// Create an instance, adapter and device of our own, with no window.
    ///
    /// Respects `WGPU_BACKEND` (e.g. `vulkan` or `gl`; a value naming no
    /// backend is [`GpuError::BadBackend`]), prefers a high
    /// performance adapter and falls back to a software one (lavapipe or
    /// llvmpipe). Requests only the optional features (timestamps, float32 blending) the adapter has,
    /// and the adapter's own limits (so 128 MiB storage bindings are usable).
    ///
    /// wgpu's default handler panics on errors raised outside an error scope;
    /// this device instead records them (and device loss), and the next
    /// [`Gpu::scoped`], [`Gpu::submit_and_wait`] or [`Gpu::check`] returns them.
    ///
    /// Blocks the calling thread (pollster); see [`Gpu::headless_async`]. Not on the
    /// web (`wasm32`), where nothing may block: call [`Gpu::headless_async`] there.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn headless() -> Result<Gpu> {
        pollster::block_on(Self::headless_async())
    }

    /// The async form of [`Gpu::headless`].
    pub async fn headless_async() -> Result<Gpu> {
        if wgpu::Instance::enabled_backend_features().is_empty() {
            return Err(GpuError::NoAdapter {
                tried: "this build of wgpu has no backend for this platform (pelage's stage \
                        crates enable none: enable the facade's `backends` feature or wgpu's \
                        `vulkan`, `metal`, `dx12` or `gles`)"
                    .into(),
            });
        }
        if let Some(value) = std::env::var_os("WGPU_BACKEND") {
            let value = value.to_string_lossy().into_owned();
            if wgpu::Backends::from_comma_list(&value).is_empty() {
                return Err(GpuError::BadBackend { value });
            }
        }
        let desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        let backends = desc.backends;
        let instance = wgpu::Instance::new(desc);

        // A real GPU first, then whatever software adapter the system has.
        let mut tried = vec![format!("backends {backends:?}")];
        let mut adapter = None;
        for force_fallback_adapter in [false, true] {
            let options = wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter,
                compatible_surface: None,
                apply_limit_buckets: false,
            };
            match instance.request_adapter(&options).await {
                Ok(found) => {
                    adapter = Some(found);
                    break;
                }
                Err(e) => tried.push(format!("fallback={force_fallback_adapter}: {e}")),
            }
        }
        let Some(adapter) = adapter else {
            return Err(GpuError::NoAdapter {
                tried: tried.join("; "),
            });
        };

        let features = adapter.features() & WANTED_FEATURES;
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("pelage"),
                required_features: features,
                required_limits: adapter.limits(),
                ..Default::default()
            })
            .await
            .map_err(|e| GpuError::RequestDevice(e.to_string()))?;

        // Record errors instead of letting wgpu panic on them.
        let recorded = Arc::new(Mutex::new(Recorded::default()));
        let sink = recorded.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            lock(&sink).errors.push(from_wgpu(e));
        }));
        let sink = recorded.clone();
        device.set_device_lost_callback(move |reason, message| {
            lock(&sink).lost = Some(format!("{reason:?}: {message}"));
        });

        Ok(Gpu {
            features: device.features(),
            limits: device.limits(),
            downlevel: adapter.get_downlevel_capabilities().flags,
            adapter_info: Some(adapter.get_info()),
            device,
            queue,
            recorded,
        })
    }

    /// Wrap a device and queue the caller created (an engine's).
    ///
    /// Features and limits are read from the device; `adapter_info` of `None`
    /// is filled in from [`wgpu::Device::adapter_info`]. The caller's
    /// uncaptured-error and device-lost handlers are left alone: errors inside
    /// [`Gpu::scoped`] are still returned, but errors outside any scope go to
    /// the caller's handler (wgpu's default one panics).
    ///
    /// A device does not report its adapter's downlevel flags: they are taken as
    /// WebGPU-compliant, less `READ_ONLY_DEPTH_STENCIL` on the GL backend (which wgpu's
    /// GL backend never offers); [`Gpu::with_downlevel_flags`] sets the adapter's own.
    pub fn from_device(
        device: wgpu::Device,
        queue: wgpu::Queue,
        adapter_info: Option<wgpu::AdapterInfo>,
    ) -> Gpu {
        let adapter_info = adapter_info.unwrap_or_else(|| device.adapter_info());
        let mut downlevel = wgpu::DownlevelFlags::compliant();
        if adapter_info.backend == wgpu::Backend::Gl {
            downlevel.remove(wgpu::DownlevelFlags::READ_ONLY_DEPTH_STENCIL);
        }
        Gpu {
            features: device.features(),
            limits: device.limits(),
            downlevel,
            adapter_info: Some(adapter_info),
            device,
            queue,
            recorded: Arc::default(),
        }
    }

    /// The features enabled on the device.
    pub fn features(&self) -> wgpu::Features {
        self.features
    }

    /// The adapter's downlevel flags (what of WebGPU it lacks: GL has no read-only
    /// depth attachment that the same pass samples, for one).
    pub fn downlevel_flags(&self) -> wgpu::DownlevelFlags {
        self.downlevel
    }

    /// This device with the downlevel flags `flags`
    /// (`adapter.get_downlevel_capabilities().flags`): for a device from
    /// [`Gpu::from_device`], whose flags are otherwise inferred from the backend.
    #[must_use]
    pub fn with_downlevel_flags(mut self, flags: wgpu::DownlevelFlags) -> Self {
        self.downlevel = flags;
        self
    }

    /// The limits of the device.
    pub fn limits(&self) -> &wgpu::Limits {
        &self.limits
    }

    /// Whether passes can be timed ([`wgpu::Features::TIMESTAMP_QUERY`]).
    pub fn has_timestamps(&self) -> bool {
        self.features.contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// One line naming the adapter, e.g. `llvmpipe (LLVM 15.0.6, 256 bits) / Vulkan / Cpu`.
    pub fn describe(&self) -> String {
        match &self.adapter_info {
            // Browsers hide the adapter's name (WebGPU gives an empty one).
            Some(info) => format!(
                "{} / {:?} / {:?}",
                if info.name.is_empty() {
                    "unnamed adapter"
                } else {
                    &info.name
                },
                info.backend,
                info.device_type
            ),
            None => "unknown adapter".into(),
        }
    }

    /// Errors with [`GpuError::TooLarge`] if a storage buffer of `bytes` would
    /// exceed `max_storage_buffer_binding_size` (or `max_buffer_size`).
    /// `what` names the buffer in the message.
    pub fn check_storage_size(&self, what: &str, bytes: u64) -> Result<()> {
        let limit = self
            .limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size);
        if bytes > limit {
            return Err(GpuError::TooLarge {
                what: what.to_string(),
                bytes,
                limit,
            });
        }
        Ok(())
    }

    /// Run `f`; an error recorded earlier outside a scope, or a lost device, becomes
    /// `Err`.
    ///
    /// On the web (`wasm32`) a popped scope answers only after control returns to the
    /// browser's event loop, so waiting for it would block the page forever: there no
    /// scope is pushed, `f` runs, and errors it raises reach the device's
    /// uncaptured-error handler (the one [`Gpu::headless_async`] installs records them
    /// for a later [`Gpu::check`]; an engine's own handler gets them otherwise).
    #[cfg(target_arch = "wasm32")]
    pub fn scoped<R>(&self, f: impl FnOnce(&wgpu::Device) -> R) -> Result<R> {
        let value = f(&self.device);
        self.check()?;
        Ok(value)
    }

    /// Run `f` inside validation, out-of-memory and internal error scopes; any
    /// error captured there (or recorded earlier outside a scope, or a lost
    /// device) becomes `Err`. Blocks on the scopes' futures (pollster).
    ///
    /// Error scopes are per thread: `f` must do its wgpu calls on this thread.
    ///
    /// On the web (`wasm32`) no scope is pushed (nothing may block there); errors
    /// reach the device's uncaptured-error handler instead.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn scoped<R>(&self, f: impl FnOnce(&wgpu::Device) -> R) -> Result<R> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let internal = self.device.push_error_scope(wgpu::ErrorFilter::Internal);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let value = f(&self.device);
        // Pop in reverse order of pushing.
        let validation = validation.pop();
        let internal = internal.pop();
        let oom = oom.pop();
        let (validation, internal, oom) =
            pollster::block_on(async { (validation.await, internal.await, oom.await) });
        if let Some(e) = validation.or(oom).or(internal) {
            return Err(from_wgpu(e));
        }
        self.check()?;
        Ok(value)
    }

    /// Submit `commands` (in order) without waiting: what a frame loop calls. Errors
    /// wgpu reported outside error scopes (the submission's own validation among them)
    /// and a lost device are returned; no error scope is pushed, nothing blocks.
    pub fn submit(
        &self,
        commands: impl IntoIterator<Item = wgpu::CommandBuffer>,
    ) -> Result<wgpu::SubmissionIndex> {
        let index = self.queue.submit(commands);
        self.check()?;
        Ok(index)
    }

    /// Submit `commands` (in order) and wait until the queue has finished it.
    ///
    /// Errors raised by the submission, errors recorded since the last check,
    /// and a lost device are returned; a failed wait is [`GpuError::Poll`].
    pub fn submit_and_wait(
        &self,
        commands: impl IntoIterator<Item = wgpu::CommandBuffer>,
    ) -> Result<()> {
        let index = self.scoped(|_| self.queue.submit(commands))?;
        crate::wait(&self.device, Some(index))?;
        self.check()
    }

    /// Return the first error wgpu reported outside any error scope since the
    /// last check (later ones are dropped), or the reason the device was lost.
    ///
    /// Only a device made by [`Gpu::headless`] records such errors.
    pub fn check(&self) -> Result<()> {
        let mut recorded = lock(&self.recorded);
        if let Some(reason) = &recorded.lost {
            return Err(GpuError::DeviceLost(reason.clone()));
        }
        match std::mem::take(&mut recorded.errors).into_iter().next() {
            Some(first) => Err(first),
            None => Ok(()),
        }
    }
}

/// Lock the recorded-error state; a poisoned lock still holds valid data.
fn lock(recorded: &Mutex<Recorded>) -> MutexGuard<'_, Recorded> {
    recorded
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Translate a wgpu error into ours.
fn from_wgpu(e: wgpu::Error) -> GpuError {
    match e {
        wgpu::Error::OutOfMemory { source } => GpuError::OutOfMemory(source.to_string()),
        wgpu::Error::Validation { description, .. } => GpuError::Validation(description),
        wgpu::Error::Internal { description, .. } => {
            GpuError::Validation(format!("internal error: {description}"))
        }
    }
}

/// The names of `features`, as wgpu spells them (`SHADER_INT64_ATOMIC_ALL_OPS`),
/// joined with ` | `, for messages (their `Debug` form is a nested struct); "none"
/// when empty.
pub fn feature_names(features: wgpu::Features) -> String {
    let names: Vec<&str> = features.iter_names().map(|(name, _)| name).collect();
    if names.is_empty() {
        "none".into()
    } else {
        names.join(" | ")
    }
}

#[cfg(test)]
mod feature_name_tests {
    use super::feature_names;

    #[test]
    fn features_are_named_not_dumped() {
        assert_eq!(
            feature_names(wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS),
            "SHADER_INT64_ATOMIC_ALL_OPS"
        );
        assert_eq!(
            feature_names(wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::FLOAT32_BLENDABLE),
            "TIMESTAMP_QUERY | FLOAT32_BLENDABLE"
        );
        assert_eq!(feature_names(wgpu::Features::empty()), "none");
    }
}
