//! Check-point evaluation on campaign rows (thesis 3.5.3): the panorama cameras of the
//! recorded and of the adjusted trajectory, and the check points (`control/checkpoints.csv`) triangulated from
//! their observations (`control/observations.csv`) with both, for one view selection (two nearest, or all
//! within 15 m). Check points are never control. Observations naming an unknown point or panorama are
//! skipped and counted.

use super::evaluate::{
    evaluate_checkpoints, CheckObservation, CheckPointEvaluation, ViewSelection,
};
use super::from_correspondences::AdjustmentRun;
use super::id_index::index_by_id;
use crate::campaign::{CheckPoint, Observation, Recording};
use crate::geometry::PanoramaCamera;
use nalgebra::Vector3;

/// Before/after evaluation of the check points.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckPointComparison {
    /// `point_id` per check-point index of the evaluations.
    pub ids: Vec<String>,
    /// Triangulated with the recorded poses.
    pub before: CheckPointEvaluation,
    /// Triangulated with the adjusted poses.
    pub after: CheckPointEvaluation,
    /// Observations whose point or panorama is unknown.
    pub skipped_observations: usize,
}

/// The recorded panorama cameras.
pub fn recorded_cameras(
    recordings: &[Recording],
    pano_size_px: &[(u32, u32)],
) -> Vec<PanoramaCamera> {
    recordings
        .iter()
        .zip(pano_size_px)
        .map(|(r, &(w, h))| PanoramaCamera::from_recording(r, w, h))
        .collect()
}

/// The adjusted panorama cameras (adjusted centre, recorded yaw + yaw correction). The run's recordings must
/// be the given ones in the same order.
pub fn adjusted_cameras(
    recordings: &[Recording],
    pano_size_px: &[(u32, u32)],
    run: &AdjustmentRun,
) -> Result<Vec<PanoramaCamera>, String> {
    if run.recordings.len() != recordings.len() || pano_size_px.len() != recordings.len() {
        return Err(format!(
            "the adjustment has {} recordings, the campaign {} (sizes {}); pass the recordings it was run on",
            run.recordings.len(),
            recordings.len(),
            pano_size_px.len()
        ));
    }
    recordings
        .iter()
        .zip(pano_size_px)
        .zip(&run.recordings)
        .map(|((r, &(w, h)), a)| {
            if a.image_id != r.image_id {
                return Err(format!(
                    "adjusted recording '{}' does not match campaign recording '{}' at the same position",
                    a.image_id, r.image_id
                ));
            }
            Ok(PanoramaCamera::new(
                w,
                h,
                Vector3::from(a.adjusted_world),
                r.yaw_deg + a.yaw_correction_deg,
                r.pitch_deg,
                r.roll_deg,
            ))
        })
        .collect()
}

/// Check-point errors before and after the adjustment with one view selection; `sigma_px` weights the rays.
pub fn compare_checkpoints(
    recordings: &[Recording],
    pano_size_px: &[(u32, u32)],
    run: &AdjustmentRun,
    checkpoints: &[CheckPoint],
    observations: &[Observation],
    selection: ViewSelection,
    sigma_px: f64,
) -> Result<CheckPointComparison, String> {
    let before_cams = recorded_cameras(recordings, pano_size_px);
    let after_cams = adjusted_cameras(recordings, pano_size_px, run)?;
    let rec_index = index_by_id(recordings, |r| r.image_id.as_str());
    let cp_index = index_by_id(checkpoints, |c| c.point_id.as_str());
    let mut obs = Vec::with_capacity(observations.len());
    let mut skipped = 0;
    for o in observations {
        match (
            cp_index.get(o.point_id.as_str()),
            rec_index.get(o.image_id.as_str()),
        ) {
            (Some(&c), Some(&r)) => obs.push(CheckObservation {
                check_point: c,
                recording: r,
                u_px: o.u_px,
                v_px: o.v_px,
            }),
            _ => skipped += 1,
        }
    }
    let surveyed: Vec<Vector3<f64>> = checkpoints
        .iter()
        .map(|c| Vector3::new(c.x, c.y, c.z))
        .collect();
    Ok(CheckPointComparison {
        ids: checkpoints.iter().map(|c| c.point_id.clone()).collect(),
        before: evaluate_checkpoints(&before_cams, &surveyed, &obs, selection, sigma_px),
        after: evaluate_checkpoints(&after_cams, &surveyed, &obs, selection, sigma_px),
        skipped_observations: skipped,
    })
}
