//! Screening of the aerial evidence before the adjustment: every aerial control point — tied to the aerial
//! triangulation as ground control, or with its aerial pixels in the bundle — implies a correction of the
//! recordings that observe it ([`ControlEvidence`]); [`select_control`] decides which of them are used
//! (weak and inconsistent control), and what it rejects leaves the block here, its point staying a tie point.
//!
//! For a point whose aerial pixels go into the bundle, the aerial position is the point triangulated from its
//! aerial images (two or more), or else its single aerial ray intersected with the horizontal plane at the
//! height the panorama rays give it — a nadir ray is steep, so that height barely moves the position.

use super::block_point::{BlockPoint, PointKind};
use super::build_counts::BuildCounts;
use super::config::AdjustConfig;
use super::control_consistency::select_control;
use super::problem::Block;
use super::weak_control::ControlEvidence;
use super::weak_control_sigma;
use crate::geometry::{intersect_ray_plane, FrameCamera, Plane};
use nalgebra::{Matrix3, Vector2, Vector3};
use std::ops::Range;

/// Where a piece of evidence sits in the block, so that it can be taken out again.
#[derive(Clone, Debug, PartialEq)]
pub enum EvidenceSource {
    /// A ground control point: its index in `Block::control_points`.
    Ground(usize),
    /// Aerial image observations of a point in the bundle: their indices in `Block::aerial_observations`.
    AerialObservations(Range<usize>),
}

/// One control point's evidence and where it sits.
#[derive(Clone, Debug, PartialEq)]
pub struct SourcedEvidence {
    pub evidence: ControlEvidence,
    pub source: EvidenceSource,
}

/// The horizontal position (world, m) an aerial control point gives: `triangulated_world` when it has one
/// (two or more aerial images), else the ray of its first aerial pixel through `camera` intersected with the
/// horizontal plane at `height_m`. `None` when the ray does not reach that plane.
pub fn aerial_position_xy(
    triangulated_world: Option<[f64; 3]>,
    first_pixel: Option<(&FrameCamera, f64, f64)>,
    height_m: f64,
) -> Option<Vector2<f64>> {
    if let Some(p) = triangulated_world.filter(|p| p.iter().all(|v| v.is_finite())) {
        return Some(Vector2::new(p[0], p[1]));
    }
    let (camera, u_px, v_px) = first_pixel?;
    let hit = intersect_ray_plane(&camera.pixel_ray(u_px, v_px), &Plane::horizontal(height_m))?;
    hit.iter()
        .all(|v| v.is_finite())
        .then(|| Vector2::new(hit.x, hit.y))
}

/// Applies [`select_control`] to `evidence` and removes what it rejects from `block`; with
/// `weak_control_sigma_estimated`, raises the σ of weak ground control to the spread the consistent control
/// shows.
pub fn screen_control(
    block: &mut Block,
    points: &mut [BlockPoint],
    evidence: &[SourcedEvidence],
    config: &AdjustConfig,
    relative_sigma_m: f64,
    counts: &mut BuildCounts,
) {
    let plain: Vec<ControlEvidence> = evidence.iter().map(|e| e.evidence.clone()).collect();
    let selection = select_control(&plain, block.recordings.len(), config, relative_sigma_m);
    counts.weak_control_dropped = selection.weak;
    counts.inconsistent_control_dropped = selection.inconsistent;
    if config.weak_control_sigma_estimated {
        let estimate = weak_control_sigma::estimate(&plain, &selection.keep);
        if let Some(sigma_m) = estimate.sigma_m {
            // Weak control is orthophoto control, always ground control; the others keep theirs.
            let given: Vec<Matrix3<f64>> = evidence
                .iter()
                .map(|e| match e.source {
                    EvidenceSource::Ground(i) => block.control_points[i].covariance_m2,
                    EvidenceSource::AerialObservations(_) => Matrix3::zeros(),
                })
                .collect();
            let raised =
                weak_control_sigma::weak_covariances(&plain, &selection.keep, &given, sigma_m);
            for (e, cov) in evidence.iter().zip(raised) {
                if let EvidenceSource::Ground(i) = e.source {
                    block.control_points[i].covariance_m2 = cov;
                }
            }
        }
        counts.weak_control_sigma = Some(estimate);
    }
    if selection.keep.contains(&false) {
        drop_control(block, points, evidence, &selection.keep, counts);
    }
}

