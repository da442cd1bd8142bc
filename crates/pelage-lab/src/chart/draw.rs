//! Draws a [`ScatterChart`] with plotters on any backend (SVG or bitmap), so
//! that both files show the same chart.

use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::ScatterChart;
use super::ticks::{domain, format_auto, log_ticks};
use crate::font::{fit, style, text_size};
use crate::pareto_front;

/// Series colours (Tableau 10); further series get golden-angle hues.
const PALETTE: [RGBColor; 10] = [
    RGBColor(0x4e, 0x79, 0xa7),
    RGBColor(0xf2, 0x8e, 0x2b),
    RGBColor(0xe1, 0x57, 0x59),
    RGBColor(0x76, 0xb7, 0xb2),
    RGBColor(0x59, 0xa1, 0x4f),
    RGBColor(0xed, 0xc9, 0x48),
    RGBColor(0xb0, 0x7a, 0xa1),
    RGBColor(0xff, 0x9d, 0xa7),
    RGBColor(0x9c, 0x75, 0x5f),
    RGBColor(0xba, 0xb0, 0xac),
];
const INK: RGBColor = RGBColor(0x1a, 0x1a, 0x1a);
const TEXT: RGBColor = RGBColor(0x22, 0x22, 0x22);
const MUTED: RGBColor = RGBColor(0x66, 0x66, 0x66);
const FRAME: RGBColor = RGBColor(0x44, 0x44, 0x44);
const GRID: RGBColor = RGBColor(0xdc, 0xdc, 0xdc);
const GRID_MINOR: RGBColor = RGBColor(0xf0, 0xf0, 0xf0);
const FRONT: RGBColor = RGBColor(0x30, 0x30, 0x30);
const SAMPLE: RGBColor = RGBColor(0x99, 0x99, 0x99);

/// Most characters of a point label.
const POINT_LABEL_CHARS: usize = 20;
/// Without a marked front, points are labelled only when there are this few.
const LABEL_ALL_BELOW: usize = 9;

/// Errors of drawing on backend `DB`.
type DrawError<DB> = DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>;

/// A drawn data point in pixels, for the SVG tooltips.
pub(crate) struct Marker {
    pub x: i32,
    pub y: i32,
    pub r: u32,
    pub tooltip: String,
}

/// The colour of the `i`-th series.
fn series_color(i: usize) -> RGBColor {
    PALETTE.get(i).copied().unwrap_or_else(|| {
        let (r, g, b) = HSLColor((i as f64 * 0.381_966) % 1.0, 0.55, 0.5).rgb();
        RGBColor(r, g, b)
    })
}

/// `c` mixed with `other`, `f` parts of `c`.
fn mix(c: RGBColor, other: RGBColor, f: f64) -> RGBColor {
    let m = |a: u8, b: u8| (f64::from(a) * f + f64::from(b) * (1.0 - f)).round() as u8;
    RGBColor(m(c.0, other.0), m(c.1, other.1), m(c.2, other.2))
}

/// A marker: a disk of `ring` colour under a disk of `fill` colour `width`
/// pixels smaller (two filled circles: plotters' stroked circles leave gaps
/// against a filled one in bitmaps).
fn dot<C: Clone>(at: C, r: u32, fill: RGBColor, ring: RGBColor, width: u32) -> [Circle<C, u32>; 2] {
    [
        Circle::new(at.clone(), r, ring.filled()),
        Circle::new(at, r.saturating_sub(width), fill.filled()),
    ]
}

/// A legend row.
enum Entry {
    Series(String, RGBColor),
    Pareto,
    Header(String),
    Sample(String, f64),
}

/// What is drawn, worked out before drawing.
struct Plan<'a> {
    chart: &'a ScatterChart,
    /// Indices of the points that can be drawn (finite, positive on log axes).
    plotted: Vec<usize>,
    /// Indices of the Pareto points, by increasing x.
    front: Vec<usize>,
    series: Vec<&'a str>,
    note: String,
    /// Largest valid size (0 when none).
    smax: f64,
    /// Text size and the unit of spacing, in pixels.
    s: f64,
    unit: f64,
}

