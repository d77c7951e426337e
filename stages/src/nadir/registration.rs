//! Results of the nadir registration stages that later stages consume (thesis 3.4.4–3.4.5): the outcome of
//! MM-to-MM matching for one recording window, the initial MM→aerial transform, and the per-aerial-image
//! refined correspondences. Produced by `mm_matching`, `initial_transform` and `refine`; cached by the engine.

use crate::correspondence::{AerialObservation, MmTiePoint};
use crate::geometry::Similarity2;
use serde::{Deserialize, Serialize};

/// How two adjacent ortho images were related (thesis 3.4.4.2–3.4.4.3).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum PairMethod {
    /// KAZE + RANSAC homography that passed the centre-distance verification.
    Kaze,
    /// The recorded poses (KAZE failed or was rejected; `reason` says why).
    Fallback { reason: String },
}

/// One pair (detecting recording → neighbour) of an MM matching window.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PairReport {
    /// The neighbour's `image_id`.
    pub to_id: String,
    pub method: PairMethod,
    /// KAZE matches before / after RANSAC (0 when KAZE was not usable).
    pub kaze_matches: usize,
    pub kaze_inliers: usize,
    /// |projected centre distance − recorded inter-pose distance|, metres (`None` when no homography).
    pub centre_check_error_m: Option<f64>,
    /// Förstner corners transferred into the neighbour and accepted by template matching + verification.
    pub corners_matched: usize,
}

/// Output of MM-to-MM matching for the window starting at one recording (thesis 3.4.4): corners detected in
/// that recording's 3 cm ortho image, tracked into the next one or two recordings and triangulated.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MmWindowMatch {
    /// The detecting recording's `image_id`.
    pub recording_id: String,
    pub pairs: Vec<PairReport>,
    /// Förstner corners detected in the detecting ortho image.
    pub corners_detected: usize,
    /// Triangulated tie points (observations: detecting panorama first).
    pub tie_points: Vec<MmTiePoint>,
    /// For each tie point (same order): its corner position on the detecting recording's ortho ground plane,
    /// world frame, metres — where the aerial stages look for it.
    pub ground_world: Vec<[f64; 3]>,
    /// For each tie point (same order): the same corner as seen by the neighbouring recordings the
    /// triangulation kept, each on that neighbour's own ortho ground plane — what the parallax check of the
    /// aerial refinement (`refine`) looks for in the neighbours' ortho images.
    pub neighbour_ground_world: Vec<Vec<ViewGround>>,
}

/// One neighbouring recording's view of a tie point's corner: the point on its ortho ground plane, world
/// frame, metres.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViewGround {
    /// The neighbour's `image_id`.
    pub recording_id: String,
    pub ground_world: [f64; 3],
}

/// The initial transform between a recording's MM ortho image (aerial GSD, aerial orientation) and one aerial
/// nadir image (thesis 3.4.5.2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InitialTransform {
    pub recording_id: String,
    pub aerial_id: String,
    /// Maps MM ortho pixel coordinates to **full** aerial image pixel coordinates (not patch coordinates).
    pub ortho_to_aerial: Similarity2,
    /// Descriptor matches inside the error windows / RANSAC inliers.
    pub matches: usize,
    pub inliers: usize,
    /// Distance between the MM ortho centre mapped by the transform and by the recorded pose, metres (the
    /// plausibility check: must not exceed the expected maximum localisation error).
    pub centre_offset_m: f64,
    /// The same offset as a vector (x, y), world frame, metres: the correction of the recording's recorded
    /// position this transform implies (compared across the recording's nadir images by
    /// `nadir::transform_agreement`).
    pub centre_offset_world_m: [f64; 2],
    /// `true` when this transform was taken from a neighbouring recording (option `reuse_neighbour`).
    pub reused_from: Option<String>,
}

/// Outcome of the initial-transform stage for one (recording, aerial image).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum TransformOutcome {
    Accepted(InitialTransform),
    /// No plausible transform; `reason` is for metrics and the report (e.g. "12 matches, RANSAC found 3
    /// inliers < 6", "centre offset 2.3 m > 1.5 m").
    Rejected {
        recording_id: String,
        aerial_id: String,
        reason: String,
        matches: usize,
        inliers: usize,
    },
}

/// One MM tie point located in one aerial image by phase correlation (thesis 3.4.5.3).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AerialMatch {
    /// `MmTiePoint::id`.
    pub tie_point_id: String,
    pub observation: AerialObservation,
    /// The location predicted by the initial transform (full aerial pixels), before refinement.
    pub predicted_u_px: f64,
    pub predicted_v_px: f64,
    /// The pyramid level of the aerial image the tie point was located at (its pixels are 2^level full
    /// pixels): the observation's precision is the image's `sigma_px` in pixels of this level.
    #[serde(default)]
    pub level: usize,
    /// The largest disagreement (working-level px) between this location and the locations of the same corner
    /// found from the neighbouring recordings' views of it (`RefineParams::view_sigma_px`); `None` when no
    /// neighbour's view could be located.
    #[serde(default)]
    pub view_disagreement_px: Option<f64>,
}

