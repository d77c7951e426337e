//! `adjust`: one global node per adjustment configuration (thesis 3.5.3, ch. 5): the MM tie points and aerial
//! control points of the registration stages → corrected recording positions
//! (`skytie_stages::adjustment::from_correspondences::run_in_frame`; with aerial observations in the bundle, in
//! the campaign's Cartesian frame), and the independent check-point evaluation
//! before/after (thesis 3.5.3: check points triangulated from their panorama observations with the recorded
//! and the adjusted poses, two-view and multi-view). Check points are never used as control.

use crate::dag::{Handle, InputsOf, NodeCtx, Optional, RunResult, Stage, StageError};
use crate::nodes::campaign::ingest::IngestedImage;
use crate::nodes::campaign::load::CampaignSnapshot;
use crate::nodes::campaign::map_frame::campaign_frame_spec;
use crate::nodes::oblique::consensus::ObliqueOutput;
use serde::{Deserialize, Serialize};
use skytie_stages::adjustment::campaign_checkpoints::{compare_checkpoints, CheckPointComparison};
use skytie_stages::adjustment::config::AdjustConfig;
use skytie_stages::adjustment::evaluate::MULTI_VIEW_RADIUS_M;
use skytie_stages::adjustment::from_correspondences::{
    prior_sigmas_m, run_in_frame, AdjustInputs, AdjustmentRun,
};
use skytie_stages::adjustment::height_observation::{dtm_height_sigma_m, terrain_heights};
use skytie_stages::adjustment::tie_point_heights::terrain_under_tie_points;
use skytie_stages::adjustment::{RmseSummary, ViewSelection};
use skytie_stages::correction::{
    hold_insignificant, widen_off_control_sigma, OffControlSigma, Significance,
};
use skytie_stages::correspondence::{AerialControlPoint, MmTiePoint};
use skytie_stages::crs::MapFrame;
use skytie_stages::export::{checkpoint_rows, recording_support, CheckPointRow, Support};
use skytie_stages::nadir::{MmWindowMatch, RecordingControl};
use skytie_stages::oblique::SparseCloud;
use skytie_stages::orthophoto::Dtm;
use std::collections::HashMap;
use std::sync::Arc;

/// σ of a check-point observation in the panorama, pixels (the synthetic campaigns add N(0, 0.5 px)).
pub const CHECKPOINT_SIGMA_PX: f64 = 0.5;

/// Root-mean-square check-point errors, metres (thesis Tables 3-3…3-5, 5-2…5-9).
pub type Rmse = RmseSummary;

/// Check-point errors before/after with one view selection (thesis 3.5.3).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CheckPointSummary {
    pub before: Rmse,
    pub after: Rmse,
    /// Per point (the rows of `checkpoints.csv`).
    pub rows: Vec<CheckPointRow>,
    /// Observations naming an unknown check point or panorama.
    pub skipped_observations: usize,
}

impl CheckPointSummary {
    fn of(c: &CheckPointComparison) -> Self {
        CheckPointSummary {
            before: c.before.rmse,
            after: c.after.rmse,
            rows: checkpoint_rows(c),
            skipped_observations: c.skipped_observations,
        }
    }
}

/// The adjust node's output: the adjustment and the check-point evaluation before/after.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AdjustReport {
    pub run: AdjustmentRun,
    /// All recordings within 15 m of a check point (thesis' multi-view evaluation).
    pub multi_view: CheckPointSummary,
    /// The two nearest recordings (two-view evaluation).
    pub two_view: CheckPointSummary,
    /// How the σ of recordings without control of their own was widened (`run`'s σ include it).
    pub off_control_sigma: OffControlSigma,
    /// The significance test of the corrections (`run` holds the insignificant components at their recorded
    /// values); `None` without `significance_level`.
    pub significance: Option<Significance>,
}
crate::serde_artifact!(AdjustReport);

fn rmse_json(r: &Rmse) -> serde_json::Value {
    serde_json::json!({"x": r.x, "y": r.y, "z": r.z, "2d": r.d2, "3d": r.d3, "count": r.count})
}

