//! Sparse cloud of a panorama triplet (thesis 4.4.1): per side of the trajectory, three artificial
//! perspective views (view i from panorama i at yaw deviation i from the driving direction, pitch +30°),
//! AGAST corners + DAISY descriptors, matches views 1–2 and 2–3 linked through view 2 into three-view tracks,
//! outlier removal by trifocal point transfer (1, 2 → 3), and triangulation of the survivors in the original
//! equirectangular geometry with the same track triangulation as the nadir MM matching
//! ([`crate::nadir::mm_matching::tie_point::triangulate_track`]).
//!
//! Beyond the thesis, the cameras' relative positions are not taken from the recorded poses as they are: a
//! first, wider matching of both sides gives tracks from which the outer recordings' positions relative to the
//! centre are measured ([`relative_pose`]; the recorded ones are kept when the tracks do not agree on a
//! correction), and the matching, the trifocal check and the triangulation then use the measured geometry.
//!
//! Deterministic: views and sides run in parallel with ordered results; tracks are sorted by their
//! view-1/view-2 feature indices; no random sampling is involved (`seed` is kept for future estimators).

pub mod guided;
mod params;
pub mod relative_pose;

use guided::epipolar_candidates;
pub use params::SparseCloudParams;
use relative_pose::{estimate_relative_pose, PoseTrack, RelativePose, RelativePoseSettings};

use super::types::{SparseCloud, SparseCloudStats, SparsePoint, StreetSide};
use crate::campaign::Recording;
use crate::correspondence::PanoObservation;
use crate::features::agast::detect_agast;
use crate::features::daisy::DaisyExtractor;
use crate::geometry::perspective::PerspectiveView;
use crate::geometry::trifocal::TrifocalTensor;
use crate::geometry::{LocalOrigin, PanoramaCamera};
use crate::imaging::equirect::{level_for, PanoramaLevels};
use crate::matching::descriptor_match::{
    match_ratio, match_restricted, DescriptorMatch, MatchError,
};
use crate::nadir::mm_matching::tie_point::{triangulate_track, TrackTriangulation};
use crate::params::StageId;
use nalgebra::Vector3;
use rayon::prelude::*;
use std::collections::HashMap;

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("sparse_cloud", "3");

/// Corners of one view with their descriptors (row-major, `len` values each).
struct ViewFeatures {
    view: PerspectiveView,
    points_px: Vec<[f64; 2]>,
    descriptors: Vec<f32>,
    len: usize,
    corners: usize,
}

/// The pyramid level a view samples: the finest whose pixel is not smaller than the view's centre pixel.
fn view_level(view: &PerspectiveView, cam: &PanoramaCamera, max_level: usize) -> usize {
    level_for(
        cam.pixel_angle_rad(),
        view.centre_pixel_angle_rad(),
        max_level,
    )
}

/// The six views of the panorama of `rec` (three yaw deviations per side; a triplet member renders one per
/// side, but which one depends on its place in the triplet).
fn all_views(rec: &Recording, cam: &PanoramaCamera, p: &SparseCloudParams) -> Vec<PerspectiveView> {
    StreetSide::BOTH
        .iter()
        .flat_map(|&side| p.yaw_deviations_deg(side))
        .map(|d| {
            PerspectiveView::of_panorama(
                cam,
                p.view_width_px,
                p.vfov_deg,
                rec.heading_deg + d,
                p.pitch_deg,
            )
        })
        .collect()
}

/// Which rows of which pyramid levels the views of the panorama of `rec` (`width × height` px, levels
/// `0..=max_level`) sample: (level, (v0, v1)) in full-resolution rows.
pub fn panorama_bands(
    rec: &Recording,
    p: &SparseCloudParams,
    (width, height): (usize, usize),
    max_level: usize,
) -> Vec<(usize, (f64, f64))> {
    let cam = PanoramaCamera::from_recording(rec, width as u32, height as u32);
    let mut bands: Vec<(usize, (f64, f64))> = Vec::new();
    for view in all_views(rec, &cam, p) {
        let level = view_level(&view, &cam, max_level);
        let (v0, v1) = view.panorama_rows(&cam);
        match bands.iter_mut().find(|(l, _)| *l == level) {
            Some((_, r)) => *r = (r.0.min(v0), r.1.max(v1)),
            None => bands.push((level, (v0, v1))),
        }
    }
    bands
}

