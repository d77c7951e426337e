//! The transform between two adjacent ortho images (thesis 3.4.4.2–3.4.4.3): KAZE matches (ratio + mutual),
//! filtered by the recorded poses' prediction, RANSAC homography, verified by mapping the detecting image's
//! centre and comparing its distance to the neighbour's centre with the recorded inter-pose distance
//! (30 cm) and by requiring it to stay close to a translation over the corner area. If any step fails the recorded poses relate the images instead (ortho pixel → ground → ortho
//! pixel), and the reason is kept for the report.

use super::params::MmMatchParams;
use super::prepared::PreparedOrtho;
use super::OrthoView;
use crate::estimators::{ransac, RansacParams};
use crate::geometry::{Homography, PointPair};
use crate::matching::descriptor_match::match_ratio;
use crate::nadir::{OrthoGeoref, PairMethod};
use nalgebra::Vector2;

/// How detecting-ortho pixels are carried into the neighbour's ortho image.
#[derive(Clone, Debug, PartialEq)]
pub enum PairTransform {
    /// A verified KAZE homography (detecting px → neighbour px).
    Homography(Homography),
    /// The recorded poses: detecting px → world on the detecting plane → neighbour px (vertical projection).
    Poses,
}

impl PairTransform {
    /// The neighbour-ortho pixel of detecting-ortho pixel (u, v).
    pub fn transfer(
        &self,
        from: &OrthoGeoref,
        to: &OrthoGeoref,
        u_px: f64,
        v_px: f64,
    ) -> Option<(f64, f64)> {
        match self {
            PairTransform::Homography(h) => h.apply(&Vector2::new(u_px, v_px)).map(|p| (p.x, p.y)),
            PairTransform::Poses => Some(poses_transfer(from, to, u_px, v_px)),
        }
    }
}

/// Ortho pixel → world on `from`'s plane → pixel of `to` (thesis 3.4.4.3).
pub fn poses_transfer(from: &OrthoGeoref, to: &OrthoGeoref, u_px: f64, v_px: f64) -> (f64, f64) {
    to.world_to_pixel(&from.pixel_to_world(u_px, v_px))
}

/// The outcome of estimating one pair's transform.
#[derive(Clone, Debug, PartialEq)]
pub struct PairEstimate {
    pub transform: PairTransform,
    pub method: PairMethod,
    /// Matches that passed the ratio, mutual and pose-prior filters.
    pub kaze_matches: usize,
    pub kaze_inliers: usize,
    pub centre_check_error_m: Option<f64>,
}

/// Horizontal distance between the two recorded projection centres, m.
fn recorded_distance_m(a: &OrthoView, b: &OrthoView) -> f64 {
    (a.recording.x - b.recording.x).hypot(a.recording.y - b.recording.y)
}

/// Thesis 3.4.4.2 centre check: |‖H(centre_a) − centre_b‖·gsd − recorded distance|, metres.
pub fn centre_check_error_m(h: &Homography, a: &OrthoView, b: &OrthoView) -> Option<f64> {
    let ga = &a.ortho.georef;
    let gb = &b.ortho.georef;
    let c = h.apply(&Vector2::new(
        ga.width_px as f64 / 2.0,
        ga.height_px as f64 / 2.0,
    ))?;
    let d_px = (c.x - gb.width_px as f64 / 2.0).hypot(c.y - gb.height_px as f64 / 2.0);
    Some((d_px * gb.gsd_m - recorded_distance_m(a, b)).abs())
}

/// How far the homography departs from a pure translation within `radius_m` of the detecting centre, m:
/// max over four points at that radius of |(H(q) − H(c)) − (P(q) − P(c))|, P = the pose transfer (which
/// carries the common rotation and scale). Adjacent north-up orthos share rotation and, nearly, scale
/// (thesis 3.4.4.2), so a valid homography is close to a translation there; a strongly projective one is an
/// extrapolation from keypoints in one part of the image. `None` if a point maps to infinity.
pub fn homography_distortion_m(
    h: &Homography,
    a: &OrthoView,
    b: &OrthoView,
    radius_m: f64,
) -> Option<f64> {
    let (ga, gb) = (&a.ortho.georef, &b.ortho.georef);
    let (cu, cv) = (ga.width_px as f64 / 2.0, ga.height_px as f64 / 2.0);
    let r_px = radius_m / ga.gsd_m;
    let hc = h.apply(&Vector2::new(cu, cv))?;
    let pc = poses_transfer(ga, gb, cu, cv);
    let mut worst: f64 = 0.0;
    for (du, dv) in [(r_px, 0.0), (-r_px, 0.0), (0.0, r_px), (0.0, -r_px)] {
        let hq = h.apply(&Vector2::new(cu + du, cv + dv))?;
        let pq = poses_transfer(ga, gb, cu + du, cv + dv);
        let ex = (hq.x - hc.x) - (pq.0 - pc.0);
        let ey = (hq.y - hc.y) - (pq.1 - pc.1);
        worst = worst.max(ex.hypot(ey) * gb.gsd_m);
    }
    Some(worst)
}

