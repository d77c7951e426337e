//! The answer a surveyor reads in five seconds, computed from a run's output folder (or one variant's folder of
//! a sweep) alone, so the terminal summary of `skytie run` ([`Headline::from_dir`] then [`Headline::lines`]) and
//! the HTML report say the same: how far off the
//! recordings were, how far they moved and their σ after the adjustment, how many could not be corrected and
//! why, and the verification of the adjusted trajectory per segment — plus a status that says loudly when
//! nothing was corrected or the check points got worse.
//!
//! Sign convention everywhere: a correction is adjusted − recorded; a verification offset is MM − aerial (the
//! MM triangulation with the given poses minus the aerial triangulation of the same control point, i.e. how
//! far the trajectory is off); a check-point error is estimated − surveyed.
//!
//! Sources: `metrics.json` (`adjust.*`, `verify.*`), `corrections.csv` (rows of kind `recording`),
//! `verification.csv` and `verification_adjusted.csv`.

use super::inputs::{num_at, obj_at, read_csv_opt, read_csv_where, CsvTable};
use serde_json::Value;
use skytie_stages::correction::significance::COMPONENTS;
use skytie_stages::export::Support;
use std::path::Path;

/// Median, 95th percentile and maximum of a set of values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spread {
    pub median: f64,
    pub p95: f64,
    pub max: f64,
}

impl Spread {
    /// `None` for no values (non-finite ones are ignored).
    pub fn of(values: &[f64]) -> Option<Self> {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
        Some(Self {
            median: at(0.5),
            p95: at(0.95),
            max: v[v.len() - 1],
        })
    }
}

/// One verification segment (thesis Table 5-13) as the headline shows it.
#[derive(Clone, Debug, PartialEq)]
pub struct SegmentLine {
    pub label: String,
    pub first: String,
    pub last: String,
    pub points: usize,
    /// Mean horizontal offset MM − aerial, metres.
    pub offset_2d_m: Option<f64>,
    pub status: String,
}

/// Verification of one trajectory (recorded or adjusted poses).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VerificationSummary {
    pub segments: Vec<SegmentLine>,
    /// The `all` row.
    pub overall: Option<SegmentLine>,
}

impl VerificationSummary {
    fn from_csv(t: &CsvTable) -> Self {
        let mut out = Self::default();
        for r in &t.rows {
            let offset = match (t.num(r, "mean_x"), t.num(r, "mean_y")) {
                (Some(x), Some(y)) => Some(x.hypot(y)),
                _ => None,
            };
            let line = SegmentLine {
                label: t.text(r, "segment").to_string(),
                first: t.text(r, "first_image_id").to_string(),
                last: t.text(r, "last_image_id").to_string(),
                points: t.num(r, "points").unwrap_or(0.0) as usize,
                offset_2d_m: offset,
                status: t.text(r, "status").to_string(),
            };
            if line.label == "all" {
                out.overall = Some(line);
            } else {
                out.segments.push(line);
            }
        }
        out
    }

    /// Segments with this status.
    pub fn count(&self, status: &str) -> usize {
        self.segments.iter().filter(|s| s.status == status).count()
    }
}

/// The recordings' rows of `dir/corrections.csv` (`None` without the file), streamed past the series between
/// them.
pub fn corrections_of_recordings(dir: &Path) -> Result<Option<CsvTable>, String> {
    read_csv_where(&dir.join("corrections.csv"), "kind", "recording")
}

/// Whether the run's output can be used as an adjusted trajectory.
#[derive(Clone, Debug, PartialEq)]
pub enum Status {
    /// No adjustment ran (verification only, or registration only).
    NotAdjusted,
    /// The adjustment ran but no recording is tied to aerial control: the output is the recorded trajectory.
    NotCorrected(String),
    /// The check points got worse: do not use the output without looking.
    Worse(String),
    Corrected,
}

