//! 3-D median consensus of the patch registrations and the oblique control points (thesis 4.4.7).
//!
//! A *set* is all registrations between one panorama and one oblique image. Each registration that survived
//! the coarse level is a 3-D translation `matched_point_world − object_point_world`: where the oblique image
//! sees the content of the MM patch centre relative to where the (wrongly positioned) MM panoramas put it.
//! Within a set the translations share the panorama's position error, so they agree up to noise; the
//! component-wise median is the consensus and a translation farther than `threshold_m` from it is an outlier
//! (thesis 4.4.7; Table 4-8 uses 1.0, 0.5 and 0.3 m).
//!
//! **Consensus tracking** (4.4.7, last paragraph): the position error of the trajectory is locally
//! systematic, so with `tracking` the median of a set is taken over the pooled translations of all sets of
//! the panoramas within `tracking_window` positions along the trajectory (the `recordings` order) that share
//! the same oblique image; each match of the set is then tested against that pooled median. A small set with
//! mostly wrong matches is thereby rescued by its neighbours.
//!
//! **Small sets**: a median of fewer than `min_set_size` translations (pooled ones with tracking) means
//! little; such sets are kept unchanged or dropped as `small_sets` says, and counted.
//!
//! **Control points**: kept correspondences are grouped by sparse point; each group gives one
//! [`AerialControlPoint`] with all panorama observations of the sparse tie point and one oblique observation
//! per oblique image (the best score when several panoramas matched the point in the same image; the others
//! are counted). With ≥ 2 oblique images the point is intersected from the oblique rays alone
//! ([`crate::geometry::aerial_intersection`]); intersections with a too small angle or too large a
//! reprojection error are rejected (the point is not emitted; counted in [`ConsensusDiagnostics`]). An
//! oblique observation's σ is the image's `sigma_px` in pixels of the pyramid level its patches were made at
//! (`PatchMatch::level`), so it means the same distance on the façade whatever the frame's pixel count.
//!
//! Output order is deterministic: correspondences in input order (sets, then matches), control points by
//! `point_id`, aerial observations by `image_id`.

use std::collections::{BTreeMap, HashMap};

use serde::{Deserialize, Serialize};

use super::types::{ConsensusStats, ObliqueCorrespondence, PatchRegistrationSet, SparseCloud};
use super::ObliqueResult;
use crate::campaign::{AerialImage, AerialKind, Recording};
use crate::correspondence::{AerialControlPoint, AerialObservation, MmTiePoint, PanoObservation};
use crate::crs::MapFrame;
use crate::estimators::median_consensus::median_consensus;
use crate::geometry::aerial_intersection::{
    intersect_checked, AerialIntersection, IntersectionLimits, IntersectionRejection,
    PixelObservation,
};
use crate::geometry::FrameCamera;
use crate::params::{Params, StageId};
use crate::positions::positions_by;

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("oblique", "4");

/// What happens to the matches of a set smaller than `min_set_size` (`"keep"` or `"drop"` in a workflow).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SmallSetPolicy {
    /// Kept unchanged (no consensus test).
    Keep,
    /// All rejected.
    Drop,
}

crate::params! {
    /// Parameters of [`consensus`].
    pub struct ConsensusParams {
        /// Largest distance of a translation from the median translation (thesis 4.4.7; Table 4-8 also uses
        /// 1.0 and 0.3 m).
        threshold_m: f64 = 0.5, unit "m", above 0.0, max 100.0;
        /// Consensus tracking across adjacent panoramas sharing an oblique image (Table 4-8).
        tracking: bool = false;
        /// Smallest set (pooled set with tracking) for which a median is taken.
        min_set_size: usize = 3, min 1, max 1000;
        /// What happens to sets below `min_set_size`.
        small_sets: SmallSetPolicy = SmallSetPolicy::Keep;
        /// Panoramas on each side (along the trajectory) whose sets are pooled by tracking.
        tracking_window: usize = 1, min 1, max 50;
        /// Oblique control points: smallest accepted intersection angle of the oblique rays.
        min_intersection_angle_deg: f64 = 5.0, unit "deg", min 0.0, below 90.0;
        /// Oblique control points: largest accepted reprojection error, in units of the image's σ_px.
        max_reprojection_sigma: f64 = 10.0, above 0.0;
        /// σ of an oblique observation, used when the image's `sigma_px` is missing or not > 0.
        default_oblique_sigma_px: f64 = 1.0, unit "px", above 0.0;
    }
}

