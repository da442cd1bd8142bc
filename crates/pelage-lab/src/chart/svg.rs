//! Writes a [`Scene`] as a self-contained SVG document.

use std::fmt::Write;

use super::scene::{Anchor, Color, Prim, Scene};

/// A coordinate with at most two decimals and no trailing zeros.
fn num(v: f64) -> String {
    let s = format!("{v:.2}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

/// Text escaped for XML content and attributes; control characters, which
/// XML 1.0 forbids, become spaces.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if (c as u32) < 0x20 && !matches!(c, '\t' | '\n' | '\r') => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

/// `attr="#rrggbb"` plus an opacity attribute when not opaque.
fn paint(attr: &str, c: Color) -> String {
    if c.a >= 1.0 {
        format!(r#"{attr}="{}""#, c.hex())
    } else {
        format!(
            r#"{attr}="{}" {attr}-opacity="{}""#,
            c.hex(),
            num(f64::from(c.a))
        )
    }
}

/// The SVG text of `scene`.
pub(crate) fn render(scene: &Scene) -> String {
    let (w, h) = (scene.width, scene.height);
    let mut out = String::new();
    // Writing to a String cannot fail; the results are ignored deliberately.
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="DejaVu Sans Mono, Menlo, Consolas, monospace">"#
    );
    let _ = writeln!(out, "<title>{}</title>", escape(&scene.title));
    for prim in &scene.prims {
        let _ = match prim {
            Prim::Rect { x, y, w, h, fill } => writeln!(
                out,
                r#"<rect x="{}" y="{}" width="{}" height="{}" {}/>"#,
                num(*x),
                num(*y),
                num(*w),
                num(*h),
                paint("fill", *fill)
            ),
            Prim::Path {
                points,
                closed,
                color,
                width,
                dash,
            } => {
                let pts: Vec<String> = points
                    .iter()
                    .map(|(x, y)| format!("{},{}", num(*x), num(*y)))
                    .collect();
                let dash = dash
                    .map(|(on, off)| format!(r#" stroke-dasharray="{} {}""#, num(on), num(off)))
                    .unwrap_or_default();
                writeln!(
                    out,
                    r#"<{} points="{}" fill="none" {} stroke-width="{}"{dash}/>"#,
                    if *closed { "polygon" } else { "polyline" },
                    pts.join(" "),
                    paint("stroke", *color),
                    num(*width)
                )
            }
            Prim::Circle {
                cx,
                cy,
                r,
                fill,
                stroke,
                tooltip,
            } => {
                let fill = fill.map_or_else(|| r#"fill="none""#.to_string(), |c| paint("fill", c));
                let stroke = stroke
                    .map(|(c, sw)| format!(r#" {} stroke-width="{}""#, paint("stroke", c), num(sw)))
                    .unwrap_or_default();
                let head = format!(
                    r#"cx="{}" cy="{}" r="{}" {fill}{stroke}"#,
                    num(*cx),
                    num(*cy),
                    num(*r)
                );
                match tooltip {
                    Some(t) => writeln!(
                        out,
                        r#"<circle class="point" {head}><title>{}</title></circle>"#,
                        escape(t)
                    ),
                    None => writeln!(out, "<circle {head}/>"),
                }
            }
            Prim::Text {
                x,
                y,
                text,
                scale,
                anchor,
                color,
                vertical,
            } => {
                let size = 10.0 * f64::from(*scale);
                let anchor = match anchor {
                    Anchor::Start => "start",
                    Anchor::Middle => "middle",
                    Anchor::End => "end",
                };
                // `y` is the glyph centre; the baseline is half a cap height lower.
                let baseline = y + 0.35 * size;
                let transform = if *vertical {
                    format!(r#" transform="rotate(-90 {} {})""#, num(*x), num(*y))
                } else {
                    String::new()
                };
                writeln!(
                    out,
                    r#"<text x="{}" y="{}" font-size="{}" text-anchor="{anchor}" {}{transform}>{}</text>"#,
                    num(*x),
                    num(baseline),
                    num(size),
                    paint("fill", *color),
                    escape(text)
                )
            }
        };
    }
    out.push_str("</svg>\n");
    out
}
