//! Tests of CSV, text tables, Pareto fronts and chart output.

use std::path::{Path, PathBuf};

use pelage_lab::{
    LabError, ScatterChart, ScatterPoint, Table, pareto_front, write_file_atomically,
};

/// A fresh scratch folder for one test, removed when dropped.
struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

fn scratch(name: &str) -> Scratch {
    let dir = std::env::temp_dir().join(format!("pelage_lab_test_{}_{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    Scratch(dir)
}

fn row(cells: &[&str]) -> Vec<String> {
    cells.iter().map(|c| c.to_string()).collect()
}

fn point(series: &str, label: &str, x: f64, y: f64, size: Option<f64>) -> ScatterPoint {
    ScatterPoint {
        series: series.into(),
        label: label.into(),
        x,
        y,
        size,
    }
}

fn example_chart() -> ScatterChart {
    let mut points = Vec::new();
    for (k, res) in [256.0f64, 512.0, 1024.0, 2048.0].iter().enumerate() {
        let k = k as f64;
        points.push(point(
            "shadow map",
            &format!("{res}px"),
            0.4 * 2f64.powf(k),
            0.08 / (k + 1.0).powi(2),
            Some(res * res * 4.0 / 1e6),
        ));
        points.push(point(
            "deep opacity",
            &format!("{res}px x4"),
            0.9 * 2f64.powf(k),
            0.03 / (k + 1.0).powf(1.5),
            Some(res * res * 16.0 / 1e6),
        ));
        points.push(point(
            "voxel",
            &format!("{}^3", 64 * (k as u32 + 1)),
            1.5 * (k + 1.0).powi(2),
            0.05 / (k + 1.0),
            Some(8.0 * (k + 1.0).powi(3)),
        ));
    }
    points.push(point("reference", "BVH 64spp", 950.0, 0.0004, Some(300.0)));
    ScatterChart {
        title: "Shadow methods: error against time".into(),
        x_label: "GPU time per frame (ms)".into(),
        y_label: "mean FLIP error".into(),
        x_log: true,
        y_log: true,
        points,
        mark_pareto: true,
        size_label: Some("memory (MB)".into()),
    }
}

/// A small RFC 4180 parser independent of the library's.
fn parse(text: &str) -> Vec<Vec<String>> {
    let mut out = vec![];
    let mut rec = vec![];
    let mut cell = String::new();
    let mut q = false;
    let mut it = text.chars().peekable();
    while let Some(c) = it.next() {
        match (q, c) {
            (true, '"') if it.peek() == Some(&'"') => {
                it.next();
                cell.push('"');
            }
            (true, '"') => q = false,
            (true, c) => cell.push(c),
            (false, '"') => q = true,
            (false, ',') => rec.push(std::mem::take(&mut cell)),
            (false, '\n') => {
                rec.push(std::mem::take(&mut cell));
                out.push(std::mem::take(&mut rec));
            }
            (false, c) => cell.push(c),
        }
    }
    out
}

#[test]
fn csv_quoting_and_round_trip() {
    let mut t = Table::new(&["method", "ms", "note"]);
    t.push(row(&["plain", "1.5", "ok"])).unwrap();
    t.push(row(&["a,b", "2", "say \"hi\""])).unwrap();
    t.push(row(&["multi\nline", "", "x"])).unwrap();
    let csv = t.to_csv();
    assert!(csv.starts_with("method,ms,note\nplain,1.5,ok\n"));
    assert!(csv.contains("\"a,b\",2,\"say \"\"hi\"\"\""));
    assert!(csv.contains("\"multi\nline\",,x"));
    let mut all = vec![t.header.clone()];
    all.extend(t.rows.clone());
    assert_eq!(parse(&csv), all);
    assert_eq!(Table::from_csv(&csv).unwrap(), t);
    assert_eq!(
        Table::from_csv(&csv.replace('\n', "\r\n")).unwrap().rows[0],
        t.rows[0]
    );

    let dir = scratch("csv");
    let path = dir.join("sub/table.csv");
    t.write_csv(&path).unwrap();
    assert_eq!(std::fs::read_to_string(&path).unwrap(), csv);
}

#[test]
fn width_mismatch_is_an_error() {
    let mut t = Table::new(&["a", "b"]);
    assert!(matches!(t.push(row(&["1"])), Err(LabError::Invalid(_))));
    assert!(matches!(
        t.push(row(&["1", "2", "3"])),
        Err(LabError::Invalid(_))
    ));
    assert!(t.rows.is_empty());
    assert!(Table::from_csv("a,b\n1,2,3\n").is_err());
    assert!(Table::from_csv("a,\"b\n").is_err());
}

#[test]
fn pareto_hand_made() {
    // 1 dominates 3 (<= both, < both); 2 is dominated by 1 via y; 4 is best y.
    let pts = [(1.0, 5.0), (2.0, 2.0), (2.0, 3.0), (3.0, 4.0), (5.0, 1.0)];
    assert_eq!(pareto_front(&pts), vec![0, 1, 4]);
    // Equal x: only the smaller y survives. Equal y: only the smaller x.
    assert_eq!(pareto_front(&[(1.0, 2.0), (1.0, 1.0)]), vec![1]);
    assert_eq!(pareto_front(&[(2.0, 1.0), (1.0, 1.0)]), vec![1]);
    // Identical points do not dominate each other.
    assert_eq!(
        pareto_front(&[(1.0, 1.0), (1.0, 1.0), (2.0, 2.0)]),
        vec![0, 1]
    );
    // NaN and inf never appear and never dominate.
    let pts = [
        (f64::NAN, 0.0),
        (1.0, 3.0),
        (0.5, f64::INFINITY),
        (f64::NEG_INFINITY, 0.0),
        (2.0, 1.0),
    ];
    assert_eq!(pareto_front(&pts), vec![1, 4]);
    assert!(pareto_front(&[]).is_empty());
    assert_eq!(pareto_front(&[(3.0, 3.0)]), vec![0]);
    // Sorted by x even when given out of order.
    assert_eq!(
        pareto_front(&[(3.0, 1.0), (1.0, 3.0), (2.0, 2.0)]),
        vec![1, 2, 0]
    );
}

#[test]
fn text_table_alignment() {
    let mut t = Table::new(&["method", "ms", "speedup"]);
    t.push(row(&["shadow map", "1.25", "3.2x"])).unwrap();
    t.push(row(&["deep", "12.5", "1x"])).unwrap();
    t.push(row(&["x", "", "NaN"])).unwrap();
    let text = t.to_text();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 5);
    assert_eq!(lines[0], "method        ms  speedup");
    assert_eq!(lines[1], "----------  ----  -------");
    assert_eq!(lines[2], "shadow map  1.25     3.2x");
    assert_eq!(lines[3], "deep        12.5       1x");
    assert_eq!(lines[4], "x                     NaN");
}

#[test]
fn svg_has_title_series_and_markers() {
    let mut chart = example_chart();
    chart
        .points
        .push(point("broken", "nan", f64::NAN, 1.0, None));
    let svg = chart.to_svg(800, 600);
    assert!(svg.starts_with("<svg"));
    assert!(svg.contains("Shadow methods: error against time"));
    for s in [
        "shadow map",
        "deep opacity",
        "voxel",
        "reference",
        "broken",
        "Pareto front",
    ] {
        assert!(svg.contains(s), "missing {s}");
    }
    let finite = chart
        .points
        .iter()
        .filter(|p| p.x.is_finite() && p.y.is_finite())
        .count();
    assert_eq!(svg.matches("class=\"point\"").count(), finite);
    assert!(svg.contains("points not shown: 1 NaN/inf"));
    // The dashed Pareto step line.
    assert!(svg.contains("<polyline"));
    // Axis names, the size legend, log-axis decade ticks and Pareto labels.
    for s in [
        "GPU time per frame (ms)",
        "mean FLIP error",
        "area: memory (MB)",
        "\n10\n",
        "\n100\n",
        "\n1000\n",
        "\n0.001\n",
        "BVH 64spp",
    ] {
        assert!(svg.contains(s), "missing {s:?}");
    }
    // Marker area follows size: the largest memory has the largest marker.
    let voxel = marker(&svg, "voxel 256^3");
    let small = marker(&svg, "shadow map 256px");
    assert!(voxel.2 > 3 * small.2, "{voxel:?} {small:?}");
    let dir = scratch("svg");
    chart.write_svg(&dir.join("chart.svg"), 800, 600).unwrap();
    assert_eq!(std::fs::read_to_string(dir.join("chart.svg")).unwrap(), svg);
}

fn check_png(path: &Path, w: u32, h: u32) {
    let img = image::open(path).unwrap().to_rgba8();
    assert_eq!(img.dimensions(), (w, h));
    let first = *img.get_pixel(0, 0);
    assert!(img.pixels().any(|p| *p != first), "flat image");
}

/// Centre and radius in pixels of the SVG tooltip circle whose title starts
/// with `title`.
fn marker(svg: &str, title: &str) -> (u32, u32, u32) {
    let line = svg
        .lines()
        .find(|l| l.contains("class=\"point\"") && l.contains(&format!("<title>{title}")))
        .unwrap_or_else(|| panic!("no marker {title}"));
    let attr = |name: &str| -> u32 {
        let rest = &line[line.find(&format!(" {name}=\"")).unwrap() + name.len() + 3..];
        rest[..rest.find('"').unwrap()].parse().unwrap()
    };
    (attr("cx"), attr("cy"), attr("r"))
}

#[test]
fn png_markers_sit_where_the_svg_puts_them() {
    // Both files are drawn from one layout: the PNG has each series' colour
    // at the centre the SVG gives for its points, and white elsewhere.
    let chart = example_chart();
    let svg = chart.to_svg(900, 600);
    let img = chart.to_image(900, 600).unwrap();
    let reddish = |p: image::Rgba<u8>| p[0] > 200 && p[1] < 150 && p[2] < 150;
    let bluish = |p: image::Rgba<u8>| p[2] > p[0] + 30 && p[2] > 120;
    for (title, is) in [
        ("voxel 256^3", &reddish as &dyn Fn(image::Rgba<u8>) -> bool),
        ("voxel 192^3", &reddish),
        ("shadow map 512px", &bluish),
    ] {
        let (x, y, _) = marker(&svg, title);
        let p = *img.get_pixel(x, y);
        assert!(is(p), "{title} at {x},{y} is {p:?}");
    }
    assert_eq!(*img.get_pixel(1, 1), image::Rgba([255, 255, 255, 255]));
    // Text is drawn: the title band holds dark pixels.
    let dark = (0..900)
        .flat_map(|x| (0..30).map(move |y| (x, y)))
        .filter(|&(x, y)| img.get_pixel(x, y)[0] < 80)
        .count();
    assert!(dark > 200, "{dark} dark title pixels");
}

#[test]
fn png_is_decodable_and_not_flat() {
    let dir = scratch("png");
    let chart = example_chart();
    chart.write_png(&dir.join("chart.png"), 640, 480).unwrap();
    check_png(&dir.join("chart.png"), 640, 480);
    assert!(chart.write_png(&dir.join("zero.png"), 0, 10).is_err());
    assert!(!dir.join("zero.png").exists());
}

#[test]
fn example_chart_png() {
    let path = Path::new("/tmp/pelage_lab_example.png");
    example_chart().write_png(path, 900, 600).unwrap();
    check_png(path, 900, 600);
    example_chart()
        .write_svg(&path.with_extension("svg"), 900, 600)
        .unwrap();
}

#[test]
fn degenerate_charts_do_not_panic() {
    let dir = scratch("degenerate");
    let base = ScatterChart {
        title: "degenerate".into(),
        x_label: "x".into(),
        y_label: "y".into(),
        mark_pareto: true,
        ..ScatterChart::default()
    };
    let one = ScatterChart {
        points: vec![point("a", "only", 3.0, 3.0, Some(2.0))],
        ..base.clone()
    };
    let equal = ScatterChart {
        points: vec![
            point("a", "p", 2.0, 2.0, None),
            point("b", "q", 2.0, 2.0, Some(0.0)),
        ],
        ..base.clone()
    };
    let log_zero = ScatterChart {
        x_log: true,
        y_log: true,
        points: vec![
            point("a", "zero", 0.0, 1.0, None),
            point("a", "neg", 1.0, -1.0, None),
            point("a", "ok", 10.0, 0.1, Some(f64::NAN)),
            point("b", "inf", f64::INFINITY, 0.1, None),
        ],
        ..base.clone()
    };
    let all_bad = ScatterChart {
        y_log: true,
        points: vec![
            point("a", "", 1.0, 0.0, None),
            point("a", "", f64::NAN, f64::NAN, None),
        ],
        ..base.clone()
    };
    let extreme = ScatterChart {
        points: vec![
            point("a", "max", f64::MAX, -f64::MAX, Some(f64::MAX)),
            point("a", "min", -f64::MAX, f64::MAX, Some(f64::MIN_POSITIVE)),
            point("a", "tiny", 1e-300, 1e-300, Some(1e-300)),
        ],
        ..base.clone()
    };
    let many_series = ScatterChart {
        points: (0..40)
            .map(|i| {
                point(
                    &format!("series number {i} with a long name"),
                    "",
                    f64::from(i),
                    f64::from(i % 7),
                    None,
                )
            })
            .collect(),
        ..base.clone()
    };
    let cases = [
        ("empty", base.clone()),
        ("one", one),
        ("equal", equal),
        ("log_zero", log_zero),
        ("all_bad", all_bad),
        ("extreme", extreme),
        ("many_series", many_series),
    ];
    for (name, chart) in cases {
        for (w, h) in [
            (640, 480),
            (300, 120),
            (120, 300),
            (90, 70),
            (40, 30),
            (1, 1),
        ] {
            let png = dir.join(format!("{name}_{w}.png"));
            chart.write_png(&png, w, h).unwrap();
            let img = image::open(&png).unwrap();
            assert_eq!((img.width(), img.height()), (w, h));
            let svg = dir.join(format!("{name}_{w}.svg"));
            chart.write_svg(&svg, w, h).unwrap();
            let text = std::fs::read_to_string(&svg).unwrap();
            // Coordinates are never NaN or infinite (tooltips may say so).
            for tag in text.split('<').filter_map(|t| t.split('>').next()) {
                assert!(
                    !tag.contains("NaN") && !tag.contains("inf"),
                    "{name}: {tag}"
                );
            }
        }
    }
    let svg = ScatterChart {
        x_log: true,
        points: vec![
            point("a", "z", 0.0, 1.0, None),
            point("a", "o", 1.0, 1.0, None),
        ],
        ..base
    }
    .to_svg(400, 300);
    assert!(svg.contains("points not shown: 1 &lt;= 0 on log axis"));
    assert_eq!(svg.matches("class=\"point\"").count(), 1);
}

#[test]
fn atomic_write_leaves_no_temporary() {
    let dir = scratch("atomic");
    let path = dir.join("a/b/out.txt");
    write_file_atomically(&path, b"first").unwrap();
    write_file_atomically(&path, b"second").unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), b"second");
    let names: Vec<String> = std::fs::read_dir(dir.join("a/b"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["out.txt".to_string()]);
    // A folder cannot be replaced by a file: an error, and no leftovers.
    assert!(matches!(
        write_file_atomically(&dir.join("a"), b"x"),
        Err(LabError::Io { .. })
    ));
    let names: Vec<_> = std::fs::read_dir(&*dir).unwrap().collect();
    assert_eq!(names.len(), 1);
    assert!(write_file_atomically(Path::new("/"), b"x").is_err());
}