impl Plan<'_> {
    fn color_of(&self, name: &str) -> RGBColor {
        series_color(self.series.iter().position(|s| *s == name).unwrap_or(0))
    }

    fn r_default(&self) -> f64 {
        0.35 * self.s
    }

    fn r_min(&self) -> f64 {
        0.2 * self.s
    }

    fn r_max(&self) -> f64 {
        1.0 * self.s
    }

    /// Marker radius: area proportional to `size`.
    fn radius(&self, size: Option<f64>) -> f64 {
        match size {
            None => self.r_default(),
            Some(v) if v.is_finite() && v > 0.0 && self.smax > 0.0 => {
                (self.r_max() * (v / self.smax).sqrt()).clamp(self.r_min(), self.r_max())
            }
            Some(_) => self.r_min(),
        }
    }

    fn on_front(&self, i: usize) -> bool {
        self.chart.mark_pareto && self.front.contains(&i)
    }

    fn tooltip(&self, i: usize) -> String {
        let p = &self.chart.points[i];
        let size = match p.size {
            Some(v) => format!(
                ", {} = {}",
                self.chart.size_label.as_deref().unwrap_or("size"),
                format_auto(v)
            ),
            None => String::new(),
        };
        format!(
            "{} {}: x = {}, y = {}{size}",
            p.series,
            p.label,
            format_auto(p.x),
            format_auto(p.y)
        )
    }

    /// The legend rows, and the width of the swatch column.
    fn legend(&self) -> (Vec<Entry>, f64) {
        let mut entries: Vec<Entry> = self
            .series
            .iter()
            .map(|name| Entry::Series((*name).to_string(), self.color_of(name)))
            .collect();
        if self.chart.mark_pareto && !self.front.is_empty() {
            entries.push(Entry::Pareto);
        }
        let sizes: Vec<f64> = self
            .plotted
            .iter()
            .filter_map(|&i| self.chart.points[i].size)
            .filter(|v| v.is_finite() && *v > 0.0)
            .collect();
        let mut samples = Vec::new();
        if !sizes.is_empty() {
            let smin = sizes.iter().copied().fold(f64::INFINITY, f64::min);
            // The largest size, then a quarter and a sixteenth of it (half and
            // quarter radius) while they are in range and visibly smaller.
            samples.push(self.smax);
            for f in [4.0, 16.0] {
                let v = self.smax / f;
                if v >= smin * 0.999 && self.radius(Some(v)) > self.r_min() + 1.0 {
                    samples.push(v);
                }
            }
            if samples.len() == 1 && self.radius(Some(smin)) < self.r_max() - 2.0 {
                samples.push(smin);
            }
            let what = self.chart.size_label.as_deref().unwrap_or("size");
            entries.push(Entry::Header(format!("area: {what}")));
            for &v in &samples {
                entries.push(Entry::Sample(format_auto(v), self.radius(Some(v))));
            }
        }
        let swatch = samples
            .iter()
            .map(|&v| 2.0 * self.radius(Some(v)) + 2.0)
            .fold(2.0 * self.s, f64::max);
        (entries, swatch)
    }
}

/// Works out what `chart` shows at text size `s`.
fn plan(chart: &ScatterChart, s: f64) -> Plan<'_> {
    let points = &chart.points;
    let (mut nonfinite, mut nonpositive) = (0, 0);
    let mut plotted = Vec::new();
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
    let coords: Vec<(f64, f64)> = plotted
        .iter()
        .map(|&i| (points[i].x, points[i].y))
        .collect();
    let front = pareto_front(&coords)
        .into_iter()
        .filter_map(|k| plotted.get(k).copied())
        .collect();
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
        format!("points not shown: {}", notes.join(", "))
    };
    let smax = plotted
        .iter()
        .filter_map(|&i| points[i].size)
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold(0.0, f64::max);
    Plan {
        chart,
        plotted,
        front,
        series,
        note,
        smax,
        s,
        unit: (s / 4.0).max(2.0),
    }
}

