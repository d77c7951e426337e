//! The initial transform between a recording's MM ortho image and one overlapping aerial nadir image — thesis
//! 3.4.5.2 ("Finding a transformation between MM and aerial image patch").
//!
//! Steps, as in the thesis:
//! 1. the aerial patch covering the ortho footprint enlarged by the expected maximum localisation error
//!    ([`super::aerial_patch::extract_patch`]);
//! 2. a Wallis filter on both the MM ortho image and the aerial patch (masked vehicle pixels are first set to the
//!    mean of the valid ones so that the mask edge does not become a strong artificial edge);
//! 3. two KAZE detector instances (MM threshold, aerial threshold) and one descriptor configuration (extended 128,
//!    upright, one octave);
//! 4. every MM keypoint not on (or next to) masked pixels is turned into a world point on the ortho plane and
//!    projected into the aerial image; one-to-many descriptor matching against the aerial keypoints inside a
//!    window of ± the maximum localisation error (in aerial pixels) around that prediction;
//! 5. a similarity (ortho px → full aerial px) by RANSAC; hypotheses whose scale or rotation differ from the
//!    recorded-pose geometry by more than the configured tolerances are not considered (the ortho image was
//!    made at the aerial GSD and orientation, [`super::aerial_patch::ortho_params_for_aerial`]);
//! 6. plausibility: the ortho centre mapped by the transform and by the recorded pose must lie within the
//!    expected maximum localisation error of each other on the ground, else the transform is discarded.
//!
//! Option (thesis 3.4.5.2, last paragraph): [`super::neighbour_transform::reuse_neighbour`] adapts a
//! neighbouring recording's transform to this recording through the recorded relative pose.

use super::aerial_patch::{aerial_ground_similarity, extract_patch, level_of_scale, AerialPatch};
use super::ortho::{OrthoGeoref, OrthoImage};
use super::ortho_mask::{fill_masked, near_mask};
use super::registration::{InitialTransform, TransformOutcome};
use super::translation_consensus::{consensus_doubt, translation_consensus};
use crate::campaign::{AerialImage, Recording};
use crate::estimators::{ransac_filtered, RansacParams};
use crate::features::kaze::{detect_and_describe, Features, KazeParams};
use crate::geometry::{intersect_ray_plane, FrameCamera, Plane, PointPair, Similarity2};
use crate::imaging::pyramid::{PyramidError, TileSource};
use crate::imaging::wallis::{wallis_filter, WallisParams};
use crate::imaging::GrayImage;
use crate::matching::descriptor_match::match_windowed;
use crate::params::{describe, Params, StageId};
use crate::rng::pair_seed;
use nalgebra::{Vector2, Vector3};

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("transform", "5");

