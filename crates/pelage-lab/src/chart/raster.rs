//! Rasterises a [`Scene`] onto an RGBA image with simple anti-aliasing and
//! the built-in bitmap font.

use image::{Rgba, RgbaImage};

use super::scene::{Anchor, Color, Prim, Scene, text_width};
use crate::font;

/// A line segment between two points.
type Segment = ((f64, f64), (f64, f64));

/// A floating-point RGB canvas (sRGB values in `0..=1`).
struct Canvas {
    w: usize,
    h: usize,
    px: Vec<[f32; 3]>,
}

/// Pixel index range `lo..hi` covering `[a, b]`, clamped to `0..n`.
fn span(a: f64, b: f64, n: usize) -> std::ops::Range<usize> {
    let lo = a.floor().max(0.0);
    let hi = (b.ceil() + 1.0).min(n as f64);
    if hi <= lo {
        0..0
    } else {
        lo as usize..hi as usize
    }
}

/// Distance from `p` to the segment `a`-`b`.
fn segment_distance(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (qx, qy) = (a.0 + t * dx - p.0, a.1 + t * dy - p.1);
    (qx * qx + qy * qy).sqrt()
}

/// The "on" pieces of a polyline drawn with a dash pattern.
fn dashed(segments: &[Segment], on: f64, off: f64) -> Vec<Segment> {
    if !(on > 0.0 && off >= 0.0 && on.is_finite() && off.is_finite()) {
        return segments.to_vec();
    }
    let mut out = Vec::new();
    let mut drawing = true;
    let mut left = on; // length remaining in the current dash or gap
    for &(a, b) in segments {
        let len = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
        if len <= 0.0 {
            continue;
        }
        let at = |d: f64| (a.0 + (b.0 - a.0) * d / len, a.1 + (b.1 - a.1) * d / len);
        let mut d = 0.0;
        // Each step ends a dash or gap or reaches the segment end; the guard
        // only protects against absurd patterns.
        let mut guard = 0u32;
        while d < len && guard < 1_000_000 {
            guard += 1;
            let step = left.min(len - d);
            if drawing {
                out.push((at(d), at(d + step)));
            }
            d += step;
            left -= step;
            if left <= 1e-9 {
                drawing = !drawing;
                left = if drawing { on } else { off };
            }
        }
    }
    out
}

impl Canvas {
    fn new(w: usize, h: usize) -> Canvas {
        Canvas {
            w,
            h,
            px: vec![[1.0; 3]; w * h],
        }
    }

    /// Blend `c` over pixel (`x`, `y`) with extra coverage `cov`.
    fn blend(&mut self, x: usize, y: usize, c: Color, cov: f64) {
        let a = (f64::from(c.a) * cov).clamp(0.0, 1.0) as f32;
        if a <= 0.0 || x >= self.w || y >= self.h {
            return;
        }
        let p = &mut self.px[y * self.w + x];
        for (dst, src) in p.iter_mut().zip([c.r, c.g, c.b]) {
            *dst = *dst * (1.0 - a) + f32::from(src) / 255.0 * a;
        }
    }

    fn rect(&mut self, x: f64, y: f64, w: f64, h: f64, fill: Color) {
        let (x1, y1) = (x + w, y + h);
        for py in span(y, y1, self.h) {
            let cy = ((py as f64 + 1.0).min(y1) - (py as f64).max(y)).clamp(0.0, 1.0);
            for px in span(x, x1, self.w) {
                let cx = ((px as f64 + 1.0).min(x1) - (px as f64).max(x)).clamp(0.0, 1.0);
                self.blend(px, py, fill, cx * cy);
            }
        }
    }

