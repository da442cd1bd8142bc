//! Every file of the fuzz corpora (`fuzz/corpus/<target>/`, the fuzzers' findings and
//! the seeds `fuzz/examples/make_seeds.rs` writes, deep USD nesting among them) read by
//! the reader its target fuzzes, on the test's own thread (a 2 MiB stack): none may
//! panic or overflow the stack. Accepted grooms must hold their invariants.

use std::path::{Path, PathBuf};

use pelage_scene::{Groom, HairFile, MapImage, SceneFile, TfxFile, parse_obj};

/// The files of `fuzz/corpus/<target>`, sorted.
fn corpus(target: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fuzz/corpus")
        .join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|entry| entry.unwrap().path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    assert!(!files.is_empty(), "{} is empty", dir.display());
    files
}

/// Runs `read` on every file of the corpus of `target`; the number accepted.
fn read_all(target: &str, mut read: impl FnMut(&[u8], &Path) -> bool) -> usize {
    let files = corpus(target);
    let mut accepted = 0;
    for path in &files {
        let bytes = std::fs::read(path).unwrap();
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| read(&bytes, path)));
        match outcome {
            Ok(true) => accepted += 1,
            Ok(false) => {}
            Err(_) => panic!("{target}: {} panicked", path.display()),
        }
    }
    println!("{target}: {} files, {accepted} accepted", files.len());
    accepted
}

fn check(groom: &Groom) {
    assert!(groom.points().iter().all(|p| p.is_finite()));
    assert_eq!(
        *groom.offsets().last().unwrap() as usize,
        groom.point_count()
    );
    if let Some(c) = groom.colors() {
        assert_eq!(c.len(), groom.strand_count());
    }
}

#[test]
fn hair_and_tfx_corpora_are_read_without_panics() {
    read_all("hair_file", |bytes, _| match HairFile::read(bytes) {
        Ok(hair) => Groom::from_hair(&hair).map(|g| check(&g)).is_ok(),
        Err(_) => false,
    });
    read_all("tfx_file", |bytes, _| match TfxFile::read(bytes) {
        Ok(tfx) => Groom::from_tfx(&tfx).map(|g| check(&g)).is_ok(),
        Err(_) => false,
    });
}

#[test]
fn obj_and_scene_corpora_are_read_without_panics() {
    read_all("obj", |bytes, path| {
        let _ = path;
        parse_obj(&String::from_utf8_lossy(bytes)).is_ok()
    });
    read_all("scene_file", |bytes, _| {
        SceneFile::parse(&String::from_utf8_lossy(bytes)).is_ok()
    });
}

#[test]
fn the_map_corpus_is_read_without_panics() {
    let accepted = read_all("map", |bytes, path| MapImage::decode(bytes, path).is_ok());
    // Every colour type and bit depth of the seeds is decoded.
    assert!(accepted >= 15, "{accepted} maps decoded");
}

#[cfg(feature = "usd")]
#[test]
fn the_usd_corpus_deep_files_included_is_read_without_panics() {
    use pelage_scene::usd_file;
    let accepted = read_all("usd", |bytes, path| {
        match usd_file::read(bytes.to_vec(), path) {
            Ok(groom) => {
                check(&groom);
                true
            }
            Err(_) => false,
        }
    });
    assert!(accepted > 0);
    // The deep seeds are there, and the ones within the limit are read.
    for name in [
        "seed-deep-xforms-at-limit",
        "seed-deep-curves-64",
        "seed-deep-dictionaries-at-limit",
    ] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../fuzz/corpus/usd")
            .join(name);
        let bytes = std::fs::read(&path).unwrap();
        assert!(usd_file::read(bytes, &path).is_ok(), "{name}");
    }
}
