//! Special files as inputs: a FIFO (named pipe), a device or a directory given as a
//! groom, scene, mesh or map path is refused before it is opened, with an error that
//! says what the path is. Opening a FIFO for reading blocks until a writer comes, so
//! every read here runs on its own thread and the test fails (instead of hanging)
//! when one does not return within a minute.
#![cfg(unix)]

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

use pelage_scene::{Groom, MapImage, SceneFile, load_obj};

/// Runs `read` on a thread; its error text, or a test failure when it blocks.
fn error_within_a_minute(
    what: &str,
    read: impl FnOnce() -> Result<(), String> + Send + 'static,
) -> String {
    let (send, receive) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = send.send(read());
    });
    match receive.recv_timeout(Duration::from_secs(60)) {
        Ok(Ok(())) => panic!("{what}: a special file was read as an input"),
        Ok(Err(e)) => e,
        Err(_) => panic!("{what}: reading blocked for a minute (opened a FIFO?)"),
    }
}

/// A FIFO named `name` in a fresh folder (made by `mkfifo`, as a user would).
fn fifo(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pelage-fifo-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    let _ = std::fs::remove_file(&path);
    let status = std::process::Command::new("mkfifo")
        .arg(&path)
        .status()
        .expect("mkfifo runs");
    assert!(status.success());
    path
}

/// A reader run on a thread: its error text.
type Read = Box<dyn FnOnce() -> Result<(), String> + Send>;

/// Every reader, on `path`.
fn readers(path: &Path) -> Vec<(String, Read)> {
    let p = path.to_path_buf();
    let (a, b, c, d) = (p.clone(), p.clone(), p.clone(), p.clone());
    vec![
        (
            "groom".into(),
            Box::new(move || Groom::load(&a).map(drop).map_err(|e| e.to_string())),
        ),
        (
            "scene".into(),
            Box::new(move || SceneFile::load(&b).map(drop).map_err(|e| e.to_string())),
        ),
        (
            "obj".into(),
            Box::new(move || load_obj(&c).map(drop).map_err(|e| e.to_string())),
        ),
        (
            "map".into(),
            Box::new(move || MapImage::load(&d).map(drop).map_err(|e| e.to_string())),
        ),
    ]
}

#[test]
fn fifos_are_refused_before_opening() {
    let mut names = vec![
        "groom.hair",
        "groom.tfx",
        "scene.toml",
        "mesh.obj",
        "map.png",
    ];
    if cfg!(feature = "usd") {
        names.extend(["groom.usda", "groom.usdz"]);
    }
    for name in names {
        let path = fifo(name);
        for (reader, read) in readers(&path) {
            // Each reader is given the FIFO whatever its extension: none may block.
            if reader == "groom" && !name.starts_with("groom") {
                continue;
            }
            let e = error_within_a_minute(&format!("{reader} reading {name}"), read);
            assert!(e.contains("a FIFO (named pipe)"), "{reader} {name}: {e}");
            assert!(
                e.contains(name),
                "{reader} {name}: the error names the file: {e}"
            );
        }
        std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
    }
}

#[test]
fn devices_and_directories_are_refused() {
    for (path, kind) in [("/dev/zero", "a character device"), ("/tmp", "a directory")] {
        for (reader, read) in readers(Path::new(path)) {
            let e = error_within_a_minute(&format!("{reader} reading {path}"), read);
            // A groom path without a known extension is refused by extension first.
            if reader == "groom" {
                continue;
            }
            assert!(e.contains(kind), "{reader} {path}: {e}");
        }
    }
}
