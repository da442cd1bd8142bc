//! GPU time per pass, from timestamp queries.
//!
//! ```no_run
//! # fn frame(gpu: &pelage_gpu::Gpu) -> pelage_gpu::Result<()> {
//! use pelage_gpu::GpuTimer;
//! let mut timer = GpuTimer::new(gpu, 16)?; // None without TIMESTAMP_QUERY
//! let mut encoder = gpu.device.create_command_encoder(&Default::default());
//! {
//!     let _pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
//!         label: Some("grow"),
//!         timestamp_writes: timer.as_mut().and_then(|t| t.compute_pass("grow")),
//!     });
//!     // ... dispatches ...
//! }
//! if let Some(t) = &timer {
//!     t.resolve(&mut encoder);
//! }
//! gpu.submit_and_wait([encoder.finish()])?;
//! if let Some(t) = &mut timer {
//!     for (label, ms) in t.read(gpu)?.scopes {
//!         println!("{label}: {ms:.3} ms");
//!     }
//! }
//! # Ok(()) }
//! ```

use std::sync::atomic::{AtomicU32, Ordering};

use crate::context::Gpu;
use crate::error::{GpuError, Result};
use crate::readback::map_read;

/// Bytes per timestamp.
const QUERY_BYTES: u64 = wgpu::QUERY_SIZE as u64;

/// Times up to `max_scopes` passes per frame with timestamp queries.
///
/// One frame: [`GpuTimer::compute_pass`] / [`GpuTimer::render_pass`] per pass,
/// [`GpuTimer::resolve`] at the end of the encoder, submit, then
/// [`GpuTimer::read`], which also resets the timer for the next frame.
#[derive(Debug)]
pub struct GpuTimer {
    queries: wgpu::QuerySet,
    resolve_buffer: wgpu::Buffer,
    readback: wgpu::Buffer,
    max_scopes: u32,
    labels: Vec<String>,
    dropped: u32,
    /// Number of queries the last `resolve` copied out (0: not resolved).
    resolved: AtomicU32,
}

