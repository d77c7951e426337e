//! Grading the oblique pipeline against a synthetic campaign's `truth/` (the `oblique.*` truth metrics).
//! Evaluation only: the pipeline never calls this. Uses the nadir grading's [`Truth`] and [`ErrorStats`].
//!
//! **Rule for a correct oblique correspondence** (one patch match: panorama observation `mm` ↔ oblique pixel
//! `oblique_px`). With the TRUE panorama pose (`truth/recordings.csv`) and the (exact) oblique orientation:
//! 1. the panorama ray through `mm` and the oblique ray through `oblique_px` pass each other within
//!    [`CLOSEST_APPROACH_TOLERANCE_M`] = 0.15 m, in front of both cameras; and
//! 2. the reference point reprojects into the oblique image within [`REPROJECTION_TOLERANCE_PX`] = 1.5 px of
//!    `oblique_px`, or within [`REPROJECTION_TOLERANCE_M`] = 0.15 m measured on the ground at the reference
//!    point when that is more pixels (so the rule means the same on the ground for a frame finer than the
//!    thesis' ≈ 10 cm obliques: a 2.5 cm frame is allowed 6 px).
//!
//! The **reference point** is what the panorama observation depicts:
//! - with the campaign's scene (`truth/scene.toml` of skytie's generator, [`SceneOracle`]): the first surface
//!   the true panorama ray through `mm` hits. A correspondence whose surface point does not exist (sky), is
//!   hidden from the oblique camera (trees, a balcony, another building, a car that has left before the
//!   flight) or falls outside the oblique image is **non-matchable** (thesis 4.4.3, Fig. 4.7): neither inlier
//!   nor outlier, counted apart;
//! - without it (campaigns rendered by other software): the sparse tie point's object point (all its panorama
//!   observations triangulated with the true poses) when the tie point is known and triangulates, else the
//!   midpoint of the two rays' closest approach; `non_matchable` is then null. The triangulated point carries
//!   the errors of the tie point's other observations (a few centimetres to decimetres along the ray), so this
//!   reference is stricter than the surface point.
//!
//! Test 2 matters: a wrong match displaced along the epipolar line still meets the panorama ray (test 1 alone
//! would pass it); the reference point pins the position along the ray.
//!
//! Ratios follow the thesis' tables (4-2…4-8): `inlier_ratio` = inliers / (inliers + outliers), i.e. "without
//! non-matchable"; `inlier_ratio_incl_non_matchable` = inliers / all graded correspondences. The same pair
//! exists after the consensus.
//!
//! **Control point error**: a control point's `point_world` (triangulated from the oblique rays) minus the
//! true point of its MM observations (true-pose triangulation). Points whose MM rays do not triangulate
//! (degenerate) are not graded and are counted in `control_points_ungraded` — the alternative, the oblique
//! rays' own point, would compare the estimate with itself because the oblique poses are exact.

use crate::ratio::ratio_or_zero;
use std::collections::HashMap;

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use serde_json::json;

use super::types::{ObliqueResult, PatchMatch, SparseCloud, StreetSide};
use crate::correspondence::{MmTiePoint, PanoObservation};
use crate::geometry::{closest_approach, FrameCamera, PanoramaCamera};
pub use crate::nadir::grading::{ErrorStats, Truth};
use crate::params::StageId;
pub use crate::synth::scene_truth::SceneOracle;

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("grade_oblique", "5");

/// Largest closest-approach distance of the panorama and oblique rays of a correct correspondence, m.
pub const CLOSEST_APPROACH_TOLERANCE_M: f64 = 0.15;
/// Largest reprojection error of the best point in the oblique image of a correct correspondence, px.
pub const REPROJECTION_TOLERANCE_PX: f64 = 1.5;
/// The same tolerance on the ground (1.5 px of a 10 cm oblique), m: the larger of the two, in pixels, applies.
pub const REPROJECTION_TOLERANCE_M: f64 = 0.15;

/// Counts of one street side.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SideCounts {
    /// Graded correspondences (entered the consensus) / correct ones.
    pub correspondences: usize,
    pub inliers: usize,
    /// Kept by the consensus / kept and correct.
    pub kept: usize,
    pub inliers_after_consensus: usize,
    /// Graded / kept correspondences that are non-matchable (0 without the scene).
    pub non_matchable: usize,
    pub non_matchable_after_consensus: usize,
}

