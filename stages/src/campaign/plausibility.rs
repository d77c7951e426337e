//! Checks across rows that no single cell shows: a recording far outside the area the others cover, a
//! recording that jumps away from both neighbours faster than a vehicle drives, a check point far from every
//! recording, and one image file used by two rows. Rows that fail are rejected (every one of them: which of two
//! rows sharing an image is right cannot be known); a lone jump between two drives is only a warning.

use super::model::{CheckPoint, Recording};
use super::problem::{Problem, ProblemKind, Severity};
use super::unique::Sourced;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Fastest plausible speed of a mapping vehicle, m/s (250 km/h), plus a GNSS margin per step, m.
pub(crate) const MAX_SPEED_M_S: f64 = 70.0;
pub(crate) const JUMP_MARGIN_M: f64 = 10.0;
/// A point lies outside the campaign when it is farther from the recordings' median position than
/// `EXTENT_FACTOR` × the distance within which 95 % of the recordings lie, plus `EXTENT_MARGIN_M`.
pub(crate) const EXTENT_FACTOR: f64 = 10.0;
pub(crate) const EXTENT_MARGIN_M: f64 = 1000.0;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Centre (median x, y) of the recordings and the radius beyond which a point is outside the campaign.
struct Extent {
    x: f64,
    y: f64,
    r95_m: f64,
}

impl Extent {
    fn of(rows: &[Sourced<Recording>]) -> Option<Extent> {
        if rows.len() < 3 {
            return None;
        }
        let x = median(rows.iter().map(|r| r.item.x).collect());
        let y = median(rows.iter().map(|r| r.item.y).collect());
        let mut d: Vec<f64> = rows
            .iter()
            .map(|r| (r.item.x - x).hypot(r.item.y - y))
            .collect();
        d.sort_by(f64::total_cmp);
        let r95_m = d[((d.len() - 1) as f64 * 0.95) as usize];
        Some(Extent { x, y, r95_m })
    }
    fn limit_m(&self) -> f64 {
        EXTENT_FACTOR * self.r95_m + EXTENT_MARGIN_M
    }
    fn distance_m(&self, x: f64, y: f64) -> f64 {
        (x - self.x).hypot(y - self.y)
    }

    /// `rows` without those farther than [`Extent::limit_m`] from the middle (`xy` gives a row's position),
    /// each reported as lying outside the area `what` (e.g. "recordings") must lie in.
    fn keep_inside<T>(
        &self,
        rows: Vec<Sourced<T>>,
        xy: impl Fn(&T) -> (f64, f64),
        what: &str,
        problems: &mut Vec<Problem>,
    ) -> Vec<Sourced<T>> {
        rows.into_iter()
            .filter(|r| {
                let (x, y) = xy(&r.item);
                let d = self.distance_m(x, y);
                let inside = d <= self.limit_m();
                if !inside {
                    problems.push(far_away(&r.file, r.row, d, self, what));
                }
                inside
            })
            .collect()
    }
}

/// Recordings (sorted by time) without those far outside the campaign or jumping away from both neighbours.
pub(crate) fn check_trajectory(
    rows: Vec<Sourced<Recording>>,
    problems: &mut Vec<Problem>,
) -> Vec<Sourced<Recording>> {
    let rows = match Extent::of(&rows) {
        Some(e) => e.keep_inside(rows, |r| (r.x, r.y), "recordings", problems),
        None => rows,
    };
    let jumps: Vec<bool> = rows
        .windows(2)
        .map(|w| implausible(&w[0].item, &w[1].item))
        .collect();
    let mut keep = vec![true; rows.len()];
    for i in 1..rows.len().saturating_sub(1) {
        if jumps[i - 1] && jumps[i] && !implausible(&rows[i - 1].item, &rows[i + 1].item) {
            keep[i] = false;
            problems.push(outlier(&rows, i));
        }
    }
    let kept: Vec<Sourced<Recording>> = rows
        .into_iter()
        .zip(keep)
        .filter(|(_, k)| *k)
        .map(|(r, _)| r)
        .collect();
    for i in 1..kept.len() {
        if implausible(&kept[i - 1].item, &kept[i].item) {
            problems.push(lone_jump(&kept, i));
        }
    }
    kept
}

