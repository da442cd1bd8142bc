//! Contact sheets: images side by side in a grid, each with a caption.

use image::{Rgb, RgbImage, Rgba, RgbaImage};
use plotters::prelude::{BitMapBackend, IntoDrawingArea, RGBColor, Text};

use crate::{LabError, font};

/// Caption text size and strip height, in pixels.
const TEXT_SIZE: f64 = 16.0;
const CAPTION: u32 = 24;
/// Margin around and between cells, in pixels.
const MARGIN: u32 = 4;

/// Lays `cells` out `columns` to a row, each with its caption underneath (drawn with
/// the bundled DejaVu Sans; longer captions are cut at the cell's width, marked `..`),
/// on a white background. Cells may differ in size: every cell gets the largest width
/// and height.
pub fn contact_sheet(cells: &[(String, RgbaImage)], columns: u32) -> Result<RgbaImage, LabError> {
    if cells.is_empty() || columns == 0 {
        return Err(LabError::Invalid(
            "a contact sheet needs at least one image and one column".into(),
        ));
    }
    let cell_w = cells.iter().map(|(_, i)| i.width()).max().unwrap_or(1);
    let cell_h = cells.iter().map(|(_, i)| i.height()).max().unwrap_or(1);
    let columns = columns.min(cells.len() as u32);
    let rows = (cells.len() as u32).div_ceil(columns);
    let width = columns * (cell_w + MARGIN) + MARGIN;
    let height = rows * (cell_h + CAPTION + MARGIN) + MARGIN;
    if u64::from(width) * u64::from(height) > 1 << 28 {
        return Err(LabError::Invalid(format!(
            "a {width}x{height} contact sheet is too large; use smaller images"
        )));
    }
    font::register()?;
    let mut sheet = RgbaImage::from_pixel(width, height, Rgba([255, 255, 255, 255]));
    for (i, (caption, img)) in cells.iter().enumerate() {
        let (col, row) = (i as u32 % columns, i as u32 / columns);
        let x0 = MARGIN + col * (cell_w + MARGIN);
        let y0 = MARGIN + row * (cell_h + CAPTION + MARGIN);
        image::imageops::overlay(&mut sheet, img, i64::from(x0), i64::from(y0));
        let strip = caption_strip(caption, cell_w)?;
        for (x, y, Rgb([r, g, b])) in strip.enumerate_pixels() {
            sheet.put_pixel(x0 + x, y0 + img.height() + y, Rgba([*r, *g, *b, 255]));
        }
    }
    Ok(sheet)
}

/// `text` drawn by plotters on a white strip `width` pixels wide.
fn caption_strip(text: &str, width: u32) -> Result<RgbImage, LabError> {
    let mut rgb = vec![255u8; width as usize * CAPTION as usize * 3];
    {
        let strip = BitMapBackend::with_buffer(&mut rgb, (width, CAPTION)).into_drawing_area();
        let style = font::style(TEXT_SIZE, RGBColor(20, 20, 20));
        let text = font::fit(text, f64::from(width), &style);
        strip
            .draw(&Text::new(text, (0, 4), style))
            .and_then(|_| strip.present())
            .map_err(|e| LabError::Invalid(format!("cannot draw a caption: {e}")))?;
    }
    RgbImage::from_raw(width, CAPTION, rgb)
        .ok_or_else(|| LabError::Invalid("caption buffer has the wrong size".into()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lays_out_a_grid_with_captions() {
        let red = RgbaImage::from_pixel(40, 8, Rgba([255, 0, 0, 255]));
        let cells = vec![("a".to_string(), red.clone()); 3];
        let sheet = contact_sheet(&cells, 2).unwrap();
        assert_eq!(sheet.width(), 2 * (40 + MARGIN) + MARGIN);
        assert_eq!(sheet.height(), 2 * (8 + CAPTION + MARGIN) + MARGIN);
        assert_eq!(*sheet.get_pixel(MARGIN, MARGIN), Rgba([255, 0, 0, 255]));
        // The caption is drawn in dark pixels under the first image.
        let dark = (0..sheet.width())
            .flat_map(|x| (MARGIN + 8..MARGIN + 8 + CAPTION).map(move |y| (x, y)))
            .filter(|&(x, y)| sheet.get_pixel(x, y)[0] < 100)
            .count();
        assert!(dark > 0);
        assert!(contact_sheet(&[], 2).is_err());
        assert!(contact_sheet(&cells, 0).is_err());
    }
}
