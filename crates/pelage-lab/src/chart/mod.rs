//! Scatter charts: "error against time" with the Pareto front marked.

mod axis;
mod layout;
mod raster;
mod scene;
mod svg;

use std::path::Path;

use image::{ExtendedColorType, ImageEncoder, RgbaImage, codecs::png::PngEncoder};

use crate::{LabError, write_file_atomically};

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
/// Only printable ASCII is drawn in PNGs (other characters show as `?`).
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
    /// Self-contained SVG: axes with ticks and tick labels (log axes:
    /// decades), axis labels, title, one colour per series with a legend,
    /// marker area proportional to `size` when given, the Pareto front as a
    /// step line with a legend entry, and labels next to Pareto points.
    /// Each data point is one `<circle class="point">` with a `<title>`
    /// tooltip. A zero `width` or `height` is treated as 1.
    pub fn to_svg(&self, width: u32, height: u32) -> String {
        svg::render(&layout::build(self, width, height))
    }

    /// Write [`ScatterChart::to_svg`] to `path`, atomically.
    pub fn write_svg(&self, path: &Path, width: u32, height: u32) -> Result<(), LabError> {
        write_file_atomically(path, self.to_svg(width, height).as_bytes())
    }

    /// The same chart as an opaque RGBA image of `width` x `height` pixels
    /// (each side 1 to 16384).
    pub fn to_image(&self, width: u32, height: u32) -> Result<RgbaImage, LabError> {
        for (name, v) in [("width", width), ("height", height)] {
            if v == 0 || v > MAX_PNG_SIDE {
                return Err(LabError::Invalid(format!(
                    "chart {name} {v} is outside 1..={MAX_PNG_SIDE} pixels"
                )));
            }
        }
        Ok(raster::render(&layout::build(self, width, height)))
    }

    /// The same chart as a PNG at `path`, written atomically.
    pub fn write_png(&self, path: &Path, width: u32, height: u32) -> Result<(), LabError> {
        let image = self.to_image(width, height)?;
        // The image is opaque: store RGB.
        let rgb: Vec<u8> = image
            .as_raw()
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        let mut bytes = Vec::new();
        PngEncoder::new(&mut bytes)
            .write_image(&rgb, width, height, ExtendedColorType::Rgb8)
            .map_err(|e| LabError::Encode {
                path: path.to_path_buf(),
                message: e.to_string(),
            })?;
        write_file_atomically(path, &bytes)
    }
}
