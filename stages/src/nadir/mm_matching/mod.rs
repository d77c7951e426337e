//! MM-to-MM matching (thesis 3.4.4): corners of one recording's 3 cm ortho image found again in the ortho
//! images of the next one or two recordings along the trajectory, mapped back into the panoramas and
//! triangulated into MM tie points.
//!
//! Per window (detecting recording + neighbours):
//! 1. every ortho image is prepared once ([`prepared`]): masked pixels filled, KAZE features (upright, one
//!    octave) away from the vehicle mask;
//! 2. per neighbour, the pair transform ([`pair_transform`], 3.4.4.2–3.4.4.3): KAZE + RANSAC homography
//!    verified by the 30 cm centre check, else the recorded poses;
//! 3. Förstner corners of the detecting image ([`corners`], 3.4.4.4) transferred into each neighbour, located
//!    by NCC template matching ([`template`]) and verified again;
//! 4. tracks: a corner located in ≥ 1 neighbour becomes a tie point — 2-view accepted, 3-view preferred —
//!    through the exact inverse of the ortho-projection and ray triangulation ([`tie_point`], 3.4.4.5).
//!
//! Deterministic: the RANSAC seed of a pair is derived from `seed` and the two image ids; corners are
//! processed with ordered parallel collects; identical output for any thread count.

pub mod corners;
pub mod pair_transform;
pub mod params;
pub mod prepared;
pub mod template;
pub mod tie_point;

pub use pair_transform::PairTransform;
pub use params::MmMatchParams;

use crate::campaign::Recording;
use crate::correspondence::PanoObservation;
use crate::geometry::PanoramaCamera;
use crate::nadir::{MmWindowMatch, OrthoImage, PairMethod, PairReport, ViewGround};
use crate::params::{describe, Params, StageId};
use crate::rng::pair_seed;
use prepared::PreparedOrtho;
use rayon::prelude::*;

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("mm_match", "2");

/// One recording as the matcher sees it: its recorded pose, its 3 cm north-up ortho image, the panorama size.
#[derive(Clone, Copy, Debug)]
pub struct OrthoView<'a> {
    pub recording: &'a Recording,
    pub ortho: &'a OrthoImage,
    pub pano_width_px: u32,
    pub pano_height_px: u32,
}

/// A window whose parameters are invalid: no tie points, every pair reported with the reason.
fn invalid_window(detecting: &OrthoView, neighbours: &[OrthoView], reason: &str) -> MmWindowMatch {
    MmWindowMatch {
        recording_id: detecting.recording.image_id.clone(),
        pairs: neighbours
            .iter()
            .map(|n| PairReport {
                to_id: n.recording.image_id.clone(),
                method: PairMethod::Fallback {
                    reason: reason.to_string(),
                },
                kaze_matches: 0,
                kaze_inliers: 0,
                centre_check_error_m: None,
                corners_matched: 0,
            })
            .collect(),
        corners_detected: 0,
        tie_points: Vec::new(),
        ground_world: Vec::new(),
        neighbour_ground_world: Vec::new(),
    }
}

