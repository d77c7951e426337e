//! The answer of a run in a few lines, read off its `metrics.json`: how far off the recordings were, how far
//! the adjustment moved them and how well it determined them, how many could not be corrected and why, and the
//! verification of the trajectory per segment before and after. `skytie run` ends with it; the HTML report
//! opens with the same numbers.
//!
//! Sign convention everywhere: offsets and corrections are **MM − aerial** (the recorded or adjusted position
//! minus where the aerial images put it); a correction moves a recording by adjusted − recorded.

use serde_json::Value;
use std::fmt::Write as _;

/// How a run ended, for the exit status and the first line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// The trajectory was adjusted and (where check points exist) did not get worse.
    Corrected,
    /// Only verified (no adjustment in the workflow).
    VerifiedOnly,
    /// Registration only (neither adjustment nor verification in the workflow).
    RegisteredOnly,
    /// Adjusted, but no recording observes aerial control: nothing was corrected.
    NothingCorrected,
    /// Adjusted, but the check points are farther off than before.
    CheckpointsWorse,
}

impl Status {
    /// Whether the result needs the user's attention (the run then exits with [`PARTIAL_EXIT_CODE`]).
    pub fn is_warning(self) -> bool {
        matches!(self, Status::NothingCorrected | Status::CheckpointsWorse)
    }
}

/// Exit code of a run that finished but whose result must not be used as it is (nothing corrected, check
/// points worse, or items failed): documented in `skytie run --help` and docs/cli.md.
pub const PARTIAL_EXIT_CODE: i32 = 3;

/// The headline of one run (one variant of a sweep).
#[derive(Clone, Debug, PartialEq)]
pub struct Headline {
    pub status: Status,
    pub lines: Vec<String>,
}

fn num(m: &Value, path: &str) -> Option<f64> {
    path.split('.')
        .try_fold(m, |v, k| v.get(k))
        .and_then(Value::as_f64)
}

fn text<'a>(m: &'a Value, path: &str) -> Option<&'a str> {
    path.split('.')
        .try_fold(m, |v, k| v.get(k))
        .and_then(Value::as_str)
}

fn metres(v: f64) -> String {
    if v.abs() < 0.995 {
        format!("{:.0} cm", v * 100.0)
    } else {
        format!("{v:.2} m")
    }
}

/// The adjustment's metrics section (`adjust.<sources>`), if the run adjusted.
fn adjustment(m: &Value) -> Option<(&str, &Value)> {
    let section = m.get("adjust")?.as_object()?;
    section
        .iter()
        .find(|(_, v)| v.get("verdict").is_some())
        .map(|(k, v)| (k.as_str(), v))
}

/// One verification summary line: `label: N segments pass, M fail, K insufficient (tolerance …)`.
fn verification_line(m: &Value, key: &str, label: &str) -> Option<String> {
    let v = m.get(key)?;
    let segments = num(v, "segments")? as usize;
    let failed = num(v, "segments_failed").unwrap_or(0.0) as usize;
    let insufficient = num(v, "segments_insufficient").map(|n| n as usize);
    let overall = text(v, "overall.status").unwrap_or("");
    let offset = num(v, "overall.offset_2d_m");
    let mut line = format!("{label}: {segments} segment(s), {failed} fail");
    if let Some(n) = insufficient {
        let _ = write!(line, ", {n} without enough control");
    }
    match (overall, offset) {
        ("insufficient", _) => line.push_str("; too few aerial control points to tell"),
        (_, Some(o)) => {
            let _ = write!(line, "; mean horizontal offset {} ({overall})", metres(o));
        }
        _ => {}
    }
    Some(line)
}

