//! Scene files: `SceneFile::parse` must never panic on any text, and whatever it
//! accepts must write out (`to_toml`) to text that parses again and writes out the
//! same (compared as text, so NaN-free and NaN-carrying fields alike round trip).

#![no_main]

use libfuzzer_sys::fuzz_target;
use pelage_scene::SceneFile;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(file) = SceneFile::parse(&text) {
        let written = file.to_toml().expect("an accepted scene writes out");
        let again = SceneFile::parse(&written).expect("a written scene parses again");
        let rewritten = again.to_toml().expect("and writes out again");
        assert_eq!(written, rewritten, "the round trip changed the scene");
        // Building the mesh must not panic either (OBJ paths simply fail to load).
        let _ = file.mesh(std::path::Path::new("fuzz.toml"));
    }
});
