//! `verify`: without adjusting, how far off are the recorded positions? Per trajectory segment, aerial control
//! points vs the same points triangulated from the MM data alone (thesis Table 5-13;
//! `skytie_stages::adjustment::verify`), with a pass/fail flag against a tolerance.

use crate::dag::{Handle, NodeCtx, RawFile, RawFileValue, Stage, StageError};
use crate::nodes::adjust::pano_sizes;
use crate::nodes::campaign::CampaignSnapshot;
use skytie_stages::adjustment::verify::{verify, Verification, VerifyConfig};
use skytie_stages::correspondence::AerialControlPoint;
use skytie_stages::nadir::RecordingControl;
use std::sync::Arc;

crate::serde_artifact!(Verification);

/// `verify` metrics: overall and per-segment offsets and the flag.
pub fn verify_metrics(v: &Verification) -> serde_json::Value {
    let seg = |s: &skytie_stages::adjustment::verify::VerificationSegment| {
        serde_json::json!({
            "points": s.points,
            "mean_m": s.mean_m,
            "sd_m": s.sd_m,
            "sigma_mean_m": s.sigma_mean_m,
            "offset_2d_m": s.offset_2d_m,
            "status": s.status.label(),
        })
    };
    serde_json::json!({
        "passed": v.passed(),
        "segments": v.segments.len(),
        "segments_failed": v.segments.iter().filter(|s| s.status.label() == "fail").count(),
        "overall": seg(&v.overall),
        "skipped_single_aerial": v.skipped_single_aerial,
        "skipped_mm": v.skipped_mm,
    })
}

/// The verification node.
pub struct VerifyStage;

impl Stage for VerifyStage {
    const NAME: &'static str = "verify";
    const VERSION: &'static str = "3";
    type Params = VerifyConfig;
    type Output = Verification;
    type Inputs = (
        Handle<CampaignSnapshot>,
        Vec<RawFile>,
        Vec<Handle<RecordingControl>>,
    );

    fn run(
        &self,
        config: &VerifyConfig,
        (snap, panos, control): (
            Arc<CampaignSnapshot>,
            Vec<RawFileValue>,
            Vec<Arc<RecordingControl>>,
        ),
        _: &NodeCtx,
    ) -> Result<Verification, StageError> {
        let sizes = pano_sizes(&panos)?;
        let points: Vec<AerialControlPoint> = control
            .iter()
            .flat_map(|r| r.points.iter().cloned())
            .collect();
        verify(&snap.campaign.recordings, &sizes, &points, config).map_err(StageError::new)
    }
}
