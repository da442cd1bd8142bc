//! `pelage trace` and `pelage compare` end to end: a tiny path-traced scene file (PNG,
//! HDR, hair mask; no NaN; the background only seen, the ambient lighting), the bounds
//! of `--spp` and `--bounces`, and compare's numbers on images with known answers. The
//! trace runs need an adapter (lavapipe is enough) to grow the strands.

use std::path::Path;

mod common;
use common::{Scratch, ok, pelage, text};

/// Runs `args`, asserts exit code 2 without a panic, returns stderr.
fn usage_error(args: &[&str]) -> String {
    let out = pelage(args);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "pelage {args:?}:\n{stderr}");
    assert!(!stderr.contains("panicked"), "pelage {args:?}:\n{stderr}");
    stderr
}

/// A few thick strands on a small ball, no light but the ambient sky, a black background:
/// every pixel the camera sees past the ball is black, the hair is lit by the sky alone.
const SKY_ONLY: &str = r#"
[mesh]
kind = "icosphere"
radius = 0.4
subdivisions = 1

[hair.roots]
count = 150

[hair.growth]
segments = 4
length = 0.35
width = 0.06
tip_width = 0.5
color = [0.6, 0.45, 0.3]
color_jitter = 0.0
opacity = 1.0

[shade]
background = [0.0, 0.0, 0.0]
ambient = 1.5
mesh_color = [0.3, 0.3, 0.3]

[shade.model]
model = "chiang"

[camera]
eye = [0.0, 0.2, 3.0]
target = [0.0, 0.0, 0.0]
fov_y = 0.6

[[lights]]
kind = "directional"
direction = [0.0, -1.0, 0.0]
intensity = 0.0
"#;

#[test]
fn trace_writes_png_hdr_and_mask_with_the_renderers_background_and_sky() {
    let dir = Scratch::new("sky");
    let scene = dir.file("scene.toml", SKY_ONLY);
    let scene = scene.to_string_lossy();
    let common = ["trace", "--scene", &scene, "--size", "32x24", "--spp", "2"];
    let png = dir.arg("t.png");
    let stdout = ok(&[&common[..], &["--bounces", "4", "-o", &png]].concat());
    assert!(stdout.contains("wrote"), "{stdout}");
    let image = image::open(&png).expect("the PNG").to_rgba8();
    assert_eq!(image.dimensions(), (32, 24));
    let mask = image::open(dir.path("t.mask.png"))
        .expect("the mask beside the PNG")
        .to_luma8();
    assert_eq!(mask.dimensions(), (32, 24));

    let hdr = dir.arg("t.hdr");
    ok(&[&common[..], &["--seed", "5", "-o", &hdr]].concat());
    let radiance = image::open(&hdr).expect("the HDR").to_rgb32f();
    assert_eq!(radiance.dimensions(), (32, 24));
    let mask = image::open(dir.path("t.mask.png"))
        .expect("the mask beside the HDR")
        .to_luma8();
    assert!(
        radiance.pixels().all(|p| p.0.iter().all(|v| v.is_finite())),
        "a pixel is not finite"
    );
    // Camera rays past the ball see the background: black.
    for (x, y) in [(0, 0), (31, 0), (0, 23), (31, 23)] {
        assert_eq!(radiance.get_pixel(x, y).0, [0.0; 3], "corner ({x}, {y})");
        assert_eq!(mask.get_pixel(x, y).0, [0], "corner ({x}, {y})");
    }
    // The hair is lit, by the sky (ambient / π) alone: the only light has intensity 0.
    let hair: Vec<f32> = radiance
        .pixels()
        .zip(mask.pixels())
        .filter(|(_, m)| m.0[0] >= 128)
        .map(|(p, _)| p.0.iter().sum::<f32>() / 3.0)
        .collect();
    let mean = hair.iter().sum::<f32>() / hair.len().max(1) as f32;
    println!("{} hair pixels, mean radiance {mean:.4}", hair.len());
    assert!(hair.len() >= 10, "{} hair pixels", hair.len());
    assert!(mean > 0.02, "the hair is not lit by the sky: {mean}");
    // The same scene seen as the old path tracer saw it (the background lighting the
    // hair) would be black: the background is black.

    // compare of the trace with itself: nothing differs.
    let out = ok(&["compare", &hdr, &hdr]);
    assert!(out.contains("mean FLIP, image: 0.0000"), "{out}");
    assert!(out.contains("(TEST/REF): 1.0000"), "{out}");
}

