//! USD grooms (feature `usd`): `BasisCurves` read from text, binary and zip packages,
//! every basis against hand-computed points, widths and colours of every
//! interpolation, the prim's transform, the round trip through the writers, and an
//! error naming the file, prim and attribute for every bad file.

use std::path::Path;

use glam::Vec3;
use pelage_scene::usd_file::{self, CUBIC_SAMPLES, UsdFileError};
use pelage_scene::{Groom, GroomError, GroomSource, SceneFile};

fn read(text: &str) -> Result<Groom, GroomError> {
    usd_file::read(text.as_bytes().to_vec(), Path::new("test.usda"))
}

/// A `.usda` layer with one `BasisCurves` prim `/Hair` holding `body`.
fn curves(body: &str) -> String {
    format!("#usda 1.0\n\ndef BasisCurves \"Hair\"\n{{\n{body}\n}}\n")
}

fn close(a: Vec3, b: Vec3) -> bool {
    a.distance(b) < 1e-5
}

fn usd_error(result: Result<Groom, GroomError>) -> UsdFileError {
    match result {
        Err(GroomError::Usd(e)) => *e,
        other => panic!("expected a USD error, got {other:?}"),
    }
}

#[test]
fn linear_curves_are_read_as_they_are() {
    let groom = read(&curves(
        r#"uniform token type = "linear"
        int[] curveVertexCounts = [3, 2]
        point3f[] points = [(0, 0, 0), (0, 1, 0), (0, 2, 0.5), (1, 0, 0), (1, 1, 0)]"#,
    ))
    .unwrap();
    assert_eq!(groom.offsets(), &[0, 3, 5]);
    assert_eq!(groom.points()[2], Vec3::new(0.0, 2.0, 0.5));
    assert_eq!(groom.widths(), None);
    assert_eq!(groom.colors(), None);
}

#[test]
fn a_bezier_segment_passes_its_ends_and_its_midpoint_is_the_hand_computed_one() {
    // P(1/2) = (P0 + 3 P1 + 3 P2 + P3) / 8 = (0.5, 0.75, 0).
    let groom = read(&curves(
        r#"uniform token type = "cubic"
        uniform token basis = "bezier"
        int[] curveVertexCounts = [4]
        point3f[] points = [(0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 0)]"#,
    ))
    .unwrap();
    let p = groom.points();
    assert_eq!(p.len(), CUBIC_SAMPLES + 1);
    assert!(close(p[0], Vec3::ZERO));
    assert!(
        close(p[CUBIC_SAMPLES / 2], Vec3::new(0.5, 0.75, 0.0)),
        "{p:?}"
    );
    assert!(close(p[CUBIC_SAMPLES], Vec3::X));
    // The fallbacks: type cubic, basis bezier.
    let fallback = read(&curves(
        r#"int[] curveVertexCounts = [4]
        point3f[] points = [(0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 0)]"#,
    ))
    .unwrap();
    assert_eq!(fallback, groom);
}

#[test]
fn a_catmull_rom_curve_passes_through_its_inner_control_points() {
    let ctrl = [
        Vec3::ZERO,
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(2.0, 1.0, 0.0),
        Vec3::new(3.0, 0.0, 1.0),
        Vec3::new(4.0, 0.0, 0.0),
    ];
    let groom = read(&curves(
        r#"uniform token type = "cubic"
        uniform token basis = "catmullRom"
        int[] curveVertexCounts = [5]
        point3f[] points = [(0, 0, 0), (1, 0, 0), (2, 1, 0), (3, 0, 1), (4, 0, 0)]"#,
    ))
    .unwrap();
    let p = groom.points();
    // Nonperiodic: 2 segments, from P1 through P2 to P3.
    assert_eq!(p.len(), 2 * CUBIC_SAMPLES + 1);
    for (sample, control) in [(0, 1), (CUBIC_SAMPLES, 2), (2 * CUBIC_SAMPLES, 3)] {
        assert!(close(p[sample], ctrl[control]), "{sample}: {:?}", p[sample]);
    }
    // Pinned: 4 segments, through every control point, ends included.
    let pinned = read(&curves(
        r#"uniform token type = "cubic"
        uniform token basis = "catmullRom"
        uniform token wrap = "pinned"
        int[] curveVertexCounts = [5]
        point3f[] points = [(0, 0, 0), (1, 0, 0), (2, 1, 0), (3, 0, 1), (4, 0, 0)]"#,
    ))
    .unwrap();
    let p = pinned.points();
    assert_eq!(p.len(), 4 * CUBIC_SAMPLES + 1);
    for (k, c) in ctrl.iter().enumerate() {
        assert!(
            close(p[k * CUBIC_SAMPLES], *c),
            "{k}: {:?}",
            p[k * CUBIC_SAMPLES]
        );
    }
}

