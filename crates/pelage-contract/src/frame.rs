//! The frame every pass after stage 1 is prepared and recorded with: which part of the
//! strand buffer holds this frame's strands, and an id that makes the stages' order data.

use std::sync::atomic::{AtomicU64, Ordering};

/// What part of the strand buffer holds this frame's strands: the first `strands`
/// strands, each `segments + 1` vertices stored one after the other (strand `i` starts
/// at vertex `i * (segments + 1)`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StrandLayout {
    /// Strands grown this frame.
    pub strands: u32,
    /// Segments per strand this frame.
    pub segments: u32,
}

impl StrandLayout {
    /// Vertices grown this frame.
    pub fn vertices(&self) -> u64 {
        u64::from(self.strands) * u64::from(self.segments + 1)
    }

    /// Segments grown this frame.
    pub fn segment_count(&self) -> u64 {
        u64::from(self.strands) * u64::from(self.segments)
    }

    /// The layout in one `u64` (for an atomic): strands in the high half.
    pub fn to_bits(self) -> u64 {
        (u64::from(self.strands) << 32) | u64::from(self.segments)
    }

    /// The layout [`StrandLayout::to_bits`] packed.
    pub fn from_bits(v: u64) -> Self {
        Self {
            strands: (v >> 32) as u32,
            segments: v as u32,
        }
    }
}

/// One frame of stage 1, as stage 1's `prepare` (`pelage_strands::StrandStage::prepare`)
/// returns it: the strands and segments grown this frame, and an id no other frame of
/// any stage 1 method in the process shares.
///
/// Every later pass takes it twice: when it writes its per-frame uniforms (its
/// `prepare`, which reads `layout`) and when it records (its `encode`, which refuses a
/// frame other than the one it was prepared for). So the order of the stages is data
/// the caller hands over, not a convention: a pass prepared for a stale frame is a
/// [`FrameOrderError`], never a picture drawn with the wrong strand count.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StrandFrame {
    /// This frame's strands and segments per strand.
    pub layout: StrandLayout,
    /// Unique per frame and stage 1 instance (0 is never used).
    pub id: u64,
}

impl StrandFrame {
    /// A frame of `layout` with a fresh id (what stage 1 calls once per frame; an engine
    /// that writes the strand buffer itself calls it too).
    pub fn next(layout: StrandLayout) -> Self {
        static NEXT_ID: AtomicU64 = AtomicU64::new(1);
        Self {
            layout,
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
        }
    }

    /// Errors unless `self` is the frame `stage` was prepared for (`prepared`, 0 when
    /// it never was).
    pub fn check_prepared(&self, stage: &str, prepared: u64) -> Result<(), FrameOrderError> {
        if prepared == self.id {
            return Ok(());
        }
        Err(FrameOrderError {
            stage: stage.to_string(),
            prepared,
            given: self.id,
        })
    }
}

/// A pass recorded for a stage 1 frame other than the one its per-frame uniforms were
/// written for: stages prepared out of order, or one of them not prepared this frame.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "{stage} was prepared for strand frame {prepared} but is recorded for frame {given}; \
     each frame, prepare stage 1 first, then every later stage with the StrandFrame it \
     returned, and record them all with that same frame"
)]
pub struct FrameOrderError {
    /// The pass that refused.
    pub stage: String,
    /// The frame id it was prepared for (0: never).
    pub prepared: u64,
    /// The frame id it was asked to record.
    pub given: u64,
}

/// The id of a prepared frame, readable from `&self` encoders (0: not prepared yet).
#[derive(Debug, Default)]
pub struct PreparedFrame(AtomicU64);

impl PreparedFrame {
    /// Remembers `frame` as the one the uniforms were written for.
    pub fn set(&self, frame: &StrandFrame) {
        self.0.store(frame.id, Ordering::Release);
    }

    /// Errors unless `frame` is the one last remembered (see [`StrandFrame::check_prepared`]).
    pub fn check(&self, stage: &str, frame: &StrandFrame) -> Result<(), FrameOrderError> {
        frame.check_prepared(stage, self.0.load(Ordering::Acquire))
    }
}
