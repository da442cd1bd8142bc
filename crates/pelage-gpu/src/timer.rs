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

use std::collections::VecDeque;
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, AtomicU32, Ordering};

use crate::context::Gpu;
use crate::error::{GpuError, Result};
use crate::readback::map_read;

/// Bytes per timestamp.
const QUERY_BYTES: u64 = wgpu::QUERY_SIZE as u64;

/// Readback buffers a timer cycles through: a frame's timestamps are read while the
/// next ones are recorded.
const READBACKS: usize = 3;

/// A frame whose timestamps are on their way back (see [`GpuTimer::submitted`]).
#[derive(Debug)]
struct InFlight {
    slot: usize,
    /// Bytes mapped, from 0.
    bytes: u64,
    labels: Vec<String>,
    dropped: u32,
    /// 0 while mapping, 1 mapped, 2 the map failed.
    state: Arc<AtomicU8>,
}

/// Times up to `max_scopes` passes per frame with timestamp queries.
///
/// One frame: [`GpuTimer::compute_pass`] / [`GpuTimer::render_pass`] per pass,
/// [`GpuTimer::resolve`] at the end of the encoder, submit, then either
/// [`GpuTimer::read`] (waits for the GPU) or, in a frame loop that must not wait,
/// [`GpuTimer::submitted`] and later [`GpuTimer::try_read`], which returns the
/// timings of an earlier frame once the GPU has finished it. Either resets the timer
/// for the next frame.
#[derive(Debug)]
pub struct GpuTimer {
    queries: wgpu::QuerySet,
    resolve_buffer: wgpu::Buffer,
    readbacks: Vec<wgpu::Buffer>,
    /// The readback the next `resolve` copies into (never one in flight).
    slot: usize,
    in_flight: VecDeque<InFlight>,
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
        let (queries, resolve_buffer, readbacks) = gpu.scoped(|device| {
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
            let readbacks = (0..READBACKS)
                .map(|_| {
                    buffer(
                        "pelage timer readback",
                        wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    )
                })
                .collect();
            (queries, resolve, readbacks)
        })?;
        Ok(Some(GpuTimer {
            queries,
            resolve_buffer,
            readbacks,
            slot: 0,
            in_flight: VecDeque::new(),
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
        crate::audit::pass_begun(label);
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
            encoder.copy_buffer_to_buffer(
                &self.resolve_buffer,
                0,
                &self.readbacks[self.slot],
                0,
                bytes,
            );
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
        let bytes = map_read(
            gpu,
            &self.readbacks[self.slot],
            0..u64::from(count) * QUERY_BYTES,
        )?;
        Ok(report(gpu, labels, dropped, &bytes))
    }

    /// After the encoder holding the passes and [`GpuTimer::resolve`] was submitted:
    /// starts reading this frame's timestamps back without waiting, and resets the
    /// timer for the next frame. [`GpuTimer::try_read`] returns them once the GPU has
    /// finished the frame.
    ///
    /// Three frames can be in flight; a fourth waits for the oldest (the CPU running
    /// that far ahead of the GPU is held back here, as a swap chain would).
    pub fn submitted(&mut self, gpu: &Gpu) -> Result<()> {
        let labels = std::mem::take(&mut self.labels);
        let dropped = std::mem::take(&mut self.dropped);
        let resolved = self.resolved.swap(0, Ordering::Relaxed);
        if labels.is_empty() {
            return Ok(());
        }
        let count = 2 * labels.len() as u32;
        if resolved != count {
            return Err(GpuError::Validation(format!(
                "GpuTimer::submitted: {} scopes were recorded but resolve() did not see them \
                 all; call timer.resolve(&mut encoder) after the last timed pass, then submit",
                labels.len()
            )));
        }
        let state = Arc::new(AtomicU8::new(0));
        let flag = state.clone();
        let buffer = &self.readbacks[self.slot];
        // No error scope: a failed map reaches the callback, and try_read skips it.
        buffer.map_async(
            wgpu::MapMode::Read,
            0..u64::from(count) * QUERY_BYTES,
            move |result| flag.store(if result.is_ok() { 1 } else { 2 }, Ordering::Release),
        );
        self.in_flight.push_back(InFlight {
            slot: self.slot,
            bytes: u64::from(count) * QUERY_BYTES,
            labels,
            dropped,
            state,
        });
        // The next resolve needs a readback that is not in flight.
        while self.in_flight.len() >= self.readbacks.len() {
            crate::wait(&gpu.device, None)?;
            if let Some(oldest) = self.in_flight.pop_front() {
                self.readbacks[oldest.slot].unmap();
            }
        }
        self.slot = (0..self.readbacks.len())
            .map(|k| (self.slot + 1 + k) % self.readbacks.len())
            .find(|s| self.in_flight.iter().all(|f| f.slot != *s))
            .unwrap_or(self.slot);
        Ok(())
    }

    /// The timings of the newest frame passed to [`GpuTimer::submitted`] that the GPU
    /// has finished since the last call (older finished frames are dropped), or `None`
    /// when none has finished yet. Never waits for the GPU.
    pub fn try_read(&mut self, gpu: &Gpu) -> Result<Option<TimerReport>> {
        gpu.device
            .poll(wgpu::PollType::Poll)
            .map_err(|e| GpuError::Poll(e.to_string()))?;
        let mut newest = None;
        while let Some(front) = self.in_flight.front() {
            match front.state.load(Ordering::Acquire) {
                0 => break,
                state => {
                    let Some(frame) = self.in_flight.pop_front() else {
                        break;
                    };
                    let buffer = &self.readbacks[frame.slot];
                    if state == 1 {
                        let bytes = buffer
                            .get_mapped_range(0..frame.bytes)
                            .map(|view| view.to_vec())
                            .map_err(|e| GpuError::Map(e.to_string()));
                        buffer.unmap();
                        newest = Some(report(gpu, frame.labels, frame.dropped, &bytes?));
                    }
                }
            }
        }
        Ok(newest)
    }

    /// Waits for every frame in flight and returns the newest one's timings (`None`
    /// when none is in flight).
    pub fn wait(&mut self, gpu: &Gpu) -> Result<Option<TimerReport>> {
        if self.in_flight.is_empty() {
            return Ok(None);
        }
        crate::wait(&gpu.device, None)?;
        self.try_read(gpu)
    }
}

/// Ticks `bytes` (begin, end per scope) as milliseconds per label.
fn report(gpu: &Gpu, labels: Vec<String>, dropped: u32, bytes: &[u8]) -> TimerReport {
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
    TimerReport { scopes, dropped }
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
