//! `.hair` reader: `HairFile::read` must never panic on any bytes, and
//! whatever it accepts must survive `write` → `read` unchanged (compared bit
//! for bit, so NaN thickness / transparency / colour values count as equal to
//! themselves). When the input's info field is UTF-8 padded with NULs and its
//! array field has no unknown bits, the written bytes must also equal the
//! input's leading bytes (`read` ignores trailing bytes).
//!
//! The only `write` error allowed for a file `read` accepted is `BadInfo`
//! from an info field that is not UTF-8: `read` decodes it lossily, and the
//! U+FFFD replacement characters can make it longer than 88 bytes.

#![no_main]

use libfuzzer_sys::fuzz_target;
use pelage_scene::hair_file::{HEADER_SIZE, INFO_SIZE};
use pelage_scene::{HairFile, HairFileError};

/// Bit patterns of `values`.
fn bits(values: impl IntoIterator<Item = f32>) -> Vec<u32> {
    values.into_iter().map(f32::to_bits).collect()
}

/// Every field of `h`, floats as bit patterns, so that two files compare
/// equal exactly when they hold the same values.
#[allow(clippy::type_complexity)]
fn fingerprint(h: &HairFile) -> (Vec<u16>, [Vec<u32>; 4], String, [bool; 4], u32, Vec<u32>) {
    (
        h.segments.clone(),
        [
            bits(h.points.iter().flat_map(|p| p.to_array())),
            bits(h.thickness.iter().copied()),
            bits(h.transparency.iter().copied()),
            bits(h.colors.iter().flat_map(|p| p.to_array())),
        ],
        h.info.clone(),
        [
            h.has_segments,
            h.has_thickness,
            h.has_transparency,
            h.has_colors,
        ],
        h.default_segments,
        bits(
            [h.default_thickness, h.default_transparency]
                .into_iter()
                .chain(h.default_color.to_array()),
        ),
    )
}

/// Whether `read` → `write` must give back the input's bytes: the info field
/// is UTF-8 followed only by NULs, and the array field has no unknown bits.
fn exact_round_trip_expected(data: &[u8]) -> bool {
    let Some(info) = data.get(HEADER_SIZE - INFO_SIZE..HEADER_SIZE) else {
        return false;
    };
    let text_len = info.iter().position(|&b| b == 0).unwrap_or(INFO_SIZE);
    let (text, padding) = info.split_at(text_len);
    let arrays = data
        .get(12..16)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    std::str::from_utf8(text).is_ok()
        && padding.iter().all(|&b| b == 0)
        && arrays.is_some_and(|a| a < 32)
}

fuzz_target!(|data: &[u8]| {
    let Ok(hair) = HairFile::read(data) else {
        return;
    };

    // Invariants of an accepted file.
    let n = hair.points.len();
    assert_eq!(hair.thickness.len(), n);
    assert_eq!(hair.transparency.len(), n);
    assert_eq!(hair.colors.len(), n);
    assert!(hair.points.iter().all(|p| p.is_finite()));
    let ranges: Vec<_> = hair.strand_ranges().collect();
    assert_eq!(
        ranges.len(),
        hair.segments.len(),
        "strand_ranges stopped early"
    );
    assert_eq!(ranges.last().map_or(0, |r| r.end), n);
    assert_eq!(hair.strands().count(), hair.segments.len());

    let bytes = match hair.write() {
        Ok(bytes) => bytes,
        Err(HairFileError::BadInfo {
            len,
            has_nul: false,
        }) if len > INFO_SIZE && !exact_round_trip_expected(data) => {
            return;
        }
        Err(e) => panic!("read accepted a file that write refuses: {e}"),
    };
    let back = HairFile::read(&bytes).expect("write produced a file read refuses");
    assert_eq!(
        fingerprint(&back),
        fingerprint(&hair),
        "write → read changed the file"
    );
    assert_eq!(
        back.write().expect("second write"),
        bytes,
        "write is not stable"
    );
    if exact_round_trip_expected(data) {
        assert_eq!(
            data.get(..bytes.len()),
            Some(&bytes[..]),
            "read → write changed the bytes"
        );
    }
});