#[test]
fn a_bspline_starts_at_the_known_blend_and_a_pinned_one_at_its_first_point() {
    // Uniform cubic B-spline: P(0) = (P0 + 4 P1 + P2) / 6, P(1) = (P1 + 4 P2 + P3) / 6.
    let body = r#"uniform token type = "cubic"
        uniform token basis = "bspline"
        int[] curveVertexCounts = [4]
        point3f[] points = [(0, 0, 0), (1, 0, 0), (2, 3, 0), (3, 0, 0)]"#;
    let groom = read(&curves(body)).unwrap();
    let p = groom.points();
    assert_eq!(p.len(), CUBIC_SAMPLES + 1);
    assert!(close(p[0], Vec3::new(1.0, 0.5, 0.0)), "{:?}", p[0]);
    assert!(
        close(p[CUBIC_SAMPLES], Vec3::new(2.0, 2.0, 0.0)),
        "{:?}",
        p[CUBIC_SAMPLES]
    );
    // P(1/2) = (P0 + 23 P1 + 23 P2 + P3) / 48.
    let half =
        (Vec3::ZERO + 23.0 * Vec3::X + 23.0 * Vec3::new(2.0, 3.0, 0.0) + Vec3::new(3.0, 0.0, 0.0))
            / 48.0;
    assert!(
        close(p[CUBIC_SAMPLES / 2], half),
        "{:?}",
        p[CUBIC_SAMPLES / 2]
    );
    let pinned = read(&curves(
        &body.replace("int[]", "uniform token wrap = \"pinned\"\n        int[]"),
    ))
    .unwrap();
    let p = pinned.points();
    assert_eq!(p.len(), 3 * CUBIC_SAMPLES + 1);
    assert!(close(p[0], Vec3::ZERO) && close(p[3 * CUBIC_SAMPLES], Vec3::new(3.0, 0.0, 0.0)));
}

#[test]
fn periodic_curves_are_closed() {
    let linear = read(&curves(
        r#"uniform token type = "linear"
        uniform token wrap = "periodic"
        int[] curveVertexCounts = [3]
        point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]"#,
    ))
    .unwrap();
    assert_eq!(linear.points(), &[Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ZERO]);
    let bspline = read(&curves(
        r#"uniform token type = "cubic"
        uniform token basis = "bspline"
        uniform token wrap = "periodic"
        int[] curveVertexCounts = [4]
        point3f[] points = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]"#,
    ))
    .unwrap();
    let p = bspline.points();
    assert_eq!(p.len(), 4 * CUBIC_SAMPLES + 1);
    assert!(close(p[0], p[4 * CUBIC_SAMPLES]));
    // (P0 + 4 P1 + P2) / 6 = (5/6, 1/6, 0).
    assert!(
        close(p[0], Vec3::new(5.0 / 6.0, 1.0 / 6.0, 0.0)),
        "{:?}",
        p[0]
    );
}