/// Why recordings could not be tied to aerial control, from the registration chains' counts.
fn registration_lines(m: &Value) -> Vec<String> {
    let mut out = Vec::new();
    if m.get("nadir").is_some() {
        let recordings = num(m, "nadir.recordings").unwrap_or(0.0);
        let with_aerial = num(m, "nadir.recordings_with_aerial").unwrap_or(0.0);
        let control = num(m, "nadir.control_points").unwrap_or(0.0);
        let tried = num(m, "nadir.transforms_tried").unwrap_or(0.0);
        let accepted = num(m, "nadir.transforms_accepted").unwrap_or(0.0);
        out.push(format!(
            "nadir (road markings): {with_aerial:.0} of {recordings:.0} recordings registered to aerial images, \
             {control:.0} control points; {accepted:.0} of {tried:.0} initial transforms accepted"
        ));
    }
    if m.get("oblique").is_some() {
        let with = num(m, "oblique.recordings_with_correspondences").unwrap_or(0.0);
        let control = num(m, "oblique.control_points").unwrap_or(0.0);
        let planes = num(m, "oblique.planes").unwrap_or(0.0);
        out.push(format!(
            "oblique (façades): {with:.0} recordings with correspondences, {control:.0} control points, \
             {planes:.0} façade planes"
        ));
    }
    out
}

/// The headline of the run whose metrics are `m` (the content of `metrics.json` or of a variant's).
pub fn headline(m: &Value) -> Headline {
    let mut lines = Vec::new();
    let name = text(m, "campaign.name").unwrap_or("campaign");
    let recordings = num(m, "campaign.recordings").unwrap_or(0.0) as usize;
    let status = match adjustment(m) {
        Some((sources, a)) => {
            let verdict = text(a, "verdict").unwrap_or("");
            let count = num(a, "trajectory.count").unwrap_or(0.0) as usize;
            let with_control = num(a, "trajectory.with_control").unwrap_or(0.0) as usize;
            let status = match verdict {
                "nothing_corrected" => Status::NothingCorrected,
                "checkpoints_worse" => Status::CheckpointsWorse,
                _ => Status::Corrected,
            };
            lines.push(match status {
                Status::NothingCorrected => format!(
                    "NOT CORRECTED: {name}: none of the {recordings} recordings could be tied to aerial control; \
                     the trajectory was not adjusted (no trajectory_adjusted.csv)"
                ),
                Status::CheckpointsWorse => format!(
                    "NOT DELIVERED: {name}: the adjustment ({sources}) made the check points worse; \
                     no trajectory_adjusted.csv — see the report"
                ),
                _ => format!("{name}: {count} recordings adjusted ({sources})"),
            });
            if let (Some(before), Some(after), Some(n)) = (
                num(a, "checkpoints.before.2d"),
                num(a, "checkpoints.after.2d"),
                num(a, "checkpoints.after.count"),
            ) {
                if n > 0.0 {
                    lines.push(format!(
                        "check points ({n:.0}): {} before → {} after (RMSE 2D)",
                        metres(before),
                        metres(after)
                    ));
                }
            }
            if let (Some(median), Some(p95), Some(max)) = (
                num(a, "trajectory.moved_2d_m.median"),
                num(a, "trajectory.moved_2d_m.p95"),
                num(a, "trajectory.moved_2d_m.max"),
            ) {
                lines.push(format!(
                    "recordings moved by {} (median; 95 %: {}, max {}) horizontally",
                    metres(median),
                    metres(p95),
                    metres(max)
                ));
            }
            if let (Some(median), Some(max)) = (
                num(a, "trajectory.sigma_2d_m.median"),
                num(a, "trajectory.sigma_2d_m.max"),
            ) {
                lines.push(format!(
                    "σ after adjustment: {} (median), {} (max), horizontal",
                    metres(median),
                    metres(max)
                ));
            }
            if with_control < count {
                lines.push(format!(
                    "{with_control} of {count} recordings observe aerial control themselves; {} follow their \
                     neighbours through tie points and relative constraints",
                    count - with_control
                ));
            }
            if status == Status::NothingCorrected || with_control * 2 < count {
                lines.extend(registration_lines(m));
            }
            status
        }
        None if m.get("verify").is_some() => {
            lines.push(format!(
                "{name}: {recordings} recordings verified (not adjusted)"
            ));
            Status::VerifiedOnly
        }
        None => {
            lines.push(format!(
                "{name}: {recordings} recordings registered (no adjustment or verification)"
            ));
            lines.extend(registration_lines(m));
            Status::RegisteredOnly
        }
    };
    if let Some(l) = verification_line(m, "verify", "verification of the recorded trajectory") {
        lines.push(l);
    }
    if let Some(l) = verification_line(
        m,
        "verify_adjusted",
        "verification of the adjusted trajectory",
    ) {
        lines.push(l);
    }
    let errors = num(m, "campaign.input_errors").unwrap_or(0.0);
    if errors > 0.0 {
        lines.push(format!(
            "{errors:.0} input problem(s): the affected items were skipped (`skytie check` lists them)"
        ));
    }
    lines.push("(offsets and corrections: MM − aerial, metres on the ground)".to_string());
    Headline { status, lines }
}

