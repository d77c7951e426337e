//! The initial transform of a panorama's ground ortho into the orthophoto (the orthophoto's counterpart of
//! thesis 3.4.5.2). An orthophoto is north-up with a known pixel size, and the ortho is made north-up at the
//! orthophoto's working resolution, so the two differ by a translation only: the recording's position error
//! (plus the orthophoto's own error there). It is found like a frame's in translation mode
//! (`nadir::initial_transform`): both images Wallis-filtered; KAZE keypoints in each (the ortho's vehicle pixels
//! filled with the mean of the valid ones, its keypoints next to the mask left out); every ortho keypoint
//! matched by descriptor to the orthophoto keypoints within ± `max_localisation_error_m` of where the recorded
//! position puts it; the translation that most matches agree on within `ransac_threshold_px`
//! (`nadir::translation_consensus`), kept when it has at least `min_inliers`, beats the best competing
//! translation by `min_consensus_margin` and is not what chance gives (`max_false_alarms`, a-contrario). Its
//! offset must lie within `max_localisation_error_m`. Every failure rejects the recording, with its reason.

use super::OrthophotoParams;
use crate::geometry::{PointPair, Similarity2};
use crate::imaging::georef::GeoTransform;
use crate::imaging::pyramid::{PyramidError, TileSource};
use crate::nadir::aerial_patch::AerialWindow;
use crate::nadir::initial_transform::{
    rejected, wallis_kaze, Rejection, TransformParams, WindowedQuery,
};
use crate::nadir::ortho_mask::{fill_masked, near_mask};
use crate::nadir::translation_consensus::{consensus_doubt, translation_consensus};
use crate::nadir::{InitialTransform, OrthoGeoref, OrthoImage, TransformOutcome};
use nalgebra::Vector2;

/// Ortho pixel → full orthophoto pixel for the ortho's recorded placement.
pub fn nominal_transform(georef: &OrthoGeoref, photo: &GeoTransform) -> Similarity2 {
    let p0 = georef.pixel_to_world(0.0, 0.0);
    let p1 = georef.pixel_to_world(1.0, 0.0);
    let (u0, v0) = photo.world_to_pixel(p0.x, p0.y);
    let (u1, v1) = photo.world_to_pixel(p1.x, p1.y);
    Similarity2::from_ab(u1 - u0, v1 - v0, u0, v0)
}

/// Register `ortho` (recording `recording_id`) in the orthophoto tile `photo` (id `photo_id`, placed by
/// `photo_transform`); see the module documentation. `Err` only when the orthophoto cannot be read.
pub fn register_translation(
    ortho: &OrthoImage,
    recording_id: &str,
    photo: &dyn TileSource,
    photo_id: &str,
    photo_transform: &GeoTransform,
    p: &OrthophotoParams,
) -> Result<TransformOutcome, PyramidError> {
    let nominal = nominal_transform(&ortho.georef, photo_transform);
    let t = &p.transform;
    let margin_px = t.max_localisation_error_m / ortho.georef.gsd_m + 4.0;
    let size = (ortho.image.width, ortho.image.height);
    let found = match AerialWindow::read(photo, size, &nominal, margin_px)? {
        Some(win) => find_translation(ortho, &win, &nominal, photo_transform, t),
        None => Err(rejected(
            "the orthophoto does not cover the recording",
            0,
            0,
        )),
    };
    Ok(match found {
        Ok((ortho_to_aerial, matches, inliers, offset)) => {
            TransformOutcome::Accepted(InitialTransform {
                recording_id: recording_id.to_string(),
                aerial_id: photo_id.to_string(),
                ortho_to_aerial,
                matches,
                inliers,
                centre_offset_m: offset[0].hypot(offset[1]),
                centre_offset_world_m: offset,
                reused_from: None,
            })
        }
        Err(r) => TransformOutcome::Rejected {
            recording_id: recording_id.to_string(),
            aerial_id: photo_id.to_string(),
            reason: r.reason,
            matches: r.matches,
            inliers: r.inliers,
        },
    })
}

