//! Turns a [`ScatterChart`] into drawing primitives at a given pixel size.

use super::ScatterChart;
use super::axis::{Axis, format_auto};
use super::scene::{Anchor, Color, Prim, Scene, text_height, text_width, truncate};
use crate::pareto_front;

/// Series colours (Tableau 10); further series get golden-angle hues.
const PALETTE: [Color; 10] = [
    Color::rgb(0x4e, 0x79, 0xa7),
    Color::rgb(0xf2, 0x8e, 0x2b),
    Color::rgb(0xe1, 0x57, 0x59),
    Color::rgb(0x76, 0xb7, 0xb2),
    Color::rgb(0x59, 0xa1, 0x4f),
    Color::rgb(0xed, 0xc9, 0x48),
    Color::rgb(0xb0, 0x7a, 0xa1),
    Color::rgb(0xff, 0x9d, 0xa7),
    Color::rgb(0x9c, 0x75, 0x5f),
    Color::rgb(0xba, 0xb0, 0xac),
];

const WHITE: Color = Color::rgb(0xff, 0xff, 0xff);
const INK: Color = Color::rgb(0x1a, 0x1a, 0x1a);
const TEXT: Color = Color::rgb(0x22, 0x22, 0x22);
const MUTED: Color = Color::rgb(0x66, 0x66, 0x66);
const FRAME: Color = Color::rgb(0x44, 0x44, 0x44);
const GRID: Color = Color::rgb(0xdc, 0xdc, 0xdc);
const GRID_MINOR: Color = Color::rgb(0xf0, 0xf0, 0xf0);
const FRONT: Color = Color::rgb(0x30, 0x30, 0x30);

/// Most characters of a point label.
const POINT_LABEL_CHARS: usize = 20;
/// Without a marked front, points are labelled only when there are this few.
const LABEL_ALL_BELOW: usize = 9;

/// The colour of the `i`-th series.
fn series_color(i: usize) -> Color {
    if let Some(c) = PALETTE.get(i) {
        return *c;
    }
    let hue = (i as f64 * 137.507_764) % 360.0;
    hsl(hue, 0.55, 0.5)
}

/// HSL (hue in degrees) to an opaque colour.
fn hsl(h: f64, s: f64, l: f64) -> Color {
    let c = (1.0 - (2.0 * l - 1.0).abs()) * s;
    let hp = h / 60.0;
    let x = c * (1.0 - (hp % 2.0 - 1.0).abs());
    let (r, g, b) = match hp as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = l - c / 2.0;
    let u = |v: f64| ((v + m).clamp(0.0, 1.0) * 255.0).round() as u8;
    Color::rgb(u(r), u(g), u(b))
}

/// Characters of text at `scale` that fit in `avail` pixels.
fn max_chars(avail: f64, scale: u32) -> usize {
    let s = f64::from(scale);
    ((avail + s) / (6.0 * s)).floor().max(0.0) as usize
}

/// The centre of the pixel containing `v` (crisp one-pixel lines).
fn snap(v: f64) -> f64 {
    v.floor() + 0.5
}

/// A legend row.
enum Entry {
    Series(String, Color),
    Pareto,
    Header(String),
    Sample(String, f64),
}

/// An axis-aligned box `(x0, y0, x1, y1)` used to keep labels apart.
type Bounds = (f64, f64, f64, f64);

/// Whether two boxes overlap.
fn overlaps(a: Bounds, b: Bounds) -> bool {
    a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3
}