crate::params! {
    /// Parameters of the initial MM→aerial transform (thesis 3.4.5.2). Intensities are 0..1.
    pub struct TransformParams {
        /// Expected maximum localisation error of the MM platform: enlarges the aerial patch, sets the matching
        /// window (± this, in aerial pixels) and the plausibility limit of the centre offset.
        max_localisation_error_m: f64 = 1.5, unit "m", above 0.0, max 50.0;
        /// Wallis target mean m_f.
        wallis_target_mean: f32 = WallisParams::default().target_mean;
        /// Wallis target standard deviation s_f.
        wallis_target_std: f32 = WallisParams::default().target_std, above 0.0;
        /// Wallis contrast expansion constant c.
        wallis_contrast_c: f32 = WallisParams::default().contrast_c, min 0.0, max 1.0;
        /// Wallis brightness forcing constant b.
        wallis_brightness_b: f32 = WallisParams::default().brightness_b, min 0.0, max 1.0;
        /// Wallis statistics window side (odd; even values are rounded up).
        wallis_window_px: usize = WallisParams::default().window_px, unit "px", min 3, max 501;
        /// KAZE detector threshold (det Hessian) of the MM instance.
        kaze_threshold_mm: f32 = 0.0001, above 0.0;
        /// KAZE detector threshold of the aerial instance.
        kaze_threshold_aerial: f32 = 0.0001, above 0.0;
        /// KAZE octaves (thesis: one, the images share a similar scale).
        kaze_octaves: usize = 1, min 1, max 8;
        /// KAZE sub-levels per octave; octaves × sub-levels must give at least 3 levels.
        kaze_sublevels: usize = 4, min 1, max 16;
        /// 128-value descriptor (thesis: extended).
        descriptor_extended: bool = true;
        /// No rotation invariance (thesis: upright).
        upright: bool = true;
        /// Ratio test between the nearest and second-nearest aerial descriptor inside the window
        /// (d1 < ratio·d2); values above 1 keep every nearest neighbour.
        match_ratio: f32 = 0.9, above 0.0;
        /// MM keypoints with a masked (vehicle) pixel within this radius, in ortho pixels, are not used.
        mask_clearance_px: f64 = 3.0, unit "px", min 0.0, max 100.0;
        /// RANSAC inlier threshold, in aerial pixels at the working level (the pixels the registration works
        /// in, `OrthoParams::registration_gsd_m`).
        ransac_threshold_px: f64 = 2.0, unit "px", above 0.0;
        /// RANSAC confidence.
        ransac_confidence: f64 = 0.999, above 0.0, below 1.0;
        /// RANSAC maximum number of samples.
        ransac_max_iterations: usize = 2000, min 1;
        /// Fewer RANSAC inliers than this reject the transform (a similarity needs 2).
        min_inliers: usize = 6, min 2;
        /// Largest relative difference between a hypothesis' scale and the recorded-pose scale (ortho px →
        /// aerial px).
        max_scale_deviation: f64 = 0.1, above 0.0, below 1.0;
        /// Largest difference between a hypothesis' rotation and the recorded-pose rotation.
        max_rotation_deg: f64 = 5.0, unit "deg", above 0.0, max 180.0;
        /// Seed of RANSAC; each (recording, aerial image) pair derives its own stream from it.
        seed: u64 = 1;
        /// Estimate scale and rotation too (2-point RANSAC similarity within `max_scale_deviation` and
        /// `max_rotation_deg`) instead of the translation alone (exhaustive 1-point consensus,
        /// [`super::translation_consensus`]).
        estimate_shape: bool = false;
        /// Fewer inliers than this fraction of the descriptor matches reject the transform.
        min_inlier_ratio: f64 = 0.0, min 0.0, max 1.0;
        /// The winning translation must have at least this many times the support of the best competing one
        /// (more than 2 × `ransac_threshold_px` away), else the content is ambiguous. Translation mode only.
        min_consensus_margin: f64 = 1.0, min 1.0;
        /// Agreement across the recording's nadir images (`nadir::transform_agreement`): a transform whose
        /// implied recording offset lies farther than this from the median offset implied by ≥ 2 other accepted
        /// transforms of the same recording is rejected; 0 = no check.
        max_offset_disagreement_m: f64 = 1.2, unit "m", min 0.0;
        /// A-contrario test of the translation consensus (translation mode): reject it when random matches would
        /// give a consensus as large this often or more (expected number of false alarms,
        /// [`super::translation_consensus::false_alarms`]). 0.1: with ±15 px windows and a 2 px threshold a
        /// consensus of 7 among 105 matches (NFA 0.40, what chance gives) is rejected, 6 among 60 (NFA 0.09) and
        /// 6 among 8 (NFA < 10⁻⁶) are kept.
        max_false_alarms: f64 = 0.1, above 0.0;
    }
    check(p, v) {
        crate::params::check_finite("wallis_target_mean", &p.wallis_target_mean, v);
        if p.kaze_octaves.saturating_mul(p.kaze_sublevels) < 3 {
            v.push(crate::params::Violation::new(
                "kaze_sublevels",
                format!(
                    "kaze_octaves × kaze_sublevels must give at least 3 levels, got {} × {}",
                    p.kaze_octaves, p.kaze_sublevels
                ),
            ));
        }
    }
}

impl TransformParams {
    /// The Wallis filter settings.
    pub fn wallis(&self) -> WallisParams {
        WallisParams {
            target_mean: self.wallis_target_mean,
            target_std: self.wallis_target_std,
            contrast_c: self.wallis_contrast_c,
            brightness_b: self.wallis_brightness_b,
            window_px: self.wallis_window_px,
        }
    }

    /// One KAZE instance (thesis: the MM and aerial instances differ only in `threshold`).
    pub fn kaze(&self, threshold: f32) -> KazeParams {
        KazeParams {
            threshold,
            octaves: self.kaze_octaves,
            sublevels: self.kaze_sublevels,
            upright: self.upright,
            extended: self.descriptor_extended,
            ..KazeParams::default()
        }
    }