/// The headline numbers of one result folder.
#[derive(Clone, Debug, PartialEq)]
pub struct Headline {
    /// The adjustment configuration (`nadir`, `oblique`, `combined`), when one ran.
    pub configuration: Option<String>,
    pub recordings: usize,
    /// Mean horizontal offset MM − aerial of the recorded trajectory (verification, all segments), metres.
    pub offset_before_2d_m: Option<f64>,
    /// Check-point RMSE 2D before / after and the number of check points.
    pub checkpoints_2d_m: Option<(f64, f64, usize)>,
    /// Recordings vs the campaign's truth (synthetic campaigns): RMSE 2D before / after, metres.
    pub truth_2d_m: Option<(f64, f64)>,
    /// Horizontal length of the corrections, metres.
    pub moved_2d_m: Option<Spread>,
    /// Horizontal σ after the adjustment, √(σE² + σN²), metres.
    pub sigma_2d_m: Option<Spread>,
    /// Recordings per [`Support`] (controlled, bridged, extrapolated, uncorrected).
    pub support: [usize; 4],
    pub verification_before: Option<VerificationSummary>,
    pub verification_after: Option<VerificationSummary>,
    /// What the registration chains found (shown when recordings could not be corrected).
    pub registration: Vec<String>,
    /// The corrections held at the recorded values because they were not significant (`None` without the
    /// test).
    pub held: Option<HeldSummary>,
    pub status: Status,
}

/// The significance test of the corrections (`adjust.<sources>.significance` in `metrics.json`).
#[derive(Clone, Debug, PartialEq)]
pub struct HeldSummary {
    /// The test's significance level α.
    pub level: f64,
    /// Recordings whose horizontal / height / yaw corrections were held.
    pub recordings_held: [usize; 3],
    /// Held stretches per component.
    pub stretches: [usize; 3],
    /// Yaw was estimated, so tested.
    pub yaw_tested: bool,
    /// Recordings in the run.
    pub recordings: usize,
}

impl HeldSummary {
    fn from_metrics(a: &Value, recordings: usize) -> Option<Self> {
        let s = a.get("significance").filter(|v| !v.is_null())?;
        let mut stretches = [0; 3];
        for h in s.get("held")?.as_array()? {
            let component = h.get("component").and_then(Value::as_str);
            if let Some(k) = COMPONENTS.iter().position(|n| Some(*n) == component) {
                stretches[k] += 1;
            }
        }
        let held = |k: &str| num_at(s, &format!("held_recordings.{k}")).unwrap_or(0.0) as usize;
        Some(Self {
            level: num_at(s, "level")?,
            recordings_held: COMPONENTS.map(held),
            stretches,
            yaw_tested: s.get("yaw_tested").and_then(Value::as_bool) == Some(true),
            recordings,
        })
    }

    /// Nothing was applied anywhere: the output is the recorded trajectory.
    pub fn everything_held(&self) -> bool {
        let all = |k: usize| self.recordings_held[k] == self.recordings;
        self.recordings > 0 && all(0) && all(1) && (!self.yaw_tested || all(2))
    }

    /// The headline's sentence, `None` when every correction was applied.
    fn line(&self) -> Option<String> {
        let names = ["horizontal position", "height", "yaw"];
        let parts: Vec<String> = (0..3)
            .filter(|&k| self.recordings_held[k] > 0)
            .map(|k| {
                let n = self.stretches[k];
                format!(
                    "{} of {} of {} recordings ({n} {})",
                    names[k],
                    self.recordings_held[k],
                    self.recordings,
                    if n == 1 { "stretch" } else { "stretches" }
                )
            })
            .collect();
        (!parts.is_empty()).then(|| {
            format!(
                "Kept at the recorded values (corrections not significant at α = {}): {}; `held` in \
                 trajectory_adjusted.csv, σ widened by the correction not applied.",
                self.level,
                parts.join(", ")
            )
        })
    }
}

fn support_index(s: Support) -> usize {
    match s {
        Support::Controlled => 0,
        Support::Bridged => 1,
        Support::Extrapolated => 2,
        Support::Uncorrected => 3,
    }
}