#[test]
fn atomic_write_takes_a_255_byte_name_and_leaves_nothing_else() {
    let dir = scratch("atomic_long");
    let path = dir.join(format!("{}.csv", "n".repeat(251)));
    write_file_atomically(&path, b"long").unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), b"long");
    assert_eq!(std::fs::read_dir(&*dir).unwrap().count(), 1);
}

#[cfg(unix)]
#[test]
fn atomic_write_follows_links_and_writes_through_devices() {
    use std::os::unix::fs::FileTypeExt;
    let dir = scratch("atomic_link");
    std::fs::write(dir.join("real.csv"), b"old").unwrap();
    std::os::unix::fs::symlink("real.csv", dir.join("link.csv")).unwrap();
    write_file_atomically(&dir.join("link.csv"), b"new").unwrap();
    assert!(
        std::fs::symlink_metadata(dir.join("link.csv"))
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert_eq!(std::fs::read(dir.join("real.csv")).unwrap(), b"new");
    write_file_atomically(Path::new("/dev/null"), b"gone").unwrap();
    assert!(
        std::fs::symlink_metadata("/dev/null")
            .unwrap()
            .file_type()
            .is_char_device()
    );
    #[cfg(target_os = "linux")]
    {
        let e = write_file_atomically(Path::new("/dev/full"), b"x").unwrap_err();
        assert!(e.to_string().contains("/dev/full"), "{e}");
    }
}