impl AdjustReport {
    /// The `adjust.<config>` metrics: check points before/after, iterations, observations, rejected,
    /// cost. Recording errors vs truth come from the `grade_adjust` node.
    pub fn metrics(&self) -> serde_json::Value {
        let r = &self.run;
        serde_json::json!({ r.config.sources.label(): {
            "checkpoints": {
                "before": rmse_json(&self.multi_view.before),
                "after": rmse_json(&self.multi_view.after),
            },
            "checkpoints_two_view": {
                "before": rmse_json(&self.two_view.before),
                "after": rmse_json(&self.two_view.after),
            },
            "iterations": r.iterations,
            "termination": r.termination,
            "observations": r.observations,
            "rejected": r.rejected_total,
            "rejected_by_kind": r.rejected,
            "cost": r.final_cost,
            "variance_factor": r.variance_factor,
            "redundancy": r.redundancy,
            "build": build_metrics(r),
            "relative_sigma": r.relative_sigma,
            "height_observations": r.config.dtm_height.then(|| serde_json::json!({
                "source": r.build.heights.source.label(),
                "observed": r.build.heights.observed,
                "without_terrain": r.build.heights.without_terrain,
                "sigma_m": r.build.heights.sigma_m,
            })),
            "off_control_sigma": self.off_control_sigma,
            "significance": self.significance.as_ref().map(significance_metrics),
            "trajectory": recording_metrics(r),
            "yaw_chains": (!r.yaw_chains.is_empty()).then(|| yaw_chain_metrics(r)),
            "verdict": self.verdict().label(),
        }})
    }
}

/// The significance tests: the level and window, the recordings whose horizontal / height / yaw corrections
/// were significant and held, and the held stretches.
fn significance_metrics(s: &Significance) -> serde_json::Value {
    let [horizontal, height, yaw] = s.held_recordings();
    serde_json::json!({
        "level": s.level,
        "window_m": s.window_m,
        "yaw_tested": s.yaw_tested,
        "significant_recordings": {"horizontal": s.significant[0], "height": s.significant[1], "yaw": s.significant[2]},
        "held_recordings": {"horizontal": horizontal, "height": height, "yaw": yaw},
        "held": s.held,
    })
}

/// Per chain of recordings linked by yaw terms: its first and last recording, how many, the common yaw
/// correction with its σ, and whether the evidence supported it (`tied`; otherwise each recording kept its own
/// yaw prior, `adjustment::yaw_support`).
fn yaw_chain_metrics(r: &AdjustmentRun) -> serde_json::Value {
    let id = |i: usize| r.recordings.get(i).map(|rec| rec.image_id.as_str());
    r.yaw_chains
        .iter()
        .map(|c| {
            serde_json::json!({
                "first": c.recordings.first().and_then(|&i| id(i)),
                "last": c.recordings.last().and_then(|&i| id(i)),
                "recordings": c.recordings.len(),
                "correction_deg": c.correction_rad.to_degrees(),
                "sigma_deg": c.sigma_rad.to_degrees(),
                "tied": c.tied,
            })
        })
        .collect()
}

/// The `build` counts; the height observations are under their own key, and the counts of the control checks
/// and of the extrapolation anchors only when they ran.
fn build_metrics(r: &AdjustmentRun) -> serde_json::Value {
    let mut v = serde_json::to_value(r.build).unwrap_or_default();
    if let Some(m) = v.as_object_mut() {
        m.remove("heights");
        if !r.config.dtm_tie_heights {
            m.remove("tie_point_heights");
        }
        if r.config.weak_control_tolerance_m.is_none() {
            m.remove("weak_control_dropped");
        }
        if r.config.control_consistency_window.is_none() {
            m.remove("inconsistent_control_dropped");
        }
        if !r.config.extrapolation_anchor {
            m.remove("extrapolation_anchors");
        }
        if r.config.chain_end_min_aerial_observations <= 1 {
            m.remove("chain_end_evidence_dropped");
        }
        if !r.config.weak_control_sigma_estimated {
            m.remove("weak_control_sigma");
        }
    }
    v
}

/// How far the adjustment moved the recordings and how well it determined them: counts, horizontal shift
/// (adjusted − recorded) and horizontal σ (√(σx² + σy²)) as median / 95th percentile / maximum, metres. A
/// recording "with control" observes at least one aerial control point itself; the others are carried by tie
/// points and relative constraints.
fn recording_metrics(r: &AdjustmentRun) -> serde_json::Value {
    let with_control = observes_control(r);
    let moved: Vec<f64> = r
        .recordings
        .iter()
        .map(|rec| {
            (rec.adjusted_world[0] - rec.recorded_world[0])
                .hypot(rec.adjusted_world[1] - rec.recorded_world[1])
        })
        .collect();
    let sigma: Vec<f64> = r
        .recordings
        .iter()
        .map(|rec| rec.sigma_m[0].hypot(rec.sigma_m[1]))
        .collect();
    serde_json::json!({
        "count": r.recordings.len(),
        "with_control": with_control.iter().filter(|&&c| c).count(),
        "moved_2d_m": spread(moved),
        "sigma_2d_m": spread(sigma),
    })
}