#[test]
fn help_of_trace_and_compare() {
    let top = ok(&["--help"]);
    assert!(top.contains("trace") && top.contains("compare"), "{top}");
    let trace = ok(&["trace", "--help"]);
    for word in [
        "--scene",
        "--size",
        "--spp",
        "1..=65536",
        "--bounces",
        "1..=1024",
        "--seed",
        "--time",
        ".png",
        ".hdr",
        "mask",
        "background",
        "ambient",
        "Examples:",
    ] {
        assert!(trace.contains(word), "trace --help lacks {word}:\n{trace}");
    }
    let compare = ok(&["compare", "--help"]);
    for word in ["REF", "TEST", "--mask", "--heat", "FLIP", "Examples:"] {
        assert!(
            compare.contains(word),
            "compare --help lacks {word}:\n{compare}"
        );
    }
}

#[test]
fn trace_bounds_and_bad_options_are_named() {
    let dir = Scratch::new("bounds");
    let scene = dir.file("scene.toml", SKY_ONLY);
    let scene = scene.to_string_lossy();
    let out = dir.arg("t.png");
    let run = |extra: &[&str]| {
        let mut args = vec!["trace", "--scene", &scene, "-o", &out];
        if !extra.contains(&"--size") {
            args.extend_from_slice(&["--size", "8x8"]);
        }
        args.extend_from_slice(extra);
        usage_error(&args)
    };
    for (args, words) in [
        (&["--spp", "0"][..], &["--spp", "1..=65536"][..]),
        (&["--spp", "65537"], &["--spp", "1..=65536"]),
        (&["--spp", "-3"], &["--spp"]),
        (&["--bounces", "0"], &["--bounces", "1..=1024"]),
        (&["--bounces", "1025"], &["--bounces", "1..=1024"]),
        (&["--shadow", "voxel"], &["--shadow", "path tracer"]),
        (&["--oit", "k_buffer"], &["--oit"]),
        (&["--lod"], &["--lod"]),
        (&["--time", "nan"], &["--time"]),
        (&["--size", "9000x8"], &["--size", "8192"]),
    ] {
        let stderr = run(args);
        for word in words {
            assert!(stderr.contains(word), "{args:?}: lacks {word}:\n{stderr}");
        }
    }
    let stderr = usage_error(&["trace", "--scene", &scene, "-o", &dir.arg("t.jpg")]);
    assert!(
        stderr.contains("-o") && stderr.contains("t.jpg"),
        "{stderr}"
    );
    // The scattering lab's --spp has the same bound.
    let stderr = usage_error(&["lab", "scattering", "--spp", "4294967295"]);
    assert!(
        stderr.contains("--spp") && stderr.contains("1..=65536"),
        "{stderr}"
    );
    assert!(!dir.path("t.png").exists());
}

/// Writes a linear image as Radiance HDR.
fn write_hdr(path: &Path, w: u32, h: u32, pixels: &[[f32; 3]]) {
    let rgb: Vec<image::Rgb<f32>> = pixels.iter().map(|p| image::Rgb(*p)).collect();
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    image::codecs::hdr::HdrEncoder::new(file)
        .encode(&rgb, w as usize, h as usize)
        .unwrap();
}

/// The number after `key` in `out`.
fn number(out: &str, key: &str) -> f64 {
    let at = out
        .find(key)
        .unwrap_or_else(|| panic!("no `{key}` in:\n{out}"))
        + key.len();
    let rest = out[at..].trim_start();
    let end = rest
        .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | '-' | '+')))
        .unwrap_or(rest.len());
    rest[..end]
        .parse()
        .unwrap_or_else(|e| panic!("`{}` after `{key}`: {e}", &rest[..end]))
}