/// The truth grades of one run of the oblique pipeline.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ObliqueGrade {
    /// Graded correspondences before the consensus (every match not rejected at the coarse level).
    pub correspondences: usize,
    /// Correspondences that could not be graded (panorama or oblique image missing from the truth).
    pub ungraded: usize,
    /// inliers + outliers + non-matchable = correspondences.
    pub inliers: usize,
    pub outliers: usize,
    /// inliers / (inliers + outliers), "without non-matchable" (0 when none).
    pub inlier_ratio: f64,
    /// inliers / correspondences.
    pub inlier_ratio_incl_non_matchable: f64,
    /// Among the correspondences kept by the consensus.
    pub inliers_after_consensus: usize,
    pub outliers_after_consensus: usize,
    pub inlier_ratio_after_consensus: f64,
    pub inlier_ratio_after_consensus_incl_non_matchable: f64,
    /// Kept correspondences that are non-matchable (`None` without the scene).
    pub non_matchable_after_consensus: Option<usize>,
    /// What the correspondences were compared with: `"scene surface point"` or `"tie point"`.
    pub reference: String,
    /// Triangulated control points vs truth.
    pub control_points: ErrorStats,
    /// Triangulated control points whose MM rays do not triangulate with the true poses.
    pub control_points_ungraded: usize,
    /// Graded correspondences that are non-matchable (`None` without the scene: see the module doc).
    pub non_matchable: Option<usize>,
    /// Reprojection error of the reference point in the oblique image over the kept matchable correspondences,
    /// px (diagnostic: how far off the wrong ones are).
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