    /// RANSAC settings (seed not yet specialised to a pair).
    pub fn ransac(&self) -> RansacParams {
        RansacParams {
            threshold: self.ransac_threshold_px,
            confidence: self.ransac_confidence,
            max_iterations: self.ransac_max_iterations,
            seed: self.seed,
        }
    }
}

/// The similarity ortho px → full aerial px implied by the recorded pose (ortho plane projected through the
/// aerial camera), fitted by least squares to the footprint's corners and centre. `None` if the footprint does
/// not project in front of the camera.
pub fn nominal_transform(georef: &OrthoGeoref, cam: &FrameCamera) -> Option<Similarity2> {
    let (w, h) = (georef.width_px as f64, georef.height_px as f64);
    let mut pairs = [PointPair::new(0.0, 0.0, 0.0, 0.0); 5];
    for (pair, (x, y)) in
        pairs
            .iter_mut()
            .zip([(0.0, 0.0), (w, 0.0), (w, h), (0.0, h), (0.5 * w, 0.5 * h)])
    {
        let (u, v) = cam.project_world(&georef.pixel_to_world(x, y))?;
        *pair = PointPair::new(x, y, u, v);
    }
    Similarity2::least_squares(&pairs)
}

/// Horizontal offset (east, north), metres, from the recorded foot point (the ortho centre placed by the recorded
/// pose) to where `ortho_to_aerial` puts the ortho centre on the ground (its aerial pixel's ray intersected with the
/// horizontal plane of the foot point). With a correct transform this is the correction of the recorded position:
/// true ≈ recorded + offset.
pub fn centre_offset_world(
    ortho_to_aerial: &Similarity2,
    georef: &OrthoGeoref,
    cam: &FrameCamera,
) -> Option<[f64; 2]> {
    let centre = Vector2::new(georef.width_px as f64 / 2.0, georef.height_px as f64 / 2.0);
    let a = ortho_to_aerial.apply(&centre);
    let ground = intersect_ray_plane(
        &cam.pixel_ray(a.x, a.y),
        &Plane::horizontal(georef.foot_world[2]),
    )?;
    let offset = [
        ground.x - georef.foot_world[0],
        ground.y - georef.foot_world[1],
    ];
    offset.iter().all(|c| c.is_finite()).then_some(offset)
}

/// Wraps an angle difference into [−180°, 180°).
fn wrap_deg(a: f64) -> f64 {
    (a + 180.0).rem_euclid(360.0) - 180.0
}

/// The KAZE features of the Wallis-filtered image with threshold `threshold`; `Err` names what failed.
pub(crate) fn wallis_kaze(
    img: &GrayImage,
    p: &TransformParams,
    threshold: f32,
    what: &str,
) -> Result<Features, String> {
    let filtered = wallis_filter(img, &p.wallis())
        .map_err(|e| format!("Wallis filter of the {what} failed: {e}"))?;
    Ok(detect_and_describe(&filtered, &p.kaze(threshold)))
}

/// Thesis 3.4.5.2 for one (recording, aerial image): see the module documentation. `mm_ortho` is the recording's
/// ortho image (ideally made with [`super::aerial_patch::ortho_params_for_aerial`] for this aerial image),
/// `aerial` the grey aerial image (0..1; its pyramid, read at the ortho's level) of the `cameras.csv` row
/// `aerial_row`. Never panics on data: every failure is a `Rejected` with a reason; `Err` only when the image
/// cannot be read.
pub fn initial_transform(
    rec: &Recording,
    mm_ortho: &OrthoImage,
    aerial: &dyn TileSource,
    aerial_row: &AerialImage,
    p: &TransformParams,
) -> Result<TransformOutcome, PyramidError> {
    // The only reading: the aerial patch, at the level the ortho was made for (its nominal scale ≈ 2^level).
    let cam = FrameCamera::from_aerial(aerial_row);
    let patch = match nominal_transform(&mm_ortho.georef, &cam) {
        Some(nominal) => extract_patch(
            aerial,
            &cam,
            &mm_ortho.georef,
            p.max_localisation_error_m,
            level_of_scale(nominal.scale),
        )?,
        None => None,
    };
    let size = (aerial.layout().width, aerial.layout().height);
    Ok(
        match find_transform(rec, mm_ortho, size, patch.as_ref(), aerial_row, p) {
            Ok(t) => TransformOutcome::Accepted(t),
            Err(r) => r.into_outcome(rec, aerial_row),
        },
    )
}

