//! Region and texture maps (`MapImage::decode`: PNG through `image`, every colour type
//! and bit depth): must never panic on any bytes, and an accepted map has one texel
//! per pixel of a size within `MAX_MAP_SIZE` on each side.

#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use pelage_scene::{MAX_MAP_SIZE, MapImage};

fuzz_target!(|data: &[u8]| {
    let Ok(map) = MapImage::decode(data, Path::new("fuzz.png")) else {
        return;
    };
    assert!(map.width() >= 1 && map.width() <= MAX_MAP_SIZE);
    assert!(map.height() >= 1 && map.height() <= MAX_MAP_SIZE);
});
