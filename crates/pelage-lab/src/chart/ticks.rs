//! Axis ranges, log-axis ticks and tick labels: what plotters leaves to the
//! caller. Its linear ticks are used as they are; its log ticks are decades
//! only (none on a range inside one decade), so a log axis gets its ticks here.

use plotters::coord::ranged1d::Ranged;
use plotters::coord::types::RangedCoordf64;

/// Largest magnitude of an axis end: keeps `hi - lo` finite for plotters.
const LIMIT: f64 = f64::MAX / 4.0;

/// The padded range that shows `values` (finite, and positive on a log axis).
pub(crate) fn domain(values: &[f64], log: bool) -> (f64, f64) {
    let t: Vec<f64> = values
        .iter()
        .map(|&v| if log { v.log10() } else { v })
        .filter(|v| v.is_finite())
        .collect();
    if t.is_empty() {
        return if log { (1.0, 10.0) } else { (0.0, 1.0) };
    }
    let min = t.iter().copied().fold(f64::INFINITY, f64::min);
    let max = t.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    // Halves, so that huge ranges do not overflow.
    let mid = min / 2.0 + max / 2.0;
    let mut half = max / 2.0 - min / 2.0;
    if half <= mid.abs() * 1e-9 || half <= 0.0 {
        half = if log {
            0.5
        } else if mid == 0.0 {
            1.0
        } else {
            mid.abs() * 0.1
        };
    }
    if log {
        let half = half * 1.08;
        let lo = 10f64.powf(mid - half).max(f64::MIN_POSITIVE);
        (lo, 10f64.powf(mid + half).clamp(lo * 2.0, LIMIT))
    } else {
        let half = half * 1.1;
        ((mid - half).max(-LIMIT), (mid + half).min(LIMIT))
    }
}

/// Ticks of the log axis `lo..hi`, at most about `max` of them: every decade
/// (or every n-th) when two or more are in range, else 1-2-5 or 1..9
/// multiples, else plotters' linear ticks. Returns labelled ticks and the
/// minor grid values.
pub(crate) fn log_ticks(lo: f64, hi: f64, max: usize) -> (Vec<f64>, Vec<f64>) {
    let pow = |k: i32| 10f64.powi(k);
    let (k0, k1) = (lo.log10().ceil() as i32, hi.log10().floor() as i32);
    let in_range = |v: &f64| *v >= lo && *v <= hi;
    let decades = (k1 - k0 + 1).max(0) as usize;
    if decades >= 2 {
        let every = decades.div_ceil(max.max(2)) as i32;
        let major = (k0..=k1).filter(|k| k.rem_euclid(every) == 0).map(pow);
        let minor: Vec<f64> = if every == 1 && decades <= 12 {
            (k0 - 1..=k1)
                .flat_map(|k| (2..=9).map(move |j| f64::from(j) * pow(k)))
                .filter(in_range)
                .collect()
        } else {
            Vec::new()
        };
        return (major.collect(), minor);
    }
    for mults in [&[1, 2, 5][..], &[1, 2, 3, 4, 5, 6, 7, 8, 9][..]] {
        let ticks: Vec<f64> = (k0 - 1..=k1 + 1)
            .flat_map(|k| mults.iter().map(move |&j| f64::from(j) * pow(k)))
            .filter(in_range)
            .collect();
        if ticks.len() >= 2 && ticks.len() <= max.max(2) {
            return (ticks, Vec::new());
        }
    }
    (RangedCoordf64::from(lo..hi).key_points(max), Vec::new())
}

/// Short label for any value: plain decimals for moderate magnitudes,
/// scientific notation (`2.5e-4`) otherwise; about 4 significant digits.
pub(crate) fn format_auto(v: f64) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    if v == 0.0 {
        return "0".to_string();
    }
    if !(1e-3..1e6).contains(&v.abs()) {
        let s = format!("{v:.3e}");
        // Trailing zeros of the mantissa go.
        return match s.split_once('e') {
            Some((m, e)) => format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.')),
            None => s,
        };
    }
    let rounded: f64 = format!("{v:.3e}").parse().unwrap_or(v);
    format!("{rounded}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats() {
        assert_eq!(format_auto(0.30000000000000004), "0.3");
        assert_eq!(format_auto(1e-5), "1e-5");
        assert_eq!(format_auto(2.5e7), "2.5e7");
        assert_eq!(format_auto(1234.5678), "1235");
        assert_eq!(format_auto(100.0), "100");
    }

    #[test]
    fn log_axes() {
        let (lo, hi) = domain(&[0.01, 100.0], true);
        let (major, minor) = log_ticks(lo, hi, 10);
        let labels: Vec<String> = major.iter().map(|v| format_auto(*v)).collect();
        assert_eq!(labels, ["0.01", "0.1", "1", "10", "100"]);
        assert!(minor.contains(&20.0) && minor.iter().all(|v| *v >= lo && *v <= hi));
        // Every other decade when space is short.
        assert_eq!(log_ticks(lo, hi, 3).0, [0.01, 1.0, 100.0]);
        // Inside one decade: 1-2-5 multiples or finer, never fewer than two.
        let (lo, hi) = domain(&[2.0, 3.0], true);
        assert!(log_ticks(lo, hi, 10).0.len() >= 2);
        let (lo, hi) = domain(&[5.0, 5.0], true);
        assert!(log_ticks(lo, hi, 10).0.len() >= 2);
    }

    #[test]
    fn domains() {
        assert_eq!(domain(&[], false), (0.0, 1.0));
        let (lo, hi) = domain(&[5.0, 5.0], false);
        assert!(lo < 5.0 && hi > 5.0);
        let (lo, hi) = domain(&[-f64::MAX, f64::MAX], false);
        assert!((hi - lo).is_finite());
        let (lo, hi) = domain(&[1e-300, 1e300], true);
        assert!(lo > 0.0 && lo < 1e-300 && hi > 1e300 && (hi - lo).is_finite());
    }
}