/// Why a transform (or an orthophoto registration) was rejected, with the matches and inliers it had got to by
/// then.
pub(crate) struct Rejection {
    pub(crate) reason: String,
    pub(crate) matches: usize,
    pub(crate) inliers: usize,
}

impl Rejection {
    /// The outcome of (recording `rec`, aerial image `aerial_row`) rejected for this reason.
    fn into_outcome(self, rec: &Recording, aerial_row: &AerialImage) -> TransformOutcome {
        TransformOutcome::Rejected {
            recording_id: rec.image_id.clone(),
            aerial_id: aerial_row.image_id.clone(),
            reason: self.reason,
            matches: self.matches,
            inliers: self.inliers,
        }
    }
}

pub(crate) fn rejected(reason: impl Into<String>, matches: usize, inliers: usize) -> Rejection {
    Rejection {
        reason: reason.into(),
        matches,
        inliers,
    }
}

/// MM keypoints to be matched with windowed descriptor matching: their descriptors, ortho pixels and
/// predicted positions in the other image's window.
#[derive(Default)]
pub(crate) struct WindowedQuery {
    descriptors: Vec<f32>,
    ortho_px: Vec<(f64, f64)>,
    predicted_px: Vec<[f64; 2]>,
}

impl WindowedQuery {
    /// Adds a keypoint with its descriptor, its ortho pixel and its predicted (window) pixel.
    pub(crate) fn push(&mut self, descriptor: &[f32], ortho_px: (f64, f64), predicted: (f64, f64)) {
        self.descriptors.extend_from_slice(descriptor);
        self.ortho_px.push(ortho_px);
        self.predicted_px.push([predicted.0, predicted.1]);
    }

    /// How many keypoints were added.
    pub(crate) fn len(&self) -> usize {
        self.ortho_px.len()
    }

    /// The keypoints matched to `train`'s within ±`window_px` of their predictions (Lowe `ratio`), each as a
    /// pair (ortho pixel → full pixel of the other image, through `to_full` from window pixels).
    pub(crate) fn match_pairs(
        &self,
        train: &Features,
        window_px: f64,
        ratio: f32,
        to_full: impl Fn(f64, f64) -> (f64, f64),
    ) -> Result<Vec<PointPair>, Rejection> {
        let train_px: Vec<[f64; 2]> = train
            .keypoints
            .iter()
            .map(|k| [f64::from(k.u_px), f64::from(k.v_px)])
            .collect();
        let matched = match_windowed(
            &self.descriptors,
            &self.predicted_px,
            &train.descriptors,
            &train_px,
            train.descriptor_len,
            window_px,
            ratio,
        )
        .map_err(|e| rejected(format!("descriptor matching failed: {e}"), 0, 0))?;
        Ok(matched
            .iter()
            .flatten()
            .map(|m| {
                let (u, v) = self.ortho_px[m.query];
                let (fu, fv) = to_full(train_px[m.train][0], train_px[m.train][1]);
                PointPair::new(u, v, fu, fv)
            })
            .collect())
    }
}

