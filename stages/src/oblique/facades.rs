//! Façade planes, visibility hypothesis and thinning of one panorama triplet (thesis 4.4.2–4.4.4): the
//! per-triplet `facades` stage.
//!
//! 1. Collinearity criterion on the three recording locations ([`trajectory`]); if it fails, no side gets a
//!    plane (both sides counted in `sides_without_plane`).
//! 2. Per side (points carry their `side`): MLESAC planes with the reference vector horizontal and
//!    perpendicular to the centre recording's `heading`, max angle 5°, band 0.5 m, ≥ 10 inliers, in a local
//!    frame at the centre recording; normal oriented towards the recording; local frame of eq. 4/7
//!    ([`plane`]).
//! 3. Occlusion: sparse points of either side between plane and centre recording ([`occlusion`]); planes with
//!    more than `occlusion_max_points` are dropped (counted in `occluded`).
//! 4. Visibility hypothesis per oblique image: θ, φ, theoretical resolution, centroid inside the image
//!    ([`visibility`]).
//! 5. Box-grid thinning of the inliers that the centre recording observes: the patch centres ([`thinning`]).
//!
//! The cloud may hold the points of neighbouring triplets too (`SparseCloud::with_neighbours`): they help
//! fit the planes, but only points observed by the centre panorama become patch centres.
//!
//! Deterministic: MLESAC and thinning seeds mix `seed` with a hash of the centre `image_id`, the side and the
//! plane index. Never panics on user data: invalid params, a centre that is not the cloud's centre, or
//! non-finite positions give no planes (counted as sides without a plane).

// `!(x > t)` is used on purpose throughout: it also rejects NaN, which `x <= t` would let through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod occlusion;
pub mod params;
pub mod plane;
pub mod thinning;
pub mod trajectory;
pub mod visibility;

pub use params::{FacadeParams, ThinningSplit};

use self::occlusion::OcclusionCorridor;
use self::plane::{fit_side_planes, SidePlaneSettings};
use self::thinning::box_grid_thin;
use self::trajectory::{check_collinearity, reference_normal};
use self::visibility::{check_visibility, horizontal_axes};
use crate::campaign::{AerialImage, Recording};
use crate::geometry::local_frame::LocalOrigin;
use crate::geometry::FrameCamera;
use crate::oblique::types::{FacadePlane, FacadeStats, SparseCloud, StreetSide, TripletFacades};
use crate::params::{Params, StageId};
use crate::rng::{mix_seed, stable_hash};
use nalgebra::Vector3;

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("facades", "4");