/// Render view `view`, detect AGAST corners and describe them with DAISY (corners whose descriptor window
/// leaves the view are dropped).
fn view_features(
    view: PerspectiveView,
    pano: &PanoramaLevels,
    cam: &PanoramaCamera,
    p: &SparseCloudParams,
) -> ViewFeatures {
    let img = view.render_levels(pano, cam, view_level(&view, cam, pano.max_level()));
    let corners = detect_agast(&img, &p.agast);
    let ex = DaisyExtractor::new(&img, &p.daisy);
    let len = ex.descriptor_len();
    let mut points_px = Vec::with_capacity(corners.len());
    let mut descriptors = Vec::with_capacity(corners.len() * len);
    let mut d = vec![0f32; len];
    for c in &corners {
        if ex.describe(c.x_px, c.y_px, &mut d) {
            points_px.push([c.x_px, c.y_px]);
            descriptors.extend_from_slice(&d);
        }
    }
    ViewFeatures {
        view,
        points_px,
        descriptors,
        len,
        corners: corners.len(),
    }
}

/// Matches of view `a`'s features (query) with view `b`'s (train): ratio test and mutual check, among the
/// candidates within `tolerance_px` of each feature's epipolar segment ([`guided`]) when it is set.
fn match_pair(
    a: &ViewFeatures,
    b: &ViewFeatures,
    len: usize,
    tolerance_px: Option<f64>,
    p: &SparseCloudParams,
) -> Result<Vec<DescriptorMatch>, MatchError> {
    let Some(tol) = tolerance_px else {
        return match_ratio(&a.descriptors, &b.descriptors, len, p.match_ratio, p.mutual);
    };
    let candidates = epipolar_candidates(
        &a.view,
        &b.view,
        &a.points_px,
        &b.points_px,
        p.min_depth_m,
        p.max_range_m,
        tol,
    );
    match_restricted(
        &a.descriptors,
        &b.descriptors,
        len,
        p.match_ratio,
        p.mutual,
        |qi| candidates[qi].iter().copied(),
    )
}

/// The three views of one side with their features (view i from panorama i).
fn side_features(
    side: StreetSide,
    recs: [&Recording; 3],
    panos: [&PanoramaLevels; 3],
    cams: &[PanoramaCamera; 3],
    p: &SparseCloudParams,
) -> Vec<ViewFeatures> {
    let deviations = p.yaw_deviations_deg(side);
    (0..3)
        .into_par_iter()
        .map(|i| {
            let view = PerspectiveView::of_panorama(
                &cams[i],
                p.view_width_px,
                p.vfov_deg,
                recs[i].heading_deg + deviations[i],
                p.pitch_deg,
            );
            view_features(view, panos[i], &cams[i], p)
        })
        .collect()
}

/// Matches views 1–2 and 2–3 of one side and links them through view 2 into three-view tracks (thesis
/// 4.4.1), sorted: (matches 1–2, matches 2–3, tracks of feature indices).
fn side_tracks(
    feats: &[ViewFeatures],
    tolerance_px: Option<f64>,
    p: &SparseCloudParams,
) -> (usize, usize, Vec<[usize; 3]>) {
    let len = feats[0].len;
    let pair = |a: usize, b: usize| match_pair(&feats[a], &feats[b], len, tolerance_px, p);
    let (m12, m23) = rayon::join(|| pair(0, 1), || pair(1, 2));
    // Lengths agree by construction; an error can only mean no descriptors at all.
    let (m12, m23) = (m12.unwrap_or_default(), m23.unwrap_or_default());
    let next: HashMap<usize, usize> = m23.iter().map(|m| (m.query, m.train)).collect();
    let mut tracks: Vec<[usize; 3]> = m12
        .iter()
        .filter_map(|m| next.get(&m.train).map(|&k| [m.query, m.train, k]))
        .collect();
    tracks.sort_unstable();
    (m12.len(), m23.len(), tracks)
}