/// Draws `chart` on `root` and returns the data points as drawn.
pub(crate) fn draw<DB: DrawingBackend>(
    chart: &ScatterChart,
    root: &DrawingArea<DB, Shift>,
) -> Result<Vec<Marker>, DrawError<DB>> {
    root.fill(&WHITE)?;
    let (w, h) = root.dim_in_pixel();
    let s = (f64::from(w.min(h)) / 26.0).clamp(11.0, 40.0);
    let plan = plan(chart, s);
    let xs: Vec<f64> = plan.plotted.iter().map(|&i| chart.points[i].x).collect();
    let ys: Vec<f64> = plan.plotted.iter().map(|&i| chart.points[i].y).collect();
    let (x0, x1) = domain(&xs, chart.x_log);
    let (y0, y1) = domain(&ys, chart.y_log);
    // Tick counts for the space there is (labels of about five characters).
    let nx = (f64::from(w) / (4.5 * s)).clamp(2.0, 10.0) as usize;
    let ny = (f64::from(h) / (2.5 * s)).clamp(2.0, 10.0) as usize;
    let log_axis = |lo: f64, hi: f64, n: usize| {
        let (major, minor) = log_ticks(lo, hi, n);
        (lo..hi)
            .log_scale()
            .with_key_points(major)
            .with_light_points(minor)
    };
    let linear = |lo: f64, hi: f64| RangedCoordf64::from(lo..hi);
    match (chart.x_log, chart.y_log) {
        (false, false) => plot(&plan, root, linear(x0, x1), linear(y0, y1), nx, ny),
        (true, false) => plot(&plan, root, log_axis(x0, x1, nx), linear(y0, y1), nx, ny),
        (false, true) => plot(&plan, root, linear(x0, x1), log_axis(y0, y1, ny), nx, ny),
        (true, true) => plot(
            &plan,
            root,
            log_axis(x0, x1, nx),
            log_axis(y0, y1, ny),
            nx,
            ny,
        ),
    }
}

/// The label format of the `n` ticks plotters puts on `axis`: decimals for the
/// step on a linear axis of moderate values, else [`format_auto`].
fn tick_format<R: Ranged<ValueType = f64>>(
    axis: &R,
    n: usize,
    log: bool,
) -> impl Fn(&f64) -> String + use<R> {
    let ticks = axis.key_points(n);
    let biggest = ticks.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let step = ticks
        .windows(2)
        .map(|t| t[1] - t[0])
        .fold(f64::INFINITY, f64::min);
    let plain = !log && step.is_finite() && step > 0.0 && (1e-3..1e6).contains(&biggest);
    let decimals = (-step.log10().floor()).clamp(0.0, 17.0) as usize;
    move |v: &f64| {
        if plain {
            format!("{v:.decimals$}")
        } else {
            format_auto(*v)
        }
    }
}

