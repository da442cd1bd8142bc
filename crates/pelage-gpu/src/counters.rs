//! Counts of the GPU objects pelage creates and of the times it waits for the GPU, so
//! that "nothing is created per frame in steady state" and "a frame never waits" are
//! measured facts rather than claims.
//!
//! Every buffer and bind group the library creates goes through [`create_buffer`],
//! [`create_buffer_init`] or [`create_bind_group`], and every blocking wait for the GPU
//! through [`wait`] (a test scans the stage crates' sources for direct calls). The
//! counts are per thread: a frame is prepared and recorded on one thread, and tests
//! running side by side do not see each other's.

use std::cell::Cell;

use wgpu::util::DeviceExt;

thread_local! {
    static BUFFERS: Cell<u64> = const { Cell::new(0) };
    static BIND_GROUPS: Cell<u64> = const { Cell::new(0) };
    static WAITS: Cell<u64> = const { Cell::new(0) };
}

/// How many buffers and bind groups pelage has created on this thread so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Created {
    /// Buffers created.
    pub buffers: u64,
    /// Bind groups created.
    pub bind_groups: u64,
}

impl Created {
    /// The counts now.
    pub fn now() -> Self {
        Self {
            buffers: BUFFERS.with(Cell::get),
            bind_groups: BIND_GROUPS.with(Cell::get),
        }
    }

    /// What was created between `earlier` and `self`.
    pub fn since(&self, earlier: &Created) -> Created {
        Created {
            buffers: self.buffers.saturating_sub(earlier.buffers),
            bind_groups: self.bind_groups.saturating_sub(earlier.bind_groups),
        }
    }
}

fn count(counter: &'static std::thread::LocalKey<Cell<u64>>) {
    counter.with(|c| c.set(c.get() + 1));
}

/// How many times pelage has waited for the GPU on this thread so far ([`wait`]: a
/// readback, `Gpu::submit_and_wait`, the renderer holding its frames in flight, ...).
/// A frame's prepare, record and after-submit step leave it unchanged.
pub fn waits() -> u64 {
    WAITS.with(Cell::get)
}

/// `device.poll(Wait)` until `submission` (every submission when `None`) has finished,
/// counted ([`waits`]): the one place pelage blocks on the GPU.
pub fn wait(device: &wgpu::Device, submission: Option<wgpu::SubmissionIndex>) -> crate::Result<()> {
    count(&WAITS);
    device
        .poll(wgpu::PollType::Wait {
            submission_index: submission,
            timeout: None,
        })
        .map(|_| ())
        .map_err(|e| crate::GpuError::Poll(e.to_string()))
}

/// `device.create_bind_group(desc)`, counted.
pub fn create_bind_group(
    device: &wgpu::Device,
    desc: &wgpu::BindGroupDescriptor<'_>,
) -> wgpu::BindGroup {
    count(&BIND_GROUPS);
    let group = device.create_bind_group(desc);
    crate::audit::group_created(&group, desc);
    group
}

/// `device.create_buffer(desc)`, counted.
pub fn create_buffer(device: &wgpu::Device, desc: &wgpu::BufferDescriptor<'_>) -> wgpu::Buffer {
    count(&BUFFERS);
    device.create_buffer(desc)
}

/// `device.create_buffer_init(desc)`, counted.
pub fn create_buffer_init(
    device: &wgpu::Device,
    desc: &wgpu::util::BufferInitDescriptor<'_>,
) -> wgpu::Buffer {
    count(&BUFFERS);
    device.create_buffer_init(desc)
}
