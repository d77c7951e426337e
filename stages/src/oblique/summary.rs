//! The oblique pipeline's own counts (the `oblique.*` metrics that need no truth): how many sparse
//! points, planes, patches, correspondences and control points each stage produced and what each dropped.

use serde::{Deserialize, Serialize};
use serde_json::json;

use super::types::{ObliqueResult, PatchRegistrationSet, SparseCloud, TripletFacades};

/// Counts of one run of the oblique pipeline (one variant).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ObliqueSummary {
    /// Triplets with a sparse cloud, and the sparse points summed over them (thesis 4.4.1).
    pub triplets: usize,
    pub sparse_points: usize,
    /// Sparse cloud drops: tracks rejected by trifocal transfer and at triangulation.
    pub rejected_trifocal: usize,
    pub rejected_triangulation: usize,
    /// Triplets whose relative positions were measured from their tracks and used, and the mean of their
    /// larger outer-position correction, metres.
    pub relative_pose_corrected: usize,
    pub relative_pose_correction_mean_m: f64,
    /// Façade planes accepted (4.4.2) and the sides without one, planes occluded, views rejected (4.4.3).
    pub planes: usize,
    pub sides_without_plane: usize,
    pub occluded_planes: usize,
    pub visible_views: usize,
    pub rejected_views: usize,
    /// Registration sets (panorama × oblique image), patch centres offered and registrations produced
    /// (including those rejected at the coarse level) (4.4.5–4.4.6).
    pub registration_sets: usize,
    pub patch_candidates: usize,
    pub patches: usize,
    /// Patch drops: real-resolution ratio, outside image/panorama, failed registration, coarse 2-D consensus.
    pub rejected_resolution: usize,
    pub rejected_outside: usize,
    pub failed_registrations: usize,
    pub rejected_coarse: usize,
    /// 3-D consensus (4.4.7): correspondences entered, kept, rejected; sets below the minimum size.
    pub correspondences: usize,
    pub consensus_kept: usize,
    pub consensus_rejected: usize,
    pub small_sets: usize,
    pub recordings_with_correspondences: usize,
    /// Oblique control points triangulated (≥ 2 oblique images) and single-image points.
    pub control_points: usize,
    pub single_image_points: usize,
}

impl ObliqueSummary {
    /// Sums the stages' own statistics.
    pub fn from_parts(
        clouds: &[SparseCloud],
        facades: &[TripletFacades],
        sets: &[PatchRegistrationSet],
        result: &ObliqueResult,
    ) -> ObliqueSummary {
        let mut s = ObliqueSummary {
            triplets: clouds.len(),
            registration_sets: sets.len(),
            ..Default::default()
        };
        let mut correction_sum_m = 0.0;
        for c in clouds {
            s.sparse_points += c.points.len();
            s.rejected_trifocal += c.stats.rejected_trifocal;
            s.rejected_triangulation += c.stats.rejected_triangulation;
            s.relative_pose_corrected += c.stats.pose_corrected;
            correction_sum_m += c.stats.pose_correction_m();
        }
        if s.relative_pose_corrected > 0 {
            s.relative_pose_correction_mean_m = correction_sum_m / s.relative_pose_corrected as f64;
        }
        for f in facades {
            s.planes += f.planes.len();
            s.sides_without_plane += f.stats.sides_without_plane;
            s.occluded_planes += f.stats.occluded;
            s.visible_views += f.stats.visible_views;
            s.rejected_views += f.stats.rejected_views;
        }
        for r in sets {
            s.patch_candidates += r.stats.candidates;
            s.patches += r.matches.len();
            s.rejected_resolution += r.stats.rejected_resolution;
            s.rejected_outside += r.stats.rejected_outside;
            s.failed_registrations += r.stats.failed;
            s.rejected_coarse += r.matches.iter().filter(|m| m.rejected_coarse).count();
        }
        let c = &result.stats;
        s.correspondences = c.correspondences;
        s.consensus_kept = c.kept;
        s.consensus_rejected = c.rejected;
        s.small_sets = c.small_sets;
        s.recordings_with_correspondences = c.recordings_with_correspondences;
        s.control_points = c.control_points;
        s.single_image_points = c.single_image_points;
        s
    }

    /// The `oblique.*` metrics that need no truth (to be put under the `oblique` namespace).
    pub fn metrics(&self) -> serde_json::Value {
        json!({
            "triplets": self.triplets,
            "sparse_points": self.sparse_points,
            "relative_pose_corrected": self.relative_pose_corrected,
            "relative_pose_correction_mean_m": self.relative_pose_correction_mean_m,
            "planes": self.planes,
            "registration_sets": self.registration_sets,
            "patches": self.patches,
            "correspondences": self.correspondences,
            "consensus_kept": self.consensus_kept,
            "consensus_rejected": self.consensus_rejected,
            "recordings_with_correspondences": self.recordings_with_correspondences,
            "control_points": self.control_points,
            "single_image_points": self.single_image_points,
            "dropped": {
                "trifocal": self.rejected_trifocal,
                "triangulation": self.rejected_triangulation,
                "sides_without_plane": self.sides_without_plane,
                "occluded_planes": self.occluded_planes,
                "rejected_views": self.rejected_views,
                "patch_resolution": self.rejected_resolution,
                "patch_outside": self.rejected_outside,
                "patch_failed": self.failed_registrations,
                "coarse_consensus": self.rejected_coarse,
                "consensus": self.consensus_rejected,
                "small_sets": self.small_sets,
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::oblique::types::{ConsensusStats, PatchStats, SparseCloudStats};

    #[test]
    fn counts_are_summed_from_the_parts() {
        let cloud = SparseCloud {
            recordings: ["a".into(), "b".into(), "c".into()],
            points: Vec::new(),
            stats: SparseCloudStats {
                rejected_trifocal: 4,
                ..Default::default()
            },
        };
        let set = PatchRegistrationSet {
            recording: "b".into(),
            oblique_image_id: "o".into(),
            matches: Vec::new(),
            stats: PatchStats {
                candidates: 7,
                failed: 2,
                ..Default::default()
            },
        };
        let result = ObliqueResult {
            correspondences: Vec::new(),
            control: Vec::new(),
            stats: ConsensusStats {
                correspondences: 5,
                kept: 3,
                rejected: 2,
                control_points: 1,
                ..Default::default()
            },
        };
        let s = ObliqueSummary::from_parts(&[cloud.clone(), cloud], &[], &[set], &result);
        assert_eq!((s.triplets, s.rejected_trifocal), (2, 8));
        assert_eq!((s.patch_candidates, s.failed_registrations), (7, 2));
        assert_eq!(
            (s.correspondences, s.consensus_kept, s.control_points),
            (5, 3, 1)
        );
        let m = s.metrics();
        assert_eq!(m["correspondences"], 5);
        assert_eq!(m["dropped"]["trifocal"], 8);
    }
}