fn fallback(reason: String, matches: usize, inliers: usize, centre: Option<f64>) -> PairEstimate {
    PairEstimate {
        transform: PairTransform::Poses,
        method: PairMethod::Fallback { reason },
        kaze_matches: matches,
        kaze_inliers: inliers,
        centre_check_error_m: centre,
    }
}

/// Estimate the transform detecting → neighbour (thesis 3.4.4.2, fallback 3.4.4.3).
pub fn estimate_pair(
    det: &OrthoView,
    det_prep: &PreparedOrtho,
    nb: &OrthoView,
    nb_prep: &PreparedOrtho,
    p: &MmMatchParams,
    seed: u64,
) -> PairEstimate {
    let (fa, fb) = (&det_prep.features, &nb_prep.features);
    if fa.len() < p.min_inliers || fb.len() < p.min_inliers {
        return fallback(
            format!(
                "too few KAZE keypoints ({} in {}, {} in {}; need {})",
                fa.len(),
                det.recording.image_id,
                fb.len(),
                nb.recording.image_id,
                p.min_inliers
            ),
            0,
            0,
            None,
        );
    }
    let matches = match match_ratio(
        &fa.descriptors,
        &fb.descriptors,
        fa.descriptor_len,
        p.kaze_ratio,
        true,
    ) {
        Ok(m) => m,
        Err(e) => return fallback(format!("descriptor matching failed: {e}"), 0, 0, None),
    };
    let (ga, gb) = (&det.ortho.georef, &nb.ortho.georef);
    let prior_px = p.kaze_prior_window_m / gb.gsd_m;
    let pairs: Vec<PointPair> = matches
        .iter()
        .filter_map(|m| {
            let (ka, kb) = (&fa.keypoints[m.query], &fb.keypoints[m.train]);
            let (ua, va) = (ka.u_px as f64, ka.v_px as f64);
            let (ub, vb) = (kb.u_px as f64, kb.v_px as f64);
            if p.kaze_prior_window_m > 0.0 {
                let (pu, pv) = poses_transfer(ga, gb, ua, va);
                if (pu - ub).hypot(pv - vb) > prior_px {
                    return None;
                }
            }
            Some(PointPair::new(ua, va, ub, vb))
        })
        .collect();
    let n = pairs.len();
    if n < p.min_inliers {
        return fallback(
            format!(
                "{n} KAZE matches consistent with the recorded poses < {}",
                p.min_inliers
            ),
            n,
            0,
            None,
        );
    }
    let rp = RansacParams {
        threshold: p.ransac_threshold_px,
        confidence: 0.995,
        max_iterations: p.ransac_max_iterations,
        seed,
    };
    let Some(result) = ransac::<Homography>(&pairs, &rp) else {
        return fallback(
            format!("RANSAC found no homography in {n} matches"),
            n,
            0,
            None,
        );
    };
    let inliers = result.inliers.len();
    if inliers < p.min_inliers {
        return fallback(
            format!(
                "RANSAC homography has {inliers} inliers of {n} matches < {}",
                p.min_inliers
            ),
            n,
            inliers,
            None,
        );
    }
    let Some(err) = centre_check_error_m(&result.model, det, nb) else {
        return fallback(
            "the homography maps the image centre to infinity".into(),
            n,
            inliers,
            None,
        );
    };
    if err > p.verify_tolerance_m {
        return fallback(
            format!(
                "centre check failed: |projected − recorded distance| = {err:.3} m > {:.3} m",
                p.verify_tolerance_m
            ),
            n,
            inliers,
            Some(err),
        );
    }
    if let Some(distortion_m) =
        homography_distortion_m(&result.model, det, nb, p.max_corner_distance_m)
    {
        if distortion_m > p.max_homography_distortion_m {
            return fallback(
                format!(
                    "homography is not near a translation: {distortion_m:.3} m off at {:.1} m from the centre > {:.3} m",
                    p.max_corner_distance_m, p.max_homography_distortion_m
                ),
                n,
                inliers,
                Some(err),
            );
        }
    } else {
        return fallback(
            "the homography maps part of the corner area to infinity".into(),
            n,
            inliers,
            Some(err),
        );
    }
    PairEstimate {
        transform: PairTransform::Homography(result.model),
        method: PairMethod::Kaze,
        kaze_matches: n,
        kaze_inliers: inliers,
        centre_check_error_m: Some(err),
    }
}
