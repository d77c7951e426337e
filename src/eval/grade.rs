//! The numbers of one evaluation cell, read from its run's output folder and the campaign's `truth/`: nadir
//! and oblique inlier ratios, recordings and check points before/after the adjustment (RMSE 2D/3D, largest 2D
//! error), how many recordings lie beyond the 95 % ellipse of their stated σ, the largest error of the
//! recordings the output declares controlled by aerial evidence, and the verification's flags compared with the
//! true offset of each segment.

use crate::report::inputs::{num_at, read_csv_opt, RunOutputs};
use serde_json::Value;
use skytie_stages::campaign::{read_recordings_csv, Recording};
use skytie_stages::estimators::normal_quantile::chi2_2_quantile;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// Which way a metric gets better.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Better {
    Higher,
    Lower,
    /// Not judged (a property of the input, e.g. the error before adjustment).
    Shown,
}

/// One reported number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetricDef {
    pub key: &'static str,
    /// Column title in the table.
    pub title: &'static str,
    pub better: Better,
    /// Smallest change that counts as a regression (the noise band is at least this), in the metric's unit.
    pub floor: f64,
}

/// A segment counts as off when its recorded positions are off by more than this on average, m.
pub const SEGMENT_OFF_M: f64 = 0.3;
/// A flagged segment none of whose recordings is off by this much is a false alarm, m. (The largest offset, not
/// the mean: the verification fails a segment on a few points off beyond its tolerance, the recordings near
/// them being off whatever the segment's mean says, and a drift that starts inside a segment is such a case.)
pub const SEGMENT_GOOD_M: f64 = 0.2;

/// Every metric, in table order.
pub const METRICS: [MetricDef; 20] = [
    MetricDef {
        key: "nadir_inlier",
        title: "nadir inlier",
        better: Better::Higher,
        floor: 0.005,
    },
    MetricDef {
        key: "nadir_registered",
        title: "rec. w/ aerial",
        better: Better::Higher,
        floor: 0.03,
    },
    MetricDef {
        key: "oblique_inlier",
        title: "obl. inlier",
        better: Better::Higher,
        floor: 0.01,
    },
    MetricDef {
        key: "oblique_inlier_nm",
        title: "obl. inl. +nm",
        better: Better::Higher,
        floor: 0.01,
    },
    MetricDef {
        key: "corrected",
        title: "corrected",
        better: Better::Higher,
        floor: 0.001,
    },
    MetricDef {
        key: "rec_2d_before",
        title: "rec 2D before",
        better: Better::Shown,
        floor: 0.0,
    },
    MetricDef {
        key: "rec_2d_after",
        title: "rec 2D after",
        better: Better::Lower,
        floor: 0.005,
    },
    MetricDef {
        key: "rec_3d_after",
        title: "rec 3D after",
        better: Better::Lower,
        floor: 0.01,
    },
    MetricDef {
        key: "rec_max_2d_after",
        title: "rec max 2D",
        better: Better::Lower,
        floor: 0.01,
    },
    MetricDef {
        key: "rec_max_2d_controlled",
        title: "rec max 2D ctrl",
        better: Better::Lower,
        floor: 0.01,
    },
    MetricDef {
        key: "rec_beyond_sigma95",
        title: "rec > σ 95 %",
        better: Better::Lower,
        floor: 0.03,
    },
    MetricDef {
        key: "cp_2d_before",
        title: "cp 2D before",
        better: Better::Shown,
        floor: 0.0,
    },
    MetricDef {
        key: "cp_2d_after",
        title: "cp 2D after",
        better: Better::Lower,
        floor: 0.005,
    },
    MetricDef {
        key: "cp_3d_after",
        title: "cp 3D after",
        better: Better::Lower,
        floor: 0.01,
    },
    MetricDef {
        key: "cp_max_2d_after",
        title: "cp max 2D",
        better: Better::Lower,
        floor: 0.01,
    },
    MetricDef {
        key: "cp_bias_2d_after",
        title: "cp bias 2D",
        better: Better::Lower,
        floor: 0.005,
    },
    MetricDef {
        key: "segments_off",
        title: "seg. off",
        better: Better::Shown,
        floor: 0.0,
    },
    MetricDef {
        key: "verify_detected",
        title: "off flagged",
        better: Better::Higher,
        floor: 0.001,
    },
    MetricDef {
        key: "verify_off_passed",
        title: "off passed",
        better: Better::Lower,
        floor: 0.001,
    },
    MetricDef {
        key: "verify_false",
        title: "false flags",
        better: Better::Lower,
        floor: 0.0,
    },
];

