//! Rejecting rows whose id is not unique: every row sharing the id is skipped (which one is right cannot be
//! known), each repeat reported with the row of the first occurrence.

use super::problem::{Problem, ProblemKind};
use std::collections::HashMap;
use std::path::PathBuf;

/// A parsed row and where it came from.
pub(crate) struct Sourced<T> {
    pub item: T,
    /// Relative to the campaign root.
    pub file: PathBuf,
    pub row: usize,
}

/// Keep only rows whose `id` occurs once; report each later occurrence (naming the first) as an error on
/// `column` with `hint` saying what to do. Order of the kept rows is unchanged.
pub(crate) fn keep_unique<T>(
    rows: Vec<Sourced<T>>,
    id: impl Fn(&T) -> String,
    column: &str,
    hint: &str,
    problems: &mut Vec<Problem>,
) -> Vec<Sourced<T>> {
    let mut first: HashMap<String, usize> = HashMap::new();
    let mut duplicated = vec![false; rows.len()];
    for (i, r) in rows.iter().enumerate() {
        let key = id(&r.item);
        match first.get(&key) {
            Some(&j) => {
                duplicated[i] = true;
                duplicated[j] = true;
                let f = &rows[j];
                let place = if f.file == r.file {
                    format!("row {}", f.row)
                } else {
                    format!("{}:{}", f.file.to_string_lossy().replace('\\', "/"), f.row)
                };
                problems.push(
                    Problem::error(
                        &r.file,
                        Some(r.row),
                        Some(column),
                        format!("'{key}' is also used on {place}; both rows skipped"),
                        hint,
                    )
                    .with_kind(ProblemKind::Duplicate),
                );
            }
            None => {
                first.insert(key, i);
            }
        }
    }
    rows.into_iter()
        .zip(duplicated)
        .filter(|(_, d)| !d)
        .map(|(r, _)| r)
        .collect()
}