/// Per recording of the run: whether it observes aerial control itself (`export::Support::Controlled`: a
/// control point used in the adjustment).
pub fn observes_control(r: &AdjustmentRun) -> Vec<bool> {
    recording_support(r)
        .iter()
        .map(|s| s.support == Support::Controlled)
        .collect()
}

/// Whether an adjustment corrected the trajectory, as far as the run can tell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Some recordings observe aerial control, and the check points (if any) did not get worse.
    Corrected,
    /// No recording observes aerial control: the adjustment only smoothed the recorded trajectory.
    NothingCorrected,
    /// The check points are farther off after the adjustment than before (by more than 1 mm RMSE 2D).
    CheckpointsWorse,
}

impl Verdict {
    /// The label written into metrics (`adjust.<sources>.verdict`).
    pub fn label(self) -> &'static str {
        match self {
            Verdict::Corrected => "corrected",
            Verdict::NothingCorrected => "nothing_corrected",
            Verdict::CheckpointsWorse => "checkpoints_worse",
        }
    }
}

impl AdjustReport {
    /// See [`Verdict`]. Only a [`Verdict::Corrected`] adjustment is delivered as the adjusted trajectory.
    pub fn verdict(&self) -> Verdict {
        let (before, after) = (&self.multi_view.before, &self.multi_view.after);
        if !observes_control(&self.run).contains(&true) {
            Verdict::NothingCorrected
        } else if before.count > 0 && after.d2 > before.d2 + 0.001 {
            Verdict::CheckpointsWorse
        } else {
            Verdict::Corrected
        }
    }
}

/// Median, 95th percentile (nearest rank) and maximum of finite values; nulls when there are none.
fn spread(mut values: Vec<f64>) -> serde_json::Value {
    values.retain(|v| v.is_finite());
    values.sort_by(f64::total_cmp);
    let at = |q: f64| {
        (!values.is_empty())
            .then(|| values[((q * values.len() as f64).ceil() as usize).clamp(1, values.len()) - 1])
    };
    serde_json::json!({"median": at(0.5), "p95": at(0.95), "max": values.last()})
}

/// The adjustment node. Inputs: snapshot, ingested panoramas (snapshot order: their sizes and detail levels),
/// the nadir windows' tie points and
/// the recordings' aerial control points, the oblique chain's sparse clouds (MM tie points) with its consensus
/// output (oblique control points) — empty lists for a source that is not used — and the campaign's DTM (none
/// or one; read with `dtm_height`).
pub struct AdjustStage;

impl Stage for AdjustStage {
    crate::nodes::stage_types!(skytie_stages::adjustment::from_correspondences::STAGE, AdjustConfig => AdjustReport,
        inputs: (Handle<CampaignSnapshot>, Vec<Handle<IngestedImage>>, Vec<Optional<MmWindowMatch>>, Vec<Optional<RecordingControl>>, (Vec<Optional<SparseCloud>>, Vec<Optional<ObliqueOutput>>), Vec<Handle<Dtm>>));