fn to_array(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// Finds the façade planes of one triplet (module documentation). `triplet` holds recordings i−1, i, i+1 in
/// trajectory order (`triplet[1]` must be `cloud.centre()`); `oblique` are the candidate oblique images.
pub fn find_facades(
    cloud: &SparseCloud,
    triplet: [&Recording; 3],
    oblique: &[AerialImage],
    p: &FacadeParams,
) -> TripletFacades {
    let mut stats = FacadeStats {
        candidate_points: cloud.points.len(),
        ..Default::default()
    };
    let recording = cloud.centre().to_string();
    let centre = triplet[1];
    let usable = p.validate().is_ok()
        && centre.image_id == recording
        && check_collinearity(
            triplet,
            p.max_collinearity_deviation_m,
            p.min_triplet_span_m,
        )
        .is_ok();
    if !usable {
        stats.sides_without_plane = StreetSide::BOTH.len();
        return TripletFacades {
            recording,
            planes: Vec::new(),
            stats,
        };
    }

    // Local frame at the centre recording (thesis coordinates are ≈ 10⁵ m).
    let origin = LocalOrigin::new(Vector3::new(centre.x, centre.y, centre.z));
    let recording_local = Vector3::zeros();
    let finite: Vec<bool> = cloud
        .points
        .iter()
        .map(|sp| sp.tie.point_world.iter().all(|c| c.is_finite()))
        .collect();
    let local: Vec<Vector3<f64>> = cloud
        .points
        .iter()
        .map(|sp| origin.to_local(&Vector3::from(sp.tie.point_world)))
        .collect();
    let occluder_candidates: Vec<Vector3<f64>> = local
        .iter()
        .zip(&finite)
        .filter(|(_, &ok)| ok)
        .map(|(q, _)| *q)
        .collect();
    let mut cameras: Vec<(&AerialImage, FrameCamera)> = oblique
        .iter()
        .map(|img| (img, FrameCamera::from_aerial(img)))
        .collect();
    cameras.sort_by(|a, b| a.0.image_id.cmp(&b.0.image_id));

    let triplet_hash = stable_hash(&recording);
    let mut planes = Vec::new();
    for side in StreetSide::BOTH {
        let side_idx: Vec<usize> = (0..cloud.points.len())
            .filter(|&i| cloud.points[i].side == side && finite[i])
            .collect();
        let side_points: Vec<Vector3<f64>> = side_idx.iter().map(|&i| local[i]).collect();
        let settings = SidePlaneSettings {
            reference: reference_normal(centre, side),
            max_angle_deg: p.max_angle_deg,
            inlier_band_m: p.inlier_band_m,
            min_points: p.min_points,
            max_planes: p.max_planes_per_side,
            max_trials: p.mlesac_max_trials,
            confidence: p.mlesac_confidence,
            em_iterations: p.mlesac_em_iterations,
        };
        let side_seed = mix_seed(p.seed, triplet_hash ^ stable_hash(side.label()));
        let found = fit_side_planes(&side_points, &recording_local, &settings, |k| {
            mix_seed(side_seed, 2 * k as u64)
        });
        if found.is_empty() {
            stats.sides_without_plane += 1;
        }
        for (k, lp) in found.into_iter().enumerate() {
            let inliers: Vec<usize> = lp.inliers.iter().map(|&j| side_idx[j]).collect();
            // The corridor uses the plane's horizontal / vertical axes: the eigenvector axes of eq. 4/7 may be
            // rotated a few degrees, and a rotated rectangle reaches down to street level at its corners.
            let (horizontal, up) = horizontal_axes(&lp.normal);
            let corridor = OcclusionCorridor::new(
                lp.centroid,
                lp.normal,
                horizontal,
                up,
                inliers.iter().map(|&i| local[i]),
                p.inlier_band_m,
            );
            let occluding_points = corridor.count(&recording_local, &occluder_candidates);
            if occluding_points > p.occlusion_max_points {
                stats.occluded += 1;
                continue;
            }
            // Patch centres are the inliers close to the plane (`max_centre_offset_m`) that the centre panorama
            // observes: a point of a neighbouring triplet
            // that it does not observe would need a projected observation, which carries the recordings'
            // relative pose error into the correspondence.
            let observed: Vec<usize> = inliers
                .iter()
                .copied()
                .filter(|&i| {
                    cloud.points[i]
                        .tie
                        .observations
                        .iter()
                        .any(|o| o.image_id == recording)
                })
                .filter(|&i| {
                    !((local[i] - lp.centroid).dot(&lp.normal).abs() > p.max_centre_offset_m)
                })
                .collect();
            // Thinning in the local frame, relative to the centroid (thesis 4.4.4).
            let rel: Vec<[f64; 3]> = observed
                .iter()
                .map(|&i| to_array(&(local[i] - lp.centroid)))
                .collect();
            let kept = box_grid_thin(
                &rel,
                p.thinning_max_points_per_box,
                p.thinning_max_box_m,
                p.thinning_split,
                mix_seed(side_seed, 2 * k as u64 + 1),
            );
            let thinned: Vec<usize> = kept.iter().map(|&j| observed[j]).collect();
            let centroid_world = origin.to_world(&lp.centroid);
            let mut views = Vec::new();
            for (img, cam) in &cameras {
                match check_visibility(
                    &img.image_id,
                    cam,
                    &lp.normal,
                    &centroid_world,
                    p.max_view_angle_deg,
                    p.max_resolution_m,
                ) {
                    Ok(view) => views.push(view),
                    Err(_) => stats.rejected_views += 1,
                }
            }
            stats.visible_views += views.len();
            stats.planes += 1;
            stats.inliers += inliers.len();
            stats.thinned += thinned.len();
            planes.push(FacadePlane {
                side,
                normal_world: to_array(&lp.normal),
                centroid_world: to_array(&centroid_world),
                axis_u_world: to_array(&lp.axis_u),
                axis_v_world: to_array(&lp.axis_v),
                inliers,
                thinned,
                occluding_points,
                views,
            });
        }
    }
    TripletFacades {
        recording,
        planes,
        stats,
    }
}