/// What the nadir and oblique chains registered, from their metrics (one line each).
fn registration_lines(m: &Value) -> Vec<String> {
    let n = |k: &str| num_at(m, k).unwrap_or(0.0);
    let mut out = Vec::new();
    if obj_at(m, "nadir").is_some() {
        out.push(format!(
            "nadir (road markings): {:.0} of {:.0} recordings registered to aerial images, {:.0} control \
             points; {:.0} of {:.0} initial transforms accepted",
            n("nadir.recordings_with_aerial"),
            n("nadir.recordings"),
            n("nadir.control_points"),
            n("nadir.transforms_accepted"),
            n("nadir.transforms_tried")
        ));
    }
    // What the adjustment used: the oblique chain's second pass when it ran one.
    let oblique = ["oblique_pass2", "oblique"]
        .into_iter()
        .find(|k| obj_at(m, k).is_some());
    if let Some(ns) = oblique {
        out.push(format!(
            "oblique (façades): {:.0} recordings with correspondences, {:.0} control points, {:.0} façade \
             planes{}",
            n(&format!("{ns}.recordings_with_correspondences")),
            n(&format!("{ns}.control_points")),
            n(&format!("{ns}.planes")),
            if ns == "oblique" {
                ""
            } else {
                " (second pass, around the first adjustment)"
            }
        ));
    }
    out
}

/// The first adjustment configuration in `metrics.json` (a plain run has one).
fn adjustment(m: &Value) -> Option<(String, &Value)> {
    obj_at(m, "adjust").and_then(|a| a.iter().next().map(|(k, v)| (k.clone(), v)))
}

impl Headline {
    /// Reads the headline of the result folder `dir` (`OUT`, or `OUT/variants/<name>` of a sweep). Err when
    /// `metrics.json` or one of the CSV files is unreadable (the message names the file).
    pub fn from_dir(dir: &Path) -> Result<Self, String> {
        // Only the recordings' rows: the series between them is most of a long campaign's file.
        let corrections = corrections_of_recordings(dir)?;
        Self::from_dir_with(dir, corrections.as_ref())
    }

