//! Writes the seed corpora `corpus/hair_file/seed-*` and `corpus/obj/seed-*`:
//! small valid files (the `.hair` ones through pelage's own writer) plus edge
//! cases. Run from `fuzz/`: `cargo run --example make_seeds`.

use std::path::Path;

use glam::Vec3;
use pelage_scene::HairFile;
use pelage_scene::hair_file::{HEADER_SIZE, INFO_SIZE, SIGNATURE};

/// A `.hair` header with the given counts and array bits, default segment
/// count 0, thickness 1, transparency 0, colour white, empty info.
fn header(hair_count: u32, point_count: u32, arrays: u32, default_segments: u32) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER_SIZE);
    out.extend_from_slice(&SIGNATURE);
    for x in [hair_count, point_count, arrays, default_segments] {
        out.extend_from_slice(&x.to_le_bytes());
    }
    for x in [1.0f32, 0.0, 1.0, 1.0, 1.0] {
        out.extend_from_slice(&x.to_le_bytes());
    }
    out.resize(HEADER_SIZE, 0);
    out
}

fn strand(root: Vec3, points: usize) -> Vec<Vec3> {
    (0..points)
        .map(|i| root + Vec3::new(0.01 * i as f32, 0.1 * i as f32, 0.0))
        .collect()
}

