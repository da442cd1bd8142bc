//! USD groom reader (`.usda`, `.usdc`, `.usdz` through openusd): `usd_file::read`
//! must never panic on any bytes, and whatever it accepts must be a groom that
//! passes its own invariants (finite points, one width per point, one colour per
//! strand) and survives `to_usda` → `read` and `to_usdc` → `read` unchanged (the
//! writers write linear curves, which read back point for point).

#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use pelage_scene::usd_file;

fuzz_target!(|data: &[u8]| {
    let Ok(groom) = usd_file::read(data.to_vec(), Path::new("fuzz.usd")) else {
        return;
    };
    assert!(groom.strand_count() >= 1);
    assert!(groom.points().iter().all(|p| p.is_finite()));
    assert_eq!(*groom.offsets().last().unwrap() as usize, groom.point_count());
    if let Some(w) = groom.widths() {
        assert_eq!(w.len(), groom.point_count());
        assert!(w.iter().all(|w| w.is_finite() && *w >= 0.0));
    }
    if let Some(c) = groom.colors() {
        assert_eq!(c.len(), groom.strand_count());
    }
    // Single-point strands cannot be written as linear curves (USD needs two).
    if groom.offsets().windows(2).any(|w| w[1] - w[0] < 2) {
        return;
    }
    let text = usd_file::to_usda(&groom).expect("to_usda refused an accepted groom");
    let back = usd_file::read(text.into_bytes(), Path::new("back.usda"))
        .expect("read refused what to_usda wrote");
    assert_eq!(back, groom, "to_usda -> read changed the groom");
    let crate_bytes = usd_file::to_usdc(&groom).expect("to_usdc refused an accepted groom");
    let back = usd_file::read(crate_bytes, Path::new("back.usdc"))
        .expect("read refused what to_usdc wrote");
    assert_eq!(back, groom, "to_usdc -> read changed the groom");
});
