//! Exact compositing: every fragment of a pixel, sorted by depth, blended front to
//! back. The ground truth for every transparency method (`shade/oit/*.wgsl`).

/// One fragment: depth along the view axis, straight (not premultiplied) linear colour, alpha.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fragment {
    /// Sort key: nearer is smaller.
    pub depth: f32,
    /// Linear RGB, not premultiplied.
    pub color: [f32; 3],
    /// Coverage in [0, 1].
    pub alpha: f32,
}

/// Sorts `fragments` by depth (stable, so equal depths keep their order) and composites
/// them over `background` (linear RGB): `C = sum_i T_i a_i c_i + T_n background` with
/// `T_i = prod_{j<i} (1 - a_j)`. Alphas are clamped to [0, 1]; fragments with a NaN
/// depth sort last.
pub fn composite_sorted(fragments: &mut [Fragment], background: [f32; 3]) -> [f32; 3] {
    fragments.sort_by(|a, b| a.depth.total_cmp(&b.depth));
    let mut color = [0.0f64; 3];
    let mut transmittance = 1.0f64;
    for f in fragments.iter() {
        let a = f64::from(f.alpha.clamp(0.0, 1.0));
        for (c, fc) in color.iter_mut().zip(f.color) {
            *c += transmittance * a * f64::from(fc);
        }
        transmittance *= 1.0 - a;
    }
    let mut out = [0.0f32; 3];
    for ((o, c), b) in out.iter_mut().zip(color).zip(background) {
        *o = (c + transmittance * f64::from(b)) as f32;
    }
    out
}

/// An 8-bit sRGB value to linear light (IEC 61966-2-1).
pub fn srgb8_to_linear(v: u8) -> f32 {
    let c = f32::from(v) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear light to 8-bit sRGB, rounded to nearest (what an `Rgba8UnormSrgb` target stores).
pub fn linear_to_srgb8(v: f32) -> u8 {
    let c = v.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5).clamp(0.0, 255.0) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_does_not_matter_and_sorting_does() {
        let red = Fragment {
            depth: 1.0,
            color: [1.0, 0.0, 0.0],
            alpha: 0.5,
        };
        let blue = Fragment {
            depth: 2.0,
            color: [0.0, 0.0, 1.0],
            alpha: 0.5,
        };
        let a = composite_sorted(&mut [red, blue], [0.0, 1.0, 0.0]);
        let b = composite_sorted(&mut [blue, red], [0.0, 1.0, 0.0]);
        assert_eq!(a, b);
        // red over blue over green: 0.5 red, 0.25 blue, 0.25 green.
        assert_eq!(a, [0.5, 0.25, 0.25]);
        assert_eq!(composite_sorted(&mut [], [0.3, 0.2, 0.1]), [0.3, 0.2, 0.1]);
    }

    #[test]
    fn srgb_round_trips() {
        for v in 0..=255u8 {
            assert_eq!(linear_to_srgb8(srgb8_to_linear(v)), v);
        }
    }
}
