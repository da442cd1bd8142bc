//! The auto quality mode: given an error budget, the cheapest configuration the labs
//! measured, and why.
//!
//! The candidates come from measured rows (the lod lab's own runs, `shadows.csv` of
//! `pelage lab shadows`, `oit.csv` of `pelage lab oit`); nothing here guesses an error or
//! a time. Each pick says which rows qualified, what it costs and what it misses by.

use pelage_lab::Table;

/// The largest errors a pick may have.
#[derive(Clone, Copy, Debug)]
pub struct Budget {
    /// Mean FLIP of the image against the reference image (LOD, transparency).
    pub flip: f64,
    /// RMSE of transmittance at the strand vertices against ray tracing (shadows).
    pub transmittance_rmse: f64,
}

impl Default for Budget {
    fn default() -> Self {
        Self {
            flip: 0.05,
            transmittance_rmse: 0.15,
        }
    }
}

/// One measured configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct Candidate {
    /// What it is (method and parameters).
    pub name: String,
    /// Its measured error (FLIP or RMSE, see the budget).
    pub error: f64,
    /// Its measured time, milliseconds.
    pub time_ms: f64,
}

/// A choice and its reason.
#[derive(Clone, Debug, PartialEq)]
pub struct Pick {
    /// The cheapest candidate within the budget, or the most accurate one when none is.
    pub chosen: Candidate,
    /// Whether `chosen` is within the budget.
    pub within_budget: bool,
    /// One line: how many candidates qualified and what the runner-up costs.
    pub why: String,
}

/// The cheapest of `candidates` whose error is at most `budget`; when none is, the most
/// accurate one (flagged). `None` for no candidates.
pub fn cheapest(candidates: &[Candidate], budget: f64) -> Option<Pick> {
    let mut ok: Vec<&Candidate> = candidates
        .iter()
        .filter(|c| c.error.is_finite() && c.time_ms.is_finite() && c.error <= budget)
        .collect();
    ok.sort_by(|a, b| a.time_ms.total_cmp(&b.time_ms));
    if let Some(best) = ok.first() {
        let why = match ok.get(1) {
            Some(next) => format!(
                "{} of {} within error {budget}; cheapest at {:.2} ms (next: {} at {:.2} ms)",
                ok.len(),
                candidates.len(),
                best.time_ms,
                next.name,
                next.time_ms
            ),
            None => format!("the only one of {} within error {budget}", candidates.len()),
        };
        return Some(Pick {
            chosen: (*best).clone(),
            within_budget: true,
            why,
        });
    }
    let best = candidates
        .iter()
        .filter(|c| c.error.is_finite())
        .min_by(|a, b| a.error.total_cmp(&b.error))?;
    Some(Pick {
        chosen: best.clone(),
        within_budget: false,
        why: format!(
            "none of {} within error {budget}: the most accurate one misses by {:.4}",
            candidates.len(),
            best.error - budget
        ),
    })
}

/// Column `name` of `table`, or an error naming the file's columns.
fn column(table: &Table, name: &str) -> Result<usize, String> {
    table
        .header
        .iter()
        .position(|h| h == name)
        .ok_or_else(|| format!("no column `{name}` (columns: {})", table.header.join(", ")))
}

/// The rows of `table` (from `pelage lab shadows`) for `groom` as candidates: name
/// `method resolution pcf`, error `rmse`, time `wall_ms`.
pub fn shadow_candidates(table: &Table, groom: &str) -> Result<Vec<Candidate>, String> {
    let [g, m, r, p, t, e] =
        ["groom", "method", "resolution", "pcf", "wall_ms", "rmse"].map(|c| column(table, c));
    let (g, m, r, p, t, e) = (g?, m?, r?, p?, t?, e?);
    Ok(table
        .rows
        .iter()
        .filter(|row| row.get(g).is_some_and(|v| v == groom))
        .filter_map(|row| {
            Some(Candidate {
                name: format!("{} {} pcf {}", row.get(m)?, row.get(r)?, row.get(p)?),
                error: row.get(e)?.parse().ok()?,
                time_ms: row.get(t)?.parse().ok()?,
            })
        })
        .collect())
}