impl Headline {
    /// The lines, indented under a title.
    pub fn render(&self) -> String {
        let mut out = String::new();
        for (i, l) in self.lines.iter().enumerate() {
            let _ = writeln!(out, "{}{l}", if i == 0 { "" } else { "  " });
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn a_corrected_run_states_before_after_movement_and_verification() {
        let m = json!({
            "campaign": {"name": "demo", "recordings": 39, "input_errors": 0},
            "adjust": {"combined": {
                "verdict": "corrected",
                "checkpoints": {"before": {"2d": 0.784, "count": 12}, "after": {"2d": 0.036, "count": 12}},
                "trajectory": {"count": 39, "with_control": 14,
                    "moved_2d_m": {"median": 0.79, "p95": 0.9, "max": 1.02},
                    "sigma_2d_m": {"median": 0.02, "max": 0.05}}
            }},
            "nadir": {"recordings": 39, "recordings_with_aerial": 14, "control_points": 40,
                      "transforms_tried": 60, "transforms_accepted": 45},
            "verify": {"segments": 2, "segments_failed": 2, "overall": {"status": "fail", "offset_2d_m": 0.8}},
            "verify_adjusted": {"segments": 2, "segments_failed": 0, "overall": {"status": "pass", "offset_2d_m": 0.01}}
        });
        let h = headline(&m);
        assert_eq!(h.status, Status::Corrected);
        let text = h.render();
        assert!(
            text.contains("check points (12): 78 cm before → 4 cm after"),
            "{text}"
        );
        assert!(
            text.contains("moved by 79 cm (median; 95 %: 90 cm, max 1.02 m)"),
            "{text}"
        );
        assert!(
            text.contains("14 of 39 recordings observe aerial control"),
            "{text}"
        );
        assert!(text.contains("nadir (road markings): 14 of 39"), "{text}");
        assert!(
            text.contains("adjusted trajectory: 2 segment(s), 0 fail"),
            "{text}"
        );
        assert!(text.contains("MM − aerial"), "{text}");
    }

    #[test]
    fn a_run_that_corrected_nothing_says_so_first() {
        let m = json!({
            "campaign": {"name": "tiny", "recordings": 6},
            "adjust": {"combined": {"verdict": "nothing_corrected",
                "trajectory": {"count": 6, "with_control": 0}}},
            "nadir": {"recordings": 6, "recordings_with_aerial": 0, "control_points": 0}
        });
        let h = headline(&m);
        assert_eq!(h.status, Status::NothingCorrected);
        assert!(h.status.is_warning());
        assert!(h.lines[0].starts_with("NOT CORRECTED"), "{:?}", h.lines);
        assert!(
            h.render().contains("0 of 6 recordings registered"),
            "{}",
            h.render()
        );
    }
}
