//! Printing GPU times.

/// Prints `title` and one line per pass (label, milliseconds) and their total; says so
/// when there are none (the adapter has no timestamp queries).
pub fn print_pass_times(passes: &[(String, f64)], title: &str) {
    if passes.is_empty() {
        println!("GPU time per pass: n/a (the adapter has no timestamp queries)");
        return;
    }
    println!("{title}");
    for (label, ms) in passes {
        println!("  {label:<28} {ms:9.3} ms");
    }
    let total: f64 = passes.iter().map(|(_, ms)| ms).sum();
    println!("  {:<28} {total:9.3} ms", "frame");
}

/// The median of each pass over frames: `frames` holds each frame's (label, ms) list;
/// labels keep the order they first appeared in.
pub fn median_per_pass(frames: &[Vec<(String, f64)>]) -> Vec<(String, f64)> {
    let mut per_pass: Vec<(String, Vec<f64>)> = Vec::new();
    for passes in frames {
        for (label, ms) in passes {
            match per_pass.iter_mut().find(|(l, _)| l == label) {
                Some((_, v)) => v.push(*ms),
                None => per_pass.push((label.clone(), vec![*ms])),
            }
        }
    }
    per_pass
        .into_iter()
        .map(|(label, mut v)| {
            v.sort_by(f64::total_cmp);
            let median = v.get(v.len() / 2).copied().unwrap_or(f64::NAN);
            (label, median)
        })
        .collect()
}
