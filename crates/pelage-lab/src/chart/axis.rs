//! Axis ranges, tick positions and tick labels.

/// A finished axis: its range in transformed units (log10 of the value on a
/// log axis), labelled ticks and unlabelled minor grid values.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Axis {
    pub log: bool,
    pub lo: f64,
    pub hi: f64,
    pub ticks: Vec<(f64, String)>,
    pub minor: Vec<f64>,
}

impl Axis {
    /// Position of data value `v` along the axis: 0 at `lo`, 1 at `hi`.
    /// Computed with halves so that huge ranges do not overflow.
    pub fn frac(&self, v: f64) -> f64 {
        let t = if self.log { v.log10() } else { v };
        let span = self.hi / 2.0 - self.lo / 2.0;
        if span > 0.0 {
            (t / 2.0 - self.lo / 2.0) / span
        } else {
            0.5
        }
    }

    /// Build an axis for `values` (already filtered: finite, and positive on a
    /// log axis). `fits` says whether a set of tick labels has room; the
    /// densest candidate that fits is chosen, the sparsest if none does.
    pub fn build(values: &[f64], log: bool, fits: &dyn Fn(&[String]) -> bool) -> Axis {
        let (lo, hi) = domain(values, log);
        let mut axis = Axis {
            log,
            lo,
            hi,
            ticks: Vec::new(),
            minor: Vec::new(),
        };
        if log {
            axis.log_ticks(fits);
        } else {
            axis.ticks = linear_ticks(lo, hi, fits);
        }
        axis
    }

    /// Ticks of a log axis: decades if there are at least two in range, else
    /// 1-2-5 sequences, else 1..9 multiples, else linear ticks.
    fn log_ticks(&mut self, fits: &dyn Fn(&[String]) -> bool) {
        let (lo, hi) = (self.lo, self.hi);
        let k0 = lo.ceil() as i32;
        let k1 = hi.floor() as i32;
        let decades: Vec<i32> = (k0..=k1).collect();
        if decades.len() >= 2 {
            let mut chosen: Vec<(f64, String)> = Vec::new();
            let mut every = 1;
            for m in [1, 2, 3, 5, 10, 20, 50, 100] {
                every = m;
                chosen = decades
                    .iter()
                    .filter(|k| k.rem_euclid(m) == 0)
                    .map(|&k| {
                        let v = pow10(k);
                        (v, format_auto(v))
                    })
                    .collect();
                if chosen.len() < 2 || fits(&labels(&chosen)) {
                    break;
                }
            }
            if every == 1 && decades.len() <= 12 {
                for k in (k0 - 1)..=k1 {
                    for j in 2..=9 {
                        let v = f64::from(j) * pow10(k);
                        let t = v.log10();
                        if t >= lo && t <= hi {
                            self.minor.push(v);
                        }
                    }
                }
            }
            self.ticks = chosen;
            return;
        }
        let in_range = |mults: &[u32]| -> Vec<(f64, String)> {
            let mut out = Vec::new();
            for k in (k0 - 1)..=(k1 + 1) {
                for &j in mults {
                    let v = f64::from(j) * pow10(k);
                    let t = v.log10();
                    if t >= lo && t <= hi {
                        out.push((v, format_auto(v)));
                    }
                }
            }
            out
        };
        for mults in [&[1u32, 2, 5][..], &[1, 2, 3, 4, 5, 6, 7, 8, 9][..]] {
            let ticks = in_range(mults);
            if ticks.len() >= 2 && fits(&labels(&ticks)) {
                self.ticks = ticks;
                return;
            }
        }
        let (vlo, vhi) = (pow10f(lo), pow10f(hi));
        self.ticks = linear_ticks(vlo, vhi, fits)
            .into_iter()
            .filter(|(v, _)| *v > 0.0)
            .collect();
    }
}

/// The labels of `ticks`.
fn labels(ticks: &[(f64, String)]) -> Vec<String> {
    ticks.iter().map(|(_, l)| l.clone()).collect()
}

/// 10 to an integer power.
fn pow10(k: i32) -> f64 {
    10f64.powi(k)
}

/// 10 to a real power.
fn pow10f(t: f64) -> f64 {
    10f64.powf(t)
}