/// The outer recordings' positions relative to the centre measured from the tracks of a wide first matching
/// of both sides ([`relative_pose`]); the corrections of the three centres, or `None` when the recorded
/// positions are kept (too few agreeing tracks, or a correction beyond `pose_max_correction_m`).
fn measured_relative_pose(
    sides: &[Vec<ViewFeatures>],
    cams: &[PanoramaCamera; 3],
    p: &SparseCloudParams,
    stats: &mut SparseCloudStats,
) -> Option<RelativePose> {
    let wide = p
        .epipolar_tolerance_px
        .map(|_| p.pose_epipolar_tolerance_px);
    let mut tracks = Vec::new();
    for feats in sides {
        let (_, _, t) = side_tracks(feats, wide, p);
        tracks.extend(t.iter().map(|t| PoseTrack {
            bearings_world: std::array::from_fn(|v| {
                let [x, y] = feats[v].points_px[t[v]];
                feats[v].view.pixel_to_ray_world(x, y)
            }),
        }));
    }
    stats.pose_tracks += tracks.len();
    let pixel_rad = sides.first()?.first()?.view.centre_pixel_angle_rad();
    let mut scales_rad = Vec::new();
    let mut scale_px = p.pose_epipolar_tolerance_px;
    while scale_px > p.trifocal_tolerance_px {
        scales_rad.push(scale_px * pixel_rad);
        scale_px /= 2.0;
    }
    scales_rad.push(p.trifocal_tolerance_px * pixel_rad);
    let settings = RelativePoseSettings {
        prior_sigma_m: p.pose_prior_sigma_m,
        ray_sigma_rad: pixel_rad,
        scales_rad,
        min_tracks: p.pose_min_tracks,
        max_correction_m: p.pose_max_correction_m,
    };
    // Centres relative to the middle one (world coordinates are 10⁵ m).
    let centres: [Vector3<f64>; 3] =
        std::array::from_fn(|i| cams[i].center_world - cams[1].center_world);
    estimate_relative_pose(&centres, &tracks, &settings)
}

