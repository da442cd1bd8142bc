//! Embed every `.wgsl` file under the workspace's `wgsl/` folder.
//!
//! Writes `$OUT_DIR/wgsl_sources.rs` with
//! `pub static SOURCES: &[(&str, &str)] = &[("shared/math.wgsl", include_str!("/abs/path")), ...];`
//! sorted by path, paths relative to `wgsl/` with `/` separators. A missing or
//! empty folder gives an empty list.

use std::path::{Path, PathBuf};
use std::{env, fs, io};

fn main() -> io::Result<()> {
    let manifest = PathBuf::from(env::var("CARGO_MANIFEST_DIR").map_err(io::Error::other)?);
    let root = manifest.join("../../wgsl");
    // A directory makes cargo rescan it entirely, so added files are seen too.
    println!("cargo:rerun-if-changed={}", root.display());
    println!("cargo:rerun-if-changed=build.rs");

    let mut files = Vec::new();
    if root.is_dir() {
        walk(&root, &root, &mut files)?;
    }
    files.sort();

    let mut out = String::from(
        "/// Every `.wgsl` file under the workspace's `wgsl/` folder as (path relative to \
         `wgsl/`, source), sorted by path; embedded at build time by `build.rs`.\n\
         pub static SOURCES: &[(&str, &str)] = &[\n",
    );
    for (name, path) in &files {
        println!("cargo:rerun-if-changed={}", path.display());
        let abs = fs::canonicalize(path)?;
        let Some(abs) = abs.to_str() else {
            println!("cargo:warning=skipping shader with a non-UTF-8 path: {abs:?}");
            continue;
        };
        out.push_str(&format!("    ({name:?}, include_str!({abs:?})),\n"));
    }
    out.push_str("];\n");

    let dest = PathBuf::from(env::var("OUT_DIR").map_err(io::Error::other)?);
    fs::write(dest.join("wgsl_sources.rs"), out)
}

/// Collect (relative name, path) of every `.wgsl` file below `dir`.
fn walk(root: &Path, dir: &Path, files: &mut Vec<(String, PathBuf)>) -> io::Result<()> {
    for entry in fs::read_dir(dir)? {
        let path = entry?.path();
        if path.is_dir() {
            walk(root, &path, files)?;
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            let Ok(relative) = path.strip_prefix(root) else {
                continue;
            };
            let name: Vec<String> = relative
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            files.push((name.join("/"), path));
        }
    }
    Ok(())
}
