//! Grading the nadir pipeline against a synthetic campaign's `truth/` (the `nadir.*` truth metrics).
//! Evaluation only: the pipeline never calls this; the engine runs it as a separate node when `truth/` exists.
//!
//! The rule for a **correct** MM–aerial correspondence (one MM tie point located in one aerial image): the tie
//! point's panorama observations, triangulated with the **true** recording poses, give its true object point X;
//! the correspondence is correct when X, projected into the aerial image with its true pose, lies within
//! [`CORRECT_TOLERANCE_PX`] (one aerial pixel) of the aerial observation — i.e. the MM rays and the aerial ray
//! meet within one aerial pixel — or within [`CORRECT_TOLERANCE_M`] (one pixel of the thesis' 10 cm frames)
//! measured on the ground at X when that is more pixels, so the rule means the same on the ground for a frame
//! finer than 10 cm (a 2.5 cm frame is allowed 4 px). A control point's error is its (aerial-triangulated) position minus X.
//! An MM tie point is correct when every one of its panorama rays passes within [`MM_CORRECT_TOLERANCE_M`] of X.

use crate::campaign::{AerialImage, Recording};
use crate::correspondence::{AerialControlPoint, MmTiePoint, PanoObservation};
use crate::estimators::median_consensus::median_in_place;
use crate::geometry::{triangulate_rays, FrameCamera, PanoramaCamera, Ray};
use crate::nadir::registration::AerialRefinement;
use crate::params::StageId;
use crate::ratio::ratio_or_zero;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("grade_nadir", "5");

/// A correspondence is correct within this distance, aerial pixels.
pub const CORRECT_TOLERANCE_PX: f64 = 1.0;
/// The same tolerance on the ground, m: the larger of the two, in pixels of the aerial image at X, applies.
pub const CORRECT_TOLERANCE_M: f64 = 0.10;
/// An MM tie point's rays must pass within this distance of the true point, metres.
pub const MM_CORRECT_TOLERANCE_M: f64 = 0.05;

/// True poses of a synthetic campaign, keyed by `image_id`, with each panorama's size in pixels.
pub struct Truth {
    pub recordings: HashMap<String, (Recording, u32, u32)>,
    /// True aerial poses (the recorded ones where `truth/aerial_*.csv` does not exist).
    pub aerial: HashMap<String, AerialImage>,
}

/// Error statistics of a set of 3-D errors, metres.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ErrorStats {
    pub count: usize,
    /// Signed mean error (world x, y, z), m: a systematic offset shows here while the medians below stay at
    /// the noise level.
    pub mean_m: [f64; 3],
    pub median_horizontal_m: f64,
    pub rms_horizontal_m: f64,
    pub median_vertical_m: f64,
    pub rms_vertical_m: f64,
}

impl ErrorStats {
    /// Statistics of `errors` (world frame, metres).
    pub fn from_errors(errors: &[Vector3<f64>]) -> Self {
        if errors.is_empty() {
            return Self::default();
        }
        let mut h: Vec<f64> = errors.iter().map(|e| e.x.hypot(e.y)).collect();
        let mut v: Vec<f64> = errors.iter().map(|e| e.z.abs()).collect();
        let rms = |x: &[f64]| (x.iter().map(|a| a * a).sum::<f64>() / x.len() as f64).sqrt();
        let (rh, rv) = (rms(&h), rms(&v));
        let mean = errors.iter().sum::<Vector3<f64>>() / errors.len() as f64;
        Self {
            count: errors.len(),
            mean_m: [mean.x, mean.y, mean.z],
            median_horizontal_m: median_in_place(&mut h).unwrap_or(0.0),
            rms_horizontal_m: rh,
            median_vertical_m: median_in_place(&mut v).unwrap_or(0.0),
            rms_vertical_m: rv,
        }
    }
}