/// Lay out `chart` at `width` x `height` pixels.
pub(crate) fn build(chart: &ScatterChart, width: u32, height: u32) -> Scene {
    let width = width.max(1);
    let height = height.max(1);
    let w = f64::from(width);
    let h = f64::from(height);
    let s: u32 = ((w.min(h) / 240.0).floor() as u32).clamp(1, 4);
    let sf = f64::from(s);
    let gh = text_height(s);
    let cw = 6.0 * sf;
    let pad = 3.0 * sf + 4.0;
    let gap = 2.0 * sf + 1.0;
    let tick_len = 2.0 * sf + 2.0;
    let points = &chart.points;

    // Which points can be drawn.
    let mut nonfinite = 0usize;
    let mut nonpositive = 0usize;
    let mut plotted: Vec<usize> = Vec::new();
    for (i, p) in points.iter().enumerate() {
        if !(p.x.is_finite() && p.y.is_finite()) {
            nonfinite += 1;
        } else if (chart.x_log && p.x <= 0.0) || (chart.y_log && p.y <= 0.0) {
            nonpositive += 1;
        } else {
            plotted.push(i);
        }
    }

    let mut series: Vec<&str> = Vec::new();
    for p in points {
        if !series.contains(&p.series.as_str()) {
            series.push(&p.series);
        }
    }
    let color_of = |name: &str| series_color(series.iter().position(|s| *s == name).unwrap_or(0));

    let coords: Vec<(f64, f64)> = plotted
        .iter()
        .map(|&i| (points[i].x, points[i].y))
        .collect();
    let front: Vec<usize> = pareto_front(&coords)
        .into_iter()
        .filter_map(|k| plotted.get(k).copied())
        .collect();
    let mut on_front = vec![false; points.len()];
    for &i in &front {
        on_front[i] = true;
    }

    // Marker radii: area proportional to size.
    let valid = |v: f64| v.is_finite() && v > 0.0;
    let sizes: Vec<f64> = plotted
        .iter()
        .filter_map(|&i| points[i].size.filter(|v| valid(*v)))
        .collect();
    let smax = sizes.iter().copied().fold(0.0f64, f64::max);
    let smin = sizes.iter().copied().fold(f64::INFINITY, f64::min);
    let r_def = 2.0 * sf + 1.5;
    let r_min = 1.5 * sf + 0.5;
    let r_max = 7.0 * sf + 2.0;
    let radius_of = |size: Option<f64>| -> f64 {
        match size {
            None => r_def,
            Some(v) if valid(v) && smax > 0.0 => (r_max * (v / smax).sqrt()).clamp(r_min, r_max),
            Some(_) => r_min,
        }
    };

    // Title and note.
    let title_scale = if text_width(&chart.title, s + 1) <= w - 2.0 * pad {
        s + 1
    } else {
        s
    };
    let title = truncate(&chart.title, max_chars(w - 2.0 * pad, title_scale));
    let title_h = text_height(title_scale);
    let mut notes = Vec::new();
    if nonfinite > 0 {
        notes.push(format!("{nonfinite} NaN/inf"));
    }
    if nonpositive > 0 {
        notes.push(format!("{nonpositive} <= 0 on log axis"));
    }
    let note = if notes.is_empty() {
        String::new()
    } else {
        truncate(
            &format!("points not shown: {}", notes.join(", ")),
            max_chars(w - 2.0 * pad, s),
        )
    };

    // Legend.
    let mut entries: Vec<Entry> = series
        .iter()
        .map(|name| Entry::Series((*name).to_string(), color_of(name)))
        .collect();
    if chart.mark_pareto && !front.is_empty() {
        entries.push(Entry::Pareto);
    }
    let mut samples: Vec<f64> = Vec::new();
    if !sizes.is_empty() {
        // The largest size, then a quarter and a sixteenth of it (half and
        // quarter radius) while they are in range and visibly smaller.
        samples.push(smax);
        for f in [4.0, 16.0] {
            let v = smax / f;
            if v >= smin * 0.999 && radius_of(Some(v)) > r_min + 0.5 {
                samples.push(v);
            }
        }
        if samples.len() == 1 && radius_of(Some(smin)) < r_max - 1.0 {
            samples.push(smin);
        }
        let header = chart.size_label.as_deref().unwrap_or("size");
        entries.push(Entry::Header(format!("area: {header}")));
        for &v in &samples {
            entries.push(Entry::Sample(format_auto(v), radius_of(Some(v))));
        }
    }
    let swatch_w = samples
        .iter()
        .map(|&v| 2.0 * radius_of(Some(v)) + 2.0)
        .fold(3.0 * cw, f64::max);
    let legend_chars = max_chars(0.3 * w - swatch_w - gap, s).max(4);
    for e in &mut entries {
        match e {
            Entry::Series(t, _) | Entry::Header(t) | Entry::Sample(t, _) => {
                *t = truncate(t, legend_chars);
            }
            Entry::Pareto => {}
        }
    }
    let legend_text_w = entries
        .iter()
        .map(|e| match e {
            Entry::Series(t, _) | Entry::Header(t) | Entry::Sample(t, _) => text_width(t, s),
            Entry::Pareto => text_width("Pareto front", s),
        })
        .fold(0.0f64, f64::max);
    let legend_w = swatch_w + gap + legend_text_w;
    let show_legend = !entries.is_empty() && legend_w <= 0.45 * w;
    let right = if show_legend {
        legend_w + 2.0 * pad
    } else {
        pad
    };

    // Plot area and axes.
    let note_h = if note.is_empty() { 0.0 } else { gap + gh };
    let top = pad + title_h + note_h + pad + gh / 2.0;
    let bottom = tick_len + gap + gh + 2.0 * gap + gh + pad;
    let py0 = top;
    let py1 = (h - bottom).max(py0 + 1.0);
    let plot_h = py1 - py0;
    let ys: Vec<f64> = plotted.iter().map(|&i| points[i].y).collect();
    let y_fits = |labels: &[String]| labels.len() as f64 * gh * 2.5 <= plot_h;
    let yaxis = Axis::build(&ys, chart.y_log, &y_fits);
    let ylab_w = yaxis
        .ticks
        .iter()
        .map(|(_, l)| text_width(l, s))
        .fold(0.0f64, f64::max);
    let left = pad + gh + 2.0 * gap + ylab_w + gap + tick_len;
    let px0 = left;
    let px1 = (w - right).max(px0 + 1.0);
    let plot_w = px1 - px0;
    let xs: Vec<f64> = plotted.iter().map(|&i| points[i].x).collect();
    let x_fits = |labels: &[String]| {
        labels
            .iter()
            .map(|l| text_width(l, s) + 2.0 * cw)
            .sum::<f64>()
            <= plot_w
    };
    let xaxis = Axis::build(&xs, chart.x_log, &x_fits);

    let (x0, x1, y0, y1) = (snap(px0), snap(px1), snap(py0), snap(py1));
    let map_x = |v: f64| x0 + xaxis.frac(v) * (x1 - x0);
    let map_y = |v: f64| y1 - yaxis.frac(v) * (y1 - y0);

    let mut prims: Vec<Prim> = Vec::new();
    let line = |a: (f64, f64), b: (f64, f64), color: Color| Prim::Path {
        points: vec![a, b],
        closed: false,
        color,
        width: 1.0,
        dash: None,
    };
    let text = |x: f64, y: f64, t: &str, anchor: Anchor, color: Color| Prim::Text {
        x,
        y,
        text: t.to_string(),
        scale: s,
        anchor,
        color,
        vertical: false,
    };
    prims.push(Prim::Rect {
        x: 0.0,
        y: 0.0,
        w,
        h,
        fill: WHITE,
    });

    // Grid.
    for (values, color) in [
        (xaxis.minor.clone(), GRID_MINOR),
        (xaxis.ticks.iter().map(|t| t.0).collect(), GRID),
    ] {
        for v in values {
            let x = snap(map_x(v));
            if x > x0 && x < x1 {
                prims.push(line((x, y0), (x, y1), color));
            }
        }
    }
    for (values, color) in [
        (yaxis.minor.clone(), GRID_MINOR),
        (yaxis.ticks.iter().map(|t| t.0).collect(), GRID),
    ] {
        for v in values {
            let y = snap(map_y(v));
            if y > y0 && y < y1 {
                prims.push(line((x0, y), (x1, y), color));
            }
        }
    }

    // Pareto front as a step line (the boundary of the dominated region).
    let front_width = (0.75 * sf).max(1.0);
    let front_dash = Some((4.0 * sf, 3.0 * sf));
    if chart.mark_pareto && front.len() >= 2 {
        let mut steps = Vec::new();
        let mut prev_y: Option<f64> = None;
        for &i in &front {
            let (x, y) = (map_x(points[i].x), map_y(points[i].y));
            if let Some(py) = prev_y {
                steps.push((x, py));
            }
            steps.push((x, y));
            prev_y = Some(y);
        }
        prims.push(Prim::Path {
            points: steps,
            closed: false,
            color: FRONT,
            width: front_width,
            dash: front_dash,
        });
    }

    // Markers, largest first so that small ones stay visible.
    let mut order = plotted.clone();
    order.sort_by(|&a, &b| radius_of(points[b].size).total_cmp(&radius_of(points[a].size)));
    for &i in &order {
        let p = &points[i];
        let color = color_of(&p.series);
        let stroke = if chart.mark_pareto && on_front[i] {
            (INK, sf.max(1.5))
        } else {
            (color.darken(0.6), (0.5 * sf).max(1.0))
        };
        let size = match p.size {
            Some(v) => format!(
                ", {} = {}",
                chart.size_label.as_deref().unwrap_or("size"),
                format_auto(v)
            ),
            None => String::new(),
        };
        prims.push(Prim::Circle {
            cx: map_x(p.x),
            cy: map_y(p.y),
            r: radius_of(p.size),
            fill: Some(color.with_alpha(0.8)),
            stroke: Some(stroke),
            tooltip: Some(format!(
                "{} {}: x = {}, y = {}{size}",
                p.series,
                p.label,
                format_auto(p.x),
                format_auto(p.y)
            )),
        });
    }

    // Frame, ticks, tick labels, axis labels.
    prims.push(Prim::Path {
        points: vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1)],
        closed: true,
        color: FRAME,
        width: 1.0,
        dash: None,
    });
    for (v, label) in &xaxis.ticks {
        let x = snap(map_x(*v));
        prims.push(line((x, y1), (x, y1 + tick_len), FRAME));
        prims.push(text(
            x,
            y1 + tick_len + gap + gh / 2.0,
            label,
            Anchor::Middle,
            TEXT,
        ));
    }
    for (v, label) in &yaxis.ticks {
        let y = snap(map_y(*v));
        prims.push(line((x0 - tick_len, y), (x0, y), FRAME));
        prims.push(text(x0 - tick_len - gap, y, label, Anchor::End, TEXT));
    }
    let x_label = truncate(&chart.x_label, max_chars(x1 - x0, s));
    prims.push(text(
        (x0 + x1) / 2.0,
        y1 + tick_len + gap + gh + 2.0 * gap + gh / 2.0,
        &x_label,
        Anchor::Middle,
        TEXT,
    ));
    prims.push(Prim::Text {
        x: pad + gh / 2.0,
        y: (y0 + y1) / 2.0,
        text: truncate(&chart.y_label, max_chars(y1 - y0, s)),
        scale: s,
        anchor: Anchor::Middle,
        color: TEXT,
        vertical: true,
    });
    prims.push(Prim::Text {
        x: w / 2.0,
        y: pad + title_h / 2.0,
        text: title,
        scale: title_scale,
        anchor: Anchor::Middle,
        color: INK,
        vertical: false,
    });
    if !note.is_empty() {
        prims.push(text(
            w / 2.0,
            pad + title_h + gap + gh / 2.0,
            &note,
            Anchor::Middle,
            MUTED,
        ));
    }
    if plotted.is_empty() {
        let msg = truncate("no points to show", max_chars(x1 - x0, s));
        prims.push(text(
            (x0 + x1) / 2.0,
            (y0 + y1) / 2.0,
            &msg,
            Anchor::Middle,
            MUTED,
        ));
    }

    // Point labels, placed greedily where they do not collide.
    let mut labelled: Vec<usize> = if chart.mark_pareto {
        front.clone()
    } else if plotted.len() < LABEL_ALL_BELOW {
        plotted.clone()
    } else {
        Vec::new()
    };
    labelled.sort_by(|&a, &b| points[a].x.total_cmp(&points[b].x));
    let mut taken: Vec<Bounds> = labelled
        .iter()
        .map(|&i| {
            let (cx, cy, r) = (
                map_x(points[i].x),
                map_y(points[i].y),
                radius_of(points[i].size),
            );
            (cx - r, cy - r, cx + r, cy + r)
        })
        .collect();
    let inside = (x0 + 2.0, y0 + 2.0, x1 - 2.0, y1 - 2.0);
    for &i in &labelled {
        let label = truncate(points[i].label.trim(), POINT_LABEL_CHARS);
        if label.is_empty() {
            continue;
        }
        let (cx, cy, r) = (
            map_x(points[i].x),
            map_y(points[i].y),
            radius_of(points[i].size),
        );
        let tw = text_width(&label, s);
        let off = r + gap;
        // Left of and below a Pareto point is empty (a point there would
        // dominate it) and clear of the step line, which leaves it going right.
        let centred = (cx - tw / 2.0, cx + tw / 2.0);
        let candidates = [
            (cx - off, cy, Anchor::End, (cx - off - tw, cx - off)),
            (cx, cy + off + gh / 2.0, Anchor::Middle, centred),
            (cx + off, cy, Anchor::Start, (cx + off, cx + off + tw)),
            (cx, cy - off - gh / 2.0, Anchor::Middle, centred),
        ];
        for (tx, ty, anchor, (bx0, bx1)) in candidates {
            let b = (
                bx0 - 1.0,
                ty - gh / 2.0 - 1.0,
                bx1 + 1.0,
                ty + gh / 2.0 + 1.0,
            );
            let within = b.0 >= inside.0 && b.1 >= inside.1 && b.2 <= inside.2 && b.3 <= inside.3;
            if within && !taken.iter().any(|t| overlaps(*t, b)) {
                taken.push(b);
                prims.push(text(tx, ty, &label, anchor, TEXT));
                break;
            }
        }
    }

    // Legend to the right of the plot.
    if show_legend {
        let lx = x1 + pad;
        let sx = lx + swatch_w / 2.0;
        let tx = lx + swatch_w + gap;
        let mut cursor = y0;
        for (k, e) in entries.iter().enumerate() {
            let row = match e {
                Entry::Sample(_, r) => (gh + 2.0 * gap).max(2.0 * r + gap),
                Entry::Header(_) => gh + 4.0 * gap,
                _ => gh + 2.0 * gap,
            };
            if cursor + row > h - pad {
                let more = format!("+{} more", entries.len() - k);
                prims.push(text(lx, cursor + gh / 2.0, &more, Anchor::Start, MUTED));
                break;
            }
            let cy = match e {
                Entry::Header(_) => cursor + row - gap - gh / 2.0,
                _ => cursor + row / 2.0,
            };
            match e {
                Entry::Series(t, c) => {
                    prims.push(Prim::Circle {
                        cx: sx,
                        cy,
                        r: r_def,
                        fill: Some(c.with_alpha(0.8)),
                        stroke: Some((c.darken(0.6), (0.5 * sf).max(1.0))),
                        tooltip: None,
                    });
                    prims.push(text(tx, cy, t, Anchor::Start, TEXT));
                }
                Entry::Pareto => {
                    prims.push(Prim::Path {
                        points: vec![(lx + 1.0, cy), (lx + swatch_w - 2.0 * sf, cy)],
                        closed: false,
                        color: FRONT,
                        width: front_width,
                        dash: front_dash,
                    });
                    prims.push(Prim::Circle {
                        cx: sx,
                        cy,
                        r: r_def,
                        fill: Some(WHITE),
                        stroke: Some((INK, sf.max(1.5))),
                        tooltip: None,
                    });
                    prims.push(text(tx, cy, "Pareto front", Anchor::Start, TEXT));
                }
                Entry::Header(t) => prims.push(text(lx, cy, t, Anchor::Start, TEXT)),
                Entry::Sample(t, r) => {
                    prims.push(Prim::Circle {
                        cx: sx,
                        cy,
                        r: *r,
                        fill: Some(Color::rgb(0x99, 0x99, 0x99).with_alpha(0.5)),
                        stroke: Some((MUTED, (0.5 * sf).max(1.0))),
                        tooltip: None,
                    });
                    prims.push(text(tx, cy, t, Anchor::Start, TEXT));
                }
            }
            cursor += row;
        }
    }

    prims.retain(Prim::is_finite);
    Scene {
        width,
        height,
        title: chart.title.clone(),
        prims,
    }
}