/// The rows of `table` (from `pelage lab oit`) for `scene` at the measured opacity
/// nearest `opacity` as candidates: name `config`, error `mean_flip`, time `gpu_ms`.
pub fn oit_candidates(
    table: &Table,
    scene: &str,
    opacity: f64,
) -> Result<(f64, Vec<Candidate>), String> {
    let [s, o, c, t, e] =
        ["scene", "opacity", "config", "gpu_ms", "mean_flip"].map(|c| column(table, c));
    let (s, o, c, t, e) = (s?, o?, c?, t?, e?);
    let rows: Vec<&Vec<String>> = table
        .rows
        .iter()
        .filter(|row| row.get(s).is_some_and(|v| v == scene))
        .collect();
    let nearest = rows
        .iter()
        .filter_map(|row| row.get(o)?.parse::<f64>().ok())
        .min_by(|a, b| (a - opacity).abs().total_cmp(&(b - opacity).abs()))
        .ok_or_else(|| format!("no rows for scene `{scene}`"))?;
    Ok((
        nearest,
        rows.iter()
            .filter(|row| {
                row.get(o)
                    .and_then(|v| v.parse::<f64>().ok())
                    .is_some_and(|v| v == nearest)
            })
            .filter_map(|row| {
                Some(Candidate {
                    name: row.get(c)?.clone(),
                    error: row.get(e)?.parse().ok()?,
                    time_ms: row.get(t)?.parse().ok()?,
                })
            })
            .collect(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(name: &str, error: f64, time_ms: f64) -> Candidate {
        Candidate {
            name: name.into(),
            error,
            time_ms,
        }
    }

    #[test]
    fn picks_the_cheapest_within_budget_or_the_most_accurate() {
        let all = [c("a", 0.01, 9.0), c("b", 0.04, 3.0), c("c", 0.2, 1.0)];
        let pick = cheapest(&all, 0.05).unwrap();
        assert_eq!(pick.chosen.name, "b");
        assert!(pick.within_budget);
        let pick = cheapest(&all, 0.001).unwrap();
        assert_eq!(pick.chosen.name, "a");
        assert!(!pick.within_budget);
        assert!(cheapest(&[], 0.1).is_none());
    }

    #[test]
    fn reads_the_labs_tables() {
        let shadows = Table::from_csv(
            "groom,method,resolution,pcf,gpu_ms,wall_ms,memory_mb,rmse,p95\n\
             dense_fur,voxel,32^3,-,9,9.5,0.1,0.16,0.3\n\
             dense_fur,dom,256,1,20,21,1,0.09,0.2\n\
             long_hair,voxel,32^3,-,1,1,0.1,0.5,0.9\n",
        )
        .unwrap();
        let rows = shadow_candidates(&shadows, "dense_fur").unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(cheapest(&rows, 0.1).unwrap().chosen.name, "dom 256 pcf 1");
        let oit = Table::from_csv(
            "scene,opacity,method,config,gpu_ms,memory_mb,slices,mean_flip\n\
             creature,0.3,wboit,wboit,1,0,1,0.01\n\
             creature,0.8,wboit,wboit,1,0,1,0.09\n\
             creature,0.8,k_buffer,k=8,2,6,1,0.004\n",
        )
        .unwrap();
        let (opacity, rows) = oit_candidates(&oit, "creature", 0.6).unwrap();
        assert_eq!(opacity, 0.8);
        assert_eq!(cheapest(&rows, 0.05).unwrap().chosen.name, "k=8");
        assert!(
            shadow_candidates(&oit, "x")
                .unwrap_err()
                .contains("no column")
        );
    }
}