/// The truth grades of one run of the nadir pipeline.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct NadirGrade {
    /// MM tie point × aerial image correspondences that could be graded / are correct.
    pub tie_points: usize,
    pub correct_tie_points: usize,
    /// Correspondences whose MM observations could not be triangulated with the true poses.
    pub ungraded: usize,
    /// MM tie points graded / correct (rays within [`MM_CORRECT_TOLERANCE_M`] of the true point).
    pub mm_tie_points: usize,
    pub mm_tie_points_correct: usize,
    /// Aerial control points (≥ 2 aerial images) vs their true points.
    pub control_points: ErrorStats,
    /// The correspondences the pipeline delivers — the aerial observations of the control points, after their
    /// multi-image consistency check (3.4.5.4) — graded / correct by the same rule.
    pub delivered_tie_points: usize,
    pub delivered_correct: usize,
    /// Error (aerial px) of the graded correspondences: median, 90th percentile, largest.
    pub correspondence_error_px: [f64; 3],
    /// Signed mean offset (u, v) of the correct correspondences from their true projections, aerial px: a
    /// matching bias (a half-pixel convention, a template's centre) shows here.
    pub correct_mean_offset_px: [f64; 2],
    /// The wrong correspondences (error above the tolerance), largest error first, so a user can
    /// look at each one (`skytie tool ortho`, the report's registration views).
    pub wrong: Vec<WrongCorrespondence>,
}

/// One MM tie point × aerial image correspondence that is wrong by the truth.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WrongCorrespondence {
    pub tie_point_id: String,
    pub aerial_id: String,
    /// Distance between the aerial observation and the true point's projection, aerial px.
    pub error_px: f64,
    /// The observation minus the true projection (u, v), aerial px.
    pub offset_px: [f64; 2],
    /// Aerial images the tie point was located in (this one included).
    pub aerial_images: usize,
}

impl NadirGrade {
    /// correct / graded correspondences (0 when there are none).
    pub fn inlier_ratio(&self) -> f64 {
        ratio_or_zero(self.correct_tie_points, self.tie_points)
    }

    /// correct / graded delivered correspondences (0 when there are none).
    pub fn delivered_inlier_ratio(&self) -> f64 {
        ratio_or_zero(self.delivered_correct, self.delivered_tie_points)
    }
}

impl Truth {
    fn ray(&self, o: &PanoObservation) -> Option<(Ray, f64)> {
        let (rec, w, h) = self.recordings.get(&o.image_id)?;
        let cam = PanoramaCamera::from_recording(rec, *w, *h);
        Some((cam.pixel_ray(o.u_px, o.v_px), cam.angular_sigma_rad(0.5)))
    }

    /// The true object point of a set of panorama observations (triangulated with the true poses).
    pub fn true_point(&self, observations: &[PanoObservation]) -> Option<Vector3<f64>> {
        let (rays, sigmas): (Vec<Ray>, Vec<f64>) =
            observations.iter().filter_map(|o| self.ray(o)).unzip();
        if rays.len() < 2 || rays.len() != observations.len() {
            return None;
        }
        triangulate_rays(&rays, &sigmas).ok().map(|t| t.point_world)
    }

    /// (u, v) minus the true projection of `x_world` into aerial image `aerial_id`, aerial px, and the
    /// correctness tolerance there, px ([`CORRECT_TOLERANCE_PX`], or [`CORRECT_TOLERANCE_M`] in pixels of
    /// the image at `x_world` when that is larger).
    fn aerial_offset_px(
        &self,
        aerial_id: &str,
        x_world: &Vector3<f64>,
        u: f64,
        v: f64,
    ) -> Option<([f64; 2], f64)> {
        let cam = FrameCamera::from_aerial(self.aerial.get(aerial_id)?);
        let (pu, pv) = cam.project_world(x_world)?;
        let pixel_m = (x_world - cam.center_world).norm() / cam.focal_px;
        let tolerance_px = CORRECT_TOLERANCE_PX.max(CORRECT_TOLERANCE_M / pixel_m);
        Some(([u - pu, v - pv], tolerance_px))
    }
}