impl ObliqueGrade {
    /// The `oblique.*` truth metrics (to be put under the `oblique` namespace).
    pub fn metrics(&self) -> serde_json::Value {
        let side = |s: &SideCounts| {
            json!({
                "correspondences": s.correspondences,
                "inliers": s.inliers,
                "kept": s.kept,
                "inliers_after_consensus": s.inliers_after_consensus,
                "non_matchable": s.non_matchable,
                "non_matchable_after_consensus": s.non_matchable_after_consensus,
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
            "inlier_ratio_incl_non_matchable": self.inlier_ratio_incl_non_matchable,
            "inliers_after_consensus": self.inliers_after_consensus,
            "outliers_after_consensus": self.outliers_after_consensus,
            "inlier_ratio_after_consensus": self.inlier_ratio_after_consensus,
            "inlier_ratio_after_consensus_incl_non_matchable":
                self.inlier_ratio_after_consensus_incl_non_matchable,
            "non_matchable_after_consensus": self.non_matchable_after_consensus,
            "truth_reference": self.reference,
            "control_point_error_m": if cp.count > 0 { json!(error_3d_rms) } else { serde_json::Value::Null },
            "control_point_error": {
                "count": cp.count,
                "mean_m": cp.mean_m,
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

/// The truth verdict of one oblique correspondence (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    Correct,
    Wrong,
    /// The panorama observation's surface point is sky, hidden from the oblique camera or outside its image.
    NonMatchable,
}

/// Grades one patch match by the rule of the module doc, or `None` when its panorama or oblique image is not
/// in the truth. `tie` is the match's sparse tie point (the reference without a scene).
pub fn grade_match(
    truth: &Truth,
    scene: Option<&SceneOracle>,
    tie: Option<&MmTiePoint>,
    m: &PatchMatch,
) -> Option<Verdict> {
    match_errors(truth, scene, tie, m).map(|e| e.verdict())
}

/// The two quantities the grading rule tests, for diagnostics: closest approach of the panorama and oblique
/// rays (m; infinite when they do not pass in front of both cameras) and the reprojection error of the
/// reference point in the oblique image (px; infinite when it does not project); `matchable` is false for a
/// non-matchable correspondence.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatchErrors {
    pub closest_approach_m: f64,
    pub reprojection_px: f64,
    /// Size of one oblique pixel at the reference point (distance from the camera / focal length), m.
    pub pixel_m: f64,
    pub matchable: bool,
}

impl MatchErrors {
    /// The reprojection tolerance of this correspondence, px: [`REPROJECTION_TOLERANCE_PX`], or
    /// [`REPROJECTION_TOLERANCE_M`] in pixels at the reference point when that is larger.
    pub fn tolerance_px(&self) -> f64 {
        let ground_px = if self.pixel_m > 0.0 {
            REPROJECTION_TOLERANCE_M / self.pixel_m
        } else {
            0.0
        };
        REPROJECTION_TOLERANCE_PX.max(ground_px)
    }

    /// The rule of the module doc.
    pub fn verdict(&self) -> Verdict {
        if !self.matchable {
            Verdict::NonMatchable
        } else if self.closest_approach_m <= CLOSEST_APPROACH_TOLERANCE_M
            && self.reprojection_px <= self.tolerance_px()
        {
            Verdict::Correct
        } else {
            Verdict::Wrong
        }
    }
}

/// [`MatchErrors`] of one patch match; `None` when its panorama or oblique image is not in the truth.
pub fn match_errors(
    truth: &Truth,
    scene: Option<&SceneOracle>,
    tie: Option<&MmTiePoint>,
    m: &PatchMatch,
) -> Option<MatchErrors> {
    observation_errors(
        truth,
        scene,
        tie.map(|t| t.observations.as_slice()),
        &m.mm,
        &m.oblique_image_id,
        m.oblique_px,
    )
}

/// [`MatchErrors`] of one correspondence given as observations: the panorama observation `mm`, the oblique
/// observation `oblique_px` in `oblique_image_id`, and the sparse tie point's panorama observations
/// `tie_observations` (the reference without a scene). The rule of the module doc; shared with the report's
/// registration views. `None` when the panorama or the oblique image is not in the truth.
pub fn observation_errors(
    truth: &Truth,
    scene: Option<&SceneOracle>,
    tie_observations: Option<&[PanoObservation]>,
    mm: &PanoObservation,
    oblique_image_id: &str,
    oblique_px: [f64; 2],
) -> Option<MatchErrors> {
    let (rec, w, h) = truth.recordings.get(&mm.image_id)?;
    let pano = PanoramaCamera::from_recording(rec, *w, *h);
    let cam = FrameCamera::from_aerial(truth.aerial.get(oblique_image_id)?);
    let [u, v] = oblique_px;
    let pano_ray = pano.pixel_ray(mm.u_px, mm.v_px);
    let far = MatchErrors {
        closest_approach_m: f64::INFINITY,
        reprojection_px: f64::INFINITY,
        pixel_m: 0.0,
        matchable: true,
    };
    let surface = match scene {
        Some(scene) => {
            let seen = scene.mm_surface_point(&pano_ray).filter(|x| {
                scene.visible_from_aerial(&cam.center_world, x)
                    && cam
                        .project_world(x)
                        .is_some_and(|(pu, pv)| cam.contains(pu, pv))
            });
            if seen.is_none() {
                return Some(MatchErrors {
                    matchable: false,
                    ..far
                });
            }
            seen
        }
        None => None,
    };
    let oblique_ray = cam.pixel_ray(u, v);
    let Some(ca) = closest_approach(&pano_ray, &oblique_ray) else {
        return Some(far);
    };
    if !ca.in_front_of_both() {
        return Some(far);
    }
    let reference: Vector3<f64> = surface
        .or_else(|| tie_observations.and_then(|o| truth.true_point(o)))
        .unwrap_or_else(|| ca.midpoint_world());
    Some(MatchErrors {
        closest_approach_m: ca.distance_m,
        reprojection_px: cam
            .project_world(&reference)
            .map_or(f64::INFINITY, |(pu, pv)| (pu - u).hypot(pv - v)),
        pixel_m: (reference - cam.center_world).norm() / cam.focal_px,
        matchable: true,
    })
}

/// Grades every correspondence of `result` (before and after the consensus, per side) and its control
/// points against the truth. `clouds` gives the sparse tie points (true object points); `scene`, when the
/// campaign's scene can be rebuilt, the surface points and visibility (module doc).
pub fn grade_oblique(
    truth: &Truth,
    scene: Option<&SceneOracle>,
    clouds: &[SparseCloud],
    result: &ObliqueResult,
) -> ObliqueGrade {
    let ties: HashMap<&str, &MmTiePoint> = clouds
        .iter()
        .flat_map(|c| c.points.iter())
        .map(|p| (p.tie.id.as_str(), &p.tie))
        .collect();
    let mut g = ObliqueGrade {
        reference: if scene.is_some() {
            "scene surface point"
        } else {
            "tie point"
        }
        .into(),
        ..ObliqueGrade::default()
    };
    let mut kept_graded = 0;
    let (mut non_matchable, mut non_matchable_kept) = (0, 0);
    let mut kept_reprojection: Vec<f64> = Vec::new();
    for c in &result.correspondences {
        let m = &c.matched;
        let Some(errors) = match_errors(truth, scene, ties.get(m.point_id.as_str()).copied(), m)
        else {
            g.ungraded += 1;
            continue;
        };
        let verdict = errors.verdict();
        let ok = verdict == Verdict::Correct;
        let nm = verdict == Verdict::NonMatchable;
        if c.kept && !nm {
            kept_reprojection.push(errors.reprojection_px);
        }
        g.correspondences += 1;
        g.inliers += usize::from(ok);
        non_matchable += usize::from(nm);
        let side = match m.side {
            StreetSide::Left => &mut g.left,
            StreetSide::Right => &mut g.right,
        };
        side.correspondences += 1;
        side.inliers += usize::from(ok);
        side.non_matchable += usize::from(nm);
        if c.kept {
            kept_graded += 1;
            side.kept += 1;
            side.inliers_after_consensus += usize::from(ok);
            side.non_matchable_after_consensus += usize::from(nm);
            g.inliers_after_consensus += usize::from(ok);
            non_matchable_kept += usize::from(nm);
        }
    }
    g.outliers = g.correspondences - g.inliers - non_matchable;
    g.outliers_after_consensus = kept_graded - g.inliers_after_consensus - non_matchable_kept;
    g.inlier_ratio = ratio_or_zero(g.inliers, g.inliers + g.outliers);
    g.inlier_ratio_incl_non_matchable = ratio_or_zero(g.inliers, g.correspondences);
    g.inlier_ratio_after_consensus = ratio_or_zero(
        g.inliers_after_consensus,
        g.inliers_after_consensus + g.outliers_after_consensus,
    );
    g.inlier_ratio_after_consensus_incl_non_matchable =
        ratio_or_zero(g.inliers_after_consensus, kept_graded);
    if scene.is_some() {
        g.non_matchable = Some(non_matchable);
        g.non_matchable_after_consensus = Some(non_matchable_kept);
    }
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
