//! Drawing primitives in pixel coordinates, shared by the SVG writer and the
//! rasteriser so that both produce the same chart.

use crate::font;

/// An sRGB colour with straight alpha in `0.0..=1.0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Color {
    pub r: u8,
    pub g: u8,
    pub b: u8,
    pub a: f32,
}

impl Color {
    /// An opaque colour.
    pub const fn rgb(r: u8, g: u8, b: u8) -> Color {
        Color { r, g, b, a: 1.0 }
    }

    /// The same colour with alpha `a`.
    pub fn with_alpha(self, a: f32) -> Color {
        Color {
            a: a.clamp(0.0, 1.0),
            ..self
        }
    }

    /// The colour scaled towards black by `f` (`1.0` keeps it).
    pub fn darken(self, f: f32) -> Color {
        let d = |c: u8| (f32::from(c) * f.clamp(0.0, 1.0)).round() as u8;
        Color {
            r: d(self.r),
            g: d(self.g),
            b: d(self.b),
            a: self.a,
        }
    }

    /// `#rrggbb`.
    pub fn hex(self) -> String {
        format!("#{:02x}{:02x}{:02x}", self.r, self.g, self.b)
    }
}

/// Horizontal alignment of text relative to its anchor point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Anchor {
    Start,
    Middle,
    End,
}

/// One drawing operation.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Prim {
    /// A filled axis-aligned rectangle.
    Rect {
        x: f64,
        y: f64,
        w: f64,
        h: f64,
        fill: Color,
    },
    /// A stroked polyline (a polygon outline when `closed`), optionally dashed
    /// with `(on, off)` lengths in pixels.
    Path {
        points: Vec<(f64, f64)>,
        closed: bool,
        color: Color,
        width: f64,
        dash: Option<(f64, f64)>,
    },
    /// A circle; `tooltip` marks a data point (and becomes its SVG title).
    Circle {
        cx: f64,
        cy: f64,
        r: f64,
        fill: Option<Color>,
        stroke: Option<(Color, f64)>,
        tooltip: Option<String>,
    },
    /// A line of text drawn with the bitmap font at integer `scale`; `y` is
    /// the vertical centre of the glyphs. `vertical` text reads bottom to top
    /// and is centred on (`x`, `y`).
    Text {
        x: f64,
        y: f64,
        text: String,
        scale: u32,
        anchor: Anchor,
        color: Color,
        vertical: bool,
    },
}

impl Prim {
    /// Whether every coordinate is finite (others are dropped by renderers).
    pub fn is_finite(&self) -> bool {
        match self {
            Prim::Rect { x, y, w, h, .. } => [x, y, w, h].iter().all(|v| v.is_finite()),
            Prim::Path { points, width, .. } => {
                width.is_finite() && points.iter().all(|(x, y)| x.is_finite() && y.is_finite())
            }
            Prim::Circle {
                cx, cy, r, stroke, ..
            } => {
                cx.is_finite()
                    && cy.is_finite()
                    && r.is_finite()
                    && stroke.is_none_or(|(_, w)| w.is_finite())
            }
            Prim::Text { x, y, .. } => x.is_finite() && y.is_finite(),
        }
    }
}

/// A complete chart ready to be written.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Scene {
    pub width: u32,
    pub height: u32,
    pub title: String,
    pub prims: Vec<Prim>,
}

/// Width in pixels of `text` drawn at `scale`.
pub(crate) fn text_width(text: &str, scale: u32) -> f64 {
    let n = text.chars().count() as f64;
    if n == 0.0 {
        0.0
    } else {
        f64::from(scale) * (n * f64::from(font::ADVANCE) - f64::from(font::ADVANCE - font::GLYPH_W))
    }
}

/// Height in pixels of glyphs drawn at `scale`.
pub(crate) fn text_height(scale: u32) -> f64 {
    f64::from(scale * font::GLYPH_H)
}

/// `text` cut to at most `max` characters, marking the cut with `..`.
pub(crate) fn truncate(text: &str, max: usize) -> String {
    let n = text.chars().count();
    if n <= max {
        text.to_string()
    } else if max <= 2 {
        text.chars().take(max).collect()
    } else {
        let mut s: String = text.chars().take(max - 2).collect();
        s.push_str("..");
        s
    }
}