/// The padded range (in transformed units) that shows `values`.
fn domain(values: &[f64], log: bool) -> (f64, f64) {
    let t: Vec<f64> = values
        .iter()
        .map(|&v| if log { v.log10() } else { v })
        .filter(|v| v.is_finite())
        .collect();
    if t.is_empty() {
        return (0.0, 1.0);
    }
    let min = t.iter().copied().fold(f64::INFINITY, f64::min);
    let max = t.iter().copied().fold(f64::NEG_INFINITY, f64::max);
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
    let half = half * if log { 1.08 } else { 1.1 };
    let lo = (mid - half).max(f64::MIN);
    let hi = (mid + half).min(f64::MAX);
    (lo, hi)
}

/// A 1-2-5 step near `raw`.
fn nice_step(raw: f64) -> Option<f64> {
    if !(raw.is_finite() && raw > 0.0) {
        return None;
    }
    let exp = raw.log10().floor();
    let base = 10f64.powf(exp);
    let f = raw / base;
    let nice = if f <= 1.0 {
        1.0
    } else if f <= 2.0 {
        2.0
    } else if f <= 5.0 {
        5.0
    } else {
        10.0
    };
    let step = nice * base;
    (step.is_finite() && step > 0.0).then_some(step)
}

/// Labelled linear ticks in `lo..=hi`, densest that fits.
fn linear_ticks(lo: f64, hi: f64, fits: &dyn Fn(&[String]) -> bool) -> Vec<(f64, String)> {
    let mut last = Vec::new();
    for target in (2..=10).rev() {
        let ticks = linear_ticks_for(lo, hi, target);
        if ticks.len() >= 2 && fits(&labels(&ticks)) {
            return ticks;
        }
        if !ticks.is_empty() {
            last = ticks;
        }
    }
    last
}

/// Labelled linear ticks in `lo..=hi` with about `target` intervals.
fn linear_ticks_for(lo: f64, hi: f64, target: u32) -> Vec<(f64, String)> {
    let span = hi / 2.0 - lo / 2.0;
    let Some(step) = nice_step(span / f64::from(target) * 2.0) else {
        return Vec::new();
    };
    let first = (lo / step).ceil();
    let mut values = Vec::new();
    for i in 0..200 {
        let mut v = (first + f64::from(i)) * step;
        if !v.is_finite() || v > hi + step * 1e-9 {
            break;
        }
        if v.abs() < step * 1e-9 {
            v = 0.0;
        }
        values.push(v);
    }
    let biggest = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let sci = biggest >= 1e6 || (biggest > 0.0 && biggest < 1e-3);
    let step_exp = step.log10().floor();
    values
        .into_iter()
        .map(|v| {
            let label = if sci && v == 0.0 {
                "0".to_string()
            } else if sci {
                let digits = (v.abs().log10().floor() - step_exp).clamp(0.0, 8.0) as usize;
                tidy_sci(&format!("{v:.digits$e}"))
            } else {
                let digits = (-step_exp).clamp(0.0, 17.0) as usize;
                format!("{v:.digits$}")
            };
            (v, label)
        })
        .collect()
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
    let a = v.abs();
    if !(1e-3..1e6).contains(&a) {
        return tidy_sci(&format!("{v:.3e}"));
    }
    let rounded: f64 = format!("{v:.3e}").parse().unwrap_or(v);
    format!("{rounded}")
}

/// Remove trailing zeros from the mantissa of Rust's `{:e}` output.
fn tidy_sci(s: &str) -> String {
    match s.split_once('e') {
        Some((m, e)) if m.contains('.') => {
            let m = m.trim_end_matches('0').trim_end_matches('.');
            format!("{m}e{e}")
        }
        _ => s.to_string(),
    }
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
    fn linear() {
        let t = linear_ticks_for(0.0, 1.0, 5);
        let l: Vec<&str> = t.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(l, ["0.0", "0.2", "0.4", "0.6", "0.8", "1.0"]);
    }

    #[test]
    fn log_decades() {
        let a = Axis::build(&[0.01, 100.0], true, &|_| true);
        let l: Vec<&str> = a.ticks.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(l, ["0.01", "0.1", "1", "10", "100"]);
        let narrow = Axis::build(&[2.0, 3.0], true, &|_| true);
        assert!(narrow.ticks.len() >= 2);
        let equal = Axis::build(&[5.0, 5.0], false, &|_| true);
        assert!(equal.ticks.len() >= 2);
    }
}
