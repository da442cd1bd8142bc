//! Scatter charts: "error against time" with the Pareto front marked.

mod draw;
mod ticks;

use std::fmt::Write;
use std::path::Path;

use image::{ExtendedColorType, ImageEncoder, RgbImage, RgbaImage, codecs::png::PngEncoder};
use plotters::prelude::{BitMapBackend, IntoDrawingArea, SVGBackend};

use crate::{LabError, font, write_file_atomically};

/// Largest PNG side accepted, in pixels.
const MAX_PNG_SIDE: u32 = 16_384;

/// One measured configuration in a [`ScatterChart`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ScatterPoint {
    /// Series (method) name: one colour and one legend entry per series.
    pub series: String,
    /// Short label of this configuration, shown next to Pareto points.
    pub label: String,
    /// Cost, e.g. milliseconds.
    pub x: f64,
    /// Error, e.g. mean FLIP.
    pub y: f64,
    /// Optional third quantity (e.g. memory) encoded as marker area.
    pub size: Option<f64>,
}

/// A scatter plot of [`ScatterPoint`]s, written as SVG or PNG.
///
/// Points with a NaN or infinite coordinate, and points with a coordinate
/// `<= 0` on a log axis, are skipped; their count is noted under the title.
/// Text is drawn with the bundled DejaVu Sans (characters it lacks show as a
/// box); long texts are cut to fit, marked with `..`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ScatterChart {
    /// Title at the top.
    pub title: String,
    /// Label of the horizontal axis.
    pub x_label: String,
    /// Label of the vertical axis.
    pub y_label: String,
    /// Logarithmic horizontal axis.
    pub x_log: bool,
    /// Logarithmic vertical axis.
    pub y_log: bool,
    /// The data.
    pub points: Vec<ScatterPoint>,
    /// Draw the Pareto front (both coordinates minimised) as a step line,
    /// ring and label its points, and add it to the legend.
    pub mark_pareto: bool,
    /// What marker area stands for (legend heading); `"size"` when unset.
    pub size_label: Option<String>,
}

impl ScatterChart {
    /// Self-contained SVG, drawn with plotters: axes with ticks and tick
    /// labels (log axes: decades), axis labels, title, one colour per series
    /// with a legend, marker area proportional to `size` when given, the
    /// Pareto front as a dashed step line with a legend entry, and labels next
    /// to Pareto points. Text names the generic `sans-serif` family. Each data
    /// point also gets one transparent `<circle class="point">` on top with a
    /// `<title>` tooltip. A zero `width` or `height` is treated as 1.
    pub fn to_svg(&self, width: u32, height: u32) -> String {
        let (width, height) = (width.max(1), height.max(1));
        let mut svg = String::new();
        let mut markers = Vec::new();
        {
            let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
            // Writing to a String cannot fail and the font is bundled: an error
            // leaves the chart drawn so far, still a complete SVG.
            if font::register().is_ok() {
                markers = draw::draw(self, &root).unwrap_or_default();
            }
            let _ = root.present();
        }
        // Tooltips, which plotters does not draw, go on top before `</svg>`.
        let end = svg.rfind("</svg>").unwrap_or(svg.len());
        let mut tips = String::new();
        for m in &markers {
            let _ = writeln!(
                tips,
                r##"<circle class="point" cx="{}" cy="{}" r="{}" fill="#000" fill-opacity="0"><title>{}</title></circle>"##,
                m.x,
                m.y,
                m.r,
                escape(&m.tooltip)
            );
        }
        svg.insert_str(end, &tips);
        svg
    }

    /// Write [`ScatterChart::to_svg`] to `path`, atomically.
    pub fn write_svg(&self, path: &Path, width: u32, height: u32) -> Result<(), LabError> {
        write_file_atomically(path, self.to_svg(width, height).as_bytes())
    }

    /// The same chart as an opaque RGBA image of `width` x `height` pixels
    /// (each side 1 to 16384).
    pub fn to_image(&self, width: u32, height: u32) -> Result<RgbaImage, LabError> {
        Ok(image::DynamicImage::ImageRgb8(self.to_rgb(width, height)?).to_rgba8())
    }

    /// The same chart as a PNG at `path`, written atomically.
    pub fn write_png(&self, path: &Path, width: u32, height: u32) -> Result<(), LabError> {
        // The image is opaque: store RGB.
        let image = self.to_rgb(width, height)?;
        let mut bytes = Vec::new();
        PngEncoder::new(&mut bytes)
            .write_image(image.as_raw(), width, height, ExtendedColorType::Rgb8)
            .map_err(|e| LabError::Encode {
                path: path.to_path_buf(),
                message: e.to_string(),
            })?;
        write_file_atomically(path, &bytes)
    }

    /// The chart drawn by plotters' bitmap backend.
    fn to_rgb(&self, width: u32, height: u32) -> Result<RgbImage, LabError> {
        for (name, v) in [("width", width), ("height", height)] {
            if v == 0 || v > MAX_PNG_SIDE {
                return Err(LabError::Invalid(format!(
                    "chart {name} {v} is outside 1..={MAX_PNG_SIDE} pixels"
                )));
            }
        }
        font::register()?;
        let mut rgb = vec![0u8; width as usize * height as usize * 3];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, (width, height)).into_drawing_area();
            draw::draw(self, &root)
                .and_then(|_| root.present())
                .map_err(|e| LabError::Invalid(format!("cannot draw the chart: {e}")))?;
        }
        RgbImage::from_raw(width, height, rgb)
            .ok_or_else(|| LabError::Invalid("chart buffer has the wrong size".into()))
    }
}

/// Text escaped for XML content; control characters, which XML 1.0 forbids,
/// become spaces.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            c if c.is_control() => out.push(' '),
            c => out.push(c),
        }
    }
    out
}