/// Draws the chart with axes `x` and `y` and `nx`, `ny` ticks (linear axes).
fn plot<DB, X, Y>(
    plan: &Plan,
    root: &DrawingArea<DB, Shift>,
    x: X,
    y: Y,
    nx: usize,
    ny: usize,
) -> Result<Vec<Marker>, DrawError<DB>>
where
    DB: DrawingBackend,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let chart = plan.chart;
    let (w, h) = root.dim_in_pixel();
    let (w, h) = (f64::from(w), f64::from(h));
    let (s, u) = (plan.s, plan.unit);
    let text = style(s, TEXT);
    let line_h = text_size("Mg", &text).1;

    // Title and note.
    let title_style = style(1.3 * s, INK).pos(Pos::new(HPos::Center, VPos::Top));
    let title = fit(&chart.title, w - 4.0 * u, &title_style);
    // plotters' ab_glyph text sits about a fifth of its size above a top anchor.
    let lift = 0.2 * 1.3 * s;
    let mut top = 2.0 * u + lift + text_size("Mg", &title_style).1;
    root.draw(&Text::new(
        title,
        ((w / 2.0) as i32, (u + lift) as i32),
        title_style,
    ))?;
    if !plan.note.is_empty() {
        let note_style = style(s, MUTED).pos(Pos::new(HPos::Center, VPos::Top));
        let note = fit(&plan.note, w - 4.0 * u, &note_style);
        let at = ((w / 2.0) as i32, (top + 0.2 * s) as i32);
        root.draw(&Text::new(note, at, note_style))?;
        top += line_h + u;
    }

    // Legend, on the right when it takes under 45% of the width.
    let (mut entries, swatch) = plan.legend();
    for e in &mut entries {
        if let Entry::Series(t, _) | Entry::Header(t) | Entry::Sample(t, _) = e {
            *t = fit(t, 0.35 * w - swatch - u, &text);
        }
    }
    let legend_w = swatch
        + u
        + entries
            .iter()
            .map(|e| match e {
                Entry::Series(t, _) | Entry::Header(t) | Entry::Sample(t, _) => {
                    text_size(t, &text).0
                }
                Entry::Pareto => text_size("Pareto front", &text).0,
            })
            .fold(0.0, f64::max);
    let show_legend = !entries.is_empty() && legend_w <= 0.45 * w;
    let right = if show_legend {
        legend_w + 4.0 * u
    } else {
        2.0 * u
    };

    // Label areas: ticks, tick labels and the axis name.
    let x: X::CoordDescType = x.into();
    let y: Y::CoordDescType = y.into();
    // Tick labels with as many decimals as the step needs on linear axes.
    let x_fmt = tick_format(&x, nx, chart.x_log);
    let y_fmt = tick_format(&y, ny, chart.y_log);
    let y_labels = y
        .key_points(ny)
        .iter()
        .map(|v| text_size(&y_fmt(v), &text).0)
        .fold(0.0, f64::max);
    let tick = u as i32;
    let x_area = tick as f64 + 2.0 * line_h + 2.0 * u;
    let y_area = tick as f64 + y_labels + line_h + 3.0 * u;
    let plot_w = w - 2.0 * u - y_area - right;
    let plot_h = h - top - u - x_area;
    if plot_w < 2.0 * s || plot_h < 2.0 * s {
        // Too small for a chart: the title alone.
        return Ok(Vec::new());
    }

    let mut ctx = ChartBuilder::on(root)
        .margin_top(top as i32)
        .margin_left(2.0 * u)
        .margin_right(right as i32)
        .margin_bottom(u)
        .x_label_area_size(x_area as i32)
        .y_label_area_size(y_area as i32)
        .build_cartesian_2d(x, y)?;
    let light = |log: bool| if log { 10 } else { 0 };
    ctx.configure_mesh()
        .x_labels(nx)
        .y_labels(ny)
        .x_max_light_lines(light(chart.x_log))
        .y_max_light_lines(light(chart.y_log))
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .x_desc(fit(&chart.x_label, plot_w, &text))
        .y_desc(fit(&chart.y_label, plot_h, &text))
        .label_style(text.clone())
        .axis_desc_style(text.clone())
        .bold_line_style(GRID)
        .light_line_style(GRID_MINOR)
        .axis_style(FRAME)
        .set_all_tick_mark_size(tick)
        .draw()?;
    let (px, py) = ctx.plotting_area().get_pixel_range();
    root.draw(&Rectangle::new(
        [(px.start, py.start), (px.end, py.end)],
        FRAME.stroke_width(1),
    ))?;
    let points = &chart.points;
    let at = |i: usize| (points[i].x, points[i].y);
    let thin = (s / 16.0).round().max(1.0) as u32;

    // The Pareto front as a dashed step line (the edge of the dominated region).
    if chart.mark_pareto && plan.front.len() >= 2 {
        let mut steps = Vec::new();
        for (k, &i) in plan.front.iter().enumerate() {
            if k > 0 {
                steps.push((points[i].x, points[plan.front[k - 1]].y));
            }
            steps.push(at(i));
        }
        ctx.draw_series(DashedLineSeries::new(
            steps,
            (0.4 * s) as u32,
            (0.3 * s) as u32,
            FRONT.stroke_width(thin),
        ))?;
    }

    // Markers, largest first so that small ones stay visible.
    let mut order = plan.plotted.clone();
    order.sort_by(|&a, &b| {
        plan.radius(points[b].size)
            .total_cmp(&plan.radius(points[a].size))
    });
    let mut markers = Vec::new();
    for &i in &order {
        let color = plan.color_of(&points[i].series);
        let r = plan.radius(points[i].size).round().max(1.0) as u32;
        let fill = mix(color, WHITE, 0.8);
        ctx.draw_series(if plan.on_front(i) {
            dot(at(i), r, fill, INK, thin + 1)
        } else {
            dot(at(i), r, fill, mix(color, BLACK, 0.6), thin)
        })?;
        let (mx, my) = ctx.backend_coord(&at(i));
        markers.push(Marker {
            x: mx,
            y: my,
            r,
            tooltip: plan.tooltip(i),
        });
    }
    if plan.plotted.is_empty() {
        let msg = style(s, MUTED).pos(Pos::new(HPos::Center, VPos::Center));
        let centre = ((px.start + px.end) / 2, (py.start + py.end) / 2);
        root.draw(&Text::new("no points to show", centre, msg))?;
    }

    label_points(plan, root, &ctx, (px.clone(), py.clone()))?;
    if show_legend {
        let origin = (f64::from(px.end) + 2.0 * u, f64::from(py.start));
        draw_legend(plan, root, &entries, swatch, origin, h - u)?;
    }
    Ok(markers)
}