/// Removes the evidence `keep` rejects (parallel to `evidence`) from the block: ground control points and
/// aerial image observations. A point left without ground control or aerial observations becomes a tie point
/// again; its aerial pixels stay listed in [`BlockPoint::aerial`] (all of them, used or not).
fn drop_control(
    block: &mut Block,
    points: &mut [BlockPoint],
    evidence: &[SourcedEvidence],
    keep: &[bool],
    counts: &mut BuildCounts,
) {
    let mut keep_ground = vec![true; block.control_points.len()];
    let mut keep_aerial = vec![true; block.aerial_observations.len()];
    let mut touched = Vec::new();
    for (e, _) in evidence.iter().zip(keep).filter(|(_, &k)| !k) {
        match &e.source {
            EvidenceSource::Ground(i) => {
                keep_ground[*i] = false;
                touched.push(block.control_points[*i].point);
                counts.control_as_gcp -= 1;
            }
            EvidenceSource::AerialObservations(range) => {
                for flag in &mut keep_aerial[range.clone()] {
                    *flag = false;
                }
                touched.extend(
                    block.aerial_observations[range.clone()]
                        .iter()
                        .map(|o| o.point),
                );
                counts.aerial_observations -= range.len();
                counts.control_as_aerial_observations -= 1;
            }
        }
    }
    let mut flags = keep_ground.iter();
    block
        .control_points
        .retain(|_| *flags.next().unwrap_or(&true));
    let mut flags = keep_aerial.iter();
    block
        .aerial_observations
        .retain(|_| *flags.next().unwrap_or(&true));
    let mut still_control = vec![false; points.len()];
    for p in block
        .control_points
        .iter()
        .map(|c| c.point)
        .chain(block.aerial_observations.iter().map(|o| o.point))
    {
        still_control[p] = true;
    }
    for p in touched {
        if !still_control[p] {
            points[p].kind = PointKind::Tie;
        }
    }
}

/// The evidence of a point `p` whose aerial pixels went into the bundle as `observations`: its aerial
/// position ([`aerial_position_xy`]) minus its position from the panorama rays with the recorded poses
/// (`block.points_initial_world`). `None` when no observation was added or no aerial position exists.
pub fn aerial_observation_evidence(
    block: &Block,
    camera_of: impl Fn(usize) -> FrameCamera,
    p: usize,
    triangulated_world: Option<[f64; 3]>,
    observations: Range<usize>,
    recordings: Vec<usize>,
    spread: nalgebra::Matrix2<f64>,
) -> Option<SourcedEvidence> {
    if observations.is_empty() {
        return None;
    }
    let first = block.aerial_observations.get(observations.start)?;
    let initial: Vector3<f64> = *block.points_initial_world.get(p)?;
    let camera = camera_of(first.camera);
    let xy = aerial_position_xy(
        triangulated_world,
        Some((&camera, first.u_px, first.v_px)),
        initial.z,
    )?;
    Some(SourcedEvidence {
        evidence: ControlEvidence {
            correction_m: xy - Vector2::new(initial.x, initial.y),
            recordings,
            weak: false,
            spread,
        },
        source: EvidenceSource::AerialObservations(observations),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::BrownDistortion;

    /// A nadir camera 800 m above (155 000, 463 000) in RD-like coordinates, with some lens distortion.
    fn nadir() -> FrameCamera {
        FrameCamera::from_opk(
            Vector3::new(155_000.0, 463_000.0, 810.0),
            0.0,
            0.0,
            30.0,
            10_000.0,
            3000.0,
            2000.0,
            6000,
            4000,
            BrownDistortion {
                k1: -0.01,
                ..BrownDistortion::NONE
            },
        )
    }

    #[test]
    fn a_single_nadir_pixel_gives_its_point_at_the_panorama_height() {
        let camera = nadir();
        let point = Vector3::new(155_040.0, 462_970.0, 10.0);
        let (u, v) = camera.project_world(&point).expect("in view");
        let xy = aerial_position_xy(None, Some((&camera, u, v)), 10.0).expect("hit");
        assert!((xy - Vector2::new(point.x, point.y)).norm() < 1e-6, "{xy}");
        // A height 0.3 m wrong moves it by 0.3 m × 50 m / 800 m: the ray is steep.
        let off = aerial_position_xy(None, Some((&camera, u, v)), 10.3).expect("hit");
        let moved = (off - Vector2::new(point.x, point.y)).norm();
        assert!((moved - 0.3 * 50.0 / 800.0).abs() < 1e-3, "{moved}");
        // A triangulated position wins over the ray.
        let t = aerial_position_xy(Some([1.0, 2.0, 3.0]), Some((&camera, u, v)), 10.0);
        assert_eq!(t, Some(Vector2::new(1.0, 2.0)));
        // A plane above the camera is not reached.
        assert_eq!(aerial_position_xy(None, Some((&camera, u, v)), 900.0), None);
        assert_eq!(aerial_position_xy(None, None, 10.0), None);
    }
}