/// The translation of the module documentation in the orthophoto window `win`: the transform ortho px → full
/// orthophoto px, the matches, the inliers and the offset (east, north) of the recording, m.
fn find_translation(
    ortho: &OrthoImage,
    win: &AerialWindow,
    nominal: &Similarity2,
    photo_transform: &GeoTransform,
    t: &TransformParams,
) -> Result<(Similarity2, usize, usize, [f64; 2]), Rejection> {
    let scale = win.window.scale();
    // The matching window, in pixels of the orthophoto level the ortho meets (≈ ortho pixels).
    let window_px = t.max_localisation_error_m / (photo_transform.pixel_m * scale);
    let pairs = matched_keypoints(ortho, win, t, window_px)?;
    let n_matches = pairs.len();
    let threshold_px = t.ransac_threshold_px * scale;
    let c = translation_consensus(&pairs, nominal, threshold_px).ok_or_else(|| {
        rejected(
            format!("{n_matches} matches, no translation consensus"),
            n_matches,
            0,
        )
    })?;
    let n = c.inliers.len();
    if n < t.min_inliers {
        return Err(rejected(
            format!(
                "{n_matches} matches, a consensus of {n} inliers < {}",
                t.min_inliers
            ),
            n_matches,
            n,
        ));
    }
    let limits = (t.min_consensus_margin, t.max_false_alarms);
    if let Some(reason) = consensus_doubt(&c, n_matches, limits, t.ransac_threshold_px, window_px) {
        return Err(rejected(reason, n_matches, n));
    }
    // The ortho centre's shift in full orthophoto pixels, on the ground (north-up: v grows southwards).
    let centre = Vector2::new(ortho.image.width as f64, ortho.image.height as f64) / 2.0;
    let d = c.model.apply(&centre) - nominal.apply(&centre);
    let offset = [
        d.x * photo_transform.pixel_m,
        -d.y * photo_transform.pixel_m,
    ];
    let offset_m = offset[0].hypot(offset[1]);
    if !(offset_m <= t.max_localisation_error_m) {
        return Err(rejected(
            format!(
                "centre offset {offset_m:.2} m > {} m",
                t.max_localisation_error_m
            ),
            n_matches,
            n,
        ));
    }
    Ok((c.model, n_matches, n, offset))
}

/// KAZE keypoints of the Wallis-filtered ortho (off the vehicle mask) matched to those of the orthophoto
/// window within ± `window_px` of their nominal place, as (ortho px, full orthophoto px) pairs; fewer than
/// `min_inliers` is a rejection.
fn matched_keypoints(
    ortho: &OrthoImage,
    win: &AerialWindow,
    t: &TransformParams,
    window_px: f64,
) -> Result<Vec<PointPair>, Rejection> {
    let (w, h) = (ortho.image.width, ortho.image.height);
    if ortho.valid.len() != w * h {
        return Err(rejected(
            format!(
                "the ortho image is inconsistent: {w}×{h} px, {} mask values",
                ortho.valid.len()
            ),
            0,
            0,
        ));
    }
    let mm = wallis_kaze(
        &fill_masked(ortho),
        t,
        t.kaze_threshold_mm,
        "MM ortho image",
    )
    .map_err(|e| rejected(e, 0, 0))?;
    let photo = wallis_kaze(
        &win.window.image,
        t,
        t.kaze_threshold_aerial,
        "orthophoto window",
    )
    .map_err(|e| rejected(e, 0, 0))?;
    if mm.is_empty() || photo.is_empty() {
        return Err(rejected(
            format!(
                "no KAZE keypoints in the {} (thresholds {} / {})",
                if mm.is_empty() {
                    "MM ortho image"
                } else {
                    "orthophoto window"
                },
                t.kaze_threshold_mm,
                t.kaze_threshold_aerial
            ),
            0,
            0,
        ));
    }
    let mut query = WindowedQuery::default();
    for (i, k) in mm.keypoints.iter().enumerate() {
        let (u, v) = (f64::from(k.u_px), f64::from(k.v_px));
        if near_mask(&ortho.valid, w, h, u, v, t.mask_clearance_px) {
            continue;
        }
        let p = win.ortho_to_window.apply(&Vector2::new(u, v));
        query.push(mm.descriptor(i), (u, v), (p.x, p.y));
    }
    let pairs = query.match_pairs(&photo, window_px, t.match_ratio, |u, v| {
        win.window.to_full(u, v)
    })?;
    if pairs.len() < t.min_inliers {
        return Err(rejected(
            format!(
                "{} descriptor matches in the ±{window_px:.1} px windows < {} required ({} MM, {} orthophoto \
                 keypoints)",
                pairs.len(),
                t.min_inliers,
                query.len(),
                photo.len()
            ),
            pairs.len(),
            0,
        ));
    }
    Ok(pairs)
}