    /// Stroke segments with round ends; overlapping segments are blended
    /// once (maximum coverage) so joints do not darken.
    fn segments(&mut self, segs: &[Segment], color: Color, width: f64) {
        if segs.is_empty() {
            return;
        }
        let hw = width.max(1.0) / 2.0;
        let alpha = width.clamp(0.0, 1.0);
        let (mut bx0, mut by0, mut bx1, mut by1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for &(a, b) in segs {
            bx0 = bx0.min(a.0.min(b.0));
            by0 = by0.min(a.1.min(b.1));
            bx1 = bx1.max(a.0.max(b.0));
            by1 = by1.max(a.1.max(b.1));
        }
        let xs = span(bx0 - hw - 1.0, bx1 + hw + 1.0, self.w);
        let ys = span(by0 - hw - 1.0, by1 + hw + 1.0, self.h);
        let (mw, mh) = (xs.len(), ys.len());
        if mw == 0 || mh == 0 {
            return;
        }
        let mut cover = vec![0.0f64; mw * mh];
        for &(a, b) in segs {
            let sx = span(a.0.min(b.0) - hw - 1.0, a.0.max(b.0) + hw + 1.0, self.w);
            let sy = span(a.1.min(b.1) - hw - 1.0, a.1.max(b.1) + hw + 1.0, self.h);
            for py in sy {
                for px in sx.clone() {
                    let d = segment_distance((px as f64 + 0.5, py as f64 + 0.5), a, b);
                    let c = (hw + 0.5 - d).clamp(0.0, 1.0);
                    let k = (py - ys.start) * mw + (px - xs.start);
                    if let Some(m) = cover.get_mut(k) {
                        *m = m.max(c);
                    }
                }
            }
        }
        for (k, c) in cover.iter().enumerate() {
            if *c > 0.0 {
                self.blend(xs.start + k % mw, ys.start + k / mw, color, c * alpha);
            }
        }
    }

    fn circle(
        &mut self,
        cx: f64,
        cy: f64,
        r: f64,
        fill: Option<Color>,
        stroke: Option<(Color, f64)>,
    ) {
        let r = r.max(0.0);
        let sw = stroke.map_or(0.0, |(_, w)| w.max(0.0));
        let ext = r + sw / 2.0 + 1.0;
        for py in span(cy - ext, cy + ext, self.h) {
            for px in span(cx - ext, cx + ext, self.w) {
                let d = ((px as f64 + 0.5 - cx).powi(2) + (py as f64 + 0.5 - cy).powi(2)).sqrt();
                if let Some(f) = fill {
                    self.blend(px, py, f, (r + 0.5 - d).clamp(0.0, 1.0));
                }
                if let Some((c, _)) = stroke {
                    let hw = sw.max(1.0) / 2.0;
                    let cov = (hw + 0.5 - (d - r).abs()).clamp(0.0, 1.0) * sw.min(1.0);
                    self.blend(px, py, c, cov);
                }
            }
        }
    }

    fn text(
        &mut self,
        (x, y): (f64, f64),
        text: &str,
        scale: u32,
        anchor: Anchor,
        color: Color,
        vertical: bool,
    ) {
        let s = scale.max(1) as i64;
        let tw = text_width(text, scale);
        let th = f64::from(scale * font::GLYPH_H);
        let shift = match anchor {
            Anchor::Start => 0.0,
            Anchor::Middle => tw / 2.0,
            Anchor::End => tw,
        };
        // Origin of the text box in text coordinates (u along, v down).
        let (ox, oy) = if vertical {
            ((x - th / 2.0).round() as i64, (y + shift).round() as i64)
        } else {
            ((x - shift).round() as i64, (y - th / 2.0).round() as i64)
        };
        for (k, ch) in text.chars().enumerate() {
            let g = font::glyph(ch);
            for col in 0..font::GLYPH_W {
                for row in 0..font::GLYPH_ROWS {
                    if !font::pixel(g, col, row) {
                        continue;
                    }
                    let u = (k as i64 * i64::from(font::ADVANCE) + i64::from(col)) * s;
                    let v = i64::from(row) * s;
                    for du in 0..s {
                        for dv in 0..s {
                            let (px, py) = if vertical {
                                (ox + v + dv, oy - (u + du) - 1)
                            } else {
                                (ox + u + du, oy + v + dv)
                            };
                            if px >= 0 && py >= 0 {
                                self.blend(px as usize, py as usize, color, 1.0);
                            }
                        }
                    }
                }
            }
        }
    }
}

/// The pixels of `scene`.
pub(crate) fn render(scene: &Scene) -> RgbaImage {
    let mut canvas = Canvas::new(scene.width as usize, scene.height as usize);
    for prim in &scene.prims {
        match prim {
            Prim::Rect { x, y, w, h, fill } => canvas.rect(*x, *y, *w, *h, *fill),
            Prim::Path {
                points,
                closed,
                color,
                width,
                dash,
            } => {
                let mut segs: Vec<_> = points.windows(2).map(|p| (p[0], p[1])).collect();
                if let (true, Some(first), Some(last)) = (*closed, points.first(), points.last()) {
                    segs.push((*last, *first));
                }
                if let Some((on, off)) = dash {
                    segs = dashed(&segs, *on, *off);
                }
                canvas.segments(&segs, *color, *width);
            }
            Prim::Circle {
                cx,
                cy,
                r,
                fill,
                stroke,
                ..
            } => canvas.circle(*cx, *cy, *r, *fill, *stroke),
            Prim::Text {
                x,
                y,
                text,
                scale,
                anchor,
                color,
                vertical,
            } => canvas.text((*x, *y), text, *scale, *anchor, *color, *vertical),
        }
    }
    let to8 = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    RgbaImage::from_fn(scene.width, scene.height, |x, y| {
        let p = canvas
            .px
            .get(y as usize * canvas.w + x as usize)
            .copied()
            .unwrap_or([1.0; 3]);
        Rgba([to8(p[0]), to8(p[1]), to8(p[2]), 255])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_dashed_paths_are_drawn_to_the_end() {
        let pts = [
            (125.5, 66.75),
            (180.26, 66.75),
            (180.26, 176.68),
            (289.78, 286.61),
            (675.5, 286.61),
            (675.5, 523.24),
        ];
        let segs: Vec<_> = pts.windows(2).map(|p| (p[0], p[1])).collect();
        let pieces = dashed(&segs, 8.0, 6.0);
        let mut c = Canvas::new(900, 600);
        c.segments(&pieces, Color::rgb(0, 0, 0), 1.5);
        let dark = |x: usize, y: usize| c.px[y * 900 + x][0] < 0.5;
        let far_right = (560..670).filter(|&x| dark(x, 286)).count();
        let far_down = (440..523).filter(|&y| dark(675, y)).count();
        assert!(far_right > 50, "{far_right}");
        assert!(far_down > 40, "{far_down}");
    }
}
