//! How the correspondences entered an adjustment block: the counts the block builder keeps of tie points,
//! control, aerial observations, relative constraints and the control its checks dropped (`metrics.json`
//! `adjust.<sources>.build`).

use super::height_observation::HeightObservations;
use super::weak_control_sigma::WeakSigmaEstimate;
use serde::{Deserialize, Serialize};

/// How the correspondences entered the block.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BuildCounts {
    pub tie_points: usize,
    pub control_points: usize,
    /// Control points used as triangulated control (thesis scheme).
    pub control_as_gcp: usize,
    /// Control points whose aerial pixels went into the bundle.
    pub control_as_aerial_observations: usize,
    /// Control points not used: a single aerial observation in the thesis scheme, or no usable point.
    pub control_unused: usize,
    pub aerial_observations: usize,
    /// Aerial observations left out because the point's initial position is not in front of that camera.
    pub aerial_observations_skipped: usize,
    pub relative_constraints: usize,
    /// The recordings' observed heights (`dtm_height`).
    pub heights: HeightObservations,
    /// Weak orthophoto control points not used because they disagree with the strong control along the
    /// trajectory (`weak_control_tolerance_m`).
    pub weak_control_dropped: usize,
    /// Control points not used because their correction disagrees with the control of the neighbouring
    /// recordings (`control_consistency_window`).
    pub inconsistent_control_dropped: usize,
    /// Aerial points left out because they alone anchored a chain end with too few aerial observations
    /// (`chain_end_min_aerial_observations`).
    pub chain_end_evidence_dropped: usize,
    /// Recordings beyond the first or last recording with control tied to it (`extrapolation_anchor`).
    pub extrapolation_anchors: usize,
    /// Tie points whose height was observed from the terrain model (`dtm_tie_heights`).
    pub tie_point_heights: usize,
    /// The weak control's σ measured against the strong control of the same recordings
    /// (`weak_control_sigma_estimated`; `None` when off).
    pub weak_control_sigma: Option<WeakSigmaEstimate>,
}