/// The numbers of one cell (a metric is absent when the run did not produce it).
pub type CellMetrics = BTreeMap<String, f64>;

/// The one adjustment configuration's section of the metrics (`adjust.<sources>`).
fn adjust_section(m: &Value) -> Option<&Value> {
    let obj = m.get("adjust")?.as_object()?;
    obj.get("combined").or_else(|| obj.values().next())
}

/// The ellipse probability: a recording whose squared 2-D error normalised by its stated σ (per axis) exceeds
/// the χ²(2) quantile of this lies outside the 95 % ellipse of its stated precision.
const ELLIPSE_P: f64 = 0.95;

/// The true recordings by `image_id`.
type TrueOf<'a> = HashMap<&'a str, &'a Recording>;

/// [`TrueOf`] of `truth/recordings.csv`'s rows, read once per cell.
fn true_of(truth: &[Recording]) -> TrueOf<'_> {
    truth.iter().map(|r| (r.image_id.as_str(), r)).collect()
}

/// What the truth says of the delivered recordings (`trajectory_adjusted.csv`).
#[derive(Debug, PartialEq)]
struct DeliveredRecordings {
    /// The share whose horizontal error lies outside the 95 % ellipse of their stated σ (`sigma_x`, `sigma_y`):
    /// about 0.05 when the stated precision is honest, more when it is optimistic. A recording without a
    /// truth row or a positive finite σ is not counted.
    beyond_sigma95: Option<f64>,
    /// The largest horizontal error, m, of the recordings whose `correction` is `controlled` — those the output
    /// says aerial evidence corrected, as opposed to `bridged` or `extrapolated` ones it only carried along
    /// (None when there is no such recording).
    controlled_max_2d_m: Option<f64>,
}

/// [`DeliveredRecordings`] of the run in `out` (None when the adjustment was withheld and the file is absent).
fn delivered_recordings(
    out: &Path,
    true_of: &TrueOf,
) -> Result<Option<DeliveredRecordings>, String> {
    let Some(t) = read_csv_opt(&out.join("trajectory_adjusted.csv"))? else {
        return Ok(None);
    };
    let limit = chi2_2_quantile(ELLIPSE_P).unwrap_or(f64::INFINITY);
    let (mut beyond, mut counted) = (0usize, 0usize);
    let mut controlled_max: Option<f64> = None;
    for row in &t.rows {
        let Some(truth) = true_of.get(t.text(row, "image_id")) else {
            continue;
        };
        let (Some(x), Some(y)) = (t.num(row, "x"), t.num(row, "y")) else {
            continue;
        };
        let (ex, ey) = (x - truth.x, y - truth.y);
        if t.text(row, "correction") == "controlled" {
            controlled_max = Some(controlled_max.unwrap_or(0.0).max(ex.hypot(ey)));
        }
        let (Some(sx), Some(sy)) = (t.num(row, "sigma_x"), t.num(row, "sigma_y")) else {
            continue;
        };
        if !(sx > 0.0 && sy > 0.0 && sx.is_finite() && sy.is_finite()) {
            continue;
        }
        let q = (ex / sx).powi(2) + (ey / sy).powi(2);
        counted += 1;
        beyond += usize::from(q > limit);
    }
    Ok(Some(DeliveredRecordings {
        beyond_sigma95: (counted > 0).then(|| beyond as f64 / counted as f64),
        controlled_max_2d_m: controlled_max,
    }))
}