#[test]
fn widths_of_every_interpolation() {
    let linear = |widths: &str| {
        read(&curves(&format!(
            r#"uniform token type = "linear"
            int[] curveVertexCounts = [2, 3]
            point3f[] points = [(0, 0, 0), (0, 1, 0), (1, 0, 0), (1, 1, 0), (1, 2, 0)]
            {widths}"#
        )))
    };
    let w = |g: Groom| g.widths().unwrap().to_vec();
    assert_eq!(
        w(linear(r#"float[] widths = [0.5] (interpolation = "constant")"#).unwrap()),
        vec![0.5; 5]
    );
    assert_eq!(
        w(linear(r#"float[] widths = [0.1, 0.2] (interpolation = "uniform")"#).unwrap()),
        vec![0.1, 0.1, 0.2, 0.2, 0.2]
    );
    // Vertex is the fallback; varying is the same on linear curves.
    let vertex = [0.1, 0.2, 0.3, 0.4, 0.5];
    assert_eq!(
        w(linear("float[] widths = [0.1, 0.2, 0.3, 0.4, 0.5]").unwrap()),
        vertex
    );
    assert_eq!(
        w(
            linear(r#"float[] widths = [0.1, 0.2, 0.3, 0.4, 0.5] (interpolation = "varying")"#)
                .unwrap()
        ),
        vertex
    );
    // A cubic curve: varying widths sit at the segment ends, vertex widths follow the
    // basis (a bezier of widths 0, 1, 1, 0 is 0.75 in the middle).
    let bezier = |widths: &str| {
        read(&curves(&format!(
            r#"int[] curveVertexCounts = [4]
            point3f[] points = [(0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 0)]
            {widths}"#
        )))
        .unwrap()
    };
    let g = bezier(r#"float[] widths = [0.2, 0.6] (interpolation = "varying")"#);
    let widths = g.widths().unwrap();
    assert!((widths[CUBIC_SAMPLES / 2] - 0.4).abs() < 1e-6, "{widths:?}");
    let g = bezier("float[] widths = [0, 1, 1, 0]");
    assert!((g.widths().unwrap()[CUBIC_SAMPLES / 2] - 0.75).abs() < 1e-6);
}

#[test]
fn display_colors_are_kept_per_strand() {
    let body = |color: &str| {
        curves(&format!(
            r#"uniform token type = "linear"
            int[] curveVertexCounts = [2, 2]
            point3f[] points = [(0, 0, 0), (0, 1, 0), (1, 0, 0), (1, 1, 0)]
            {color}"#
        ))
    };
    let red = Vec3::X;
    let green = Vec3::Y;
    let groom = read(&body(
        r#"color3f[] primvars:displayColor = [(1, 0, 0), (0, 1, 0)] (interpolation = "uniform")"#,
    ))
    .unwrap();
    assert_eq!(groom.colors(), Some(&[red, green][..]));
    // Constant is the fallback.
    let groom = read(&body("color3f[] primvars:displayColor = [(1, 0, 0)]")).unwrap();
    assert_eq!(groom.colors(), Some(&[red, red][..]));
    // Vertex: the root's colour.
    let groom = read(&body(
        r#"color3f[] primvars:displayColor = [(1, 0, 0), (0, 0, 1), (0, 1, 0), (0, 0, 1)] (interpolation = "vertex")"#,
    ))
    .unwrap();
    assert_eq!(groom.colors(), Some(&[red, green][..]));
    // Resampling keeps one colour per kept strand.
    let r = groom.resample(4).unwrap();
    assert_eq!(r.colors, Some(vec![red, green]));
}

#[test]
fn the_transforms_of_the_prim_and_its_ancestors_are_applied() {
    let text = r#"#usda 1.0
def Xform "World"
{
    double3 xformOp:translate = (1, 2, 3)
    uniform token[] xformOpOrder = ["xformOp:translate"]

    def BasisCurves "Hair"
    {
        float3 xformOp:scale = (2, 2, 2)
        double xformOp:rotateZ = 90
        uniform token[] xformOpOrder = ["xformOp:rotateZ", "xformOp:scale"]
        uniform token type = "linear"
        int[] curveVertexCounts = [2]
        point3f[] points = [(0, 0, 0), (1, 0, 0)]
        float[] widths = [0.5] (interpolation = "constant")
    }
}
"#;
    let groom = read(text).unwrap();
    // p' = T · Rz(90°) · S · p: (1, 0, 0) -> (2, 0, 0) -> (0, 2, 0) -> (1, 4, 3).
    assert!(close(groom.points()[0], Vec3::new(1.0, 2.0, 3.0)));
    assert!(
        close(groom.points()[1], Vec3::new(1.0, 4.0, 3.0)),
        "{:?}",
        groom.points()
    );
    // Widths scale with the cube root of the volume scale (2).
    assert!((groom.widths().unwrap()[0] - 1.0).abs() < 1e-6);
}

#[test]
fn every_curves_prim_is_read_and_other_prims_are_not() {
    let text = r#"#usda 1.0
def Xform "A"
{
    def BasisCurves "One"
    {
        uniform token type = "linear"
        int[] curveVertexCounts = [2]
        point3f[] points = [(0, 0, 0), (0, 1, 0)]
    }
}
def BasisCurves "B"
{
    uniform token type = "linear"
    int[] curveVertexCounts = [2, 2]
    point3f[] points = [(1, 0, 0), (1, 1, 0), (2, 0, 0), (2, 1, 0)]
    float[] widths = [0.3] (interpolation = "constant")
}
class BasisCurves "Template"
{
    uniform token type = "linear"
    int[] curveVertexCounts = [2]
    point3f[] points = [(9, 0, 0), (9, 1, 0)]
}
def Mesh "Head"
{
}
"#;
    let groom = read(text).unwrap();
    assert_eq!(groom.strand_count(), 3);
    // /A/One has no widths: 0, the renderer's default.
    assert_eq!(groom.widths().unwrap(), &[0.0, 0.0, 0.3, 0.3, 0.3, 0.3]);
}

fn sample() -> Groom {
    Groom::from_strands(&[
        vec![
            Vec3::ZERO,
            Vec3::new(0.1, 1.0, 0.0),
            Vec3::new(0.3, 2.0, 0.1),
        ],
        vec![Vec3::X, Vec3::new(1.0, 1.0, 0.5)],
    ])
    .unwrap()
}

/// [`sample`] with vertex widths and per-strand colours, read from text.
fn rich() -> Groom {
    let groom = read(&curves(
        r#"uniform token type = "linear"
        int[] curveVertexCounts = [3, 2]
        point3f[] points = [(0, 0, 0), (0.1, 1, 0), (0.3, 2, 0.1), (1, 0, 0), (1, 1, 0.5)]
        float[] widths = [0.01, 0.02, 0.005, 0.03, 0.001] (interpolation = "vertex")
        color3f[] primvars:displayColor = [(0.5, 0.25, 0.125), (0.1, 0.2, 0.3)] (interpolation = "uniform")"#,
    ))
    .unwrap();
    assert_eq!(groom.points(), sample().points());
    groom
}

#[test]
fn usda_usdc_and_usdz_round_trips_give_the_same_groom() {
    let dir = std::env::temp_dir().join(format!("pelage-usd-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for groom in [sample(), rich()] {
        for ext in ["usda", "usdc", "usd", "usdz"] {
            let path = dir.join(format!("groom.{ext}"));
            std::fs::write(&path, usd_file::encode(&groom, &path).unwrap()).unwrap();
            let back = Groom::load(&path).unwrap();
            assert_eq!(back, groom, "{ext}");
            // And again: usda -> Groom -> usda -> Groom.
            std::fs::write(&path, usd_file::encode(&back, &path).unwrap()).unwrap();
            assert_eq!(Groom::load(&path).unwrap(), groom, "{ext}, twice");
        }
    }
    let text = usd_file::to_usda(&rich()).unwrap();
    for expected in [
        "def BasisCurves \"Groom\"",
        "uniform token type = \"linear\"",
        "primvars:displayColor",
        "interpolation = \"vertex\"",
    ] {
        assert!(text.contains(expected), "{expected} not in {text}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_usdz_package_is_read() {
    let groom = sample();
    let back = usd_file::read(usd_file::to_usdz(&groom).unwrap(), Path::new("groom.usdz")).unwrap();
    assert_eq!(back, groom);
}

#[test]
fn a_scene_file_groom_may_be_a_usd_file() {
    let dir = std::env::temp_dir().join(format!("pelage-usd-scene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let usda = dir.join("hair.usda");
    std::fs::write(&usda, usd_file::encode(&sample(), &usda).unwrap()).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        "[mesh]\nkind = \"none\"\n\n[groom]\npath = \"hair.usda\"\nsegments = 4\n",
    )
    .unwrap();
    let file = SceneFile::load(&scene).unwrap();
    let groom = file.groom(&scene).unwrap().unwrap();
    assert_eq!((groom.strands, groom.segments), (2, 4));
    assert!(file.mesh(&scene).unwrap().indices.is_empty());
    assert_eq!(
        GroomSource {
            segments: 4,
            ..GroomSource::new(dir.join("hair.usda"))
        }
        .load()
        .unwrap(),
        groom
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Every bad file gives its error, naming the file, the prim and the attribute.
#[test]
fn bad_files_name_the_prim_and_attribute() {
    let linear = |rest: &str| curves(&format!("uniform token type = \"linear\"\n{rest}"));
    let cases: Vec<(String, &str)> = vec![
        (
            linear("int[] curveVertexCounts = [2]"),
            "/Hair has no points",
        ),
        (
            linear("point3f[] points = [(0, 0, 0), (0, 1, 0)]"),
            "/Hair has no curveVertexCounts",
        ),
        (
            linear(
                "int[] curveVertexCounts = [2, 2]\npoint3f[] points = [(0, 0, 0), (0, 1, 0), (1, 0, 0)]",
            ),
            "/Hair.curveVertexCounts add up to 4 but /Hair.points has 3",
        ),
        (
            linear(
                "int[] curveVertexCounts = [2]\npoint3f[] points = [(0, 0, 0), (0, 1, 0)]\nfloat[] widths = [1, 2, 3]",
            ),
            "/Hair.widths has 3 entries but vertex interpolation needs 2",
        ),
        (
            linear(
                "int[] curveVertexCounts = [2]\npoint3f[] points = [(0, 0, 0), (0, 1, 0)]\nfloat[] widths = [-1] (interpolation = \"constant\")",
            ),
            "/Hair.widths[0] is -1",
        ),
        (
            linear("int[] curveVertexCounts = [2]\npoint3f[] points = [(0, 0, 0), (nan, 1, 0)]"),
            "/Hair.points[1] is",
        ),
        (
            linear(
                "int[] curveVertexCounts = [2]\npoint3f[] points = [(0, 0, 0), (0, 1, 0)]\ncolor3f[] primvars:displayColor = [(1, 0, 0)] (interpolation = \"faceVarying\")",
            ),
            "/Hair.primvars:displayColor:interpolation is \"faceVarying\"",
        ),
        (
            linear("int[] curveVertexCounts = [-2]\npoint3f[] points = [(0, 0, 0), (0, 1, 0)]"),
            "/Hair.curveVertexCounts add up to 0",
        ),
        (
            linear("int[] curveVertexCounts = [1]\npoint3f[] points = [(0, 0, 0)]"),
            "/Hair.curveVertexCounts[0] is 1",
        ),
        (
            linear("int[] curveVertexCounts = [2]\nint[] points = [1, 2]"),
            "/Hair.points holds",
        ),
        (
            curves(
                "uniform token basis = \"hermite\"\nint[] curveVertexCounts = [4]\npoint3f[] points = [(0, 0, 0), (0, 1, 0), (0, 2, 0), (0, 3, 0)]",
            ),
            "/Hair.basis is \"hermite\"",
        ),
        (
            curves(
                "uniform token type = \"nurbs\"\nint[] curveVertexCounts = [2]\npoint3f[] points = [(0, 0, 0), (0, 1, 0)]",
            ),
            "/Hair.type is \"nurbs\"",
        ),
        (
            curves(
                "uniform token wrap = \"spiral\"\nint[] curveVertexCounts = [4]\npoint3f[] points = [(0, 0, 0), (0, 1, 0), (0, 2, 0), (0, 3, 0)]",
            ),
            "/Hair.wrap is \"spiral\"",
        ),
        (
            curves(
                "int[] curveVertexCounts = [5]\npoint3f[] points = [(0, 0, 0), (0, 1, 0), (0, 2, 0), (0, 3, 0), (0, 4, 0)]",
            ),
            "/Hair.curveVertexCounts[0] is 5; a bezier curve needs 4, 7, 10",
        ),
        (
            curves(
                "uniform token wrap = \"periodic\"\nint[] curveVertexCounts = [4]\npoint3f[] points = [(0, 0, 0), (0, 1, 0), (0, 2, 0), (0, 3, 0)]",
            ),
            "a periodic bezier curve needs a multiple of 3 vertices",
        ),
        (
            linear(
                "int[] curveVertexCounts = [2]\npoint3f[] points = [(0, 0, 0), (0, 1, 0)]\nfloat3 xformOp:shear = (1, 0, 0)\nuniform token[] xformOpOrder = [\"xformOp:shear\"]",
            ),
            "the transform of /Hair: xformOp:shear",
        ),
        (
            "#usda 1.0\ndef Mesh \"Head\"\n{\n}\n".to_owned(),
            "has no BasisCurves prim",
        ),
        (
            "#usda 1.0\ndef BasisCurves \"Hair\" {\n".to_owned(),
            "cannot parse the usda file test.usda",
        ),
        ("not usd at all".to_owned(), "test.usda is not a USD file"),
        (
            "PXR-USDC\0\0\0garbage".to_owned(),
            "cannot parse the usdc file",
        ),
    ];
    for (text, expected) in cases {
        let e = usd_error(read(&text));
        let message = e.to_string();
        assert!(
            message.contains(expected),
            "expected {expected:?} in {message:?}"
        );
        assert!(message.contains("test.usda"), "{message}");
    }
    // A zip that is no USD package.
    let e = usd_error(usd_file::read(
        b"PK\x03\x04 not a zip".to_vec(),
        Path::new("x.usdz"),
    ));
    assert!(
        matches!(e, UsdFileError::Package { .. }) && e.to_string().contains("Could not find EOCD"),
        "{e}"
    );
    // A missing file and an unknown extension.
    let e = Groom::load("/nonexistent/groom.usda").unwrap_err();
    assert!(e.to_string().contains("/nonexistent/groom.usda"), "{e}");
    let e = usd_file::encode(&sample(), Path::new("/tmp/groom.abc")).unwrap_err();
    assert!(matches!(e, UsdFileError::Write { .. }), "{e}");
}

#[test]
fn a_stream_that_is_not_usd_is_refused_before_it_is_read() {
    // /dev/zero is endless: the reader refuses the device before opening it.
    let e = usd_error(usd_file::load(Path::new("/dev/zero")));
    assert!(matches!(e, UsdFileError::Io { .. }), "{e}");
    assert!(e.to_string().contains("/dev/zero"), "{e}");
    assert!(e.to_string().contains("a character device"), "{e}");
}

/// `depth - 1` nested `def Xform` prims around a linear curve: braces nest `depth`
/// deep, brackets `depth + 2` (the curve's `[(0, 0, 0), ...]`).
fn nested_xforms(depth: usize) -> String {
    let mut text = String::from("#usda 1.0\n");
    for level in 0..depth - 1 {
        text.push_str(&format!("def Xform \"X{level}\" {{\n"));
    }
    text.push_str("def BasisCurves \"C\" {\n uniform token type = \"linear\"\n int[] curveVertexCounts = [2]\n point3f[] points = [(0, 0, 0), (0, 1, 0)]\n");
    text.push_str(&"}\n".repeat(depth));
    text
}

/// Runs `f` on a thread with a 2 MiB stack (the default of a spawned thread).
fn on_a_small_stack<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    std::thread::Builder::new()
        .stack_size(2 << 20)
        .spawn(f)
        .unwrap()
        .join()
        .expect("no stack overflow")
}

#[test]
fn nesting_is_read_up_to_the_limit_on_a_small_stack_and_refused_past_it() {
    let limit = usd_file::MAX_USD_NESTING;
    // The prim bodies nest `limit - 2` braces deep, the curve's points `[(` 2 more.
    let at_limit = nested_xforms(limit - 2);
    let groom = on_a_small_stack(move || read(&at_limit).map(|g| g.strand_count()));
    assert_eq!(groom.unwrap(), 1);
    // Nested dictionaries and arrays recurse in the parser too.
    let dictionary = format!(
        "#usda 1.0\ndef \"A\" (\n customData = {}{{}}{}\n)\n{{\n}}\n",
        "{ dictionary d = ".repeat(limit - 3),
        " }".repeat(limit - 3)
    );
    let e = on_a_small_stack(move || read(&dictionary));
    assert!(matches!(usd_error(e), UsdFileError::NoCurves { .. }));
    for text in [
        nested_xforms(limit - 1),
        nested_xforms(10_000),
        format!(
            "#usda 1.0\ndef \"A\" {{ int[] a = {} }}\n",
            "[".repeat(100_000)
        ),
    ] {
        let e = usd_error(on_a_small_stack(move || read(&text)));
        assert!(matches!(e, UsdFileError::TooDeep { .. }), "{e}");
        let message = e.to_string();
        assert!(
            message.contains(&format!("nest {} deep", limit + 1))
                && message.contains(&format!("at most {limit} deep"))
                && message.contains("test.usda"),
            "{message}"
        );
    }
}

#[test]
fn a_binary_hierarchy_deeper_than_the_limit_is_refused() {
    use openusd::sdf::{self, ChildrenKey, FieldKey, SpecType, Value};
    let depth = usd_file::MAX_USD_NESTING + 1;
    let mut data = sdf::Data::new();
    let mut path = sdf::Path::abs_root();
    let root = data.create_spec(path.clone(), SpecType::PseudoRoot);
    root.add(ChildrenKey::PrimChildren, Value::TokenVec(vec!["P".into()]));
    for level in 0..depth {
        path = path.append_path("P").unwrap();
        let spec = data.create_spec(path.clone(), SpecType::Prim);
        spec.add(FieldKey::Specifier, Value::Specifier(sdf::Specifier::Def));
        spec.add(FieldKey::TypeName, Value::Token("Xform".into()));
        if level + 1 < depth {
            spec.add(ChildrenKey::PrimChildren, Value::TokenVec(vec!["P".into()]));
        }
    }
    let mut out = std::io::Cursor::new(Vec::new());
    openusd::usdc::CrateWriter::write(&data, &mut out).unwrap();
    let e = usd_error(usd_file::read(out.into_inner(), Path::new("deep.usdc")));
    assert!(matches!(e, UsdFileError::TooDeepPrim { .. }), "{e}");
    assert!(e.to_string().contains("deep.usdc"), "{e}");
}

#[test]
fn a_text_of_very_many_small_prims_is_refused_by_its_memory_estimate() {
    // 150 000 prims of one attribute each: openusd took about 60 times the file's
    // size to hold them.
    let mut text = String::from("#usda 1.0\n");
    for i in 0..150_000 {
        text.push_str(&format!("def \"P{i}\" {{ float a = 1 }}\n"));
    }
    let e = usd_error(read(&text));
    assert!(matches!(e, UsdFileError::TooManySpecs { .. }), "{e}");
    assert!(e.to_string().contains("test.usda"), "{e}");
    // A groom of the same size in one prim is read.
    let points: Vec<String> = (0..text.len() / 40)
        .map(|i| format!("({i}, 0, 1)"))
        .collect();
    let counts = vec!["2"; points.len() / 2].join(", ");
    let groom = read(&curves(&format!(
        "uniform token type = \"linear\"\nint[] curveVertexCounts = [{counts}]\npoint3f[] points = [{}]",
        points[..points.len() / 2 * 2].join(", ")
    )))
    .unwrap();
    assert_eq!(groom.strand_count(), points.len() / 2);
}

#[test]
fn empty_files_and_broken_packages_say_what_is_wrong() {
    for (bytes, name, expected) in [
        (Vec::new(), "empty.usdz", "is empty (0 bytes)"),
        (
            b"  \n\n".to_vec(),
            "blank.usda",
            "its 4 bytes are blank space",
        ),
        (
            b"PK\x03\x04 and nothing more".to_vec(),
            "lying.usdz",
            "not a readable zip package: ",
        ),
    ] {
        let e = usd_error(usd_file::read(bytes, Path::new(name)));
        let message = e.to_string();
        assert!(
            message.contains(name) && message.contains(expected),
            "{message}"
        );
    }
    // A zip without a USD layer.
    let mut writer = openusd::usdz::ArchiveWriter::new(std::io::Cursor::new(Vec::new()));
    writer.add_layer("notes.usda", b"#usda 1.0\n").unwrap();
    let zip = writer.finish().unwrap().into_inner();
    // Rename the entry in place so that the package holds no layer.
    let renamed: Vec<u8> = String::from_utf8_lossy(&zip)
        .replace("notes.usda", "notes.txtx")
        .into_bytes();
    if renamed.len() == zip.len() {
        let e = usd_error(usd_file::read(renamed, Path::new("nolayer.usdz")));
        assert!(e.to_string().contains("holds no USD layer"), "{e}");
    }
    // A package whose layer is deeper than the limit gets the text's check.
    let mut writer = openusd::usdz::ArchiveWriter::new(std::io::Cursor::new(Vec::new()));
    writer
        .add_layer(
            "deep.usda",
            nested_xforms(usd_file::MAX_USD_NESTING + 1).as_bytes(),
        )
        .unwrap();
    let zip = writer.finish().unwrap().into_inner();
    let e = usd_error(usd_file::read(zip, Path::new("deep.usdz")));
    assert!(matches!(e, UsdFileError::TooDeep { .. }), "{e}");
    assert!(e.to_string().contains("deep.usdz[deep.usda]"), "{e}");
}

#[test]
fn widths_too_large_after_the_transform_name_the_prim() {
    let e = usd_error(read(&format!(
        "#usda 1.0\ndef Xform \"Big\" {{\n double3 xformOp:scale = (1e6, 1e6, 1e6)\n uniform token[] xformOpOrder = [\"xformOp:scale\"]\n{}}}\n",
        curves("uniform token type = \"linear\"\nint[] curveVertexCounts = [2]\npoint3f[] points = [(0, 0, 0), (0, 1, 0)]\nfloat[] widths = [0.5, 5000]")
            .trim_start_matches("#usda 1.0\n")
    )));
    let message = e.to_string();
    assert!(
        message.contains("/Big/Hair.widths") && message.contains("at most 1e9"),
        "{message}"
    );
}