    fn run(&self, config: &AdjustConfig, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (snap, panos, windows, control, (clouds, oblique), dtm) = inputs;
        // Items whose nodes failed are absent: the adjustment uses the rest (the failures are counted).
        let (windows, control, clouds, oblique) =
            (flat(windows), flat(control), flat(clouds), flat(oblique));
        let c = &snap.campaign;
        let sizes: Vec<(u32, u32)> = panos
            .iter()
            .map(|p| {
                let size = (u32::try_from(p.width), u32::try_from(p.height));
                match size {
                    (Ok(w), Ok(h)) => Ok((w, h)),
                    _ => Err(StageError::new(format!(
                        "{}: {} × {} px is too large for a panorama",
                        p.source, p.width, p.height
                    ))),
                }
            })
            .collect::<Result<_, _>>()?;
        let detail_levels: Vec<usize> = panos.iter().map(|p| p.detail_level as usize).collect();
        let tie_points: Vec<MmTiePoint> = windows
            .iter()
            .flat_map(|w| w.tie_points.iter().cloned())
            .chain(
                clouds
                    .iter()
                    .flat_map(|c| c.points.iter().map(|p| p.tie.clone())),
            )
            .collect();
        let control_points: Vec<AerialControlPoint> = control
            .iter()
            .flat_map(|r| r.points.iter().cloned())
            .chain(
                oblique
                    .iter()
                    .flat_map(|o| o.result.control.iter().cloned()),
            )
            .collect();
        // The recordings' heights from the DTM, when asked for and the campaign has one.
        let heights = match (config.dtm_height, dtm.first(), &c.dtm) {
            (true, Some(terrain), Some(source)) => Some(terrain_heights(
                &c.recordings,
                |x, y| terrain.height_at(x, y),
                dtm_height_sigma_m(source.sigma_m, config.camera_height_sigma_m),
            )),
            _ => None,
        };
        // The nadir matching's tie points (the first of `tie_points`) are ground points: their heights from
        // the DTM, when asked for and the campaign has one.
        let nadir_tie_points: usize = windows.iter().map(|w| w.tie_points.len()).sum();
        let tie_point_heights = match (config.dtm_tie_heights, dtm.first(), &c.dtm) {
            (true, Some(terrain), Some(source)) => {
                // A tie point's XY comes from the recorded poses: it is as uncertain as the stated σ of the
                // recording that sees it first.
                let sigma_xy: HashMap<&str, f64> = c
                    .recordings
                    .iter()
                    .map(|r| {
                        let s = r.sigma_xy_m.unwrap_or(config.default_prior_sigma_xy_m);
                        (r.image_id.as_str(), s)
                    })
                    .collect();
                Some(terrain_under_tie_points(
                    &tie_points,
                    |k| k < nadir_tie_points,
                    |x, y| terrain.height_at(x, y),
                    source.sigma_m,
                    |k| {
                        tie_points[k]
                            .observations
                            .first()
                            .and_then(|o| sigma_xy.get(o.image_id.as_str()).copied())
                            .unwrap_or(0.0)
                    },
                ))
            }
            _ => None,
        };
        let inputs = AdjustInputs {
            recordings: &c.recordings,
            pano_size_px: &sizes,
            pano_detail_level: &detail_levels,
            tie_points: &tie_points,
            control: &control_points,
            nadir: &c.nadir,
            oblique: &c.oblique,
            heights: heights.as_deref(),
            tie_point_heights: tie_point_heights.as_deref(),
        };
        // With aerial observations in the bundle, it runs in the campaign's Cartesian frame.
        let frame = MapFrame::from_spec(&campaign_frame_spec(c).0)
            .map_err(|e| StageError::new(format!("adjustment: {e}")))?;
        let mut result = run_in_frame(&inputs, config, &frame)
            .map_err(|e| StageError::new(format!("adjustment failed: {e}")))?;
        // σ of the recordings without control of their own, before any output reads it.
        let priors: Vec<(Option<f64>, Option<f64>)> = c
            .recordings
            .iter()
            .map(|r| {
                let (xy, z) = prior_sigmas_m(r, config);
                (Some(xy), Some(z))
            })
            .collect();
        let off_control_sigma = widen_off_control_sigma(&mut result, &priors);
        // Then the corrections the evidence does not show are taken back, before anything reads them.
        let significance = config
            .significance_level
            .map(|level| hold_insignificant(&mut result, level, config.significance_window_m));
        let compare = |selection| {
            compare_checkpoints(
                &c.recordings,
                &sizes,
                &result,
                &c.checkpoints,
                &c.observations,
                selection,
                CHECKPOINT_SIGMA_PX,
            )
            .map(|cmp| CheckPointSummary::of(&cmp))
            .map_err(|e| StageError::new(format!("check-point evaluation: {e}")))
        };
        let multi_view = compare(ViewSelection::WithinRadius {
            radius_m: MULTI_VIEW_RADIUS_M,
        })?;
        let two_view = compare(ViewSelection::TwoNearest)?;
        Ok(AdjustReport {
            run: result,
            multi_view,
            two_view,
            off_control_sigma,
            significance,
        })
    }
}

/// The present values of optional inputs, in order.
fn flat<T>(values: Vec<Option<Arc<T>>>) -> Vec<Arc<T>> {
    values.into_iter().flatten().collect()
}
