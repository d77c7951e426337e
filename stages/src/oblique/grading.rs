//! Grading the oblique pipeline against a synthetic campaign's `truth/` (issue 5's `oblique.*` truth metrics).
//! Evaluation only: the pipeline never calls this. Uses the nadir grading's [`Truth`] and [`ErrorStats`].
//!
//! **Rule for a correct oblique correspondence** (one patch match: panorama observation `mm` ↔ oblique pixel
//! `oblique_px`). With the TRUE panorama pose (`truth/recordings.csv`) and the (exact) oblique orientation:
//! 1. the panorama ray through `mm` and the oblique ray through `oblique_px` pass each other within
//!    [`CLOSEST_APPROACH_TOLERANCE_M`] = 0.15 m, in front of both cameras; and
//! 2. the best point reprojects into the oblique image within [`REPROJECTION_TOLERANCE_PX`] = 1.5 px of
//!    `oblique_px`. The best point is the sparse tie point's TRUE object point (all its panorama
//!    observations triangulated with the true poses) when the tie point is known and triangulates; otherwise
//!    the midpoint of the two rays' closest approach.
//!
//! Test 2 with the true tie point matters: a wrong match displaced along the epipolar line still meets the
//! panorama ray (test 1 alone would pass it); the true point pins the position along the ray.
//!
//! **Control point error**: a control point's `point_world` (triangulated from the oblique rays) minus the
//! true point of its MM observations (true-pose triangulation). Points whose MM rays do not triangulate
//! (degenerate) are not graded and are counted in `control_points_ungraded` — the alternative, the oblique
//! rays' own point, would compare the estimate with itself because the oblique poses are exact.
//!
//! **non_matchable** is `None`: deciding whether a patch centre is visible in an oblique image at all needs
//! the scene's occlusion geometry, which the synthetic generator does not export (it would need to write
//! per (point, oblique image) visibility into `truth/`).

use std::collections::HashMap;

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use serde_json::json;

use super::types::{ObliqueResult, PatchMatch, SparseCloud, StreetSide};
use crate::correspondence::MmTiePoint;
use crate::geometry::{closest_approach, FrameCamera, PanoramaCamera};
pub use crate::nadir::grading::{ErrorStats, Truth};

/// Largest closest-approach distance of the panorama and oblique rays of a correct correspondence, m.
pub const CLOSEST_APPROACH_TOLERANCE_M: f64 = 0.15;
/// Largest reprojection error of the best point in the oblique image of a correct correspondence, px.
pub const REPROJECTION_TOLERANCE_PX: f64 = 1.5;

/// Counts of one street side.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SideCounts {
    /// Graded correspondences (entered the consensus) / correct ones.
    pub correspondences: usize,
    pub inliers: usize,
    /// Kept by the consensus / kept and correct.
    pub kept: usize,
    pub inliers_after_consensus: usize,
}

/// The truth grades of one run of the oblique pipeline.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ObliqueGrade {
    /// Graded correspondences before the consensus (every match not rejected at the coarse level).
    pub correspondences: usize,
    /// Correspondences that could not be graded (panorama or oblique image missing from the truth).
    pub ungraded: usize,
    pub inliers: usize,
    pub outliers: usize,
    /// inliers / correspondences (0 when none).
    pub inlier_ratio: f64,
    /// Among the correspondences kept by the consensus.
    pub inliers_after_consensus: usize,
    pub outliers_after_consensus: usize,
    pub inlier_ratio_after_consensus: f64,
    /// Triangulated control points vs truth.
    pub control_points: ErrorStats,
    /// Triangulated control points whose MM rays do not triangulate with the true poses.
    pub control_points_ungraded: usize,
    /// `None`: our campaigns cannot tell visibility (see the module doc).
    pub non_matchable: Option<usize>,
    /// Reprojection error of the true point in the oblique image over the kept correspondences, px
    /// (diagnostic: how far off the wrong ones are).
    pub kept_reprojection_px: Quantiles,
    pub left: SideCounts,
    pub right: SideCounts,
}

/// Median, 75th and 90th percentile of a sample (0 when empty; infinite values sort last).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Quantiles {
    pub median: f64,
    pub p75: f64,
    pub p90: f64,
}

impl Quantiles {
    pub fn of(x: &mut [f64]) -> Self {
        if x.is_empty() {
            return Self::default();
        }
        x.sort_by(f64::total_cmp);
        let at = |q: f64| x[((x.len() - 1) as f64 * q).round() as usize];
        Self {
            median: at(0.5),
            p75: at(0.75),
            p90: at(0.9),
        }
    }
}

fn ratio(a: usize, n: usize) -> f64 {
    if n == 0 {
        0.0
    } else {
        a as f64 / n as f64
    }
}