/// Whether going from `a` to `b` needs more than [`MAX_SPEED_M_S`] (plus the margin).
fn implausible(a: &Recording, b: &Recording) -> bool {
    let d = (b.x - a.x).hypot(b.y - a.y);
    d > MAX_SPEED_M_S * (b.time_s - a.time_s).abs() + JUMP_MARGIN_M
}

fn step(rows: &[Sourced<Recording>], i: usize, j: usize) -> String {
    let (a, b) = (&rows[i].item, &rows[j].item);
    format!(
        "{:.0} m in {:.3} s from row {}",
        (b.x - a.x).hypot(b.y - a.y),
        (b.time_s - a.time_s).abs(),
        rows[i].row
    )
}

/// An implausible position (field `x`) on `row` of `file`.
fn implausible_position(
    file: &Path,
    row: usize,
    message: String,
    hint: impl Into<String>,
) -> Problem {
    Problem::error(file, Some(row), Some("x"), message, hint).with_kind(ProblemKind::Implausible)
}

fn outlier(rows: &[Sourced<Recording>], i: usize) -> Problem {
    let r = &rows[i];
    implausible_position(
        &r.file,
        r.row,
        format!(
            "position jumps away from both neighbours ({}, {}; a vehicle drives < {MAX_SPEED_M_S} m/s) while they agree with each other",
            step(rows, i - 1, i),
            step(rows, i + 1, i)
        ),
        "check x, y (and time) of this row: a typo, a position in another CRS or a failed GNSS fix",
    )
}

fn lone_jump(rows: &[Sourced<Recording>], i: usize) -> Problem {
    let r = &rows[i];
    let message = format!(
        "position jumps {} (faster than {MAX_SPEED_M_S} m/s)",
        step(rows, i - 1, i)
    );
    let hint = "fine between two separate drives; otherwise check x, y and time of this row and the one before";
    Problem {
        severity: Severity::Warning,
        ..implausible_position(&r.file, r.row, message, hint)
    }
}

fn far_away(file: &Path, row: usize, d: f64, e: &Extent, what: &str) -> Problem {
    implausible_position(
        file,
        row,
        format!(
            "lies {d:.0} m from the middle of the campaign, while 95 % of the recordings lie within {:.0} m of it",
            e.r95_m
        ),
        format!("check x and y of this row (a typo or another CRS?); {what} must lie in the campaign's area"),
    )
}

/// Check points without those far outside the area of the recordings.
pub(crate) fn check_checkpoints(
    recordings: &[Sourced<Recording>],
    points: Vec<Sourced<CheckPoint>>,
    problems: &mut Vec<Problem>,
) -> Vec<Sourced<CheckPoint>> {
    let Some(e) = Extent::of(recordings) else {
        return points;
    };
    e.keep_inside(points, |p| (p.x, p.y), "check points", problems)
}

/// One image file referred to by a row: where the row is and the file's path on disk.
pub(crate) struct ImageUse {
    pub file: PathBuf,
    pub row: usize,
    pub path: PathBuf,
}

/// The (file, row) of every row whose image is also the image of another row, each reported with the first
/// row using it.
pub(crate) fn shared_images(
    uses: &[ImageUse],
    problems: &mut Vec<Problem>,
) -> Vec<(PathBuf, usize)> {
    let mut first: HashMap<PathBuf, usize> = HashMap::new();
    let mut shared = Vec::new();
    for (i, u) in uses.iter().enumerate() {
        let key = std::fs::canonicalize(&u.path).unwrap_or_else(|_| u.path.clone());
        match first.get(&key) {
            Some(&j) => {
                let f = &uses[j];
                let place = if f.file == u.file {
                    format!("row {}", f.row)
                } else {
                    format!("{}:{}", f.file.display(), f.row)
                };
                problems.push(
                    Problem::error(
                        &u.file,
                        Some(u.row),
                        Some("file"),
                        format!("the image is also used on {place}; both rows skipped"),
                        "give every row its own image file (two rows cannot both be right)",
                    )
                    .with_kind(ProblemKind::Duplicate),
                );
                shared.push((f.file.clone(), f.row));
                shared.push((u.file.clone(), u.row));
            }
            None => {
                first.insert(key, i);
            }
        }
    }
    shared
}