fn hair_seeds() -> Vec<(&'static str, Vec<u8>)> {
    let mut seeds = Vec::new();

    // Valid files written by pelage's writer.
    let two = HairFile::from_strands(&[strand(Vec3::ZERO, 3), strand(Vec3::X, 2)]).unwrap();
    seeds.push(("two-strands", two.write().unwrap()));

    let mut full = HairFile::from_strands(&[
        strand(Vec3::ZERO, 4),
        strand(Vec3::Y, 2),
        strand(Vec3::Z, 3),
    ])
    .unwrap();
    let n = full.points.len();
    full.has_thickness = true;
    full.has_transparency = true;
    full.has_colors = true;
    full.thickness = (0..n).map(|i| 0.1 + i as f32 * 0.01).collect();
    full.transparency = (0..n).map(|i| i as f32 / n as f32).collect();
    full.colors = (0..n)
        .map(|i| Vec3::new(0.5, 0.3, i as f32 * 0.1))
        .collect();
    full.info = "pelage fuzz seed: every array".to_owned();
    seeds.push(("all-arrays", full.write().unwrap()));

    // No segments array: every strand has the default segment count.
    let mut uniform = HairFile::from_strands(&[
        strand(Vec3::ZERO, 3),
        strand(Vec3::X, 3),
        strand(Vec3::Y, 3),
    ])
    .unwrap();
    uniform.has_segments = false;
    uniform.default_segments = 2;
    uniform.info = "default segments".to_owned();
    seeds.push(("default-segments", uniform.write().unwrap()));

    // Odd hair count (the point array starts at an odd, unaligned offset),
    // one long strand, with a thickness array.
    let mut odd = HairFile::from_strands(&[
        strand(Vec3::ZERO, 2),
        strand(Vec3::ONE, 17),
        strand(-Vec3::ONE, 2),
    ])
    .unwrap();
    odd.has_thickness = true;
    odd.thickness = vec![0.25; odd.points.len()];
    seeds.push(("odd-hair-count", odd.write().unwrap()));

    // Edge cases, hand-made.
    seeds.push(("empty", Vec::new()));
    seeds.push(("signature-only", SIGNATURE.to_vec()));
    seeds.push(("header-only-no-hair", header(0, 0, 2, 0)));
    seeds.push(("header-only-claims-hair", header(3, 9, 3, 2)));
    seeds.push(("header-no-points-bit", header(0, 0, 1, 0)));
    seeds.push((
        "header-huge-counts",
        header(u32::MAX, u32::MAX, 31, u32::MAX),
    ));
    seeds.push((
        "header-short-by-one",
        header(0, 0, 2, 0)[..HEADER_SIZE - 1].to_vec(),
    ));
    let mut bad_sig = header(0, 0, 2, 0);
    bad_sig[..4].copy_from_slice(b"HIAR");
    seeds.push(("bad-signature", bad_sig));

    // One strand, default segments larger than a u16 can hold (needs points
    // the file does not have: counts mismatch / size checks trip first).
    seeds.push(("default-segments-too-large", header(1, 65537, 2, 65536)));

    // Truncated valid file, and a valid file with trailing bytes.
    let two_bytes = two.write().unwrap();
    seeds.push(("truncated", two_bytes[..two_bytes.len() - 1].to_vec()));
    let mut trailing = two_bytes.clone();
    trailing.extend_from_slice(b"trailing bytes");
    seeds.push(("trailing-bytes", trailing));

    // Unknown array bits set alongside the known ones.
    let mut unknown = two_bytes.clone();
    unknown[12..16].copy_from_slice(&(0xffff_ffe0u32 | 3).to_le_bytes());
    seeds.push(("unknown-array-bits", unknown));

    // Info: 88 bytes without a NUL, and invalid UTF-8.
    let mut full_info = two_bytes.clone();
    full_info[HEADER_SIZE - INFO_SIZE..HEADER_SIZE].fill(b'x');
    seeds.push(("info-no-nul", full_info));
    let mut bad_info = two_bytes.clone();
    bad_info[HEADER_SIZE - INFO_SIZE..HEADER_SIZE].fill(0xff);
    seeds.push(("info-not-utf8", bad_info));

    // Segments that do not add up to the point count.
    let mut mismatch = two_bytes.clone();
    mismatch[HEADER_SIZE..HEADER_SIZE + 2].copy_from_slice(&7u16.to_le_bytes());
    seeds.push(("segment-point-mismatch", mismatch));

    // A NaN point, and a NaN thickness default (allowed: only points must be finite).
    let mut nan_point = two_bytes.clone();
    let first_point = HEADER_SIZE + 2 * 2;
    nan_point[first_point..first_point + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    seeds.push(("nan-point", nan_point));
    let mut nan_default = two_bytes.clone();
    nan_default[20..24].copy_from_slice(&f32::NAN.to_le_bytes());
    seeds.push(("nan-default-thickness", nan_default));

    seeds
}

const CUBE: &str = "\
# unit cube, quads, no normals
o cube
v -0.5 -0.5 -0.5
v  0.5 -0.5 -0.5
v  0.5  0.5 -0.5
v -0.5  0.5 -0.5
v -0.5 -0.5  0.5
v  0.5 -0.5  0.5
v  0.5  0.5  0.5
v -0.5  0.5  0.5
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 4 8 7 3
f 1 5 8 4
f 2 3 7 6
";

fn obj_seeds() -> Vec<(&'static str, String)> {
    let seeds: Vec<(&'static str, String)> = vec![
        ("cube-quads", CUBE.to_owned()),
        (
            "triangle-normals",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n".to_owned(),
        ),
        (
            "triangle-texcoords-normals",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n\
             f 1/1/1 2/2/1 3/3/1\n"
                .to_owned(),
        ),
        (
            "triangle-texcoords",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n".to_owned(),
        ),
        (
            "negative-indices",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 1 1 0\nf -3 -1 -2\n".to_owned(),
        ),
        (
            "groups-materials",
            "mtllib scene.mtl\no a\ng left\nusemtl red\nv 0 0 0\nv 1 0 0\nv 0 1 0\n\
             f 1 2 3\ng right\nusemtl blue\nv 0 0 1\nf 1 2 4\no b\nf 2 3 4\n"
                .to_owned(),
        ),
        (
            "w-and-colours",
            "v 0 0 0 1\nv 2 0 0 2\nv 0 1 0 0.5 0.5 0.5\nf 1 2 3\n".to_owned(),
        ),
        (
            "vertex-colours",
            "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n".to_owned(),
        ),
        (
            "points-lines-polygon",
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 0.5 0\np 1\nl 1 2\nf 1\nf 1 2\n\
             f 1 2 3 4 5\n"
                .to_owned(),
        ),
        (
            "polyline-three-vertices",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1\n\
             l 1/1/1 2/1/1 3/1/1\nl -3 -2 -1 -3\n"
                .to_owned(),
        ),
        (
            "crlf",
            "v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n".to_owned(),
        ),
        (
            "degenerate-and-good",
            "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n".to_owned(),
        ),
        (
            "all-degenerate",
            "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n".to_owned(),
        ),
        (
            "nan-position",
            "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_owned(),
        ),
        (
            "zero-normal",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nf 1//1 2//1 3//1\n".to_owned(),
        ),
        (
            "index-out-of-range",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n".to_owned(),
        ),
        (
            "index-zero",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n".to_owned(),
        ),
        ("comments-only", "# nothing here\n\n   \n".to_owned()),
        ("empty", String::new()),
        ("no-faces", "v 0 0 0\nv 1 0 0\nv 0 1 0\n".to_owned()),
        (
            "huge-coordinates",
            "v -3e38 0 0\nv 3e38 0 0\nv 0 3e38 0\nf 1 2 3\n".to_owned(),
        ),
        ("bad-float", "v 0 0 zero\nf 1 1 1\n".to_owned()),
        // Crashed before the fix (see crates/pelage-scene/tests/fuzz_regressions.rs).
        (
            "regression-polyline-huge-normal",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nl 1//9223372036854775807 2 3\n".to_owned(),
        ),
    ];
    seeds
}

fn write_all(dir: &Path, seeds: impl IntoIterator<Item = (&'static str, Vec<u8>)>) {
    std::fs::create_dir_all(dir).unwrap();
    for (name, bytes) in seeds {
        let path = dir.join(format!("seed-{name}"));
        std::fs::write(&path, bytes).unwrap();
        println!("{}", path.display());
    }
}

/// USD grooms: pelage's own writers' text, crate and package, and hand-written text
/// with every basis, wrap and interpolation, transforms and a few broken files.
fn usd_seeds() -> Vec<(&'static str, Vec<u8>)> {
    use pelage_scene::{Groom, usd_file};
    let groom = Groom::from_strands(&[strand(Vec3::ZERO, 3), strand(Vec3::X, 2)]).unwrap();
    let mut seeds = vec![
        (
            "written-usda",
            usd_file::to_usda(&groom).unwrap().into_bytes(),
        ),
        ("written-usdc", usd_file::to_usdc(&groom).unwrap()),
        ("written-usdz", usd_file::to_usdz(&groom).unwrap()),
    ];
    let text = |body: &str| {
        format!(
            "#usda 1.0\ndef Xform \"World\"\n{{\n    double3 xformOp:translate = (1, 2, 3)\n    float xformOp:rotateY = 30\n    uniform token[] xformOpOrder = [\"xformOp:translate\", \"xformOp:rotateY\"]\n    def BasisCurves \"Hair\"\n    {{\n{body}\n    }}\n}}\n"
        )
        .into_bytes()
    };
    let points4 = "point3f[] points = [(0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 0)]";
    seeds.push(("bezier", text(&format!("uniform token type = \"cubic\"\nuniform token basis = \"bezier\"\nint[] curveVertexCounts = [4]\n{points4}\nfloat[] widths = [0.1, 0.2] (interpolation = \"varying\")"))));
    seeds.push(("bspline-pinned", text(&format!("uniform token type = \"cubic\"\nuniform token basis = \"bspline\"\nuniform token wrap = \"pinned\"\nint[] curveVertexCounts = [4]\n{points4}\ncolor3f[] primvars:displayColor = [(1, 0, 0)]"))));
    seeds.push(("catmull-periodic", text(&format!("uniform token type = \"cubic\"\nuniform token basis = \"catmullRom\"\nuniform token wrap = \"periodic\"\nint[] curveVertexCounts = [4]\n{points4}\nfloat[] widths = [0.1, 0.2, 0.3, 0.4]\ncolor3f[] primvars:displayColor = [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 1)] (interpolation = \"vertex\")"))));
    seeds.push(("linear-uniform", text("uniform token type = \"linear\"\nint[] curveVertexCounts = [2, 2]\npoint3f[] points = [(0, 0, 0), (0, 1, 0), (1, 0, 0), (1, 1, 0)]\nfloat[] widths = [0.1, 0.2] (interpolation = \"uniform\")\ncolor3f[] primvars:displayColor = [(1, 0, 0), (0, 1, 0)] (interpolation = \"uniform\")")));
    seeds.push((
        "counts-mismatch",
        text(&format!(
            "uniform token type = \"linear\"\nint[] curveVertexCounts = [3]\n{points4}"
        )),
    ));
    seeds.push(("empty", Vec::new()));
    seeds.push(("magic-only", b"PXR-USDC".to_vec()));
    seeds.extend(deep_usd_seeds());
    seeds
}

/// USD files with nesting depth as the dimension: nested prims, curves, dictionaries,
/// arrays and variant sets around `usd_file::MAX_USD_NESTING` (below, at, past it and
/// far past it), brackets hidden in strings and comments, and a binary crate and a
/// package of a hierarchy past the limit.
fn deep_usd_seeds() -> Vec<(&'static str, Vec<u8>)> {
    use pelage_scene::usd_file::{self, MAX_USD_NESTING};
    let curve = "def BasisCurves \"C\" {\n uniform token type = \"linear\"\n int[] curveVertexCounts = [2]\n point3f[] points = [(0, 0, 0), (0, 1, 0)]\n}\n";
    // `depth` braces deep; the curve's `[(` make the brackets nest `depth + 2` deep.
    let xforms = |depth: usize| {
        let mut text = String::from("#usda 1.0\n");
        for level in 0..depth.saturating_sub(1) {
            text.push_str(&format!("def Xform \"X{level}\" {{\n"));
        }
        text.push_str(curve);
        text.push_str(&"}\n".repeat(depth.saturating_sub(1)));
        text.into_bytes()
    };
    let nested_curves = |depth: usize| {
        let mut text = String::from("#usda 1.0\n");
        for level in 0..depth {
            text.push_str(&format!("def BasisCurves \"C{level}\" {{\n uniform token type = \"linear\"\n int[] curveVertexCounts = [2]\n point3f[] points = [(0, 0, 0), (0, 1, 0)]\n double3 xformOp:translate = (1, 0, 0)\n uniform token[] xformOpOrder = [\"xformOp:translate\"]\n"));
        }
        text.push_str(&"}\n".repeat(depth));
        text.into_bytes()
    };
    let dictionaries = |depth: usize| {
        format!(
            "#usda 1.0\ndef \"A\" (\n customData = {}{{}}{}\n)\n{{\n}}\n{curve}",
            "{ dictionary d = ".repeat(depth),
            " }".repeat(depth)
        )
        .into_bytes()
    };
    let arrays = |depth: usize| {
        format!(
            "#usda 1.0\ndef \"A\" {{\n int[] a = {}1{}\n}}\n{curve}",
            "[".repeat(depth),
            "]".repeat(depth)
        )
        .into_bytes()
    };
    let variants = |depth: usize| {
        let mut text = String::from("#usda 1.0\n");
        for level in 0..depth {
            text.push_str(&format!(
                "def Xform \"V{level}\" {{\n variantSet \"s\" = {{\n \"a\" {{\n"
            ));
        }
        text.push_str(curve);
        text.push_str(&"}\n}\n}\n".repeat(depth));
        text.into_bytes()
    };
    let l = MAX_USD_NESTING;
    let mut seeds = vec![
        ("deep-xforms-32", xforms(32)),
        ("deep-xforms-at-limit", xforms(l - 2)),
        ("deep-xforms-past-limit", xforms(l - 1)),
        ("deep-xforms-2000", xforms(2000)),
        ("deep-curves-64", nested_curves(64)),
        ("deep-curves-past-limit", nested_curves(l - 1)),
        ("deep-dictionaries-at-limit", dictionaries(l - 3)),
        ("deep-dictionaries-past-limit", dictionaries(l)),
        ("deep-arrays-at-limit", arrays(l - 1)),
        ("deep-arrays-5000", arrays(5000)),
        ("deep-variants-40", variants(40)),
        ("deep-variants-past-limit", variants(l / 3 + 1)),
        (
            "deep-brackets-in-strings",
            format!(
                "#usda 1.0\n# {}\ndef \"A\" ( doc = \"{}\" ) {{\n string s = '{}'\n asset a = @{}@\n /* {} */\n}}\n{curve}",
                "{".repeat(5000),
                "(".repeat(5000),
                "[".repeat(5000),
                "{".repeat(5000),
                "[".repeat(5000)
            )
            .into_bytes(),
        ),
    ];
    // A binary hierarchy past the limit, and a package of a text past it.
    {
        use openusd::sdf::{self, ChildrenKey, FieldKey, SpecType, Value};
        let mut data = sdf::Data::new();
        let mut path = sdf::Path::abs_root();
        let root = data.create_spec(path.clone(), SpecType::PseudoRoot);
        root.add(ChildrenKey::PrimChildren, Value::TokenVec(vec!["P".into()]));
        for level in 0..=l {
            path = path.append_path("P").unwrap();
            let spec = data.create_spec(path.clone(), SpecType::Prim);
            spec.add(FieldKey::Specifier, Value::Specifier(sdf::Specifier::Def));
            spec.add(FieldKey::TypeName, Value::Token("Xform".into()));
            if level < l {
                spec.add(ChildrenKey::PrimChildren, Value::TokenVec(vec!["P".into()]));
            }
        }
        let mut out = std::io::Cursor::new(Vec::new());
        openusd::usdc::CrateWriter::write(&data, &mut out).unwrap();
        seeds.push(("deep-crate-past-limit", out.into_inner()));
    }
    let mut writer = openusd::usdz::ArchiveWriter::new(std::io::Cursor::new(Vec::new()));
    writer.add_layer("deep.usda", &xforms(l - 1)).unwrap();
    seeds.push((
        "deep-package-past-limit",
        writer.finish().unwrap().into_inner(),
    ));
    // Keep the readers' verdicts on the seeds in view when they are written.
    for (name, bytes) in &seeds {
        let verdict = usd_file::read(bytes.clone(), Path::new(name))
            .map(|g| format!("{} strands", g.strand_count()))
            .unwrap_or_else(|e| e.to_string().chars().take(120).collect());
        println!("{name}: {verdict}");
    }
    seeds
}

/// Region and texture maps: a 3 x 2 PNG of every colour type and bit depth PNG has
/// (grey 1/2/4/8/16, RGB 8/16, palette 1/2/4/8, grey + alpha 8/16, RGBA 8/16), an
/// interlaced one, a truncated one and one claiming a huge size.
fn map_seeds() -> Vec<(String, Vec<u8>)> {
    use png::{BitDepth, ColorType};
    let (width, height) = (3u32, 2u32);
    let mut seeds = Vec::new();
    let kinds = [
        (ColorType::Grayscale, &[1u8, 2, 4, 8, 16][..]),
        (ColorType::Rgb, &[8, 16][..]),
        (ColorType::Indexed, &[1, 2, 4, 8][..]),
        (ColorType::GrayscaleAlpha, &[8, 16][..]),
        (ColorType::Rgba, &[8, 16][..]),
    ];
    for (color, depths) in kinds {
        for &bits in depths {
            let depth = BitDepth::from_u8(bits).unwrap();
            let samples = color.samples();
            let row_bits = width as usize * samples * bits as usize;
            let row = row_bits.div_ceil(8);
            // Rising sample values so that every texel differs.
            let data: Vec<u8> = (0..row * height as usize)
                .map(|i| (i * 37 + 11) as u8)
                .collect();
            let mut bytes = Vec::new();
            {
                let mut encoder = png::Encoder::new(&mut bytes, width, height);
                encoder.set_color(color);
                encoder.set_depth(depth);
                if color == ColorType::Indexed {
                    let entries = 1usize << bits.min(8);
                    let palette: Vec<u8> = (0..entries * 3).map(|i| (i * 53) as u8).collect();
                    encoder.set_palette(palette);
                }
                let mut writer = encoder.write_header().unwrap();
                writer.write_image_data(&data).unwrap();
            }
            seeds.push((format!("{color:?}-{bits}").to_lowercase(), bytes));
        }
    }
    let rgba = seeds.iter().find(|(n, _)| n == "rgba-8").unwrap().1.clone();
    seeds.push(("truncated".into(), rgba[..rgba.len() / 2].to_vec()));
    let mut huge = rgba.clone();
    // IHDR width at byte 16: claim 2^31 - 1 texels across (the CRC no longer matches).
    huge[16..20].copy_from_slice(&0x7fff_ffffu32.to_be_bytes());
    seeds.push(("huge-header".into(), huge));
    seeds.push(("empty".into(), Vec::new()));
    seeds
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("corpus");
    write_all(&root.join("hair_file"), hair_seeds());
    write_all(&root.join("usd"), usd_seeds());
    let maps = root.join("map");
    std::fs::create_dir_all(&maps).unwrap();
    for (name, bytes) in map_seeds() {
        let path = maps.join(format!("seed-{name}"));
        std::fs::write(&path, bytes).unwrap();
        println!("{}", path.display());
    }
    write_all(
        &root.join("obj"),
        obj_seeds().into_iter().map(|(n, s)| (n, s.into_bytes())),
    );
}