impl ObliqueGrade {
    /// The `oblique.*` truth metrics of issue 5 (to be put under the `oblique` namespace).
    pub fn metrics(&self) -> serde_json::Value {
        let side = |s: &SideCounts| {
            json!({
                "correspondences": s.correspondences,
                "inliers": s.inliers,
                "kept": s.kept,
                "inliers_after_consensus": s.inliers_after_consensus,
            })
        };
        let cp = &self.control_points;
        let error_3d_rms = (cp.rms_horizontal_m.powi(2) + cp.rms_vertical_m.powi(2)).sqrt();
        json!({
            "graded_correspondences": self.correspondences,
            "ungraded_correspondences": self.ungraded,
            "inliers": self.inliers,
            "outliers": self.outliers,
            "inlier_ratio": self.inlier_ratio,
            "inliers_after_consensus": self.inliers_after_consensus,
            "outliers_after_consensus": self.outliers_after_consensus,
            "inlier_ratio_after_consensus": self.inlier_ratio_after_consensus,
            "control_point_error_m": if cp.count > 0 { json!(error_3d_rms) } else { serde_json::Value::Null },
            "control_point_error": {
                "count": cp.count,
                "median_horizontal_m": cp.median_horizontal_m,
                "rms_horizontal_m": cp.rms_horizontal_m,
                "median_vertical_m": cp.median_vertical_m,
                "rms_vertical_m": cp.rms_vertical_m,
                "ungraded": self.control_points_ungraded,
            },
            "non_matchable": self.non_matchable,
            "kept_reprojection_px": {
                "median": self.kept_reprojection_px.median,
                "p75": self.kept_reprojection_px.p75,
                "p90": self.kept_reprojection_px.p90,
            },
            "sides": { "left": side(&self.left), "right": side(&self.right) },
        })
    }
}

/// Grades one patch match by the rule of the module doc: `Some(correct)`, or `None` when its panorama or
/// oblique image is not in the truth. `tie` is the match's sparse tie point (for the true object point).
pub fn grade_match(truth: &Truth, tie: Option<&MmTiePoint>, m: &PatchMatch) -> Option<bool> {
    match_errors(truth, tie, m).map(|e| e.correct())
}

/// The two quantities the grading rule tests, for diagnostics: closest approach of the panorama and oblique
/// rays (m; infinite when they do not pass in front of both cameras) and the reprojection error of the best
/// point in the oblique image (px; infinite when it does not project).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatchErrors {
    pub closest_approach_m: f64,
    pub reprojection_px: f64,
}

impl MatchErrors {
    /// The rule of the module doc.
    pub fn correct(&self) -> bool {
        self.closest_approach_m <= CLOSEST_APPROACH_TOLERANCE_M
            && self.reprojection_px <= REPROJECTION_TOLERANCE_PX
    }
}

/// [`MatchErrors`] of one patch match; `None` when its panorama or oblique image is not in the truth.
pub fn match_errors(
    truth: &Truth,
    tie: Option<&MmTiePoint>,
    m: &PatchMatch,
) -> Option<MatchErrors> {
    let (rec, w, h) = truth.recordings.get(&m.mm.image_id)?;
    let pano = PanoramaCamera::from_recording(rec, *w, *h);
    let cam = FrameCamera::from_aerial(truth.aerial.get(&m.oblique_image_id)?);
    let [u, v] = m.oblique_px;
    let pano_ray = pano.pixel_ray(m.mm.u_px, m.mm.v_px);
    let oblique_ray = cam.pixel_ray(u, v);
    let far = MatchErrors {
        closest_approach_m: f64::INFINITY,
        reprojection_px: f64::INFINITY,
    };
    let Some(ca) = closest_approach(&pano_ray, &oblique_ray) else {
        return Some(far);
    };
    if !ca.in_front_of_both() {
        return Some(far);
    }
    let best: Vector3<f64> = tie
        .and_then(|t| truth.true_point(&t.observations))
        .unwrap_or_else(|| ca.midpoint_world());
    Some(MatchErrors {
        closest_approach_m: ca.distance_m,
        reprojection_px: cam
            .project_world(&best)
            .map_or(f64::INFINITY, |(pu, pv)| (pu - u).hypot(pv - v)),
    })
}

/// Grades every correspondence of `result` (before and after the consensus, per side) and its control
/// points against the truth. `clouds` gives the sparse tie points (true object points).
pub fn grade_oblique(
    truth: &Truth,
    clouds: &[SparseCloud],
    result: &ObliqueResult,
) -> ObliqueGrade {
    let ties: HashMap<&str, &MmTiePoint> = clouds
        .iter()
        .flat_map(|c| c.points.iter())
        .map(|p| (p.tie.id.as_str(), &p.tie))
        .collect();
    let mut g = ObliqueGrade::default();
    let mut kept_graded = 0;
    let mut kept_reprojection: Vec<f64> = Vec::new();
    for c in &result.correspondences {
        let m = &c.matched;
        let Some(errors) = match_errors(truth, ties.get(m.point_id.as_str()).copied(), m) else {
            g.ungraded += 1;
            continue;
        };
        let ok = errors.correct();
        if c.kept {
            kept_reprojection.push(errors.reprojection_px);
        }
        g.correspondences += 1;
        g.inliers += usize::from(ok);
        let side = match m.side {
            StreetSide::Left => &mut g.left,
            StreetSide::Right => &mut g.right,
        };
        side.correspondences += 1;
        side.inliers += usize::from(ok);
        if c.kept {
            kept_graded += 1;
            side.kept += 1;
            side.inliers_after_consensus += usize::from(ok);
            g.inliers_after_consensus += usize::from(ok);
        }
    }
    g.outliers = g.correspondences - g.inliers;
    g.outliers_after_consensus = kept_graded - g.inliers_after_consensus;
    g.inlier_ratio = ratio(g.inliers, g.correspondences);
    g.inlier_ratio_after_consensus = ratio(g.inliers_after_consensus, kept_graded);
    g.kept_reprojection_px = Quantiles::of(&mut kept_reprojection);
    let mut errors = Vec::new();
    for cp in &result.control {
        let Some(p) = cp.point_world else { continue };
        match truth.true_point(&cp.mm) {
            Some(x) => errors.push(Vector3::new(p[0], p[1], p[2]) - x),
            None => g.control_points_ungraded += 1,
        }
    }
    g.control_points = ErrorStats::from_errors(&errors);
    g
}