/// The check points after adjustment (`checkpoints.csv`): the largest 2-D error, and the length of the mean
/// horizontal error vector — a systematic offset the RMSE mixes with the noise (both m).
fn checkpoints_after(out: &Path) -> Result<Option<(f64, f64)>, String> {
    let Some(t) = read_csv_opt(&out.join("checkpoints.csv"))? else {
        return Ok(None);
    };
    let (mut max, mut sum, mut n) = (0.0f64, [0.0f64; 2], 0usize);
    for r in &t.rows {
        let (Some(d), Some(x), Some(y)) = (
            t.num(r, "after_2d"),
            t.num(r, "after_x"),
            t.num(r, "after_y"),
        ) else {
            continue;
        };
        max = max.max(d);
        sum[0] += x;
        sum[1] += y;
        n += 1;
    }
    Ok((n > 0).then(|| (max, sum[0].hypot(sum[1]) / n as f64)))
}

/// What the truth says of one verification segment.
struct SegmentTruth {
    /// Horizontal length of the mean offset of its recorded positions, m.
    mean_off_m: f64,
    /// Its worst recording's horizontal offset, m.
    max_off_m: f64,
    /// The verification's status: `pass`, `fail` or `insufficient`.
    status: String,
}

impl SegmentTruth {
    /// Flagged `fail` although none of its recordings is off by [`SEGMENT_GOOD_M`].
    fn false_flag(&self) -> bool {
        self.status == "fail" && self.max_off_m < SEGMENT_GOOD_M
    }
}

/// Per verification segment, its recorded positions' (`campaign`'s) true offsets against `truth` and the
/// verification's status.
fn segment_truth(
    out: &Path,
    campaign: &Path,
    true_of: &TrueOf,
) -> Result<Vec<SegmentTruth>, String> {
    let Some(v) = read_csv_opt(&out.join("verification.csv"))? else {
        return Ok(Vec::new());
    };
    let mut recorded = read_recordings_csv(&campaign.join("mm/recordings.csv")).0;
    recorded.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    let position_of: HashMap<&str, usize> = recorded
        .iter()
        .enumerate()
        .rev()
        .map(|(i, r)| (r.image_id.as_str(), i))
        .collect();
    let pos = |id: &str| position_of.get(id).copied();
    let mut out_rows = Vec::new();
    for row in &v.rows {
        if v.text(row, "segment") == "all" {
            continue;
        }
        let (Some(a), Some(b)) = (
            pos(v.text(row, "first_image_id")),
            pos(v.text(row, "last_image_id")),
        ) else {
            continue;
        };
        let (mut dx, mut dy, mut n, mut max) = (0.0, 0.0, 0.0, 0.0f64);
        for r in &recorded[a.min(b)..=a.max(b)] {
            if let Some(t) = true_of.get(r.image_id.as_str()) {
                dx += r.x - t.x;
                dy += r.y - t.y;
                max = max.max((r.x - t.x).hypot(r.y - t.y));
                n += 1.0;
            }
        }
        if n > 0.0 {
            out_rows.push(SegmentTruth {
                mean_off_m: (dx / n).hypot(dy / n),
                max_off_m: max,
                status: v.text(row, "status").to_string(),
            });
        }
    }
    Ok(out_rows)
}

