//! The regression guard: a committed evaluation table (`benches/eval/baseline.json`) and the comparison of a
//! new table with it. A judged metric regresses when its mean gets worse than the baseline's by more than the
//! noise band `max(floor, SD/√n)` (the standard error over the seeds), or its worst case by more than
//! `max(floor, SD)`; a row with more failed runs than before regresses too. Rows or metrics missing on either
//! side are reported, not judged.

use super::grade::{Better, METRICS};
use super::table::{Summary, Table};
use serde::{Deserialize, Serialize};

/// The file's content.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Baseline {
    /// How the table was made (the command).
    pub command: String,
    pub table: Table,
}

/// One finding of a comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct Finding {
    pub row: String,
    pub what: String,
    /// Whether it fails the guard.
    pub regression: bool,
}

/// How much worse `new` is than `old` (positive = worse) for a metric that gets better in direction `better`.
fn worsening(old: f64, new: f64, better: Better) -> f64 {
    match better {
        Better::Higher => old - new,
        _ => new - old,
    }
}

/// Compare one metric of one row.
fn compare_metric(
    row: &str,
    title: &str,
    better: Better,
    floor: f64,
    old: &Summary,
    new: &Summary,
) -> Vec<Finding> {
    let mut out = Vec::new();
    let band_mean = floor.max(old.sd / (old.n.max(1) as f64).sqrt());
    let band_worst = floor.max(old.sd);
    for (what, o, n, band) in [
        ("mean", old.mean, new.mean, band_mean),
        ("worst", old.worst, new.worst, band_worst),
    ] {
        let w = worsening(o, n, better);
        if w > band + 1e-12 {
            out.push(Finding {
                row: row.into(),
                what: format!("{title} {what}: {o:.4} → {n:.4} (worse by {w:.4}, band {band:.4})"),
                regression: true,
            });
        } else if w < -band - 1e-12 {
            out.push(Finding {
                row: row.into(),
                what: format!("{title} {what}: {o:.4} → {n:.4} (better)"),
                regression: false,
            });
        }
    }
    out
}

/// Every difference between `baseline` and `new` that matters.
pub fn compare(baseline: &Table, new: &Table) -> Vec<Finding> {
    let mut out = Vec::new();
    for (key, old) in baseline {
        let Some(row) = new.get(key) else {
            out.push(Finding {
                row: key.clone(),
                what: "not in this evaluation (not judged)".into(),
                regression: false,
            });
            continue;
        };
        if row.failed > old.failed {
            out.push(Finding {
                row: key.clone(),
                what: format!("{} failed runs (baseline {})", row.failed, old.failed),
                regression: true,
            });
        }
        for d in METRICS.iter().filter(|d| d.better != Better::Shown) {
            match (old.metrics.get(d.key), row.metrics.get(d.key)) {
                (Some(o), Some(n)) => {
                    out.extend(compare_metric(key, d.title, d.better, d.floor, o, n))
                }
                (Some(_), None) => out.push(Finding {
                    row: key.clone(),
                    what: format!("{} missing (the baseline has it)", d.title),
                    regression: true,
                }),
                _ => {}
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::table::Row;
    use std::collections::BTreeMap;

    fn row(inl: (f64, f64, f64), cp: (f64, f64, f64)) -> Row {
        let s = |(mean, worst, sd): (f64, f64, f64)| Summary {
            mean,
            worst,
            sd,
            n: 4,
        };
        Row {
            seeds: vec![1, 2, 3, 4],
            failed: 0,
            metrics: BTreeMap::from([
                ("nadir_inlier".to_string(), s(inl)),
                ("cp_2d_after".to_string(), s(cp)),
            ]),
        }
    }

    #[test]
    fn worse_beyond_the_band_fails_and_within_it_passes() {
        let base = Table::from([(
            "demo/thesis".into(),
            row((0.98, 0.95, 0.02), (0.05, 0.08, 0.02)),
        )]);
        // Within the bands: mean band max(0.005, 0.02/2) = 0.01, worst band 0.02.
        let same = Table::from([(
            "demo/thesis".into(),
            row((0.975, 0.94, 0.02), (0.058, 0.095, 0.02)),
        )]);
        assert!(
            compare(&base, &same).iter().all(|f| !f.regression),
            "{:?}",
            compare(&base, &same)
        );
        // Check points 2 cm worse on average: beyond the 1 cm band.
        let worse = Table::from([(
            "demo/thesis".into(),
            row((0.98, 0.95, 0.02), (0.07, 0.08, 0.02)),
        )]);
        let f = compare(&base, &worse);
        assert!(
            f.iter()
                .any(|f| f.regression && f.what.contains("cp 2D after mean")),
            "{f:?}"
        );
        // Better is reported, not failed; a lost metric and failed runs fail.
        let better = Table::from([(
            "demo/thesis".into(),
            row((0.99, 0.97, 0.01), (0.03, 0.04, 0.01)),
        )]);
        assert!(compare(&base, &better).iter().all(|f| !f.regression));
        let mut lost = row((0.98, 0.95, 0.02), (0.05, 0.08, 0.02));
        lost.metrics.remove("cp_2d_after");
        lost.failed = 1;
        let f = compare(&base, &Table::from([("demo/thesis".into(), lost)]));
        assert_eq!(f.iter().filter(|f| f.regression).count(), 2, "{f:?}");
    }
}

#[cfg(test)]
mod committed {
    use super::*;
    use crate::eval::Matrix;
    use std::path::Path;

    /// The committed baseline parses, and every row it judges is a preset/profile of the held-out matrix with
    /// the matrix's seeds (a baseline made on other seeds would compare unlike with like).
    #[test]
    fn the_committed_baseline_matches_the_held_out_matrix() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(root.join("benches/eval/baseline.json")).unwrap();
        let base: Baseline = serde_json::from_str(&text).unwrap();
        let matrix = Matrix::load(&root.join("benches/eval/matrix.toml")).unwrap();
        assert!(!base.table.is_empty());
        for (key, row) in &base.table {
            let (preset, profile) = key.split_once('/').unwrap();
            let cells = matrix
                .presets
                .iter()
                .find(|p| p.row() == preset)
                .unwrap_or_else(|| panic!("{key}: preset not in the matrix"));
            assert!(cells.profiles.iter().any(|p| p == profile), "{key}");
            assert_eq!(row.seeds, cells.seeds, "{key}");
            assert!(row.metrics.contains_key("cp_2d_after"), "{key}");
        }
    }
}
