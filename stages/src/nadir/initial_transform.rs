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
//! Option (thesis 3.4.5.2, last paragraph): [`reuse_neighbour`] adapts a neighbouring recording's transform to
//! this recording through the recorded relative pose.

use super::aerial_patch::{aerial_ground_similarity, extract_patch};
use super::ortho::{OrthoGeoref, OrthoImage};
use super::registration::{InitialTransform, TransformOutcome};
use super::translation_consensus::{false_alarms, translation_consensus};
use crate::campaign::{AerialImage, Recording};
use crate::estimators::{mix_seed, ransac_filtered, RansacParams};
use crate::features::kaze::{detect_and_describe, Features, KazeParams};
use crate::geometry::{intersect_ray_plane, FrameCamera, Plane, PointPair, Similarity2};
use crate::imaging::wallis::{wallis_filter, WallisParams};
use crate::imaging::GrayImage;
use crate::matching::descriptor_match::match_windowed;
use nalgebra::{Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// Parameters of the initial MM→aerial transform (thesis 3.4.5.2). Intensities are 0..1.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TransformParams {
    /// Expected maximum localisation error of the MM platform, metres: enlarges the aerial patch, sets the
    /// matching window (± this, in aerial pixels) and the plausibility limit of the centre offset.
    pub max_localisation_error_m: f64,
    /// Wallis target mean m_f (0..1 intensities).
    pub wallis_target_mean: f32,
    /// Wallis target standard deviation s_f.
    pub wallis_target_std: f32,
    /// Wallis contrast expansion constant c ∈ [0, 1].
    pub wallis_contrast_c: f32,
    /// Wallis brightness forcing constant b ∈ [0, 1].
    pub wallis_brightness_b: f32,
    /// Wallis statistics window side, pixels (odd; even values are rounded up).
    pub wallis_window_px: usize,
    /// KAZE detector threshold (det Hessian) of the MM instance.
    pub kaze_threshold_mm: f32,
    /// KAZE detector threshold of the aerial instance.
    pub kaze_threshold_aerial: f32,
    /// KAZE octaves (thesis: one, the images share a similar scale).
    pub kaze_octaves: usize,
    /// KAZE sub-levels per octave.
    pub kaze_sublevels: usize,
    /// 128-value descriptor (thesis: extended).
    pub descriptor_extended: bool,
    /// No rotation invariance (thesis: upright).
    pub upright: bool,
    /// Ratio test between the nearest and second-nearest aerial descriptor inside the window (d1 < ratio·d2;
    /// values > 1 keep every nearest neighbour).
    pub match_ratio: f32,
    /// MM keypoints with a masked (vehicle) pixel within this radius, ortho pixels, are not used.
    pub mask_clearance_px: f64,
    /// RANSAC inlier threshold, aerial pixels.
    pub ransac_threshold_px: f64,
    /// RANSAC confidence in (0, 1).
    pub ransac_confidence: f64,
    /// RANSAC maximum number of samples.
    pub ransac_max_iterations: usize,
    /// Fewer RANSAC inliers than this reject the transform.
    pub min_inliers: usize,
    /// Largest relative difference between a hypothesis' scale and the recorded-pose scale (ortho px → aerial px).
    pub max_scale_deviation: f64,
    /// Largest difference between a hypothesis' rotation and the recorded-pose rotation, degrees.
    pub max_rotation_deg: f64,
    /// Seed of RANSAC; each (recording, aerial image) pair derives its own stream from it.
    pub seed: u64,
    /// Estimate scale and rotation too (2-point RANSAC similarity within `max_scale_deviation` /
    /// `max_rotation_deg`). Default `false`: the ortho image is made at the aerial GSD and orientation, so
    /// scale and rotation are the recorded-pose ones and only the translation is estimated (exhaustive 1-point
    /// consensus, [`super::translation_consensus`]) — far less prone to a random consensus and, with few or
    /// clustered inliers, to extrapolation errors at the ortho border.
    pub estimate_shape: bool,
    /// Fewer inliers than this fraction of the descriptor matches reject the transform (a consensus that
    /// explains only a small part of the matches is likely random).
    pub min_inlier_ratio: f64,
    /// The winning translation must have at least this many times the support of the best competing one
    /// (> 2 × `ransac_threshold_px` away); ambiguous (repetitive) content is rejected. Translation mode only.
    pub min_consensus_margin: f64,
    /// Agreement across the recording's nadir images (`nadir::transform_agreement`): a transform whose implied
    /// recording offset lies farther than this from the median of the offsets implied by ≥ 2 other accepted
    /// transforms of the same recording is rejected, m (0 = no check). Default 1.2 m: the `refine` search
    /// margin (12 px) at the 10 cm aerial GSD — a transform farther off than that from its siblings cannot be
    /// corrected by the refinement, which then confirms whatever repeats there. Measured on demo seeds 1–3:
    /// implied offsets of one recording differ by 0.07 m (median), 0.5 m (p90); the aliased ones by 1.6–2.2 m.
    pub max_offset_disagreement_m: f64,
    /// A-contrario test of the translation consensus (translation mode): reject it when random matches would
    /// give a consensus as large this often or more (expected number of false alarms,
    /// [`super::translation_consensus::false_alarms`]). 0.1: with ±15 px windows and a 2 px threshold a
    /// consensus of 7 among 105 matches (NFA 0.40, what chance gives) is rejected, 6 among 60 (NFA 0.09) and
    /// 6 among 8 (NFA < 10⁻⁶) are kept.
    pub max_false_alarms: f64,
}