/// Counts of [`consensus`] that [`ConsensusStats`] has no field for (nothing is dropped silently).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ConsensusDiagnostics {
    /// Matches rejected at the coarse level (not entered into the 3-D consensus).
    pub coarse_rejected: usize,
    /// Kept correspondences whose oblique image was already observed for the same point with a better score.
    pub duplicate_observations: usize,
    /// Kept correspondences whose oblique image is not in the campaign (observation dropped).
    pub unknown_oblique_images: usize,
    /// Kept correspondences whose sparse point is not in any cloud (the point's MM observations then are the
    /// matches' own panorama observations).
    pub missing_tie_points: usize,
    /// Points seen in ≥ 2 oblique images whose intersection was rejected (not emitted).
    pub rejected_small_angle: usize,
    pub rejected_residual: usize,
    pub failed_intersection: usize,
    /// Sets whose recording is not in `recordings` (tracking cannot pool them; they are used alone).
    pub sets_unknown_recording: usize,
    /// True when the params were invalid (nothing computed).
    pub invalid_params: bool,
}

/// [`consensus_with_diagnostics`] without the extra counts, for coordinates that are Cartesian.
pub fn consensus(
    sets: &[PatchRegistrationSet],
    clouds: &[SparseCloud],
    recordings: &[Recording],
    oblique: &[AerialImage],
    pano_size_px: &[(u32, u32)],
    p: &ConsensusParams,
) -> ObliqueResult {
    let frame = MapFrame::Cartesian;
    consensus_with_diagnostics(sets, clouds, recordings, oblique, pano_size_px, p, &frame).0
}