#[test]
fn compare_of_known_images() {
    let dir = Scratch::new("compare");
    let (w, h) = (16u32, 12u32);
    // Values RGBE stores exactly (a shared exponent, 8-bit mantissas), and twice them.
    let palette = [
        [0.5, 0.25, 0.125],
        [0.25, 0.25, 0.0625],
        [0.125, 0.0625, 0.0],
    ];
    let pixels: Vec<[f32; 3]> = (0..w * h)
        .map(|i| palette[(i as usize * 7 / 5) % palette.len()])
        .collect();
    let bright: Vec<[f32; 3]> = pixels
        .iter()
        .map(|p| [2.0 * p[0], 2.0 * p[1], 2.0 * p[2]])
        .collect();
    let reference = dir.path("ref.hdr");
    write_hdr(&reference, w, h, &pixels);
    write_hdr(&dir.path("bright.hdr"), w, h, &bright);
    // The left half is hair.
    let mask =
        image::GrayImage::from_fn(w, h, |x, _| image::Luma([if x < w / 2 { 255 } else { 0 }]));
    mask.save(dir.path("ref.mask.png")).unwrap();
    let (reference, bright) = (dir.arg("ref.hdr"), dir.arg("bright.hdr"));

    let same = ok(&["compare", &reference, &reference]);
    assert!(same.contains("ref.mask.png (96 hair pixels"), "{same}");
    assert_eq!(number(&same, "mean FLIP, image:"), 0.0, "{same}");
    assert_eq!(number(&same, "mean FLIP, hair:"), 0.0, "{same}");
    assert_eq!(number(&same, "(TEST/REF):"), 1.0, "{same}");
    for channel in [" R ", " G ", " B "] {
        assert_eq!(number(&same, channel), 0.0, "{same}");
    }

    let heat = dir.arg("heat.png");
    let out = ok(&["compare", &reference, &bright, "--heat", &heat]);
    // Twice the radiance: the ratio of the hair's luminance is 2, the colour difference
    // the reference's mean hair colour.
    assert_eq!(number(&out, "(TEST/REF):"), 2.0, "{out}");
    let hair: Vec<[f32; 3]> = (0..w * h)
        .filter(|i| i % w < w / 2)
        .map(|i| pixels[i as usize])
        .collect();
    for (c, channel) in [" R ", " G ", " B "].into_iter().enumerate() {
        let expect = hair.iter().map(|p| f64::from(p[c])).sum::<f64>() / hair.len() as f64;
        let got = number(&out, channel);
        assert!(
            (got - expect).abs() < 1e-5,
            "{channel}: {got} vs {expect}\n{out}"
        );
    }
    assert!(number(&out, "mean FLIP, image:") > 0.0, "{out}");
    let map = image::open(&heat).expect("the heat map").to_rgba8();
    assert_eq!(map.dimensions(), (w, h));

    // No mask: the image-wide number only, and it says so.
    std::fs::remove_file(dir.path("ref.mask.png")).unwrap();
    let out = ok(&["compare", &reference, &bright]);
    assert!(out.contains("image-wide numbers only"), "{out}");
    assert!(
        out.contains("mean FLIP, image:") && !out.contains("hair:"),
        "{out}"
    );

    // Sizes that differ: both named.
    write_hdr(&dir.path("small.hdr"), 8, 12, &pixels[..96]);
    let stderr = usage_error(&["compare", &reference, &dir.arg("small.hdr")]);
    assert!(
        stderr.contains("16x12") && stderr.contains("8x12"),
        "{stderr}"
    );
    // Not an image: named.
    let note = dir.file("note.txt", "hello");
    let stderr = usage_error(&["compare", &reference, &note.to_string_lossy()]);
    assert!(
        stderr.contains("TEST") && stderr.contains("note.txt"),
        "{stderr}"
    );
    let stderr = usage_error(&["compare", &reference, &dir.arg("missing.png")]);
    assert!(stderr.contains("missing.png"), "{stderr}");
}
