//! `grade_nadir`: evaluation only — grades the nadir pipeline's tie points, correspondences and control points
//! against a synthetic campaign's `truth/` (`skytie_stages::nadir::grading`; the rule is stated there and in the
//! README). Added by the pipeline only when `truth/recordings.csv` exists; no processing stage reads `truth/`.

use crate::dag::{Handle, InputsOf, NodeCtx, RawFile, RawFileValue, RunResult, Stage, StageError};
use crate::nodes::campaign::load::CampaignSnapshot;
use crate::nodes::campaign::summary::SummaryParams;
use skytie_stages::campaign::{read_aerial_csv, read_recordings_csv, AerialImage};
use skytie_stages::correspondence::{AerialControlPoint, MmTiePoint};
use skytie_stages::imaging::io::dimensions;
use skytie_stages::nadir::grading::{grade_nadir, NadirGrade, Truth};
use skytie_stages::nadir::{AerialRefinement, MmWindowMatch, RecordingControl};
use std::collections::HashMap;

crate::serde_artifact!(NadirGrade);

/// The truth file names this node understands (relative to the campaign).
pub const TRUTH_RECORDINGS: &str = "truth/recordings.csv";
pub const TRUTH_AERIAL_NADIR: &str = "truth/aerial_nadir.csv";

/// `nadir` metrics from a grade (merged with the summary's `nadir` section).
pub fn grade_metrics(g: &NadirGrade) -> serde_json::Value {
    let c = &g.control_points;
    serde_json::json!({
        "correct_tie_points": g.correct_tie_points,
        "graded_tie_points": g.tie_points,
        "ungraded_tie_points": g.ungraded,
        "inlier_ratio": g.inlier_ratio(),
        "delivered_tie_points": g.delivered_tie_points,
        "delivered_correct": g.delivered_correct,
        "delivered_inlier_ratio": g.delivered_inlier_ratio(),
        "mm_tie_points_graded": g.mm_tie_points,
        "mm_tie_points_correct": g.mm_tie_points_correct,
        "correspondence_error_px": {
            "median": g.correspondence_error_px[0],
            "p90": g.correspondence_error_px[1],
            "max": g.correspondence_error_px[2],
        },
        "correct_mean_offset_px": g.correct_mean_offset_px,
        "wrong_correspondences": g.wrong.iter().map(|w| serde_json::json!({
            "tie_point": w.tie_point_id,
            "aerial_image": w.aerial_id,
            "error_px": w.error_px,
            "offset_px": w.offset_px,
            "aerial_images": w.aerial_images,
        })).collect::<Vec<_>>(),
        "control_point_error_m": {
            "count": c.count,
            "mean": c.mean_m,
            "median_horizontal": c.median_horizontal_m,
            "rms_horizontal": c.rms_horizontal_m,
            "median_vertical": c.median_vertical_m,
            "rms_vertical": c.rms_vertical_m,
        },
    })
}

/// The [`Truth`] of a campaign: `truth_files[0]` is `truth/recordings.csv` (required), `truth_files[1]` the
/// optional true aerial poses (`truth/aerial_nadir.csv` or `truth/aerial_oblique.csv`); without it the
/// recorded `aerial_rows` are taken as true. `panos` (snapshot order) give the panorama sizes. `stage` names
/// the caller in errors.
pub fn load_truth(
    snap: &CampaignSnapshot,
    truth_files: &[RawFileValue],
    panos: &[RawFileValue],
    aerial_rows: &[AerialImage],
    stage: &str,
) -> Result<Truth, StageError> {
    let Some(rec_file) = truth_files.first() else {
        return Err(StageError::new(format!(
            "internal: {stage} needs truth/recordings.csv"
        )));
    };
    let (true_recs, problems) = read_recordings_csv(&rec_file.path);
    if let Some(p) = problems.first() {
        return Err(StageError::new(format!("truth is unreadable: {p}")));
    }
    let mut sizes = HashMap::new();
    for (rec, pano) in snap.campaign.recordings.iter().zip(panos) {
        let wh = dimensions(&pano.path).map_err(|e| StageError::new(e.to_string()))?;
        sizes.insert(rec.image_id.clone(), wh);
    }
    let recordings = true_recs
        .into_iter()
        .filter_map(|r| {
            let (w, h) = *sizes.get(&r.image_id)?;
            Some((r.image_id.clone(), (r, w, h)))
        })
        .collect();
    let aerial_rows = match truth_files.get(1) {
        Some(f) => {
            let (rows, problems) = read_aerial_csv(&f.path);
            if let Some(p) = problems.first() {
                return Err(StageError::new(format!("truth is unreadable: {p}")));
            }
            rows
        }
        None => aerial_rows.to_vec(),
    };
    Ok(Truth {
        recordings,
        aerial: aerial_rows
            .into_iter()
            .map(|a| (a.image_id.clone(), a))
            .collect(),
    })
}

/// The nadir grading node. Inputs: snapshot, truth files (`truth/recordings.csv` first, then optionally
/// `truth/aerial_nadir.csv`), the panorama files in snapshot order (for their size), and the pipeline's outputs.
pub struct GradeNadir;

impl Stage for GradeNadir {
    crate::nodes::stage_types!(skytie_stages::nadir::grading::STAGE, SummaryParams => NadirGrade,
        inputs: (Handle<CampaignSnapshot>, Vec<RawFile>, Vec<RawFile>, Vec<Handle<MmWindowMatch>>, Vec<Handle<AerialRefinement>>, Vec<Handle<RecordingControl>>));

    fn run(&self, _: &SummaryParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (snap, truth_files, panos, windows, refinements, control) = inputs;
        let truth = load_truth(
            &snap,
            &truth_files,
            &panos,
            &snap.campaign.nadir,
            "grade_nadir",
        )?;
        let tie_points: Vec<&MmTiePoint> = windows.iter().flat_map(|w| &w.tie_points).collect();
        let refs: Vec<&AerialRefinement> = refinements.iter().map(|r| r.as_ref()).collect();
        let cps: Vec<&AerialControlPoint> = control.iter().flat_map(|c| &c.points).collect();
        Ok(grade_nadir(&truth, &tie_points, &refs, &cps))
    }
}