impl GpuTimer {
    /// A timer for up to `max_scopes` passes per frame (at least 1, at most
    /// 2048), or `None` when the device lacks `TIMESTAMP_QUERY` (callers then
    /// report "n/a").
    pub fn new(gpu: &Gpu, max_scopes: u32) -> Result<Option<GpuTimer>> {
        if !gpu.has_timestamps() {
            return Ok(None);
        }
        let max_scopes = max_scopes.max(1);
        let count = max_scopes
            .checked_mul(2)
            .filter(|&n| n <= wgpu::QUERY_SET_MAX_QUERIES)
            .ok_or_else(|| {
                GpuError::Validation(format!(
                    "GpuTimer::new: {max_scopes} scopes need two timestamps each, but a \
                     query set holds at most {}; ask for at most {}",
                    wgpu::QUERY_SET_MAX_QUERIES,
                    wgpu::QUERY_SET_MAX_QUERIES / 2
                ))
            })?;
        let bytes = u64::from(count) * QUERY_BYTES;
        let (queries, resolve_buffer, readback) = gpu.scoped(|device| {
            let queries = device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pelage timer"),
                ty: wgpu::QueryType::Timestamp,
                count,
            });
            let buffer = |label, usage| {
                crate::counters::create_buffer(
                    device,
                    &wgpu::BufferDescriptor {
                        label: Some(label),
                        size: bytes,
                        usage,
                        mapped_at_creation: false,
                    },
                )
            };
            let resolve = buffer(
                "pelage timer resolve",
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            );
            let readback = buffer(
                "pelage timer readback",
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            );
            (queries, resolve, readback)
        })?;
        Ok(Some(GpuTimer {
            queries,
            resolve_buffer,
            readback,
            max_scopes,
            labels: Vec::new(),
            dropped: 0,
            resolved: AtomicU32::new(0),
        }))
    }

    /// Register a scope named `label` and return the query indices for its
    /// begin and end timestamps, or `None` when all `max_scopes` are taken
    /// this frame (the pass then runs untimed; [`TimerReport::dropped`] counts it).
    fn next_scope(&mut self, label: &str) -> Option<(u32, u32)> {
        let index = u32::try_from(self.labels.len()).ok()?;
        if index >= self.max_scopes {
            self.dropped += 1;
            return None;
        }
        self.labels.push(label.to_string());
        Some((2 * index, 2 * index + 1))
    }

    /// Timestamp writes for one compute pass, recorded under `label`. `None`
    /// when capacity is exhausted this frame: the pass runs untimed and
    /// [`TimerReport::dropped`] counts it.
    ///
    /// The result borrows the timer only until the pass is begun, so the usual
    /// `timestamp_writes: timer.compute_pass("x")` in the pass descriptor works.
    pub fn compute_pass(&mut self, label: &str) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let (begin, end) = self.next_scope(label)?;
        Some(wgpu::ComputePassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(begin),
            end_of_pass_write_index: Some(end),
        })
    }

    /// Timestamp writes for one render pass; as [`GpuTimer::compute_pass`].
    pub fn render_pass(&mut self, label: &str) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        let (begin, end) = self.next_scope(label)?;
        Some(wgpu::RenderPassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(begin),
            end_of_pass_write_index: Some(end),
        })
    }

    /// Copy this frame's timestamps out of the query set; call once at the
    /// end of the frame's encoder, after the last timed pass.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        let count = 2 * self.labels.len() as u32;
        if count > 0 {
            let bytes = u64::from(count) * QUERY_BYTES;
            encoder.resolve_query_set(&self.queries, 0..count, &self.resolve_buffer, 0);
            encoder.copy_buffer_to_buffer(&self.resolve_buffer, 0, &self.readback, 0, bytes);
        }
        self.resolved.store(count, Ordering::Relaxed);
    }

    /// After the encoder holding the passes and [`GpuTimer::resolve`] was
    /// submitted: read the timestamps (waits for the GPU) and convert them to
    /// milliseconds with the queue's timestamp period, in the order the scopes
    /// were recorded. A scope whose end is before its begin (counter
    /// wraparound or a pass that never ran) reads 0 ms. Resets the timer for
    /// the next frame, also on error.
    pub fn read(&mut self, gpu: &Gpu) -> Result<TimerReport> {
        let labels = std::mem::take(&mut self.labels);
        let dropped = std::mem::take(&mut self.dropped);
        let resolved = self.resolved.swap(0, Ordering::Relaxed);
        if labels.is_empty() {
            return Ok(TimerReport {
                scopes: Vec::new(),
                dropped,
            });
        }
        let count = 2 * labels.len() as u32;
        if resolved != count {
            return Err(GpuError::Validation(format!(
                "GpuTimer::read: {} scopes were recorded but resolve() did not see them all; \
                 call timer.resolve(&mut encoder) after the last timed pass, then submit",
                labels.len()
            )));
        }
        let bytes = map_read(gpu, &self.readback, 0..u64::from(count) * QUERY_BYTES)?;
        let ns_per_tick = f64::from(gpu.queue.get_timestamp_period());
        let ticks: Vec<u64> = bytes
            .chunks_exact(8)
            .map(|c| u64::from_le_bytes(c.try_into().unwrap_or_default()))
            .collect();
        let scopes = labels
            .into_iter()
            .zip(ticks.chunks_exact(2))
            .map(|(label, pair)| {
                let elapsed = match pair {
                    [begin, end] => end.saturating_sub(*begin),
                    _ => 0,
                };
                (label, elapsed as f64 * ns_per_tick / 1.0e6)
            })
            .collect();
        Ok(TimerReport { scopes, dropped })
    }
}

/// GPU times of one frame's scopes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TimerReport {
    /// (label, milliseconds) per scope, in the order recorded.
    pub scopes: Vec<(String, f64)>,
    /// Passes that asked for timing after all scopes were taken (ran untimed).
    pub dropped: u32,
}

impl TimerReport {
    /// Sum of every scope, in milliseconds.
    pub fn total_ms(&self) -> f64 {
        self.scopes.iter().map(|(_, ms)| ms).sum()
    }

    /// Milliseconds summed per label, labels in order of first appearance.
    pub fn by_label(&self) -> Vec<(String, f64)> {
        let mut sums: Vec<(String, f64)> = Vec::new();
        for (label, ms) in &self.scopes {
            match sums.iter_mut().find(|(l, _)| l == label) {
                Some((_, sum)) => *sum += ms,
                None => sums.push((label.clone(), *ms)),
            }
        }
        sums
    }
}