impl Default for TransformParams {
    fn default() -> Self {
        let wallis = WallisParams::default();
        Self {
            max_localisation_error_m: 1.5,
            wallis_target_mean: wallis.target_mean,
            wallis_target_std: wallis.target_std,
            wallis_contrast_c: wallis.contrast_c,
            wallis_brightness_b: wallis.brightness_b,
            wallis_window_px: wallis.window_px,
            // Measured on the tiny synthetic campaign: 0.001 finds ~16 MM keypoints per ortho (too few), 1e-4 ~280.
            kaze_threshold_mm: 0.0001,
            kaze_threshold_aerial: 0.0001,
            kaze_octaves: 1,
            kaze_sublevels: 4,
            descriptor_extended: true,
            upright: true,
            match_ratio: 0.9,
            mask_clearance_px: 3.0,
            ransac_threshold_px: 2.0,
            ransac_confidence: 0.999,
            ransac_max_iterations: 2000,
            min_inliers: 6,
            max_scale_deviation: 0.1,
            max_rotation_deg: 5.0,
            seed: 1,
            estimate_shape: false,
            min_inlier_ratio: 0.0,
            min_consensus_margin: 1.0,
            max_offset_disagreement_m: 1.2,
            max_false_alarms: 0.1,
        }
    }
}

