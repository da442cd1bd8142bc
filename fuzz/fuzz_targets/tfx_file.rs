//! TressFX `.tfx` reader: `TfxFile::read` must never panic on any bytes, and
//! whatever it accepts must pass its own checks and survive `write` → `read`
//! unchanged (compared bit for bit, so NaN UVs and colours, which are carried
//! unchecked, count as equal to themselves). When the input's arrays sit
//! where `write` puts them (its header offsets equal the written ones), the
//! written bytes must also equal the input's leading bytes, apart from the
//! padding after an odd-length thickness array (which the input may fill
//! with anything, or lack when that array comes last).
//!
//! An accepted file also goes through `Groom::from_tfx`, `Groom::resample`
//! and `Groom::normalized`, which must not panic either: `from_tfx` may only
//! refuse a negative thickness, `resample` may only report that every strand
//! is degenerate, `normalized` only a width that overflows when scaled.

#![no_main]

use libfuzzer_sys::fuzz_target;
use pelage_scene::tfx_file::HEADER_SIZE;
use pelage_scene::{Groom, GroomError, TfxFile};

/// Bit patterns of `values`.
fn bits(values: impl IntoIterator<Item = f32>) -> Vec<u32> {
    values.into_iter().map(f32::to_bits).collect()
}

/// Every field of `t`, floats as bit patterns, so that two files compare
/// equal exactly when they hold the same values.
#[allow(clippy::type_complexity)]
fn fingerprint(t: &TfxFile) -> (u32, u32, Vec<u32>, [Option<Vec<u32>>; 4], Vec<u32>) {
    (
        t.version.to_bits(),
        t.vertices_per_strand,
        bits(t.positions.iter().flat_map(|p| p.to_array())),
        [
            t.strand_uv
                .as_ref()
                .map(|a| bits(a.iter().flat_map(|v| v.to_array()))),
            t.vertex_uv
                .as_ref()
                .map(|a| bits(a.iter().flat_map(|v| v.to_array()))),
            t.thickness.as_ref().map(|a| bits(a.iter().copied())),
            t.vertex_color
                .as_ref()
                .map(|a| bits(a.iter().flat_map(|v| v.to_array()))),
        ],
        t.reserved.to_vec(),
    )
}

fn u32_at(bytes: &[u8], offset: usize) -> Option<u32> {
    let b = bytes.get(offset..offset + 4)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

fuzz_target!(|data: &[u8]| {
    let Ok(tfx) = TfxFile::read(data) else {
        return;
    };

    // Invariants of an accepted file.
    tfx.check()
        .expect("read accepted a file that check refuses");
    let vps = tfx.vertices_per_strand as usize;
    let strands = tfx.strand_count();
    assert!(strands >= 1 && vps >= 2);
    assert_eq!(strands * vps, tfx.positions.len());
    assert_eq!(tfx.strands().count(), strands);
    assert!(tfx.positions.iter().all(|p| p.is_finite()));
    for (len, expected) in [
        (tfx.strand_uv.as_ref().map(Vec::len), strands),
        (tfx.vertex_uv.as_ref().map(Vec::len), strands * vps),
        (tfx.thickness.as_ref().map(Vec::len), strands),
        (tfx.vertex_color.as_ref().map(Vec::len), strands * vps),
    ] {
        assert!(len.is_none_or(|l| l == expected));
    }

    let bytes = tfx
        .write()
        .expect("read accepted a file that write refuses");
    let back = TfxFile::read(&bytes).expect("write produced a file read refuses");
    assert_eq!(
        fingerprint(&back),
        fingerprint(&tfx),
        "write → read changed the file"
    );
    assert_eq!(
        back.write().expect("second write"),
        bytes,
        "write is not stable"
    );
    if data.get(12..32) == bytes.get(12..32) {
        // Same layout: same bytes, except the thickness padding (which the
        // input may have other bytes in, or lack at its end).
        let mut padding = 0..0;
        if let (Some(t), Some(offset)) = (&tfx.thickness, u32_at(&bytes, 24)) {
            let end = offset as usize + t.len() * 4;
            padding = end..end.next_multiple_of(8);
        }
        let common = data.len().min(bytes.len());
        assert!(
            common == bytes.len() || common >= padding.start && padding.end == bytes.len(),
            "the input lacks bytes that read used"
        );
        let masked = |b: &[u8]| -> Vec<u8> {
            let mut b = b[..common].to_vec();
            if let Some(pad) = b.get_mut(padding.start.min(common)..padding.end.min(common)) {
                pad.fill(0);
            }
            b
        };
        assert_eq!(
            masked(data),
            masked(&bytes),
            "read → write changed the bytes"
        );
    }
    assert!(bytes.len() >= HEADER_SIZE);

    // The groom built from it.
    let groom = match Groom::from_tfx(&tfx) {
        Ok(groom) => groom,
        Err(GroomError::BadWidth { value, .. }) if value < 0.0 => return,
        Err(e) => panic!("from_tfx refused an accepted file: {e}"),
    };
    assert_eq!(groom.strand_count(), strands);
    assert_eq!(groom.point_count(), strands * vps);
    let segments = 1 + u32::from(data.last().copied().unwrap_or(0) % 16);
    match groom.resample(segments) {
        Ok(r) => {
            assert_eq!(r.strands + r.skipped, strands as u32);
            assert_eq!(r.points.len(), r.strands as usize * (segments as usize + 1));
            assert_eq!(r.source_strands.len(), r.strands as usize);
            assert!(r.points.iter().all(|p| p.is_finite()));
            assert_eq!(r.widths.is_some(), tfx.thickness.is_some());
        }
        Err(GroomError::AllDegenerate { strands: s }) => assert_eq!(s, strands),
        Err(e) => panic!("resample failed: {e}"),
    }
    match groom.normalized(1.0) {
        Ok(n) => {
            let (lo, hi) = n.bounds();
            assert!((hi - lo).max_element() <= 1.0 + 1e-5);
        }
        Err(GroomError::BadWidth { .. }) => {}
        Err(e) => panic!("normalized failed: {e}"),
    }
});
