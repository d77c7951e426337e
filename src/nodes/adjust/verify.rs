//! `verify`: how far off is a trajectory? Per trajectory segment, aerial control points vs the same points
//! triangulated from the MM data alone (thesis Table 5-13; `skytie_stages::adjustment::verify`), with a
//! pass/fail flag against a tolerance. The node verifies the recorded positions (no adjustment given: the
//! thesis' verification without adjusting) or, given the adjustment's result, the adjusted ones.

use crate::dag::{Handle, InputsOf, NodeCtx, Optional, RunResult, Stage, StageError};
use crate::nodes::adjust::adjustment::AdjustReport;
use crate::nodes::campaign::ingest::IngestedImage;
use crate::nodes::campaign::load::CampaignSnapshot;
use skytie_stages::adjustment::block_build::prior_sigmas_m;
use skytie_stages::adjustment::from_correspondences::RunRecording;
use skytie_stages::adjustment::verify::{verify_with_detail_levels, Verification, VerifyConfig};
use skytie_stages::campaign::Recording;
use skytie_stages::correspondence::AerialControlPoint;
use skytie_stages::nadir::RecordingControl;
use std::collections::HashMap;

crate::serde_artifact!(Verification);

/// `verify` metrics: overall and per-segment offsets and the flag.
pub fn verify_metrics(v: &Verification) -> serde_json::Value {
    let seg = |s: &skytie_stages::adjustment::verify::VerificationSegment| {
        serde_json::json!({
            "points": s.points,
            "points_3d": s.points_3d,
            "mean_m": s.mean_m,
            "sd_m": s.sd_m,
            "sigma_mean_m": s.sigma_mean_m,
            "offset_2d_m": s.offset_2d_m,
            "points_off": s.points_off,
            "unobserved_run": s.unobserved_run,
            "stated_sigma_xy_m": s.stated_sigma_xy_m,
            "status": s.status.label(),
        })
    };
    serde_json::json!({
        "passed": v.passed(),
        "segments": v.segments.len(),
        "segments_failed": v.segments.iter().filter(|s| s.status.label() == "fail").count(),
        "segments_insufficient": v.segments.iter().filter(|s| s.status.label() == "insufficient").count(),
        "overall": seg(&v.overall),
        "skipped_single_aerial": v.skipped_single_aerial,
        "skipped_mm": v.skipped_mm,
    })
}

/// The verification node. Inputs: the campaign, its ingested panoramas (snapshot order: their sizes and detail
/// levels), the aerial control points, and no or one adjustment whose poses replace the recorded ones.
pub struct VerifyStage;

impl Stage for VerifyStage {
    crate::nodes::stage_types!(skytie_stages::adjustment::verify::STAGE, VerifyConfig => Verification,
        inputs: (Handle<CampaignSnapshot>, Vec<Handle<IngestedImage>>, Vec<Optional<RecordingControl>>, Vec<Handle<AdjustReport>>));

    fn run(&self, config: &VerifyConfig, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (snap, panos, control, adjusted) = inputs;
        let mut sizes = Vec::with_capacity(panos.len());
        for p in &panos {
            match (u32::try_from(p.width), u32::try_from(p.height)) {
                (Ok(w), Ok(h)) => sizes.push((w, h)),
                _ => {
                    return Err(StageError::new(format!(
                        "{}: {} × {} px is too large for a panorama",
                        p.source, p.width, p.height
                    )))
                }
            }
        }
        let detail_levels: Vec<usize> = panos.iter().map(|p| p.detail_level as usize).collect();
        let points: Vec<AerialControlPoint> = control
            .iter()
            .flatten()
            .flat_map(|r| r.points.iter().cloned())
            .collect();
        let (recordings, stated_sigma) = match adjusted.first() {
            Some(report) => adjusted_recordings(&snap.campaign.recordings, report),
            None => (snap.campaign.recordings.clone(), Vec::new()),
        };
        verify_with_detail_levels(
            &recordings,
            &sizes,
            &detail_levels,
            &stated_sigma,
            &points,
            config,
        )
        .map_err(StageError::new)
    }
}

/// The campaign's recordings at their adjusted poses (position, and yaw where the adjustment estimated it),
/// and each one's stated horizontal σ (the larger of x and y, m); recordings the adjustment did not contain
/// keep their recorded pose and their prior σ (the adjustment's, from the row's `sigma_xy` or its default).
fn adjusted_recordings(
    recorded: &[Recording],
    report: &AdjustReport,
) -> (Vec<Recording>, Vec<f64>) {
    let adjusted: HashMap<&str, &RunRecording> = report
        .run
        .recordings
        .iter()
        .map(|r| (r.image_id.as_str(), r))
        .collect();
    recorded
        .iter()
        .map(|rec| {
            let mut rec = rec.clone();
            let sigma = match adjusted.get(rec.image_id.as_str()) {
                Some(a) => {
                    [rec.x, rec.y, rec.z] = a.adjusted_world;
                    rec.yaw_deg += a.yaw_correction_deg;
                    a.sigma_m[0].max(a.sigma_m[1])
                }
                None => prior_sigmas_m(&rec, &report.run.config).0,
            };
            (rec, sigma)
        })
        .unzip()
}
