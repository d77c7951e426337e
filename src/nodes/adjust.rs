//! `adjust`: one global node per adjustment configuration (thesis 3.5.3, ch. 5): the MM tie points and aerial
//! control points of the registration stages → corrected recording positions
//! (`skytie_stages::adjustment::from_correspondences::run`), and the independent check-point evaluation
//! before/after (thesis 3.5.3: check points triangulated from their panorama observations with the recorded
//! and the adjusted poses, two-view and multi-view). Check points are never used as control.

use crate::dag::{Handle, NodeCtx, RawFile, RawFileValue, Stage, StageError};
use crate::nodes::campaign::CampaignSnapshot;
use crate::workflow::{ParamError, StageParams};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use skytie_stages::adjustment::config::AdjustConfig;
use skytie_stages::adjustment::evaluate::MULTI_VIEW_RADIUS_M;
use skytie_stages::adjustment::from_correspondences::{run, AdjustInputs, AdjustmentRun};
use skytie_stages::adjustment::{
    evaluate_checkpoints, CheckObservation, CheckPointEvaluation, ViewSelection,
};
use skytie_stages::campaign::{Campaign, Recording};
use skytie_stages::correspondence::{AerialControlPoint, MmTiePoint};
use skytie_stages::geometry::PanoramaCamera;
use skytie_stages::imaging::io::dimensions;
use skytie_stages::nadir::{MmWindowMatch, RecordingControl};
use std::collections::HashMap;
use std::sync::Arc;

impl StageParams for AdjustConfig {
    fn validate(&self) -> Result<(), Vec<ParamError>> {
        AdjustConfig::validate(self).map_err(|errs| {
            errs.into_iter()
                .map(|(f, m)| ParamError::new(f, m))
                .collect()
        })
    }
}

/// Root-mean-square check-point errors, metres (thesis Tables 3-3…3-5, 5-2…5-9).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Rmse {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub d2: f64,
    pub d3: f64,
    pub count: usize,
}

/// One check point's error with one set of poses.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CheckPointResidual {
    pub point_id: String,
    pub views: usize,
    /// Estimated − surveyed, metres.
    pub error_m: [f64; 3],
}

/// Check-point evaluation with one set of poses and one view selection.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CheckPointReport {
    pub rmse: Rmse,
    pub points: Vec<CheckPointResidual>,
    /// Check points that could not be triangulated, with the reason.
    pub failed: Vec<(String, String)>,
}

/// The adjust node's output: the adjustment and the check-point evaluation before/after.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AdjustReport {
    pub run: AdjustmentRun,
    /// Multi-view (all recordings within 15 m) and two-view (two nearest) check-point errors.
    pub multi_view_before: CheckPointReport,
    pub multi_view_after: CheckPointReport,
    pub two_view_before: CheckPointReport,
    pub two_view_after: CheckPointReport,
}
crate::serde_artifact!(AdjustReport);

fn rmse_json(r: &Rmse) -> serde_json::Value {
    serde_json::json!({"x": r.x, "y": r.y, "z": r.z, "2d": r.d2, "3d": r.d3, "count": r.count})
}

impl AdjustReport {
    /// The `adjust.<config>` metrics (issue 6): check points before/after, iterations, observations, rejected,
    /// cost. Recording errors vs truth come from the `grade_adjust` node.
    pub fn metrics(&self) -> serde_json::Value {
        let r = &self.run;
        serde_json::json!({ r.config.sources.label(): {
            "checkpoints": {
                "before": rmse_json(&self.multi_view_before.rmse),
                "after": rmse_json(&self.multi_view_after.rmse),
            },
            "checkpoints_two_view": {
                "before": rmse_json(&self.two_view_before.rmse),
                "after": rmse_json(&self.two_view_after.rmse),
            },
            "iterations": r.iterations,
            "termination": r.termination,
            "observations": r.observations,
            "rejected": r.rejected_total,
            "rejected_by_kind": r.rejected,
            "cost": r.final_cost,
            "variance_factor": r.variance_factor,
            "redundancy": r.redundancy,
            "build": r.build,
        }})
    }
}

