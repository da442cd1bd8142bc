//! The one font of the crate: DejaVu Sans, bundled in `fonts/` (Bitstream Vera
//! licence, `fonts/DejaVuSans-LICENSE.txt`) and registered with plotters as
//! `sans-serif`, so charts and contact sheets draw text without system fonts.

use std::sync::OnceLock;

use plotters::style::{FontStyle, IntoFont, RGBColor, TextStyle, register_font};

use crate::LabError;

/// The family name text is drawn with. SVG viewers get the same generic
/// name, so an SVG shows in the viewer's own sans-serif face.
pub(crate) const FAMILY: &str = "sans-serif";

/// DejaVu Sans 2.37 (Debian's `fonts-dejavu-core`).
static DEJAVU_SANS: &[u8] =
    include_bytes!(concat!(env!("CARGO_MANIFEST_DIR"), "/fonts/DejaVuSans.ttf"));

/// Registers the bundled font with plotters (once per process).
pub(crate) fn register() -> Result<(), LabError> {
    static LOADED: OnceLock<bool> = OnceLock::new();
    let loaded =
        *LOADED.get_or_init(|| register_font(FAMILY, FontStyle::Normal, DEJAVU_SANS).is_ok());
    if loaded {
        Ok(())
    } else {
        Err(LabError::Invalid("the bundled font does not load".into()))
    }
}

/// Text of `size` pixels in `color`.
pub(crate) fn style(size: f64, color: RGBColor) -> TextStyle<'static> {
    (FAMILY, size).into_font().color(&color)
}

/// Width and height in pixels of `text` drawn with `style` (zero if the font
/// is missing).
pub(crate) fn text_size(text: &str, style: &TextStyle) -> (f64, f64) {
    let (w, h) = style.font.box_size(text).unwrap_or((0, 0));
    (f64::from(w), f64::from(h))
}

/// `text` with control characters (which XML forbids) as spaces, cut so that
/// it is at most `max` pixels wide, the cut marked with `..`.
pub(crate) fn fit(text: &str, max: f64, style: &TextStyle) -> String {
    let text: String = text
        .chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect();
    if text_size(&text, style).0 <= max {
        return text;
    }
    let chars: Vec<char> = text.chars().collect();
    // The longest prefix that fits with its marker (binary search: widths grow
    // with length).
    let (mut lo, mut hi) = (0, chars.len());
    while lo < hi {
        let mid = (lo + hi).div_ceil(2);
        let cut: String = chars[..mid].iter().collect::<String>() + "..";
        if text_size(&cut, style).0 <= max {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    if lo == 0 {
        String::new()
    } else {
        chars[..lo].iter().collect::<String>() + ".."
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measures_and_cuts() {
        register().unwrap();
        let s = style(20.0, RGBColor(0, 0, 0));
        let (w, h) = text_size("Pareto front", &s);
        assert!(w > 60.0 && w < 200.0 && h > 10.0, "{w} x {h}");
        assert!(text_size("WWWW", &s).0 > text_size("iiii", &s).0);
        assert_eq!(fit("short", 1000.0, &s), "short");
        let cut = fit("a rather long legend entry", 80.0, &s);
        assert!(
            cut.ends_with("..") && text_size(&cut, &s).0 <= 80.0,
            "{cut}"
        );
        assert_eq!(fit("anything", 1.0, &s), "");
        assert_eq!(fit("a\u{1}b", 1000.0, &s), "a b");
    }
}
