//! `checkpoints.csv`: per check point its id, the number of views used and its errors (estimated − surveyed,
//! metres) per axis, 2-D and 3-D, before (recorded poses) and after (adjusted poses) the adjustment (thesis
//! 3.5.3, Tables 5-2…5-9). Points that could not be triangulated have empty cells and the reason.

use crate::adjustment::campaign_checkpoints::CheckPointComparison;
use crate::adjustment::CheckPointError;
use serde::{Deserialize, Serialize};
use skytie_util::csv_out::{quote, write_csv};
use std::collections::HashMap;
use std::io::{self, Write};
use std::path::Path;

/// Column names of `checkpoints.csv`.
pub const CHECKPOINTS_CSV_HEADER: [&str; 15] = [
    "point_id",
    "views_before",
    "before_x",
    "before_y",
    "before_z",
    "before_2d",
    "before_3d",
    "views_after",
    "after_x",
    "after_y",
    "after_z",
    "after_2d",
    "after_3d",
    "improved_2d",
    "note",
];

/// Errors of one triangulation, metres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AxisErrors {
    pub views: usize,
    /// Estimated − surveyed X, Y, Z.
    pub error_m: [f64; 3],
}

impl AxisErrors {
    fn from_point(p: &CheckPointError) -> Self {
        Self {
            views: p.views,
            error_m: p.error_m.into(),
        }
    }

    /// Horizontal error length.
    pub fn d2(&self) -> f64 {
        self.error_m[0].hypot(self.error_m[1])
    }

    /// 3-D error length.
    pub fn d3(&self) -> f64 {
        nalgebra::Vector3::from(self.error_m).norm()
    }
}

/// One row of `checkpoints.csv`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CheckPointRow {
    pub point_id: String,
    pub before: Option<AxisErrors>,
    pub after: Option<AxisErrors>,
    /// Why a triangulation failed (empty when both succeeded).
    pub note: String,
}

/// The rows of a comparison, in check-point order.
pub fn checkpoint_rows(c: &CheckPointComparison) -> Vec<CheckPointRow> {
    // First evaluated point and first failure of each check point (as a linear search would find them).
    let first_of = |keys: &mut dyn Iterator<Item = usize>| -> HashMap<usize, usize> {
        let mut m = HashMap::new();
        for (j, k) in keys.enumerate() {
            m.entry(k).or_insert(j);
        }
        m
    };
    let index = |e: &crate::adjustment::CheckPointEvaluation| {
        (
            first_of(&mut e.points.iter().map(|p| p.check_point)),
            first_of(&mut e.failed.iter().map(|(k, _)| *k)),
        )
    };
    let (before_at, after_at) = (index(&c.before), index(&c.after));
    (0..c.ids.len())
        .map(|i| {
            let find =
                |e: &crate::adjustment::CheckPointEvaluation,
                 at: &(HashMap<usize, usize>, HashMap<usize, usize>)| {
                    at.0.get(&i).map(|&j| AxisErrors::from_point(&e.points[j]))
                };
            let reason = |e: &crate::adjustment::CheckPointEvaluation,
                          at: &(HashMap<usize, usize>, HashMap<usize, usize>),
                          when: &str| {
                at.1.get(&i).map(|&j| format!("{when}: {}", e.failed[j].1))
            };
            let note = [
                reason(&c.before, &before_at, "before"),
                reason(&c.after, &after_at, "after"),
            ]
            .into_iter()
            .flatten()
            .collect::<Vec<_>>()
            .join("; ");
            let before = find(&c.before, &before_at);
            let after = find(&c.after, &after_at);
            let note = if before.is_none() && after.is_none() && note.is_empty() {
                "no observations".to_string()
            } else {
                note
            };
            CheckPointRow {
                point_id: c.ids[i].clone(),
                before,
                after,
                note,
            }
        })
        .collect()
}

/// Writes `checkpoints.csv` (atomically; floats in shortest round-trip form).
pub fn write_checkpoint_errors_csv(path: &Path, rows: &[CheckPointRow]) -> io::Result<()> {
    let errors = |e: &Option<AxisErrors>| -> Vec<String> {
        match e {
            Some(e) => vec![
                e.views.to_string(),
                format!("{}", e.error_m[0]),
                format!("{}", e.error_m[1]),
                format!("{}", e.error_m[2]),
                format!("{}", e.d2()),
                format!("{}", e.d3()),
            ],
            None => vec![String::new(); 6],
        }
    };
    write_csv(path, &CHECKPOINTS_CSV_HEADER, |w| {
        for r in rows {
            let mut cells = vec![quote(&r.point_id)];
            cells.extend(errors(&r.before));
            cells.extend(errors(&r.after));
            cells.push(match (&r.before, &r.after) {
                (Some(b), Some(a)) => (a.d2() < b.d2()).to_string(),
                _ => String::new(),
            });
            cells.push(quote(&r.note));
            writeln!(w, "{}", cells.join(","))?;
        }
        Ok(())
    })
}
