//! Contact sheets: images side by side in a grid, each with a caption.

use image::{Rgba, RgbaImage};

use crate::LabError;
use crate::font::{ADVANCE, GLYPH_ROWS, glyph, pixel};

/// Caption text scale (font pixels per glyph pixel).
const SCALE: u32 = 2;
/// Caption strip height and margins, in pixels.
const CAPTION: u32 = GLYPH_ROWS * SCALE + 8;
const MARGIN: u32 = 4;

/// Lays `cells` out `columns` to a row, each with its caption underneath (printable
/// ASCII; longer captions are cut at the cell's width), on a white background. Cells
/// may differ in size: every cell gets the largest width and height.
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
    let mut sheet = RgbaImage::from_pixel(width, height, Rgba([255, 255, 255, 255]));
    for (i, (caption, img)) in cells.iter().enumerate() {
        let (col, row) = (i as u32 % columns, i as u32 / columns);
        let x0 = MARGIN + col * (cell_w + MARGIN);
        let y0 = MARGIN + row * (cell_h + CAPTION + MARGIN);
        image::imageops::overlay(&mut sheet, img, i64::from(x0), i64::from(y0));
        let max_chars = (cell_w / (ADVANCE * SCALE)) as usize;
        for (n, c) in caption.chars().take(max_chars).enumerate() {
            let g = glyph(c);
            let gx = x0 + n as u32 * ADVANCE * SCALE;
            let gy = y0 + img.height() + 4;
            for fy in 0..GLYPH_ROWS {
                for fx in 0..ADVANCE {
                    if pixel(g, fx, fy) {
                        for sy in 0..SCALE {
                            for sx in 0..SCALE {
                                let (px, py) = (gx + fx * SCALE + sx, gy + fy * SCALE + sy);
                                if px < width && py < height {
                                    sheet.put_pixel(px, py, Rgba([20, 20, 20, 255]));
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    Ok(sheet)
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