/// Steps 2–6 of the module documentation.
fn find_transform(
    rec: &Recording,
    mm_ortho: &OrthoImage,
    aerial_size_px: (usize, usize),
    patch: Option<&AerialPatch>,
    aerial_row: &AerialImage,
    p: &TransformParams,
) -> Result<InitialTransform, Rejection> {
    check_inputs(rec, mm_ortho, aerial_size_px, aerial_row, p)?;
    let georef = &mm_ortho.georef;
    let cam = FrameCamera::from_aerial(aerial_row);
    let max_err_m = p.max_localisation_error_m;
    let nominal = nominal_transform(georef, &cam).ok_or_else(|| {
        rejected(
            "the ortho footprint does not project into the aerial image",
            0,
            0,
        )
    })?;
    let patch = patch.ok_or_else(|| {
        rejected(
            "the ortho footprint (plus the localisation error) does not overlap the aerial image",
            0,
            0,
        )
    })?;
    let aerial_gsd_m = aerial_ground_similarity(&cam, georef.foot_world)
        .map(|(gsd, _)| gsd)
        .unwrap_or_else(|| cam.gsd_at(&Vector3::from(georef.foot_world)));
    if !(aerial_gsd_m.is_finite() && aerial_gsd_m > 0.0) {
        return Err(rejected(
            "the aerial GSD at the foot point is not positive",
            0,
            0,
        ));
    }
    // The matching window in patch pixels (the patch is at the working level: `scale` full pixels each).
    let window_px = max_err_m / (aerial_gsd_m * patch.scale);
    let pairs = matched_keypoints(mm_ortho, patch, &cam, p, window_px)?;
    let n_matches = pairs.len();
    let (model, n_inliers) = if p.estimate_shape {
        similarity_by_ransac(&pairs, &nominal, patch.scale, rec, aerial_row, p)?
    } else {
        similarity_by_translation_consensus(&pairs, &nominal, patch.scale, window_px, p)?
    };
    if n_inliers < p.min_inliers {
        return Err(rejected(
            format!(
                "{n_matches} matches, RANSAC found {n_inliers} inliers < {}",
                p.min_inliers
            ),
            n_matches,
            n_inliers,
        ));
    }
    if (n_inliers as f64) < p.min_inlier_ratio * n_matches as f64 {
        return Err(rejected(
            format!(
                "{n_matches} matches, {n_inliers} inliers < {} of the matches",
                p.min_inlier_ratio
            ),
            n_matches,
            n_inliers,
        ));
    }
    // Plausibility (thesis 3.4.5.2): the projected MM image centre must lie within the expected error.
    let offset = centre_offset_world(&model, georef, &cam).ok_or_else(|| {
        rejected(
            "the transformed ortho centre does not meet the ground plane",
            n_matches,
            n_inliers,
        )
    })?;
    let centre_offset_m = offset[0].hypot(offset[1]);
    if !(centre_offset_m <= max_err_m) {
        return Err(rejected(
            format!("centre offset {centre_offset_m:.2} m > {max_err_m} m"),
            n_matches,
            n_inliers,
        ));
    }
    Ok(InitialTransform {
        recording_id: rec.image_id.clone(),
        aerial_id: aerial_row.image_id.clone(),
        ortho_to_aerial: model,
        matches: n_matches,
        inliers: n_inliers,
        centre_offset_m,
        centre_offset_world_m: offset,
        reused_from: None,
    })
}

/// The parameters, the aerial image's size against its row and the ortho against its georeference.
fn check_inputs(
    rec: &Recording,
    mm_ortho: &OrthoImage,
    (aerial_w, aerial_h): (usize, usize),
    aerial_row: &AerialImage,
    p: &TransformParams,
) -> Result<(), Rejection> {
    if let Err(errs) = p.validate() {
        return Err(rejected(
            format!("invalid transform parameters: {}", describe(&errs)),
            0,
            0,
        ));
    }
    if aerial_w != aerial_row.width_px as usize || aerial_h != aerial_row.height_px as usize {
        return Err(rejected(
            format!(
                "aerial image {} is {}×{} px but aerial/nadir/cameras.csv says {}×{}; fix the width/height columns",
                aerial_row.file, aerial_w, aerial_h, aerial_row.width_px, aerial_row.height_px
            ),
            0,
            0,
        ));
    }
    let georef = &mm_ortho.georef;
    let (w, h) = (mm_ortho.image.width, mm_ortho.image.height);
    if w != georef.width_px || h != georef.height_px || mm_ortho.valid.len() != w * h {
        return Err(rejected(
            format!(
                "ortho image of {} is inconsistent: {w}×{h} px, georeference {}×{}, {} mask values",
                rec.image_id,
                georef.width_px,
                georef.height_px,
                mm_ortho.valid.len()
            ),
            0,
            0,
        ));
    }
    Ok(())
}