/// Labels the Pareto points (or all points of a small chart), each where it
/// overlaps neither a labelled point nor another label.
fn label_points<DB: DrawingBackend, X: Ranged<ValueType = f64>, Y: Ranged<ValueType = f64>>(
    plan: &Plan,
    root: &DrawingArea<DB, Shift>,
    ctx: &ChartContext<DB, Cartesian2d<X, Y>>,
    (px, py): (std::ops::Range<i32>, std::ops::Range<i32>),
) -> Result<(), DrawError<DB>> {
    type Bounds = (f64, f64, f64, f64);
    let overlaps = |a: Bounds, b: Bounds| a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3;
    let points = &plan.chart.points;
    let mut labelled = if plan.chart.mark_pareto {
        plan.front.clone()
    } else if plan.plotted.len() < LABEL_ALL_BELOW {
        plan.plotted.clone()
    } else {
        Vec::new()
    };
    labelled.sort_by(|&a, &b| points[a].x.total_cmp(&points[b].x));
    let place = |i: usize| {
        let (x, y) = ctx.backend_coord(&(points[i].x, points[i].y));
        (f64::from(x), f64::from(y), plan.radius(points[i].size))
    };
    let mut taken: Vec<Bounds> = labelled
        .iter()
        .map(|&i| {
            let (x, y, r) = place(i);
            (x - r, y - r, x + r, y + r)
        })
        .collect();
    let text = style(plan.s, TEXT);
    let (tw_max, th) = (
        text_size("W", &text).0 * POINT_LABEL_CHARS as f64,
        0.8 * plan.s,
    );
    let inside = (
        f64::from(px.start) + 2.0,
        f64::from(py.start) + 2.0,
        f64::from(px.end) - 2.0,
        f64::from(py.end) - 2.0,
    );
    for &i in &labelled {
        let label = fit(points[i].label.trim(), tw_max, &text);
        if label.is_empty() {
            continue;
        }
        let (x, y, r) = place(i);
        let tw = text_size(&label, &text).0;
        let off = r + plan.unit;
        // Left of and below a Pareto point is empty (a point there would
        // dominate it) and clear of the step line, which leaves it going right.
        let candidates = [
            (x - off, y, HPos::Right, x - off - tw),
            (x, y + off + th / 2.0, HPos::Center, x - tw / 2.0),
            (x + off, y, HPos::Left, x + off),
            (x, y - off - th / 2.0, HPos::Center, x - tw / 2.0),
        ];
        for (tx, ty, anchor, left) in candidates {
            let b = (
                left - 1.0,
                ty - th / 2.0 - 1.0,
                left + tw + 1.0,
                ty + th / 2.0 + 1.0,
            );
            let within = b.0 >= inside.0 && b.1 >= inside.1 && b.2 <= inside.2 && b.3 <= inside.3;
            if within && !taken.iter().any(|t| overlaps(*t, b)) {
                taken.push(b);
                let at = Pos::new(anchor, VPos::Center);
                root.draw(&Text::new(label, (tx as i32, ty as i32), text.pos(at)))?;
                break;
            }
        }
    }
    Ok(())
}