fn translation(m: &super::types::PatchMatch) -> [f64; 3] {
    let (a, b) = (&m.matched_point_world, &m.object_point_world);
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// The 3-D median consensus, optional tracking and the oblique control points (see the module doc).
/// `recordings` is in trajectory order; `pano_size_px` is accepted for the node's interface (same order as
/// `recordings`) and is not needed by the consensus itself. The oblique rays of a control point are
/// intersected in `frame` (the campaign's Cartesian frame) and the point converted back to map coordinates.
pub fn consensus_with_diagnostics(
    sets: &[PatchRegistrationSet],
    clouds: &[SparseCloud],
    recordings: &[Recording],
    oblique: &[AerialImage],
    _pano_size_px: &[(u32, u32)],
    p: &ConsensusParams,
    frame: &MapFrame,
) -> (ObliqueResult, ConsensusDiagnostics) {
    let mut diag = ConsensusDiagnostics::default();
    let mut stats = ConsensusStats::default();
    if p.validate().is_err() {
        diag.invalid_params = true;
        return (
            ObliqueResult {
                correspondences: Vec::new(),
                control: Vec::new(),
                stats,
            },
            diag,
        );
    }
    // thesis 4.4.7: translations per set (matches not rejected at the coarse level).
    let entered: Vec<Vec<usize>> = sets
        .iter()
        .map(|s| {
            (0..s.matches.len())
                .filter(|&i| !s.matches[i].rejected_coarse)
                .collect()
        })
        .collect();
    diag.coarse_rejected = sets
        .iter()
        .map(|s| s.matches.iter().filter(|m| m.rejected_coarse).count())
        .sum();
    let rank = positions_by(recordings, |r| r.image_id.as_str());
    diag.sets_unknown_recording = sets
        .iter()
        .filter(|s| !rank.contains_key(s.recording.as_str()))
        .count();
    // Sets pooled with set k (itself first; with tracking the sets of adjacent panoramas, same oblique image).
    let pool = |k: usize| -> Vec<usize> {
        let s = &sets[k];
        let mut out = vec![k];
        if !p.tracking {
            return out;
        }
        let Some(&r) = rank.get(s.recording.as_str()) else {
            return out;
        };
        for (j, t) in sets.iter().enumerate() {
            if j == k || t.oblique_image_id != s.oblique_image_id {
                continue;
            }
            if let Some(&rt) = rank.get(t.recording.as_str()) {
                if rt.abs_diff(r) <= p.tracking_window {
                    out.push(j);
                }
            }
        }
        out
    };
    let mut correspondences = Vec::new();
    let mut pooled: Vec<[f64; 3]> = Vec::new();
    for (k, s) in sets.iter().enumerate() {
        if entered[k].is_empty() {
            continue;
        }
        pooled.clear();
        for j in pool(k) {
            pooled.extend(entered[j].iter().map(|&i| translation(&sets[j].matches[i])));
        }
        let small = pooled.len() < p.min_set_size;
        stats.small_sets += usize::from(small);
        let median = median_consensus(&pooled, p.threshold_m).map(|c| c.median);
        for &i in &entered[k] {
            let m = &s.matches[i];
            let t = translation(m);
            let deviation = match median {
                Some(md) if t.iter().all(|v| v.is_finite()) => {
                    ((t[0] - md[0]).powi(2) + (t[1] - md[1]).powi(2) + (t[2] - md[2]).powi(2))
                        .sqrt()
                }
                _ => f64::INFINITY,
            };
            let kept = if !t.iter().all(|v| v.is_finite()) {
                false
            } else if small {
                p.small_sets == SmallSetPolicy::Keep
            } else {
                deviation <= p.threshold_m
            };
            correspondences.push(ObliqueCorrespondence {
                matched: m.clone(),
                recording: s.recording.clone(),
                deviation_from_median_m: deviation,
                kept,
            });
        }
    }
    stats.correspondences = correspondences.len();
    stats.kept = correspondences.iter().filter(|c| c.kept).count();
    stats.rejected = stats.correspondences - stats.kept;
    let mut with: Vec<&str> = correspondences
        .iter()
        .filter(|c| c.kept)
        .map(|c| c.recording.as_str())
        .collect();
    with.sort_unstable();
    with.dedup();
    stats.recordings_with_correspondences = with.len();

    let control = control_points(
        &correspondences,
        clouds,
        oblique,
        p,
        frame,
        (&mut stats, &mut diag),
    );
    (
        ObliqueResult {
            correspondences,
            control,
            stats,
        },
        diag,
    )
}

/// Oblique control points from the kept correspondences (see the module doc).
fn control_points(
    correspondences: &[ObliqueCorrespondence],
    clouds: &[SparseCloud],
    oblique: &[AerialImage],
    p: &ConsensusParams,
    frame: &MapFrame,
    (stats, diag): (&mut ConsensusStats, &mut ConsensusDiagnostics),
) -> Vec<AerialControlPoint> {
    let ties: HashMap<&str, &MmTiePoint> = clouds
        .iter()
        .flat_map(|c| c.points.iter())
        .map(|sp| (sp.tie.id.as_str(), &sp.tie))
        .collect();
    let images: HashMap<&str, &AerialImage> =
        oblique.iter().map(|a| (a.image_id.as_str(), a)).collect();
    // point_id → oblique image_id → best correspondence.
    let mut groups: BTreeMap<&str, BTreeMap<&str, &ObliqueCorrespondence>> = BTreeMap::new();
    for c in correspondences.iter().filter(|c| c.kept) {
        let m = &c.matched;
        if !images.contains_key(m.oblique_image_id.as_str()) {
            diag.unknown_oblique_images += 1;
            continue;
        }
        let per_image = groups.entry(m.point_id.as_str()).or_default();
        match per_image.get_mut(m.oblique_image_id.as_str()) {
            Some(best) => {
                diag.duplicate_observations += 1;
                if m.score > best.matched.score {
                    *best = c;
                }
            }
            None => {
                per_image.insert(m.oblique_image_id.as_str(), c);
            }
        }
    }
    let limits = IntersectionLimits {
        min_angle_deg: p.min_intersection_angle_deg,
        max_reprojection_sigma: p.max_reprojection_sigma,
    };
    let mut out = Vec::new();
    for (point_id, per_image) in groups {
        let mm: Vec<PanoObservation> = match ties.get(point_id) {
            Some(t) => t.observations.clone(),
            None => {
                diag.missing_tie_points += 1;
                let mut own: Vec<PanoObservation> =
                    per_image.values().map(|c| c.matched.mm.clone()).collect();
                own.sort_by(|a, b| a.image_id.cmp(&b.image_id));
                own.dedup_by(|a, b| a.image_id == b.image_id);
                own
            }
        };
        let aerial: Vec<AerialObservation> = per_image
            .iter()
            .map(|(id, c)| AerialObservation {
                image_id: id.to_string(),
                kind: AerialKind::Oblique,
                u_px: c.matched.oblique_px[0],
                v_px: c.matched.oblique_px[1],
                score: c.matched.score,
                sigma_px: None,
            })
            .collect();
        let (point_world, covariance_m2) = if aerial.len() >= 2 {
            // σ in full-resolution pixels: the image's σ in pixels of the level the patches were made at.
            let cams: Result<Vec<(FrameCamera, f64)>, _> = aerial
                .iter()
                .map(|o| {
                    let row = images[o.image_id.as_str()];
                    let sigma = if row.sigma_px.is_finite() && row.sigma_px > 0.0 {
                        row.sigma_px
                    } else {
                        p.default_oblique_sigma_px
                    };
                    let level = per_image[o.image_id.as_str()].matched.level.min(30);
                    let sigma_full_px = sigma * (1u64 << level) as f64;
                    frame
                        .camera_to_local(&FrameCamera::from_aerial(row))
                        .map(|c| (c, sigma_full_px))
                })
                .collect();
            let Ok(cams) = cams else {
                diag.failed_intersection += 1;
                continue;
            };
            let obs: Vec<PixelObservation> = aerial
                .iter()
                .zip(&cams)
                .map(|(o, (cam, sigma))| PixelObservation {
                    camera: cam,
                    u_px: o.u_px,
                    v_px: o.v_px,
                    sigma_px: *sigma,
                })
                .collect();
            match intersect_checked(&obs, &limits).map(|x| in_map(frame, &x)) {
                Ok(Some((point, covariance))) => (Some(point), Some(covariance)),
                Ok(None) => {
                    diag.failed_intersection += 1;
                    continue;
                }
                Err(IntersectionRejection::SmallAngle { .. }) => {
                    diag.rejected_small_angle += 1;
                    continue;
                }
                Err(IntersectionRejection::LargeResidual { .. }) => {
                    diag.rejected_residual += 1;
                    continue;
                }
                Err(IntersectionRejection::Triangulation(_)) => {
                    diag.failed_intersection += 1;
                    continue;
                }
            }
        } else {
            (None, None)
        };
        if point_world.is_some() {
            stats.control_points += 1;
        } else {
            stats.single_image_points += 1;
        }
        out.push(AerialControlPoint {
            map: None,
            ray_ground: None,
            tie_point_id: point_id.to_string(),
            mm,
            aerial,
            point_world,
            covariance_m2,
        });
    }
    out
}

/// An intersection in `frame` as a map point and its covariance rows (`None` when the frame cannot convert it).
fn in_map(frame: &MapFrame, x: &AerialIntersection) -> Option<([f64; 3], [[f64; 3]; 3])> {
    let point = frame.point_to_map(&x.triangulation.point_world).ok()?;
    let c = frame
        .covariance_to_map(&point, &x.triangulation.covariance_m2)
        .ok()?;
    let rows = [
        [c[(0, 0)], c[(0, 1)], c[(0, 2)]],
        [c[(1, 0)], c[(1, 1)], c[(1, 2)]],
        [c[(2, 0)], c[(2, 1)], c[(2, 2)]],
    ];
    Some(([point.x, point.y, point.z], rows))
}