/// Thesis 3.4.4: corners detected in `detecting`'s ortho, transferred into each of `neighbours` (1 = pairs, 2 =
/// triples: the next two recordings along the trajectory), refined by template matching, verified, tracked,
/// mapped back to panorama pixels via the exact inverse and triangulated (2- or 3-view).
///
/// Never panics on user data: invalid parameters (see [`Params::validate`]; callers should validate
/// first) give a window without tie points whose pairs report the problem as their fallback reason; an empty
/// panorama size gives no tie points.
pub fn match_window(
    detecting: &OrthoView,
    neighbours: &[OrthoView],
    p: &MmMatchParams,
) -> MmWindowMatch {
    if let Err(errs) = p.validate() {
        return invalid_window(
            detecting,
            neighbours,
            &format!("invalid parameters: {}", describe(&errs)),
        );
    }
    let det_id = &detecting.recording.image_id;
    let det_prep = PreparedOrtho::new(detecting.ortho, p);
    let nb_preps: Vec<PreparedOrtho> = neighbours
        .iter()
        .map(|n| PreparedOrtho::new(n.ortho, p))
        .collect();
    let corners = corners::detect_corners(detecting, &det_prep, p);

    // Pair transforms and corner locations per neighbour.
    let mut pairs = Vec::with_capacity(neighbours.len());
    let mut located = Vec::with_capacity(neighbours.len());
    for (nb, nb_prep) in neighbours.iter().zip(&nb_preps) {
        let seed = pair_seed(p.seed, det_id, &nb.recording.image_id);
        let est = pair_transform::estimate_pair(detecting, &det_prep, nb, nb_prep, p, seed);
        let found = corners::match_corners(
            detecting,
            &det_prep,
            nb,
            nb_prep,
            &corners,
            &est.transform,
            p,
        );
        pairs.push(PairReport {
            to_id: nb.recording.image_id.clone(),
            method: est.method,
            kaze_matches: est.kaze_matches,
            kaze_inliers: est.kaze_inliers,
            centre_check_error_m: est.centre_check_error_m,
            corners_matched: found.iter().flatten().count(),
        });
        located.push(found);
    }

    // Tracks → panorama observations → triangulation (3.4.4.5).
    let pano_ok = |v: &OrthoView| v.pano_width_px > 0 && v.pano_height_px > 0;
    let mut tie_points = Vec::new();
    let mut ground_world = Vec::new();
    let mut neighbour_ground_world = Vec::new();
    if pano_ok(detecting) {
        let det_cam = tie_point::camera_of(detecting);
        let nb_cams: Vec<Option<PanoramaCamera>> = neighbours
            .iter()
            .map(|n| pano_ok(n).then(|| tie_point::camera_of(n)))
            .collect();
        let track = tie_point::TrackTriangulation::from(p);
        type Located = (crate::correspondence::MmTiePoint, [f64; 3], Vec<ViewGround>);
        let results: Vec<Option<Located>> = corners
            .par_iter()
            .enumerate()
            .map(|(i, c)| {
                let first = tie_point::pano_observation(detecting, &det_cam, c.u_px, c.v_px)?;
                let mut members: Vec<(&PanoramaCamera, PanoObservation)> =
                    Vec::with_capacity(1 + neighbours.len());
                let mut views = Vec::with_capacity(neighbours.len());
                members.push((&det_cam, first));
                for (k, nb) in neighbours.iter().enumerate() {
                    let (Some(cam), Some(loc)) = (&nb_cams[k], located[k][i]) else {
                        continue;
                    };
                    if let Some(obs) = tie_point::pano_observation(nb, cam, loc.u_px, loc.v_px) {
                        members.push((cam, obs));
                        let g = nb.ortho.georef.pixel_to_world(loc.u_px, loc.v_px);
                        views.push(ViewGround {
                            recording_id: nb.recording.image_id.clone(),
                            ground_world: [g.x, g.y, g.z],
                        });
                    }
                }
                if members.len() < 2 {
                    return None;
                }
                let tp = tie_point::triangulate_track(format!("{det_id}#{i}"), &members, &track)?;
                // Only the neighbour views the triangulation kept.
                views.retain(|v| tp.observations.iter().any(|o| o.image_id == v.recording_id));
                let g = detecting.ortho.georef.pixel_to_world(c.u_px, c.v_px);
                Some((tp, [g.x, g.y, g.z], views))
            })
            .collect();
        for (tp, g, views) in results.into_iter().flatten() {
            tie_points.push(tp);
            ground_world.push(g);
            neighbour_ground_world.push(views);
        }
    }
    MmWindowMatch {
        recording_id: det_id.clone(),
        pairs,
        corners_detected: corners.len(),
        tie_points,
        ground_world,
        neighbour_ground_world,
    }
}