/// The numbers of the run in `out` (the campaign folder is taken from its provenance).
pub fn grade_cell(out: &Path) -> Result<CellMetrics, String> {
    let run = RunOutputs::read(out)?;
    let m = &run.metrics;
    let mut c = CellMetrics::new();
    let mut put = |k: &str, v: Option<f64>| {
        if let Some(v) = v.filter(|v| v.is_finite()) {
            c.insert(k.to_string(), v);
        }
    };
    // A ratio of nothing is no ratio: only with graded correspondences.
    let graded = |k: &str| num_at(m, k).is_some_and(|n| n > 0.0);
    put(
        "nadir_inlier",
        num_at(m, "nadir.inlier_ratio").filter(|_| graded("nadir.graded_tie_points")),
    );
    put(
        "nadir_registered",
        num_at(m, "nadir.recordings_with_aerial_fraction"),
    );
    // The oblique correspondences the adjustment and the exports use: the second pass's when the workflow runs
    // two (`[adjust] passes = 2`), else the first's.
    let ob = if m.get("oblique_pass2").is_some() {
        "oblique_pass2"
    } else {
        "oblique"
    };
    let at = |k: &str| num_at(m, &format!("{ob}.{k}"));
    let oblique = [
        at("inliers_after_consensus"),
        at("outliers_after_consensus"),
    ]
    .iter()
    .any(|n| n.is_some_and(|n| n > 0.0));
    put(
        "oblique_inlier",
        at("inlier_ratio_after_consensus").filter(|_| oblique),
    );
    put(
        "oblique_inlier_nm",
        at("inlier_ratio_after_consensus_incl_non_matchable").filter(|_| oblique),
    );
    if let Some(a) = adjust_section(m) {
        // 1 when the run delivered the adjusted trajectory (verdict `corrected`), 0 when it withheld it.
        let verdict = a.get("verdict").and_then(Value::as_str);
        put(
            "corrected",
            verdict.map(|v| f64::from(u8::from(v == "corrected"))),
        );
        put("rec_2d_before", num_at(a, "recordings.before.rmse_2d"));
        put("rec_2d_after", num_at(a, "recordings.after.rmse_2d"));
        put("rec_3d_after", num_at(a, "recordings.after.rmse_3d"));
        put("rec_max_2d_after", num_at(a, "recordings.after.max_2d"));
        put("cp_2d_before", num_at(a, "checkpoints.before.2d"));
        put("cp_2d_after", num_at(a, "checkpoints.after.2d"));
        put("cp_3d_after", num_at(a, "checkpoints.after.3d"));
    }
    let checkpoints = checkpoints_after(out)?;
    put("cp_max_2d_after", checkpoints.map(|c| c.0));
    put("cp_bias_2d_after", checkpoints.map(|c| c.1));
    let campaign = run.campaign_dir().ok_or_else(|| {
        format!(
            "{}: provenance.json names no campaign folder",
            out.display()
        )
    })?;
    if !campaign.is_dir() {
        return Err(format!(
            "{}: the campaign folder {} named by provenance.json is gone (its cache was moved or cleaned); \
             run the cell again",
            out.display(),
            campaign.display()
        ));
    }
    if campaign.join("truth/recordings.csv").is_file() {
        let truth = read_recordings_csv(&campaign.join("truth/recordings.csv")).0;
        let truth_by_id = true_of(&truth);
        let delivered = delivered_recordings(out, &truth_by_id)?;
        put(
            "rec_beyond_sigma95",
            delivered.as_ref().and_then(|d| d.beyond_sigma95),
        );
        put(
            "rec_max_2d_controlled",
            delivered.as_ref().and_then(|d| d.controlled_max_2d_m),
        );
        let segments = segment_truth(out, &campaign, &truth_by_id)?;
        let off: Vec<&str> = segments
            .iter()
            .filter(|s| s.mean_off_m > SEGMENT_OFF_M)
            .map(|s| s.status.as_str())
            .collect();
        put("segments_off", Some(off.len() as f64));
        if !off.is_empty() {
            let share = |status: &str| {
                off.iter().filter(|s| **s == status).count() as f64 / off.len() as f64
            };
            put("verify_detected", Some(share("fail")));
            put("verify_off_passed", Some(share("pass")));
        }
        if !segments.is_empty() {
            let false_flags = segments.iter().filter(|s| s.false_flag()).count();
            put("verify_false", Some(false_flags as f64));
        }
    }
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn truth(id: &str, x: f64, y: f64) -> Recording {
        Recording {
            image_id: id.into(),
            x,
            y,
            ..Recording::default()
        }
    }

    #[test]
    fn recordings_outside_their_stated_95_percent_ellipse_are_counted() {
        let d = tempfile::tempdir().unwrap();
        // a: 0.05 m off with σ 0.02 per axis (q = 6.25 > 5.99, outside); b: 0.04 m off with σ 0.02 (q = 4,
        // inside); c: 0.30 m off along x with σx 0.20 (inside); d: no truth row; e: no σ (both not counted).
        // Controlled: a and b (largest error 0.05 m); c, bridged, is not one of them.
        std::fs::write(
            d.path().join("trajectory_adjusted.csv"),
            "image_id,x,y,z,sigma_x,sigma_y,correction\n\
             a,100.05,200,1,0.02,0.02,controlled\n\
             b,110,200.04,1,0.02,0.02,controlled\n\
             c,120.30,200,1,0.20,0.01,bridged\n\
             d,130,200,1,0.02,0.02,controlled\n\
             e,140,200,1,,,extrapolated\n",
        )
        .unwrap();
        let t = [
            truth("a", 100.0, 200.0),
            truth("b", 110.0, 200.0),
            truth("c", 120.0, 200.0),
            truth("e", 140.0, 200.0),
        ];
        let delivered = delivered_recordings(d.path(), &true_of(&t))
            .unwrap()
            .unwrap();
        let share = delivered.beyond_sigma95.unwrap();
        assert!((share - 1.0 / 3.0).abs() < 1e-12, "{share}");
        let controlled = delivered.controlled_max_2d_m.unwrap();
        assert!((controlled - 0.05).abs() < 1e-9, "{controlled}");
        let empty = tempfile::tempdir().unwrap();
        assert_eq!(
            delivered_recordings(empty.path(), &true_of(&t)).unwrap(),
            None
        );
    }

    #[test]
    fn check_points_give_their_worst_error_and_their_mean_offset() {
        let d = tempfile::tempdir().unwrap();
        // Errors (0.03, 0.04), (0.03, −0.02), (0.03, 0.01): worst 0.05 m, mean (0.03, 0.01); a point without
        // an "after" (not observed after adjustment) is left out.
        std::fs::write(
            d.path().join("checkpoints.csv"),
            "point_id,after_x,after_y,after_2d
             a,0.03,0.04,0.05
             b,0.03,-0.02,0.036
             c,0.03,0.01,0.0316
             d,,,
",
        )
        .unwrap();
        let (max, bias) = checkpoints_after(d.path()).unwrap().unwrap();
        assert!((max - 0.05).abs() < 1e-12, "{max}");
        assert!((bias - 0.03f64.hypot(0.01)).abs() < 1e-12, "{bias}");
        let empty = tempfile::tempdir().unwrap();
        assert_eq!(checkpoints_after(empty.path()).unwrap(), None);
    }

    fn write_recordings(path: &Path, rows: &[(&str, f64, f64)]) {
        let mut text = String::from("image_id,file,time,x,y,z,heading,camera_height\n");
        for (i, (id, x, y)) in rows.iter().enumerate() {
            text += &format!("{id},{id}.jpg,2019-06-14T10:00:0{i}.000Z,{x},{y},3,90,2.2\n");
        }
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }

    #[test]
    fn a_segment_is_judged_by_its_mean_and_its_worst_recording() {
        let campaign = tempfile::tempdir().unwrap();
        let out = tempfile::tempdir().unwrap();
        let c = campaign.path();
        // Segment 0: a drift that starts inside it (offsets 0, 0, 0.5 m: mean 0.17 m, worst 0.5 m);
        // segment 1: every recording within 0.1 m.
        let ids = ["a", "b", "c", "d", "e"];
        let offsets = [(0.0, 0.0), (0.0, 0.0), (0.5, 0.0), (0.1, 0.0), (0.0, 0.05)];
        let rows = |with_offsets: bool| -> Vec<(&str, f64, f64)> {
            ids.iter()
                .zip(offsets)
                .enumerate()
                .map(|(i, (id, (dx, dy)))| {
                    let k = f64::from(u8::from(with_offsets));
                    (*id, 5.0 * i as f64 + k * dx, k * dy)
                })
                .collect()
        };
        write_recordings(&c.join("truth/recordings.csv"), &rows(false));
        write_recordings(&c.join("mm/recordings.csv"), &rows(true));
        std::fs::write(
            out.path().join("verification.csv"),
            "segment,first_image_id,last_image_id,status\n0,a,c,fail\n1,d,e,fail\nall,a,e,fail\n",
        )
        .unwrap();
        let truth = read_recordings_csv(&c.join("truth/recordings.csv")).0;
        let segments = segment_truth(out.path(), c, &true_of(&truth)).unwrap();
        assert_eq!(segments.len(), 2);
        assert!((segments[0].mean_off_m - 0.5 / 3.0).abs() < 1e-9);
        assert!((segments[0].max_off_m - 0.5).abs() < 1e-9);
        assert!((segments[1].max_off_m - 0.1).abs() < 1e-9);
        let false_flags: Vec<bool> = segments.iter().map(SegmentTruth::false_flag).collect();
        assert_eq!(false_flags, [false, true]);
    }
}