/// The points of one side from its views' features, with its part of the counts.
fn side_cloud(
    side: StreetSide,
    recs: [&Recording; 3],
    feats: &[ViewFeatures],
    cams: &[PanoramaCamera; 3],
    p: &SparseCloudParams,
    stats: &mut SparseCloudStats,
) -> Vec<SparsePoint> {
    stats.views += 3;
    stats.corners += feats.iter().map(|f| f.corners).sum::<usize>();
    let (m12, m23, tracks) = side_tracks(feats, p.epipolar_tolerance_px, p);
    stats.matches_12 += m12;
    stats.matches_23 += m23;
    stats.tracks += tracks.len();

    // Trifocal point transfer 1, 2 → 3 in a local frame at the centre recording (world ≈ 10⁵ m).
    let origin = LocalOrigin::new(cams[1].center_world);
    let ms: Vec<_> = feats
        .iter()
        .map(|f| f.view.projection_matrix(&origin))
        .collect();
    let tensor = TrifocalTensor::from_cameras(&ms[0], &ms[1], &ms[2]);
    let track_params = TrackTriangulation {
        pano_sigma_px: p.pano_sigma_px,
        max_ray_residual_m: p.max_ray_residual_m,
        min_intersection_angle_deg: p.min_intersection_angle_deg,
    };
    let centre_id = &recs[1].image_id;
    let results: Vec<Result<Option<crate::correspondence::MmTiePoint>, ()>> = tracks
        .par_iter()
        .map(|t| {
            let px = |v: usize| feats[v].points_px[t[v]];
            if !(tensor.transfer_error(px(0), px(1), px(2)) <= p.trifocal_tolerance_px) {
                return Err(());
            }
            // Back to the original equirectangular pixels (thesis 4.4.1 last paragraph).
            let obs: Vec<PanoObservation> = (0..3)
                .map(|v| {
                    let [x, y] = px(v);
                    let (u_px, v_px) = feats[v].view.pixel_to_panorama(&cams[v], x, y);
                    PanoObservation {
                        image_id: recs[v].image_id.clone(),
                        u_px,
                        v_px,
                    }
                })
                .collect();
            // The centre first: the shared triangulation never drops its first ray.
            let members = [
                (&cams[1], obs[1].clone()),
                (&cams[0], obs[0].clone()),
                (&cams[2], obs[2].clone()),
            ];
            let Some(mut tie) = triangulate_track(String::new(), &members, &track_params) else {
                return Ok(None);
            };
            let point = Vector3::from(tie.point_world);
            if !((point - cams[1].center_world).norm() <= p.max_range_m) {
                return Ok(None);
            }
            // Observations in trajectory order.
            tie.observations
                .sort_by_key(|o| recs.iter().position(|r| r.image_id == o.image_id));
            Ok(Some(tie))
        })
        .collect();
    let mut points = Vec::new();
    for r in results {
        match r {
            Err(()) => stats.rejected_trifocal += 1,
            Ok(None) => stats.rejected_triangulation += 1,
            Ok(Some(mut tie)) => {
                tie.id = format!("{centre_id}#{}#{}", &side.label()[..1], points.len());
                points.push(SparsePoint { side, tie });
            }
        }
    }
    points
}

/// The sparse cloud of the triplet `recs` (trajectory order; `panos[i]` is the panorama of `recs[i]`, with
/// the bands of [`panorama_bands`]). Parameters are assumed valid
/// ([`Params::validate`](crate::params::Params::validate)).
pub fn sparse_cloud(
    recs: [&Recording; 3],
    panos: [&PanoramaLevels; 3],
    p: &SparseCloudParams,
) -> SparseCloud {
    let mut cams: [PanoramaCamera; 3] = std::array::from_fn(|i| {
        PanoramaCamera::from_recording(recs[i], panos[i].width_px as u32, panos[i].height_px as u32)
    });
    let mut sides: Vec<Vec<ViewFeatures>> = StreetSide::BOTH
        .par_iter()
        .map(|&side| side_features(side, recs, panos, &cams, p))
        .collect();
    let mut stats = SparseCloudStats::default();
    if p.relative_pose {
        if let Some(pose) = measured_relative_pose(&sides, &cams, p, &mut stats) {
            for (i, c) in pose.corrections_m.iter().enumerate() {
                cams[i].center_world += c;
                for feats in &mut sides {
                    feats[i].view.center_world += c;
                }
            }
            stats.pose_corrected = 1;
            stats.pose_corrections_m = pose.corrections_m.map(|c| [c.x, c.y, c.z]);
        }
    }
    let per_side: Vec<(Vec<SparsePoint>, SparseCloudStats)> = StreetSide::BOTH
        .par_iter()
        .zip(sides.par_iter())
        .map(|(&side, feats)| {
            let mut stats = SparseCloudStats::default();
            let pts = side_cloud(side, recs, feats, &cams, p, &mut stats);
            (pts, stats)
        })
        .collect();
    let mut points = Vec::new();
    for (pts, s) in per_side {
        points.extend(pts);
        stats.views += s.views;
        stats.corners += s.corners;
        stats.matches_12 += s.matches_12;
        stats.matches_23 += s.matches_23;
        stats.tracks += s.tracks;
        stats.rejected_trifocal += s.rejected_trifocal;
        stats.rejected_triangulation += s.rejected_triangulation;
    }
    stats.points = points.len();
    SparseCloud {
        recordings: std::array::from_fn(|i| recs[i].image_id.clone()),
        points,
        stats,
    }
}