    /// [`Self::from_dir`] with the recordings' rows of `corrections.csv` already read
    /// ([`corrections_of_recordings`]).
    pub fn from_dir_with(dir: &Path, corrections: Option<&CsvTable>) -> Result<Self, String> {
        let path = dir.join("metrics.json");
        let bytes =
            std::fs::read(&path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
        let m: Value = serde_json::from_slice(&bytes)
            .map_err(|e| format!("{}: not valid JSON ({e})", path.display()))?;
        let before = read_csv_opt(&dir.join("verification.csv"))?;
        let after = read_csv_opt(&dir.join("verification_adjusted.csv"))?;
        Ok(Self::from_parts(
            &m,
            corrections,
            before.as_ref(),
            after.as_ref(),
        ))
    }

    /// The headline from already read files (tests, the report).
    pub fn from_parts(
        m: &Value,
        corrections: Option<&CsvTable>,
        verification: Option<&CsvTable>,
        verification_adjusted: Option<&CsvTable>,
    ) -> Self {
        let adj = adjustment(m);
        let pair = |a: &Value, key: &str| {
            Some((
                num_at(a, &format!("{key}.before.2d"))?,
                num_at(a, &format!("{key}.after.2d"))?,
            ))
        };
        let checkpoints = adj.as_ref().and_then(|(_, a)| {
            let (b, f) = pair(a, "checkpoints")?;
            Some((
                b,
                f,
                num_at(a, "checkpoints.after.count").unwrap_or(0.0) as usize,
            ))
        });
        let truth = adj.as_ref().and_then(|(_, a)| {
            Some((
                num_at(a, "recordings.before.rmse_2d")?,
                num_at(a, "recordings.after.rmse_2d")?,
            ))
        });
        let (mut moved, mut sigma, mut support) = (Vec::new(), Vec::new(), [0usize; 4]);
        if let Some(t) = corrections {
            for r in t.rows.iter().filter(|r| t.text(r, "kind") == "recording") {
                let n = |k: &str| t.num(r, k).unwrap_or(f64::NAN);
                moved.push(n("de_m").hypot(n("dn_m")));
                sigma.push(n("sigma_e_m").hypot(n("sigma_n_m")));
                if let Some(s) = Support::from_label(t.text(r, "support")) {
                    support[support_index(s)] += 1;
                }
            }
        }
        let verification_before = verification.map(VerificationSummary::from_csv);
        let offset_before = verification_before
            .as_ref()
            .and_then(|v| v.overall.as_ref())
            .and_then(|o| o.offset_2d_m)
            .or_else(|| {
                let x = num_at(m, "verify.overall.mean_m.0")?;
                Some(x.hypot(num_at(m, "verify.overall.mean_m.1")?))
            });
        let verdict = adj
            .as_ref()
            .and_then(|(_, a)| a.get("verdict"))
            .and_then(Value::as_str);
        let status = if adj.is_none() {
            Status::NotAdjusted
        } else if verdict == Some("nothing_corrected") || (verdict.is_none() && support[0] == 0) {
            Status::NotCorrected(
                "no recording observes an aerial control point, so nothing was corrected: the output \
                 trajectory is the recorded one"
                    .to_string(),
            )
        } else if let Some((b, a, _)) = checkpoints.filter(|(b, a, _)| {
            verdict == Some("checkpoints_worse") || (verdict.is_none() && a > b)
        }) {
            Status::Worse(format!(
                "the check points got worse ({b:.3} m → {a:.3} m RMSE 2D): check the registration before \
                 using the adjusted trajectory"
            ))
        } else {
            Status::Corrected
        };
        let recordings = num_at(m, "campaign.recordings").map_or(moved.len(), |v| v as usize);
        let held = adj
            .as_ref()
            .and_then(|(_, a)| HeldSummary::from_metrics(a, recordings));
        Self {
            configuration: adj.map(|(k, _)| k),
            recordings,
            offset_before_2d_m: offset_before,
            checkpoints_2d_m: checkpoints,
            truth_2d_m: truth,
            moved_2d_m: Spread::of(&moved),
            sigma_2d_m: Spread::of(&sigma),
            support,
            verification_before,
            verification_after: verification_adjusted.map(VerificationSummary::from_csv),
            registration: registration_lines(m),
            held,
            status,
        }
    }

    /// Recordings that were not corrected.
    pub fn uncorrected(&self) -> usize {
        self.support[3]
    }

    /// A delivered correction of which no segment passes the verification of the adjusted trajectory (a street
    /// with little aerial evidence, or evidence that disagrees with itself).
    pub fn unverified(&self) -> bool {
        self.verification_after
            .as_ref()
            .is_some_and(|v| !v.segments.is_empty() && v.count("pass") == 0)
    }

    /// The headline as short lines of plain text (terminal summary; the report shows the same numbers).
    pub fn lines(&self) -> Vec<String> {
        let mut out = Vec::new();
        out.push(match &self.status {
            Status::Corrected if self.held.as_ref().is_some_and(HeldSummary::everything_held) => {
                "RESULT: recorded trajectory kept: no correction is significant (the aerial evidence \
                 does not show the recorded positions off; see the σ after)"
                    .to_string()
            }
            Status::Corrected if self.unverified() => {
                "RESULT: trajectory corrected, but not verified: no segment of the adjusted trajectory passes \
                 the verification (its aerial control is too sparse or disagrees; see the σ after and the \
                 segments below)"
                    .to_string()
            }
            Status::Corrected => "RESULT: trajectory corrected".to_string(),
            Status::NotAdjusted => "RESULT: not adjusted (verification only)".to_string(),
            Status::NotCorrected(why) => format!("WARNING: NOT CORRECTED: {why}"),
            Status::Worse(why) => format!("WARNING: CHECK POINTS WORSE: {why}"),
        });
        let mut off = Vec::new();
        if let Some(o) = self.offset_before_2d_m {
            off.push(format!(
                "mean horizontal offset {o:.3} m (MM − aerial control, recorded poses)"
            ));
        }
        if let Some((b, _, n)) = self.checkpoints_2d_m {
            off.push(format!("check points {b:.3} m RMSE 2D ({n} points)"));
        }
        if let Some((b, _)) = self.truth_2d_m {
            off.push(format!("vs truth {b:.3} m RMSE 2D"));
        }
        if !off.is_empty() {
            out.push(format!("Recordings were off: {}.", off.join("; ")));
        }
        if let (Some(m), Some(s)) = (self.moved_2d_m, self.sigma_2d_m) {
            out.push(format!(
                "They moved {:.3} m (median; 95 %: {:.3} m, max {:.3} m); horizontal σ after: {:.3} m (median; \
                 max {:.3} m).",
                m.median, m.p95, m.max, s.median, s.max
            ));
        }
        if self.moved_2d_m.is_some() {
            let [c, b, e, u] = self.support;
            out.push(format!(
                "{} of {} recordings corrected ({c} by their own aerial control, {b} bridged between \
                 controlled neighbours, {e} extrapolated beyond them); {u} not corrected{}.",
                c + b + e,
                c + b + e + u,
                if u > 0 {
                    ": no aerial control point is linked to their stretch of trajectory"
                } else {
                    ""
                }
            ));
        }
        if let Some(line) = self.held.as_ref().and_then(HeldSummary::line) {
            out.push(line);
        }
        if let Some((_, a, _)) = self.checkpoints_2d_m {
            out.push(format!("Check points after: {a:.3} m RMSE 2D."));
        }
        if self.support[0] * 2 < self.recordings {
            out.extend(
                self.registration
                    .iter()
                    .map(|l| format!("Registration: {l}.")),
            );
        }
        if let Some(v) = &self.verification_after {
            out.push(format!(
                "Verification of the adjusted trajectory: {} of {} segment(s) pass, {} fail, {} insufficient (too \
                 few points, a stretch without any, or a stated σ too large for the tolerance).",
                v.count("pass"),
                v.segments.len(),
                v.count("fail"),
                v.count("insufficient")
            ));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn corrections(rows: &[(&str, f64, f64, f64, &str)]) -> CsvTable {
        let owned: Vec<Vec<String>> = rows
            .iter()
            .map(|(kind, de, dn, s, support)| {
                [
                    kind.to_string(),
                    de.to_string(),
                    dn.to_string(),
                    s.to_string(),
                    s.to_string(),
                ]
                .into_iter()
                .chain([support.to_string()])
                .collect()
            })
            .collect();
        CsvTable {
            header: ["kind", "de_m", "dn_m", "sigma_e_m", "sigma_n_m", "support"]
                .map(String::from)
                .to_vec(),
            rows: owned,
        }
    }

    /// A `verification_adjusted.csv` with the given rows (segment, first, last, points, mean x, mean y, status).
    fn verification(rows: &[&[&str]]) -> CsvTable {
        CsvTable::from_cells(
            &[
                "segment",
                "first_image_id",
                "last_image_id",
                "points",
                "mean_x",
                "mean_y",
                "status",
            ],
            rows,
        )
    }

    fn metrics(before: f64, after: f64) -> Value {
        serde_json::json!({
            "campaign": {"recordings": 3},
            "adjust": {"combined": {"checkpoints": {
                "before": {"2d": before, "count": 4}, "after": {"2d": after, "count": 4}}}}
        })
    }

    #[test]
    fn numbers_from_known_files() {
        let c = corrections(&[
            ("recording", 0.6, 0.8, 0.03, "controlled"),
            ("interpolated", 9.0, 9.0, 9.0, "controlled"),
            ("recording", 0.3, 0.4, 0.04, "bridged"),
            ("recording", 0.0, 0.0, 2.0, "uncorrected"),
        ]);
        let v = verification(&[
            &["0", "a", "b", "5", "0.03", "0.04", "pass"],
            &["1", "c", "d", "1", "0.3", "0.4", "insufficient"],
            &["all", "a", "d", "6", "0.06", "0.08", "pass"],
        ]);
        let h = Headline::from_parts(&metrics(0.8, 0.05), Some(&c), None, Some(&v));
        assert_eq!(h.status, Status::Corrected);
        assert_eq!(h.support, [1, 1, 0, 1]);
        let m = h.moved_2d_m.unwrap();
        assert_eq!((m.median, m.max), (0.5, 1.0));
        let va = h.verification_after.as_ref().unwrap();
        assert_eq!((va.count("pass"), va.count("insufficient")), (1, 1));
        assert!((va.overall.as_ref().unwrap().offset_2d_m.unwrap() - 0.1).abs() < 1e-12);
        let text = h.lines().join("\n");
        assert!(text.contains("2 of 3 recordings corrected"), "{text}");
        assert!(text.contains("1 not corrected"), "{text}");
        assert!(text.contains("Check points after: 0.050 m"), "{text}");
        assert!(!h.unverified());
        assert_eq!(h.lines()[0], "RESULT: trajectory corrected");
    }

    /// `metrics` with a significance test that held `held` (horizontal, height) of the 3 recordings.
    fn metrics_with_held(held: [usize; 2]) -> Value {
        let mut m = metrics(0.05, 0.05);
        let stretch = |component: &str, n: usize| {
            serde_json::json!({"component": component, "first_image_id": "a", "last_image_id": "c",
                "recordings": n, "largest": 1.5})
        };
        let mut stretches = Vec::new();
        for (name, n) in [("horizontal", held[0]), ("height", held[1])] {
            if n > 0 {
                stretches.push(stretch(name, n));
            }
        }
        m["adjust"]["combined"]["significance"] = serde_json::json!({
            "level": 0.05, "window_m": 100.0, "yaw_tested": false,
            "held_recordings": {"horizontal": held[0], "height": held[1], "yaw": 0},
            "held": stretches,
        });
        m
    }

    #[test]
    fn corrections_kept_for_want_of_significance_are_named() {
        let c = corrections(&[
            ("recording", 0.0, 0.0, 0.03, "controlled"),
            ("recording", 0.0, 0.0, 0.03, "controlled"),
            ("recording", 0.0, 0.0, 0.03, "controlled"),
        ]);
        let all = Headline::from_parts(&metrics_with_held([3, 3]), Some(&c), None, None);
        assert!(all.held.as_ref().unwrap().everything_held());
        let lines = all.lines();
        assert!(
            lines[0].starts_with("RESULT: recorded trajectory kept"),
            "{lines:?}"
        );
        let text = lines.join("\n");
        assert!(
            text.contains(
                "(corrections not significant at α = 0.05): horizontal position of 3 of 3 recordings (1 \
                 stretch), height of 3 of 3 recordings (1 stretch);"
            ),
            "{text}"
        );

        let part = Headline::from_parts(&metrics_with_held([0, 3]), Some(&c), None, None);
        let lines = part.lines();
        assert_eq!(lines[0], "RESULT: trajectory corrected");
        assert!(
            lines
                .iter()
                .any(|l| l.contains("height of 3 of 3 recordings")),
            "{lines:?}"
        );
        assert!(
            !lines.iter().any(|l| l.contains("horizontal position of")),
            "{lines:?}"
        );

        let none = Headline::from_parts(&metrics(0.8, 0.05), Some(&c), None, None);
        assert_eq!(none.held, None);
        assert!(!none.lines().iter().any(|l| l.starts_with("Kept at")));
    }

    #[test]
    fn a_correction_without_a_verified_segment_says_so() {
        let c = corrections(&[
            ("recording", 0.3, 0.0, 0.4, "controlled"),
            ("recording", 0.2, 0.0, 0.4, "bridged"),
        ]);
        let v = verification(&[
            &["0", "a", "b", "1", "0.3", "0.4", "insufficient"],
            &["1", "c", "d", "0", "", "", "insufficient"],
            &["all", "a", "d", "1", "0.3", "0.4", "insufficient"],
        ]);
        let h = Headline::from_parts(&metrics(0.84, 0.77), Some(&c), None, Some(&v));
        assert_eq!(h.status, Status::Corrected);
        assert!(h.unverified());
        assert!(
            h.lines()[0].starts_with("RESULT: trajectory corrected, but not verified"),
            "{:?}",
            h.lines()
        );
    }

    #[test]
    fn loud_when_nothing_was_corrected_or_check_points_got_worse() {
        let none = corrections(&[("recording", 0.0, 0.0, 2.0, "uncorrected")]);
        let h = Headline::from_parts(&metrics(0.7, 0.7), Some(&none), None, None);
        assert!(matches!(h.status, Status::NotCorrected(_)));
        assert!(h.lines()[0].starts_with("WARNING: NOT CORRECTED"));
        let some = corrections(&[("recording", 0.5, 0.0, 0.1, "controlled")]);
        let h = Headline::from_parts(&metrics(0.704, 0.737), Some(&some), None, None);
        assert!(matches!(h.status, Status::Worse(_)), "{:?}", h.status);
        let h = Headline::from_parts(&serde_json::json!({}), None, None, None);
        assert_eq!(h.status, Status::NotAdjusted);
    }
}