/// Grade MM tie points, MM–aerial correspondences and aerial control points against the truth.
pub fn grade_nadir(
    truth: &Truth,
    tie_points: &[&MmTiePoint],
    refinements: &[&AerialRefinement],
    control: &[&AerialControlPoint],
) -> NadirGrade {
    let mut g = NadirGrade::default();
    let mut true_points: HashMap<&str, Option<Vector3<f64>>> = HashMap::new();
    for tp in tie_points {
        let x = truth.true_point(&tp.observations);
        if let Some(x) = x {
            g.mm_tie_points += 1;
            let ok = tp.observations.iter().all(|o| {
                truth
                    .ray(o)
                    .map(|(r, _)| {
                        let d = x - r.origin_world;
                        (d - r.dir_world * d.dot(&r.dir_world)).norm() <= MM_CORRECT_TOLERANCE_M
                    })
                    .unwrap_or(false)
            });
            g.mm_tie_points_correct += usize::from(ok);
        }
        true_points.insert(tp.id.as_str(), x);
    }
    let mut located_in: HashMap<&str, usize> = HashMap::new();
    for m in refinements.iter().flat_map(|r| &r.matches) {
        *located_in.entry(m.tie_point_id.as_str()).or_default() += 1;
    }
    let mut errors_px = Vec::new();
    let mut correct_offset_sum_px = [0.0_f64; 2];
    for r in refinements {
        for m in &r.matches {
            let x = true_points.get(m.tie_point_id.as_str()).copied().flatten();
            let (u, v) = (m.observation.u_px, m.observation.v_px);
            let err = x.and_then(|x| truth.aerial_offset_px(&r.aerial_id, &x, u, v));
            match err {
                Some((offset, tolerance_px)) => {
                    let e = offset[0].hypot(offset[1]);
                    g.tie_points += 1;
                    errors_px.push(e);
                    if e <= tolerance_px {
                        g.correct_tie_points += 1;
                        correct_offset_sum_px[0] += offset[0];
                        correct_offset_sum_px[1] += offset[1];
                    } else {
                        g.wrong.push(WrongCorrespondence {
                            tie_point_id: m.tie_point_id.clone(),
                            aerial_id: r.aerial_id.clone(),
                            error_px: e,
                            offset_px: offset,
                            aerial_images: located_in[m.tie_point_id.as_str()],
                        });
                    }
                }
                None => g.ungraded += 1,
            }
        }
    }
    g.wrong.sort_by(|a, b| {
        b.error_px
            .total_cmp(&a.error_px)
            .then_with(|| a.tie_point_id.cmp(&b.tie_point_id))
            .then_with(|| a.aerial_id.cmp(&b.aerial_id))
    });
    if g.correct_tie_points > 0 {
        let n = g.correct_tie_points as f64;
        g.correct_mean_offset_px = correct_offset_sum_px.map(|s| s / n);
    }
    if !errors_px.is_empty() {
        let mid = median_in_place(&mut errors_px).unwrap_or(0.0); // sorts
        let at = |q: f64| errors_px[((errors_px.len() - 1) as f64 * q).round() as usize];
        g.correspondence_error_px = [mid, at(0.9), at(1.0)];
    }
    for c in control {
        let x = truth.true_point(&c.mm);
        for o in &c.aerial {
            if let Some((off, tolerance_px)) =
                x.and_then(|x| truth.aerial_offset_px(&o.image_id, &x, o.u_px, o.v_px))
            {
                g.delivered_tie_points += 1;
                g.delivered_correct += usize::from(off[0].hypot(off[1]) <= tolerance_px);
            }
        }
    }
    let errors: Vec<Vector3<f64>> = control
        .iter()
        .filter_map(|c| {
            let p = c.point_world?;
            let x = truth.true_point(&c.mm)?;
            Some(Vector3::new(p[0], p[1], p[2]) - x)
        })
        .collect();
    g.control_points = ErrorStats::from_errors(&errors);
    g
}