#[cfg(test)]
impl AerialMatch {
    /// A level-0 nadir match of the tie point `id` in `image_id`, predicted at `predicted_px` and located
    /// `shift_px` from there with the peak `score`.
    pub(crate) fn shifted(
        id: &str,
        image_id: &str,
        predicted_px: (f64, f64),
        shift_px: (f64, f64),
        score: f64,
    ) -> Self {
        AerialMatch {
            tie_point_id: id.into(),
            observation: AerialObservation {
                image_id: image_id.into(),
                kind: crate::campaign::AerialKind::Nadir,
                u_px: predicted_px.0 + shift_px.0,
                v_px: predicted_px.1 + shift_px.1,
                score,
                sigma_px: None,
            },
            predicted_u_px: predicted_px.0,
            predicted_v_px: predicted_px.1,
            level: 0,
            view_disagreement_px: None,
        }
    }
}

/// Why tie points tried in an aerial image were not kept: the refinement's funnel, per (recording, aerial
/// image) and summed over a run (`nadir.*` metrics). Encoded as its fields in sequence, so a struct that holds
/// it encodes as if they were its own.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RefinementMisses {
    /// Not located because a neighbouring recording shows the template differently (parallax check,
    /// `nadir::parallax_check`).
    pub parallax_rejected: usize,
    /// No template could be cut (it leaves the ortho image, touches a masked pixel or is nearly flat,
    /// `RefineParams::min_template_std`).
    #[serde(default)]
    pub unusable_templates: usize,
    /// The content was found beyond the search margin (`RefineParams::search_margin_px`) or the search window
    /// left the aerial image.
    #[serde(default)]
    pub beyond_search: usize,
    /// The correlation peak stayed below `RefineParams::min_peak`, or below `ControlParams::strong_peak` while
    /// the recording has a location at or above it (`nadir::peak_support`).
    #[serde(default)]
    pub weak_peaks: usize,
    /// Located, but dropped because their correction disagrees with the image's other tie points
    /// (`RefineParams::max_shift_spread_px`).
    #[serde(default)]
    pub shift_inconsistent: usize,
    /// Located, but dropped because a neighbouring recording's view of the same corner lands elsewhere in the
    /// aerial image (`RefineParams::view_sigma_px`).
    #[serde(default)]
    pub view_inconsistent: usize,
    /// Located, but dropped because the located corner departs from the tie point's MM object point by more
    /// than the image's other tie points do (`RefineParams::point_sigma_px`).
    #[serde(default)]
    pub point_inconsistent: usize,
    /// Located, but dropped because fewer than `RefineParams::min_located` tie points were located in the
    /// image (a lone located template has no other to confirm the pair's registration), or because the tie
    /// point was located in fewer than `ControlParams::min_aerial_images` nadir images while others of the
    /// recording reach that count (`nadir::peak_support`).
    pub unconfirmed: usize,
}

impl RefinementMisses {
    /// Adds `other`'s counts to these.
    pub fn add(&mut self, other: &RefinementMisses) {
        self.parallax_rejected += other.parallax_rejected;
        self.unusable_templates += other.unusable_templates;
        self.beyond_search += other.beyond_search;
        self.weak_peaks += other.weak_peaks;
        self.shift_inconsistent += other.shift_inconsistent;
        self.view_inconsistent += other.view_inconsistent;
        self.point_inconsistent += other.point_inconsistent;
        self.unconfirmed += other.unconfirmed;
    }

    /// The counts as metrics keys (`parallax_rejected`, `unusable_templates`, …) into `map`.
    pub fn put_metrics(&self, map: &mut serde_json::Map<String, serde_json::Value>) {
        for (key, n) in [
            ("parallax_rejected", self.parallax_rejected),
            ("unusable_templates", self.unusable_templates),
            ("beyond_search", self.beyond_search),
            ("weak_peaks", self.weak_peaks),
            ("shift_inconsistent", self.shift_inconsistent),
            ("view_inconsistent", self.view_inconsistent),
            ("point_inconsistent", self.point_inconsistent),
            ("unconfirmed", self.unconfirmed),
        ] {
            map.insert(key.to_string(), n.into());
        }
    }
}

/// All refined correspondences of one (recording, aerial image).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AerialRefinement {
    pub recording_id: String,
    pub aerial_id: String,
    /// Tie points tried (inside the aerial image) and located (peak accepted).
    pub tried: usize,
    /// Of `tried`: why the ones not in `matches` were not kept.
    pub misses: RefinementMisses,
    pub matches: Vec<AerialMatch>,
}

impl AerialRefinement {
    /// No tie point tried yet.
    pub fn empty(recording_id: &str, aerial_id: &str) -> Self {
        Self {
            recording_id: recording_id.to_string(),
            aerial_id: aerial_id.to_string(),
            tried: 0,
            misses: RefinementMisses::default(),
            matches: Vec::new(),
        }
    }
}

/// The aerial control points of one recording (thesis 3.4.5.4): its window's tie points located in ≥ 1 aerial
/// image(s).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RecordingControl {
    pub recording_id: String,
    pub points: Vec<crate::correspondence::AerialControlPoint>,
}