/// Steps 2–4: Wallis + two KAZE detector instances with one descriptor configuration, then every MM keypoint off
/// the mask → ortho plane (world) → aerial patch pixel, matched inside ± `window_px` of that prediction. Returns
/// the matches as (ortho px, full aerial px) pairs; too few is a rejection.
fn matched_keypoints(
    mm_ortho: &OrthoImage,
    patch: &AerialPatch,
    cam: &FrameCamera,
    p: &TransformParams,
    window_px: f64,
) -> Result<Vec<PointPair>, Rejection> {
    let mm_features = wallis_kaze(
        &fill_masked(mm_ortho),
        p,
        p.kaze_threshold_mm,
        "MM ortho image",
    )
    .map_err(|e| rejected(e, 0, 0))?;
    let aerial_features = wallis_kaze(&patch.image, p, p.kaze_threshold_aerial, "aerial patch")
        .map_err(|e| rejected(e, 0, 0))?;
    for (features, what, threshold) in [
        (&mm_features, "the MM ortho image", p.kaze_threshold_mm),
        (
            &aerial_features,
            "the aerial patch",
            p.kaze_threshold_aerial,
        ),
    ] {
        if features.is_empty() {
            return Err(rejected(
                format!("no KAZE keypoints in {what} (threshold {threshold})"),
                0,
                0,
            ));
        }
    }
    let (georef, (w, h)) = (
        &mm_ortho.georef,
        (mm_ortho.image.width, mm_ortho.image.height),
    );
    let mut query = WindowedQuery::default();
    for (i, k) in mm_features.keypoints.iter().enumerate() {
        let (u, v) = (f64::from(k.u_px), f64::from(k.v_px));
        if near_mask(&mm_ortho.valid, w, h, u, v, p.mask_clearance_px) {
            continue;
        }
        if let Some((au, av)) = cam.project_world(&georef.pixel_to_world(u, v)) {
            query.push(mm_features.descriptor(i), (u, v), patch.to_patch(au, av));
        }
    }
    let pairs = query.match_pairs(&aerial_features, window_px, p.match_ratio, |u, v| {
        patch.to_full(u, v)
    })?;
    let n_matches = pairs.len();
    if n_matches < p.min_inliers {
        return Err(rejected(
            format!(
                "{n_matches} descriptor matches in the ±{window_px:.1} px windows < {} required ({} MM, {} aerial keypoints)",
                p.min_inliers,
                query.len(),
                aerial_features.len()
            ),
            n_matches,
            0,
        ));
    }
    Ok(pairs)
}

/// Step 5: a RANSAC similarity, considering only hypotheses close to the recorded-pose scale and rotation.
/// Returns the model and its inlier count.
fn similarity_by_ransac(
    pairs: &[PointPair],
    nominal: &Similarity2,
    patch_scale: f64,
    rec: &Recording,
    aerial_row: &AerialImage,
    p: &TransformParams,
) -> Result<(Similarity2, usize), Rejection> {
    let ransac = RansacParams {
        seed: pair_seed(p.seed, &rec.image_id, &aerial_row.image_id),
        threshold: p.ransac_threshold_px * patch_scale,
        ..p.ransac()
    };
    let shape_ok = |m: &Similarity2| {
        (m.scale / nominal.scale - 1.0).abs() <= p.max_scale_deviation
            && wrap_deg((m.rotation_rad - nominal.rotation_rad).to_degrees()).abs()
                <= p.max_rotation_deg
    };
    let fit = ransac_filtered::<Similarity2>(pairs, &ransac, shape_ok).ok_or_else(|| {
        rejected(
            format!(
                "{} matches, RANSAC found no similarity within the scale/rotation tolerances",
                pairs.len()
            ),
            pairs.len(),
            0,
        )
    })?;
    Ok((fit.model, fit.inliers.len()))
}

/// Step 5 without estimating the shape: scale and rotation from the recorded pose, the translation by exhaustive
/// consensus, accepted only when it clearly beats the runner-up and is not what chance gives (a-contrario).
fn similarity_by_translation_consensus(
    pairs: &[PointPair],
    nominal: &Similarity2,
    patch_scale: f64,
    window_px: f64,
    p: &TransformParams,
) -> Result<(Similarity2, usize), Rejection> {
    let n_matches = pairs.len();
    let c = translation_consensus(pairs, nominal, p.ransac_threshold_px * patch_scale).ok_or_else(
        || {
            rejected(
                format!("{n_matches} matches, no translation consensus"),
                n_matches,
                0,
            )
        },
    )?;
    let n = c.inliers.len();
    let limits = (p.min_consensus_margin, p.max_false_alarms);
    if let Some(reason) = consensus_doubt(&c, n_matches, limits, p.ransac_threshold_px, window_px) {
        return Err(rejected(reason, n_matches, n));
    }
    Ok((c.model, n))
}