impl TransformParams {
    /// Check ranges; each error is (field, message with the allowed range).
    pub fn validate(&self) -> Result<(), Vec<(String, String)>> {
        let mut errs: Vec<(String, String)> = Vec::new();
        let mut need = |ok: bool, field: &str, msg: String| {
            if !ok {
                errs.push((field.to_string(), msg));
            }
        };
        let d = self.max_offset_disagreement_m;
        need(
            d.is_finite() && d >= 0.0,
            "max_offset_disagreement_m",
            format!("must be ≥ 0 m (0 = no check), got {d}"),
        );
        let e = self.max_localisation_error_m;
        need(
            e.is_finite() && e > 0.0 && e <= 50.0,
            "max_localisation_error_m",
            format!("must be in (0, 50] m, got {e}"),
        );
        need(
            self.wallis_target_mean.is_finite(),
            "wallis_target_mean",
            format!("must be finite, got {}", self.wallis_target_mean),
        );
        need(
            self.wallis_target_std.is_finite() && self.wallis_target_std > 0.0,
            "wallis_target_std",
            format!("must be finite and > 0, got {}", self.wallis_target_std),
        );
        need(
            (0.0..=1.0).contains(&self.wallis_contrast_c),
            "wallis_contrast_c",
            format!("must be in [0, 1], got {}", self.wallis_contrast_c),
        );
        need(
            (0.0..=1.0).contains(&self.wallis_brightness_b),
            "wallis_brightness_b",
            format!("must be in [0, 1], got {}", self.wallis_brightness_b),
        );
        need(
            (3..=501).contains(&self.wallis_window_px),
            "wallis_window_px",
            format!("must be in [3, 501] px, got {}", self.wallis_window_px),
        );
        for (field, t) in [
            ("kaze_threshold_mm", self.kaze_threshold_mm),
            ("kaze_threshold_aerial", self.kaze_threshold_aerial),
        ] {
            need(
                t.is_finite() && t > 0.0,
                field,
                format!("must be finite and > 0 (e.g. 0.001), got {t}"),
            );
        }
        need(
            (1..=8).contains(&self.kaze_octaves),
            "kaze_octaves",
            format!("must be in [1, 8], got {}", self.kaze_octaves),
        );
        need(
            (1..=16).contains(&self.kaze_sublevels) && self.kaze_octaves * self.kaze_sublevels >= 3,
            "kaze_sublevels",
            format!(
                "must be in [1, 16] with kaze_octaves × kaze_sublevels ≥ 3 levels, got {}",
                self.kaze_sublevels
            ),
        );
        need(
            self.match_ratio.is_finite() && self.match_ratio > 0.0,
            "match_ratio",
            format!(
                "must be finite and > 0 (e.g. 0.9), got {}",
                self.match_ratio
            ),
        );
        need(
            self.mask_clearance_px.is_finite() && (0.0..=100.0).contains(&self.mask_clearance_px),
            "mask_clearance_px",
            format!("must be in [0, 100] px, got {}", self.mask_clearance_px),
        );
        if let Err(msg) = self.ransac().validate() {
            need(false, "ransac_threshold_px", msg);
        }
        need(
            self.min_inliers >= 2,
            "min_inliers",
            format!(
                "must be at least 2 (a similarity needs 2 points), got {}",
                self.min_inliers
            ),
        );
        need(
            self.max_scale_deviation.is_finite()
                && self.max_scale_deviation > 0.0
                && self.max_scale_deviation < 1.0,
            "max_scale_deviation",
            format!("must be in (0, 1), got {}", self.max_scale_deviation),
        );
        need(
            self.max_rotation_deg.is_finite()
                && self.max_rotation_deg > 0.0
                && self.max_rotation_deg <= 180.0,
            "max_rotation_deg",
            format!("must be in (0, 180] degrees, got {}", self.max_rotation_deg),
        );
        need(
            self.min_inlier_ratio.is_finite() && (0.0..=1.0).contains(&self.min_inlier_ratio),
            "min_inlier_ratio",
            format!("must be in [0, 1], got {}", self.min_inlier_ratio),
        );
        need(
            self.max_false_alarms.is_finite() && self.max_false_alarms > 0.0,
            "max_false_alarms",
            format!(
                "must be > 0 (expected chance consensus; large = no test), got {}",
                self.max_false_alarms
            ),
        );
        need(
            self.min_consensus_margin.is_finite() && self.min_consensus_margin >= 1.0,
            "min_consensus_margin",
            format!("must be ≥ 1, got {}", self.min_consensus_margin),
        );
        if errs.is_empty() {
            Ok(())
        } else {
            Err(errs)
        }
    }

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

/// 64-bit FNV-1a of a string (a stable, platform-independent label hash for per-pair seeds).
fn fnv1a64(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// The RANSAC seed of one (recording, aerial image) pair: derived from the stage seed and both ids only.
pub fn pair_seed(seed: u64, recording_id: &str, aerial_id: &str) -> u64 {
    mix_seed(
        seed,
        fnv1a64(recording_id) ^ fnv1a64(aerial_id).rotate_left(29),
    )
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

/// A copy of the ortho image with masked pixels replaced by the mean of the valid ones (so the Wallis filter and
/// the detector see no artificial edge at the mask border).
fn fill_masked(ortho: &OrthoImage) -> GrayImage {
    let mut img = ortho.image.clone();
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (&g, &ok) in img.data.iter().zip(&ortho.valid) {
        if ok != 0 {
            sum += f64::from(g);
            n += 1;
        }
    }
    let fill = if n > 0 { (sum / n as f64) as f32 } else { 0.0 };
    for (g, &ok) in img.data.iter_mut().zip(&ortho.valid) {
        if ok == 0 {
            *g = fill;
        }
    }
    img
}

/// True if a masked pixel (valid = 0) lies within `radius_px` of the continuous pixel (u, v).
fn near_mask(valid: &[u8], width: usize, height: usize, u: f64, v: f64, radius_px: f64) -> bool {
    if width == 0 || height == 0 {
        return false;
    }
    let r2 = radius_px * radius_px;
    let clamp = |x: f64, n: usize| x.clamp(0.0, n as f64 - 1.0) as usize;
    let (c0, c1) = (
        clamp((u - radius_px - 0.5).floor(), width),
        clamp((u + radius_px - 0.5).ceil(), width),
    );
    let (r0, r1) = (
        clamp((v - radius_px - 0.5).floor(), height),
        clamp((v + radius_px - 0.5).ceil(), height),
    );
    for row in r0..=r1 {
        let dv = row as f64 + 0.5 - v;
        for col in c0..=c1 {
            let du = col as f64 + 0.5 - u;
            if du * du + dv * dv <= r2 && valid[row * width + col] == 0 {
                return true;
            }
        }
    }
    false
}

/// The KAZE features of the Wallis-filtered image with threshold `threshold`; `Err` names what failed.
fn wallis_kaze(
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
/// `aerial` the grey aerial image (0..1) of the `cameras.csv` row `aerial_row`. Never panics on data: every
/// failure is a `Rejected` with a reason.
pub fn initial_transform(
    rec: &Recording,
    mm_ortho: &OrthoImage,
    aerial: &GrayImage,
    aerial_row: &AerialImage,
    p: &TransformParams,
) -> TransformOutcome {
    let reject = |reason: String, matches: usize, inliers: usize| TransformOutcome::Rejected {
        recording_id: rec.image_id.clone(),
        aerial_id: aerial_row.image_id.clone(),
        reason,
        matches,
        inliers,
    };
    if let Err(errs) = p.validate() {
        let list: Vec<String> = errs.iter().map(|(f, m)| format!("{f}: {m}")).collect();
        return reject(
            format!("invalid transform parameters: {}", list.join("; ")),
            0,
            0,
        );
    }
    if aerial.width != aerial_row.width_px as usize
        || aerial.height != aerial_row.height_px as usize
    {
        return reject(
            format!(
                "aerial image {} is {}×{} px but aerial/nadir/cameras.csv says {}×{}; fix the width/height columns",
                aerial_row.file, aerial.width, aerial.height, aerial_row.width_px, aerial_row.height_px
            ),
            0,
            0,
        );
    }
    let georef = &mm_ortho.georef;
    let (w, h) = (mm_ortho.image.width, mm_ortho.image.height);
    if w != georef.width_px || h != georef.height_px || mm_ortho.valid.len() != w * h {
        return reject(
            format!(
                "ortho image of {} is inconsistent: {w}×{h} px, georeference {}×{}, {} mask values",
                rec.image_id,
                georef.width_px,
                georef.height_px,
                mm_ortho.valid.len()
            ),
            0,
            0,
        );
    }
    let cam = FrameCamera::from_aerial(aerial_row);
    let max_err_m = p.max_localisation_error_m;
    let Some(nominal) = nominal_transform(georef, &cam) else {
        return reject(
            "the ortho footprint does not project into the aerial image".into(),
            0,
            0,
        );
    };
    let Some(patch) = extract_patch(aerial, &cam, georef, max_err_m) else {
        return reject(
            "the ortho footprint (plus the localisation error) does not overlap the aerial image"
                .into(),
            0,
            0,
        );
    };
    let aerial_gsd_m = aerial_ground_similarity(&cam, georef.foot_world)
        .map(|(gsd, _)| gsd)
        .unwrap_or_else(|| cam.gsd_at(&Vector3::from(georef.foot_world)));
    if !(aerial_gsd_m.is_finite() && aerial_gsd_m > 0.0) {
        return reject(
            "the aerial GSD at the foot point is not positive".into(),
            0,
            0,
        );
    }
    let window_px = max_err_m / aerial_gsd_m;

    // Wallis + two KAZE detector instances, one descriptor configuration (thesis 3.4.5.2).
    let mm_features = match wallis_kaze(
        &fill_masked(mm_ortho),
        p,
        p.kaze_threshold_mm,
        "MM ortho image",
    ) {
        Ok(f) => f,
        Err(e) => return reject(e, 0, 0),
    };
    let aerial_features =
        match wallis_kaze(&patch.image, p, p.kaze_threshold_aerial, "aerial patch") {
            Ok(f) => f,
            Err(e) => return reject(e, 0, 0),
        };
    if mm_features.is_empty() {
        return reject(
            format!(
                "no KAZE keypoints in the MM ortho image (threshold {})",
                p.kaze_threshold_mm
            ),
            0,
            0,
        );
    }
    if aerial_features.is_empty() {
        return reject(
            format!(
                "no KAZE keypoints in the aerial patch (threshold {})",
                p.kaze_threshold_aerial
            ),
            0,
            0,
        );
    }

    // MM keypoints off the mask → ortho plane (world) → aerial patch pixel.
    let len = mm_features.descriptor_len;
    let mut query_idx: Vec<usize> = Vec::with_capacity(mm_features.len());
    let mut predicted: Vec<[f64; 2]> = Vec::with_capacity(mm_features.len());
    for (i, k) in mm_features.keypoints.iter().enumerate() {
        let (u, v) = (f64::from(k.u_px), f64::from(k.v_px));
        if near_mask(&mm_ortho.valid, w, h, u, v, p.mask_clearance_px) {
            continue;
        }
        if let Some((au, av)) = cam.project_world(&georef.pixel_to_world(u, v)) {
            let (pu, pv) = patch.to_patch(au, av);
            query_idx.push(i);
            predicted.push([pu, pv]);
        }
    }
    let mut query: Vec<f32> = Vec::with_capacity(query_idx.len() * len);
    for &i in &query_idx {
        query.extend_from_slice(mm_features.descriptor(i));
    }
    let train_px: Vec<[f64; 2]> = aerial_features
        .keypoints
        .iter()
        .map(|k| [f64::from(k.u_px), f64::from(k.v_px)])
        .collect();
    let matched = match match_windowed(
        &query,
        &predicted,
        &aerial_features.descriptors,
        &train_px,
        len,
        window_px,
        p.match_ratio,
    ) {
        Ok(m) => m,
        Err(e) => return reject(format!("descriptor matching failed: {e}"), 0, 0),
    };
    let pairs: Vec<PointPair> = matched
        .iter()
        .flatten()
        .map(|m| {
            let k = &mm_features.keypoints[query_idx[m.query]];
            let (au, av) = patch.to_full(train_px[m.train][0], train_px[m.train][1]);
            PointPair::new(f64::from(k.u_px), f64::from(k.v_px), au, av)
        })
        .collect();
    let n_matches = pairs.len();
    if n_matches < p.min_inliers {
        return reject(
            format!(
                "{n_matches} descriptor matches in the ±{window_px:.1} px windows < {} required ({} MM, {} aerial keypoints)",
                p.min_inliers,
                query_idx.len(),
                aerial_features.len()
            ),
            n_matches,
            0,
        );
    }

    let (model, n_inliers) = if p.estimate_shape {
        // RANSAC similarity; only hypotheses close to the recorded-pose scale and rotation.
        let ransac = RansacParams {
            seed: pair_seed(p.seed, &rec.image_id, &aerial_row.image_id),
            ..p.ransac()
        };
        let shape_ok = |m: &Similarity2| {
            (m.scale / nominal.scale - 1.0).abs() <= p.max_scale_deviation
                && wrap_deg((m.rotation_rad - nominal.rotation_rad).to_degrees()).abs()
                    <= p.max_rotation_deg
        };
        let Some(fit) = ransac_filtered::<Similarity2>(&pairs, &ransac, shape_ok) else {
            return reject(
                format!("{n_matches} matches, RANSAC found no similarity within the scale/rotation tolerances"),
                n_matches,
                0,
            );
        };
        (fit.model, fit.inliers.len())
    } else {
        // Scale and rotation from the recorded pose, translation by exhaustive consensus.
        let Some(c) = translation_consensus(&pairs, &nominal, p.ransac_threshold_px) else {
            return reject(
                format!("{n_matches} matches, no translation consensus"),
                n_matches,
                0,
            );
        };
        let n = c.inliers.len();
        if (n as f64) < p.min_consensus_margin * c.runner_up as f64 {
            return reject(
                format!(
                    "{n_matches} matches: ambiguous translation ({n} inliers, a competing one has {})",
                    c.runner_up
                ),
                n_matches,
                n,
            );
        }
        let nfa = false_alarms(n_matches, n, p.ransac_threshold_px, window_px);
        if nfa > p.max_false_alarms {
            return reject(
                format!(
                    "{n_matches} matches: a consensus of {n} is what chance gives (expected {nfa:.2} among \
                     random matches > {})",
                    p.max_false_alarms
                ),
                n_matches,
                n,
            );
        }
        (c.model, n)
    };
    if n_inliers < p.min_inliers {
        return reject(
            format!(
                "{n_matches} matches, RANSAC found {n_inliers} inliers < {}",
                p.min_inliers
            ),
            n_matches,
            n_inliers,
        );
    }
    if (n_inliers as f64) < p.min_inlier_ratio * n_matches as f64 {
        return reject(
            format!(
                "{n_matches} matches, {n_inliers} inliers < {} of the matches",
                p.min_inlier_ratio
            ),
            n_matches,
            n_inliers,
        );
    }

    // Plausibility (thesis 3.4.5.2): the projected MM image centre must lie within the expected error.
    let Some(offset) = centre_offset_world(&model, georef, &cam) else {
        return reject(
            "the transformed ortho centre does not meet the ground plane".into(),
            n_matches,
            n_inliers,
        );
    };
    let centre_offset_m = offset[0].hypot(offset[1]);
    if !(centre_offset_m <= max_err_m) {
        return reject(
            format!("centre offset {centre_offset_m:.2} m > {max_err_m} m"),
            n_matches,
            n_inliers,
        );
    }
    TransformOutcome::Accepted(InitialTransform {
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

/// The option "re-use a neighbour's transform" (thesis 3.4.5.2, last paragraph): the relative orientation along the
/// trajectory is accurate, so this recording's ortho pixel p shows the same ground as the neighbour's ortho pixel
/// that the *recorded* poses put at the same world point. The transform is therefore
/// `neighbour.ortho_to_aerial ∘ (this ortho px → world → neighbour ortho px)`, checked for plausibility like a
/// computed one. Matches/inliers are the neighbour's; `reused_from` names the neighbour.
pub fn reuse_neighbour(
    neighbour: &InitialTransform,
    neighbour_georef: &OrthoGeoref,
    rec: &Recording,
    georef: &OrthoGeoref,
    aerial_row: &AerialImage,
    p: &TransformParams,
) -> TransformOutcome {
    let reject = |reason: String| TransformOutcome::Rejected {
        recording_id: rec.image_id.clone(),
        aerial_id: aerial_row.image_id.clone(),
        reason,
        matches: neighbour.matches,
        inliers: neighbour.inliers,
    };
    if neighbour.aerial_id != aerial_row.image_id {
        return reject(format!(
            "neighbour {}'s transform is for aerial image {}, not {}",
            neighbour.recording_id, neighbour.aerial_id, aerial_row.image_id
        ));
    }
    let (w, h) = (georef.width_px as f64, georef.height_px as f64);
    let pairs: Vec<PointPair> = [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)]
        .iter()
        .map(|&(x, y)| {
            let (nx, ny) = neighbour_georef.world_to_pixel(&georef.pixel_to_world(x, y));
            PointPair::new(x, y, nx, ny)
        })
        .collect();
    let Some(to_neighbour) = Similarity2::least_squares(&pairs) else {
        return reject("degenerate ortho georeference".into());
    };
    let transform = neighbour.ortho_to_aerial.compose(&to_neighbour);
    let cam = FrameCamera::from_aerial(aerial_row);
    let Some(offset) = centre_offset_world(&transform, georef, &cam) else {
        return reject("the transformed ortho centre does not meet the ground plane".into());
    };
    let centre_offset_m = offset[0].hypot(offset[1]);
    if !(centre_offset_m <= p.max_localisation_error_m) {
        return reject(format!(
            "reused transform of {}: centre offset {centre_offset_m:.2} m > {} m",
            neighbour.recording_id, p.max_localisation_error_m
        ));
    }
    TransformOutcome::Accepted(InitialTransform {
        recording_id: rec.image_id.clone(),
        aerial_id: aerial_row.image_id.clone(),
        ortho_to_aerial: transform,
        matches: neighbour.matches,
        inliers: neighbour.inliers,
        centre_offset_m,
        centre_offset_world_m: offset,
        reused_from: Some(neighbour.recording_id.clone()),
    })
}
