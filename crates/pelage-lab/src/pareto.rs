//! Pareto fronts of (cost, error) points.

/// Indices of the Pareto-optimal points when both coordinates are to be
/// minimised (x = cost, y = error): a point is on the front if no other point
/// is <= in both and < in one. NaN/inf points are never on the front.
/// Returned sorted by x.
///
/// Identical points do not dominate each other, so all copies of an optimal
/// point are returned (ordered by index). Runs in O(n log n).
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].0.is_finite() && points[i].1.is_finite())
        .collect();
    order.sort_by(|&a, &b| {
        let (pa, pb) = (points[a], points[b]);
        pa.0.total_cmp(&pb.0)
            .then(pa.1.total_cmp(&pb.1))
            .then(a.cmp(&b))
    });
    let mut front = Vec::new();
    // Smallest y among points with a strictly smaller x than the current group.
    let mut best = f64::INFINITY;
    let mut start = 0;
    while start < order.len() {
        let x = points[order[start]].0;
        let mut end = start;
        while end < order.len() && points[order[end]].0 == x {
            end += 1;
        }
        let group_min = order[start..end]
            .iter()
            .map(|&i| points[i].1)
            .fold(f64::INFINITY, f64::min);
        if group_min < best {
            front.extend(
                order[start..end]
                    .iter()
                    .copied()
                    .filter(|&i| points[i].1 == group_min),
            );
            best = group_min;
        }
        start = end;
    }
    front
}