/// Draws the legend `entries` downwards from `(x, y)`, stopping above `bottom`.
fn draw_legend<DB: DrawingBackend>(
    plan: &Plan,
    root: &DrawingArea<DB, Shift>,
    entries: &[Entry],
    swatch: f64,
    (x, y): (f64, f64),
    bottom: f64,
) -> Result<(), DrawError<DB>> {
    let (s, u) = (plan.s, plan.unit);
    let thin = (s / 16.0).round().max(1.0) as u32;
    let text = style(s, TEXT).pos(Pos::new(HPos::Left, VPos::Center));
    let sx = (x + swatch / 2.0) as i32;
    let tx = (x + swatch + u) as i32;
    let r_def = plan.r_default().round() as u32;
    let mut cursor = y;
    for (k, e) in entries.iter().enumerate() {
        let row = match e {
            Entry::Sample(_, r) => (1.2 * s).max(2.0 * r + u),
            Entry::Header(_) => 1.2 * s + 2.0 * u,
            _ => 1.2 * s,
        };
        if cursor + row > bottom {
            let more = format!("+{} more", entries.len() - k);
            let at = (x as i32, (cursor + s / 2.0) as i32);
            root.draw(&Text::new(more, at, style(s, MUTED).pos(text.pos)))?;
            break;
        }
        let cy = match e {
            Entry::Header(_) => cursor + row - 0.6 * s,
            _ => cursor + row / 2.0,
        } as i32;
        match e {
            Entry::Series(t, c) => {
                for d in dot(
                    (sx, cy),
                    r_def,
                    mix(*c, WHITE, 0.8),
                    mix(*c, BLACK, 0.6),
                    thin,
                ) {
                    root.draw(&d)?;
                }
                root.draw(&Text::new(t.as_str(), (tx, cy), text.clone()))?;
            }
            Entry::Pareto => {
                let ends = [(x as i32, cy), ((x + swatch - u) as i32, cy)];
                root.draw(&DashedPathElement::new(
                    ends,
                    (0.4 * s) as u32,
                    (0.3 * s) as u32,
                    FRONT.stroke_width(thin),
                ))?;
                for d in dot((sx, cy), r_def, WHITE, INK, thin + 1) {
                    root.draw(&d)?;
                }
                root.draw(&Text::new("Pareto front", (tx, cy), text.clone()))?;
            }
            Entry::Header(t) => root.draw(&Text::new(t.as_str(), (x as i32, cy), text.clone()))?,
            Entry::Sample(t, r) => {
                let r = r.round().max(1.0) as u32;
                for d in dot((sx, cy), r, mix(SAMPLE, WHITE, 0.5), MUTED, thin) {
                    root.draw(&d)?;
                }
                root.draw(&Text::new(t.as_str(), (tx, cy), text.clone()))?;
            }
        }
        cursor += row;
    }
    Ok(())
}
