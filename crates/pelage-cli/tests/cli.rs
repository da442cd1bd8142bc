//! The `pelage` binary end to end: help texts, tiny GPU runs, and the errors a bad scene
//! file gets. The GPU runs need an adapter (lavapipe is enough) and are kept tiny.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A folder of this test's own, removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("pelage-cli-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create a scratch folder");
        Self(dir)
    }

    fn file(&self, name: &str, text: &str) -> PathBuf {
        let path = self.0.join(name);
        std::fs::write(&path, text).expect("write a scratch file");
        path
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn pelage(args: &[&str]) -> Output {
    let runtime = std::env::temp_dir().join(format!("pelage-cli-xdg-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&runtime);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let _ = std::fs::set_permissions(&runtime, std::fs::Permissions::from_mode(0o700));
    }
    let mut command = Command::new(env!("CARGO_BIN_EXE_pelage"));
    command.args(args);
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        command.env("XDG_RUNTIME_DIR", &runtime);
    }
    command.output().expect("run the pelage binary")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Runs `args`, asserts success, returns stdout.
fn ok(args: &[&str]) -> String {
    let out = pelage(args);
    assert!(
        out.status.success(),
        "pelage {args:?} failed ({}):\nstdout:\n{}\nstderr:\n{}",
        out.status,
        text(&out.stdout),
        text(&out.stderr)
    );
    text(&out.stdout)
}

/// Runs `args`, asserts a clean failure (exit 1 or 2, no panic, no Debug dump), returns stderr.
fn fails(args: &[&str]) -> String {
    let out = pelage(args);
    let stderr = text(&out.stderr);
    let code = out.status.code();
    assert!(
        matches!(code, Some(1 | 2)),
        "pelage {args:?}: expected exit code 1 or 2, got {code:?}\nstderr:\n{stderr}"
    );
    assert!(
        !stderr.contains("panicked"),
        "pelage {args:?} panicked:\n{stderr}"
    );
    assert!(
        !stderr.contains("Toml {") && !stderr.contains("Io {") && !stderr.contains("kind:"),
        "pelage {args:?} printed a Debug dump:\n{stderr}"
    );
    assert!(stderr.starts_with("error: "), "pelage {args:?}:\n{stderr}");
    stderr
}

fn assert_mentions(help: &str, words: &[&str]) {
    for word in words {
        assert!(help.contains(word), "help lacks `{word}`:\n{help}");
    }
}

#[test]
fn help_of_every_command() {
    let top = ok(&["--help"]);
    assert_mentions(
        &top,
        &["render", "animate", "lab", "bench", "info", "Examples:"],
    );
    let scene_options = [
        "--scene",
        "--size",
        "--strands",
        "--shadow",
        "--shadow-res",
        "--oit",
        "--model",
        "--lights",
        "k_buffer",
        "marschner_lut",
        "chiang",
        "key_back",
        "--melanin",
        "EU[,PHEO]",
        "[0, 50]",
        "--dual-scattering",
        "on|off",
    ];
    let render = ok(&["render", "--help"]);
    assert_mentions(&render, &scene_options);
    assert_mentions(&render, &["--time", "--out", "-o", "480x360", "Examples:"]);
    let animate = ok(&["animate", "--help"]);
    assert_mentions(&animate, &scene_options);
    assert_mentions(
        &animate,
        &["--frames", "--fps", "--out", "out/wind", "48", "24"],
    );
    assert_mentions(
        &ok(&["lab", "--help"]),
        &["shadows", "oit", "shading", "lod"],
    );
    for lab in ["shadows", "oit", "shading"] {
        assert_mentions(
            &ok(&["lab", lab, "--help"]),
            &["--quick", "--out", "out/lab"],
        );
    }
    assert_mentions(
        &ok(&["bench", "--help"]),
        &["--quick", "--out", "out/bench"],
    );
    assert_mentions(&ok(&["info", "--help"]), &["adapter", "limits"]);
}

#[test]
fn usage_errors_exit_2() {
    for args in [
        &["render", "--size", "96"][..],
        &["render", "--oit", "nope"],
        &["animate", "--frames", "0"],
        &["lab", "nope"],
        &["frobnicate"],
    ] {
        let out = pelage(args);
        assert_eq!(out.status.code(), Some(2), "pelage {args:?}");
    }
}

/// Decodes `path` and asserts it is `w` x `h` and not one flat colour.
fn assert_not_blank(path: &Path, w: u32, h: u32) {
    let image = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .into_rgba8();
    assert_eq!(image.dimensions(), (w, h), "{}", path.display());
    let mut colours: Vec<[u8; 4]> = image.pixels().map(|p| p.0).collect();
    colours.sort_unstable();
    colours.dedup();
    assert!(
        colours.len() > 16,
        "{} has only {} colours",
        path.display(),
        colours.len()
    );
}

#[test]
fn render_default_scene_tiny() {
    let dir = Scratch::new("render");
    let png = dir.0.join("sub/tiny.png");
    let png_arg = png.to_string_lossy().into_owned();
    let stdout = ok(&[
        "render",
        "--size",
        "96x72",
        "--strands",
        "500",
        "--time",
        "0.5",
        "-o",
        &png_arg,
    ]);
    assert_not_blank(&png, 96, 72);
    assert!(stdout.contains("wrote"), "{stdout}");
    assert!(
        stdout.contains("GPU time per pass"),
        "render prints the GPU time per pass:\n{stdout}"
    );
}

#[test]
fn render_with_level_of_detail_says_what_it_drew() {
    let dir = Scratch::new("render_lod");
    let png = dir.0.join("lod.png");
    let png_arg = png.to_string_lossy().into_owned();
    // 96x72 shows the creature on far fewer pixels than the default B0: it simplifies.
    let stdout = ok(&[
        "render",
        "--lod",
        "--size",
        "96x72",
        "--strands",
        "2000",
        "-o",
        &png_arg,
    ]);
    assert_not_blank(&png, 96, 72);
    let line = stdout
        .lines()
        .find(|l| l.starts_with("level of detail"))
        .unwrap_or_else(|| panic!("no level-of-detail line:\n{stdout}"));
    let drawn: u32 = line
        .rsplit(": ")
        .next()
        .and_then(|rest| rest.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("cannot read the strand count in `{line}`"));
    assert!(drawn < 2000, "{line}");
}

#[test]
fn animate_two_tiny_frames() {
    let dir = Scratch::new("animate");
    let out = dir.0.to_string_lossy().into_owned();
    ok(&[
        "animate",
        "--frames",
        "2",
        "--size",
        "64x48",
        "--strands",
        "300",
        "--shadow",
        "none",
        "--out",
        &out,
    ]);
    assert_not_blank(&dir.0.join("frame_0001.png"), 64, 48);
    let gif = std::fs::metadata(dir.0.join("wind.gif")).expect("wind.gif written");
    assert!(gif.len() > 0);
}

#[test]
fn scene_file_with_an_unknown_key() {
    let dir = Scratch::new("unknown-key");
    let scene = dir.file("unknown.toml", "[hair.roots]\ncount = 500\nbogus_key = 3\n");
    let stderr = fails(&["render", "--scene", &scene.to_string_lossy()]);
    assert_mentions(&stderr, &["unknown.toml", "bogus_key", "line 3"]);
}

#[test]
fn scene_file_with_a_wrong_type() {
    let dir = Scratch::new("wrong-type");
    let scene = dir.file("wrong.toml", "[hair.roots]\ncount = \"many\"\n");
    let stderr = fails(&["animate", "--scene", &scene.to_string_lossy()]);
    assert_mentions(&stderr, &["wrong.toml", "count", "line 2", "invalid type"]);
}

#[test]
fn missing_scene_file() {
    let dir = Scratch::new("missing");
    let path = dir.0.join("no_such_scene.toml");
    let stderr = fails(&["render", "--scene", &path.to_string_lossy()]);
    assert_mentions(&stderr, &[&path.to_string_lossy()]);
}

#[test]
fn out_of_range_strands_exit_2() {
    let out = pelage(&["render", "--strands", "0", "--size", "32x24"]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("roots.count"));
}

#[test]
fn info_prints_the_adapter() {
    let stdout = ok(&["info"]);
    assert_mentions(
        &stdout,
        &[
            "adapter",
            "name",
            "backend",
            "TIMESTAMP_QUERY",
            "SHADER_INT64_ATOMIC_MIN_MAX",
            "max_storage_buffer_binding_size",
            "k-buffer at 1920x1080",
        ],
    );
}

/// Runs `args`, asserts exit code 2 with an `error: ` message (no panic) that mentions
/// every word of `words`, returns stderr.
fn exits_2(args: &[&str], words: &[&str]) -> String {
    let out = pelage(args);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "pelage {args:?}:\n{stderr}");
    assert!(
        !stderr.contains("panicked"),
        "pelage {args:?} panicked:\n{stderr}"
    );
    assert!(stderr.starts_with("error: "), "pelage {args:?}:\n{stderr}");
    assert_mentions(&stderr, words);
    stderr
}

#[test]
fn an_unknown_key_at_marschners_own_level_is_refused() {
    // The case: this used to render with exit 0.
    let dir = Scratch::new("marschner-key");
    let scene = dir.file(
        "marschner.toml",
        "[shade.model]\nmodel = \"marschner\"\nbogus_key = 1\n",
    );
    exits_2(
        &["render", "--scene", &scene.to_string_lossy()],
        &["marschner.toml", "bogus_key", "line 3"],
    );
    let scene = dir.file(
        "none.toml",
        "[shadow]\nmethod = \"none\"\nresolution = [64, 64, 64]\n",
    );
    exits_2(
        &["render", "--scene", &scene.to_string_lossy()],
        &["none.toml", "resolution", "line 3"],
    );
}

#[test]
fn chiang_options_refuse_another_model() {
    exits_2(
        &["render", "--size", "32x24", "--melanin", "0.3"],
        &["--melanin", "chiang", "kajiya_kay"],
    );
    exits_2(
        &[
            "animate",
            "--model",
            "marschner",
            "--dual-scattering",
            "off",
        ],
        &["--dual-scattering", "chiang", "marschner"],
    );
    // A value that is not on or off, or not a number, is clap's error, naming the option.
    exits_2(
        &["render", "--model", "chiang", "--dual-scattering", "maybe"],
        &["--dual-scattering"],
    );
    exits_2(
        &["render", "--model", "chiang", "--melanin", "brown"],
        &["--melanin", "brown"],
    );
}

#[test]
fn bad_chiang_values_on_the_command_line_exit_2() {
    for (melanin, key) in [
        ("-0.5", "shading.chiang.eumelanin"),
        ("nan", "shading.chiang.eumelanin"),
        ("60", "shading.chiang.eumelanin"),
        ("0.3,-1", "shading.chiang.pheomelanin"),
        ("0.3,NaN", "shading.chiang.pheomelanin"),
    ] {
        exits_2(
            &[
                "render",
                "--size",
                "32x24",
                "--model",
                "chiang",
                "--melanin",
                melanin,
            ],
            &[key],
        );
    }
}

#[test]
fn bad_chiang_values_in_a_scene_file_exit_2() {
    let dir = Scratch::new("chiang-values");
    for (i, (line, key)) in [
        ("beta_m = 0.0", "shading.chiang.beta_m"),
        ("beta_m = 1.5", "shading.chiang.beta_m"),
        ("beta_n = nan", "shading.chiang.beta_n"),
        ("alpha_deg = nan", "shading.chiang.alpha_deg"),
        ("eta = 1.0", "shading.chiang.eta"),
        ("eumelanin = -1.0", "shading.chiang.eumelanin"),
        ("pheomelanin = nan", "shading.chiang.pheomelanin"),
        ("sigma_a = [0.1, -0.1, 0.1]", "shading.chiang.sigma_a"),
    ]
    .into_iter()
    .enumerate()
    {
        let name = format!("chiang_{i}.toml");
        let scene = dir.file(
            &name,
            &format!("[shade.model]\nmodel = \"chiang\"\n{line}\n"),
        );
        exits_2(
            &["render", "--scene", &scene.to_string_lossy()],
            &[&name, key],
        );
    }
}

/// The repository's scenes folder.
fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

#[test]
fn render_blond_chiang_tiny() {
    let dir = Scratch::new("blond");
    let png = dir.0.join("blond.png");
    let png_arg = png.to_string_lossy().into_owned();
    let scene = scenes().join("blond_chiang.toml");
    ok(&[
        "render",
        "--scene",
        &scene.to_string_lossy(),
        "--size",
        "64x48",
        "--strands",
        "400",
        "-o",
        &png_arg,
    ]);
    assert_not_blank(&png, 64, 48);
    // The options on the built-in scene: black hair, single scattering.
    let png = dir.0.join("black.png");
    let png_arg = png.to_string_lossy().into_owned();
    ok(&[
        "render",
        "--size",
        "64x48",
        "--strands",
        "400",
        "--shadow",
        "none",
        "--model",
        "chiang",
        "--melanin",
        "8",
        "--dual-scattering",
        "off",
        "-o",
        &png_arg,
    ]);
    assert_not_blank(&png, 64, 48);
}
