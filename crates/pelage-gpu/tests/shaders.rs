//! Every shader under wgsl/ is embedded and passes naga validation.

use std::path::Path;

use pelage_gpu::{SOURCES, ShaderLibrary};

/// Names of every `.wgsl` file below `dir`, relative to `root`, '/'-separated.
fn walk(root: &Path, dir: &Path, names: &mut Vec<String>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("reading {dir:?}: {e}"));
    for entry in entries {
        let path = entry.expect("directory entry").path();
        if path.is_dir() {
            walk(root, &path, names);
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            let relative = path.strip_prefix(root).expect("path below wgsl/");
            let parts: Vec<_> = relative
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            names.push(parts.join("/"));
        }
    }
}

#[test]
fn every_shader_validates() {
    // Every file on disk is embedded (build.rs saw them all).
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../wgsl");
    let mut on_disk = Vec::new();
    walk(&root, &root, &mut on_disk);
    on_disk.sort();
    let embedded: Vec<String> = SOURCES.iter().map(|(n, _)| n.to_string()).collect();
    assert!(!embedded.is_empty(), "no shaders embedded from {root:?}");
    assert_eq!(
        embedded, on_disk,
        "embedded shaders differ from wgsl/ on disk (rebuild so build.rs sees the change)"
    );

    // Validate each one, reporting all failures at once.
    let failures: Vec<String> = ShaderLibrary::names()
        .filter_map(|name| ShaderLibrary::validate(name).err().map(|e| format!("{e}")))
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {} shaders fail:\n\n{}",
        failures.len(),
        SOURCES.len(),
        failures.join("\n\n")
    );
}