/// Triangulate every check point of `campaign` with the poses `poses` (parallel to `campaign.recordings`).
pub fn evaluate_with_poses(
    campaign: &Campaign,
    poses: &[Recording],
    pano_size_px: &[(u32, u32)],
    selection: ViewSelection,
) -> CheckPointReport {
    let cameras: Vec<PanoramaCamera> = poses
        .iter()
        .zip(pano_size_px)
        .map(|(r, &(w, h))| PanoramaCamera::from_recording(r, w, h))
        .collect();
    let rec_index: HashMap<&str, usize> = campaign
        .recordings
        .iter()
        .enumerate()
        .map(|(i, r)| (r.image_id.as_str(), i))
        .collect();
    let cp_index: HashMap<&str, usize> = campaign
        .checkpoints
        .iter()
        .enumerate()
        .map(|(i, c)| (c.point_id.as_str(), i))
        .collect();
    let surveyed: Vec<Vector3<f64>> = campaign
        .checkpoints
        .iter()
        .map(|c| Vector3::new(c.x, c.y, c.z))
        .collect();
    let observations: Vec<CheckObservation> = campaign
        .observations
        .iter()
        .filter_map(|o| {
            Some(CheckObservation {
                check_point: *cp_index.get(o.point_id.as_str())?,
                recording: *rec_index.get(o.image_id.as_str())?,
                u_px: o.u_px,
                v_px: o.v_px,
            })
        })
        .collect();
    let e: CheckPointEvaluation =
        evaluate_checkpoints(&cameras, &surveyed, &observations, selection, 0.5);
    let id = |i: usize| campaign.checkpoints[i].point_id.clone();
    CheckPointReport {
        rmse: Rmse {
            x: e.rmse.x,
            y: e.rmse.y,
            z: e.rmse.z,
            d2: e.rmse.d2,
            d3: e.rmse.d3,
            count: e.rmse.count,
        },
        points: e
            .points
            .iter()
            .map(|p| CheckPointResidual {
                point_id: id(p.check_point),
                views: p.views,
                error_m: [p.error_m.x, p.error_m.y, p.error_m.z],
            })
            .collect(),
        failed: e
            .failed
            .iter()
            .map(|(i, why)| (id(*i), why.clone()))
            .collect(),
    }
}

/// Panorama sizes from the panorama files (parallel to the campaign's recordings).
pub fn pano_sizes(panos: &[RawFileValue]) -> Result<Vec<(u32, u32)>, StageError> {
    panos
        .iter()
        .map(|p| dimensions(&p.path).map_err(|e| StageError::new(e.to_string())))
        .collect()
}

/// The adjustment node. Inputs: snapshot, panorama files (snapshot order), the nadir windows' tie points and
/// the recordings' aerial control points (empty lists for a source that is not used).
pub struct AdjustStage;

impl Stage for AdjustStage {
    const NAME: &'static str = "adjust";
    const VERSION: &'static str = "1";
    type Params = AdjustConfig;
    type Output = AdjustReport;
    type Inputs = (
        Handle<CampaignSnapshot>,
        Vec<RawFile>,
        Vec<Handle<MmWindowMatch>>,
        Vec<Handle<RecordingControl>>,
    );

    fn run(
        &self,
        config: &AdjustConfig,
        (snap, panos, windows, control): (
            Arc<CampaignSnapshot>,
            Vec<RawFileValue>,
            Vec<Arc<MmWindowMatch>>,
            Vec<Arc<RecordingControl>>,
        ),
        _: &NodeCtx,
    ) -> Result<AdjustReport, StageError> {
        let c = &snap.campaign;
        let sizes = pano_sizes(&panos)?;
        let tie_points: Vec<MmTiePoint> = windows
            .iter()
            .flat_map(|w| w.tie_points.iter().cloned())
            .collect();
        let control_points: Vec<AerialControlPoint> = control
            .iter()
            .flat_map(|r| r.points.iter().cloned())
            .collect();
        let inputs = AdjustInputs {
            recordings: &c.recordings,
            pano_size_px: &sizes,
            tie_points: &tie_points,
            control: &control_points,
            nadir: &c.nadir,
            oblique: &c.oblique,
        };
        let result =
            run(&inputs, config).map_err(|e| StageError::new(format!("adjustment failed: {e}")))?;
        let adjusted: Vec<Recording> = c
            .recordings
            .iter()
            .zip(&result.recordings)
            .map(|(r, a)| {
                let mut r = r.clone();
                (r.x, r.y, r.z) = (
                    a.adjusted_world[0],
                    a.adjusted_world[1],
                    a.adjusted_world[2],
                );
                r.yaw_deg += a.yaw_correction_deg;
                r
            })
            .collect();
        let multi = ViewSelection::WithinRadius {
            radius_m: MULTI_VIEW_RADIUS_M,
        };
        Ok(AdjustReport {
            multi_view_before: evaluate_with_poses(c, &c.recordings, &sizes, multi),
            multi_view_after: evaluate_with_poses(c, &adjusted, &sizes, multi),
            two_view_before: evaluate_with_poses(
                c,
                &c.recordings,
                &sizes,
                ViewSelection::TwoNearest,
            ),
            two_view_after: evaluate_with_poses(c, &adjusted, &sizes, ViewSelection::TwoNearest),
            run: result,
        })
    }
}
