//! Verification without adjustment (thesis 5.7, Table 5-13): are a campaign's recorded
//! positions good enough? Each aerial control point triangulated from ≥ 2 aerial images is compared with the
//! same point triangulated from its MM observations alone with the RECORDED poses; the offset `MM − aerial`
//! estimates the local trajectory error. A point seen in one aerial nadir image has no aerial height, but its
//! ray is nearly vertical: taken at the MM point's own height it gives a horizontal position
//! ([`AerialRayGround`]), so it is compared horizontally (`single_image_points`) and left out of the
//! vertical and 3-D statistics. Per trajectory segment (a number of recordings or an along-track
//! length): mean and SD of the offsets in X, Y, Z and of their 3-D length (Table 5-13), the uncertainty of the
//! mean, and pass/fail against a tolerance (horizontal; vertical only with `check_height`).
//!
//! Uncertainty of the mean per axis: the larger of the empirical `SD/√n` and the propagated
//! `√(Σ σ²_k)/n` with `σ²_k` the diagonal of `C_MM + C_aerial` (a-priori triangulation covariances), so a
//! segment with few points is not overconfident. Status: `fail` when the mean offset exceeds a tolerance
//! *significantly* — the horizontal offset minus `confidence_k` σ of it above `tolerance_xy_m`, or (with
//! `check_height`) |mean Z| minus `confidence_k` σ above `tolerance_z_m` — or when at least
//! `min_points_off` points each show a horizontal offset beyond `tolerance_xy_m` by more than `confidence_k`
//! of their own σ — and the points seen from the same recordings agree (`min_neighbours`: their median offset is
//! off too): a trajectory that drifts within a segment (a GNSS outage) has a mean that proves nothing,
//! its spread is the evidence; otherwise `insufficient` with fewer than `min_points` points or when the points
//! leave a run of at least `max_unobserved_share` of the segment's recordings unobserved (they vouch only for
//! the recordings they were observed from), or when the trajectory's own stated precision cannot support a pass
//! (the verification of an adjusted trajectory: the RMS of its recordings' stated horizontal σ, times
//! `confidence_k`, beyond `tolerance_xy_m` — its recordings without control of their own carry a σ that says
//! how far they may be off, and points elsewhere in the segment do not vouch for them), `pass` otherwise.
//! One point alone never fails a segment (a single wrong correspondence must not), but two independent
//! points that both put the recordings significantly off are enough even where `min_points` are needed
//! for a pass. The height is not tested by default: nadir images from ≈ 4500 m give
//! aerial heights with metre-level errors (thesis 3.5.1.1), larger than their a-priori σ says once the aerial
//! orientations are a few centimetres off, and an offset the data cannot resolve must not fail a good campaign.

use super::id_index::index_by_id;
use crate::campaign::Recording;
use crate::correspondence::{AerialControlPoint, AerialRayGround};
use crate::estimators::median_consensus::median_in_place;
use crate::geometry::{triangulate_rays, PanoramaCamera};
use crate::params::{describe, Params, StageId};
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};
use skytie_util::csv_out::{quote, write_csv};
use std::collections::BTreeMap;
use std::io::{self, Write};
use std::ops::RangeInclusive;
use std::path::Path;

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("verify", "10");

crate::params! {
    /// Parameters of a verification (the verify node's params).
    pub struct VerifyConfig {
        /// Segment length in recordings (used when `segment_length_m` is absent).
        segment_recordings: usize = 20, min 1;
        /// Segment length along the recorded trajectory (overrides `segment_recordings`).
        segment_length_m: Option<f64> = None, unit "m", above 0.0;
        /// Largest acceptable mean horizontal offset.
        tolerance_xy_m: f64 = 0.20, unit "m", above 0.0;
        /// Largest acceptable |mean vertical offset| (with `check_height`).
        tolerance_z_m: f64 = 0.30, unit "m", above 0.0;
        /// Also fail a segment on its mean vertical offset. Off by default: heights triangulated from nadir
        /// images at ≈ 4.5 km are metres off (thesis 3.5.1.1), and centimetre errors of the aerial orientations
        /// make them worse still, so a height test flags good trajectories (measured: the `aerial` error
        /// profile, demo seed 1, segment mean Z +3.9 m with the recorded positions exact).
        check_height: bool = false;
        /// Fewer points in a segment give status `insufficient` (unless it fails on `min_points_off`).
        min_points: usize = 3, min 1;
        /// A segment fails when this many of its points each lie significantly beyond `tolerance_xy_m`
        /// (horizontal offset minus `confidence_k` σ of that point): the recordings near them are off,
        /// whatever the segment's mean says.
        min_points_off: usize = 2, min 1;
        /// A point counts as off (`min_points_off`) only when the points observed from the same recordings
        /// agree: with at least `min_neighbours` points sharing one of its recordings (itself included), the
        /// component-wise median of their offsets must be off as well (beyond `tolerance_xy_m` by more than
        /// `confidence_k` of the point's σ). A drifted trajectory moves every point seen from the drifted
        /// recordings; a wrong correspondence moves its own point only (and a window registered at a wrong
        /// place, the few points of that window). 0 = each point on its own.
        min_neighbours: usize = 5;
        /// A segment passes only when its points cover it: a run of consecutive recordings from which none of
        /// its compared points was observed, as long as this share of the segment's recordings or longer, gives
        /// `insufficient` instead of `pass` (the points vouch for the part of the segment they lie in, not for
        /// a stretch without any). Evidence of a failure still fails the segment.
        max_unobserved_share: f64 = 0.5, above 0.0, max 1.0;
        /// A segment fails on its mean only when an offset exceeds its tolerance by more than this many σ of
        /// the mean; a point counts as off (`min_points_off`) beyond this many σ of its own offset.
        confidence_k: f64 = 2.0, min 0.0;
        /// σ of a panorama observation (weights the MM triangulation), in pixels of the panorama's detail
        /// level (`PyramidLayout::detail_level`; full-resolution pixels unless the panorama was enlarged by
        /// pixel repetition), as the adjustment's `pano_sigma_px`.
        pano_sigma_px: f64 = 1.0, unit "px", above 0.0;
        /// Also compare the points seen in one aerial nadir image, horizontally: their ray taken at the MM
        /// point's height (a nadir ray is within a degree or two of vertical, so a height error of δz moves it
        /// by δz · tan(tilt)). They are left out of the vertical and 3-D statistics. Off: only points
        /// triangulated from ≥ 2 aerial images (or measured in an orthophoto) are compared.
        single_image_points: bool = true;
    }
}

/// The verdict on a segment.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum VerifyStatus {
    Pass,
    Fail,
    Insufficient,
}

impl VerifyStatus {
    pub fn label(&self) -> &'static str {
        match self {
            VerifyStatus::Pass => "pass",
            VerifyStatus::Fail => "fail",
            VerifyStatus::Insufficient => "insufficient",
        }
    }
}

/// One compared point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VerifiedPoint {
    pub tie_point_id: String,
    /// Segment index.
    pub segment: usize,
    /// Indices (in the verified recordings) of the recordings the point was observed from: the ones whose
    /// poses its MM triangulation, and so its offset, depends on.
    pub observed_from: Vec<usize>,
    /// MM triangulation (recorded poses) − aerial triangulation, world axes, metres.
    pub offset_m: [f64; 3],
    /// Diagonal of `C_MM + C_aerial` (a priori), m².
    pub variance_m2: [f64; 3],
    pub mm_views: usize,
    /// False for a point seen in one aerial image: its offset is horizontal only (`offset_m[2]` and
    /// `variance_m2[2]` are 0) and it is left out of the vertical and 3-D statistics.
    pub aerial_height: bool,
}

/// Table 5-13 statistics of one trajectory segment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VerificationSegment {
    pub index: usize,
    pub first_image_id: String,
    pub last_image_id: String,
    pub recordings: usize,
    pub points: usize,
    /// The points with an aerial height (≥ 2 aerial images or an orthophoto), the ones the vertical and
    /// 3-D statistics come from.
    pub points_3d: usize,
    /// Mean offset X, Y, Z, metres.
    pub mean_m: [f64; 3],
    /// SD of the offsets X, Y, Z, metres (0 with one point).
    pub sd_m: [f64; 3],
    /// Mean and SD of the 3-D offset lengths, metres.
    pub mean_3d_m: f64,
    pub sd_3d_m: f64,
    /// Uncertainty (σ) of the mean offset X, Y, Z, metres.
    pub sigma_mean_m: [f64; 3],
    /// Length of the mean horizontal offset, metres.
    pub offset_2d_m: f64,
    /// Points whose own horizontal offset exceeds `tolerance_xy_m` by more than `confidence_k` of their σ.
    pub points_off: usize,
    /// Longest run of consecutive recordings of the segment from which none of its compared points was
    /// observed (`max_unobserved_share`).
    pub unobserved_run: usize,
    /// RMS over the segment's recordings of their stated horizontal σ (the larger of x and y), metres; `None`
    /// when the verified poses state none (the recorded trajectory).
    pub stated_sigma_xy_m: Option<f64>,
    pub status: VerifyStatus,
}

/// The result of [`verify`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Verification {
    pub segments: Vec<VerificationSegment>,
    pub points: Vec<VerifiedPoint>,
    /// All points together (index = number of segments, ids of the first and last recording).
    pub overall: VerificationSegment,
    /// Control points without an aerial position: seen in one aerial image, and not compared
    /// horizontally (`single_image_points` off, or no ray at the ground).
    pub skipped_single_aerial: usize,
    /// Control points whose MM observations could not be triangulated (< 2 known panoramas, bad geometry).
    pub skipped_mm: usize,
    pub config: VerifyConfig,
}

impl Verification {
    /// True when no segment failed and at least one passed.
    pub fn passed(&self) -> bool {
        self.segments.iter().all(|s| s.status != VerifyStatus::Fail)
            && self.segments.iter().any(|s| s.status == VerifyStatus::Pass)
    }
}

/// Segment index of every recording.
fn segment_of_recordings(recordings: &[Recording], config: &VerifyConfig) -> Vec<usize> {
    match config.segment_length_m {
        Some(length) => {
            let mut along = 0.0;
            let mut out = Vec::with_capacity(recordings.len());
            for (i, r) in recordings.iter().enumerate() {
                if i > 0 {
                    let p = &recordings[i - 1];
                    along += (r.x - p.x).hypot(r.y - p.y);
                }
                out.push((along / length).floor() as usize);
            }
            out
        }
        None => (0..recordings.len())
            .map(|i| i / config.segment_recordings)
            .collect(),
    }
}

/// Compares aerial control points with their MM triangulation from the recorded poses, per segment.
/// `recordings` in trajectory (time) order, `pano_size_px` one per recording; every panorama at detail level 0
/// ([`verify_with_detail_levels`]).
pub fn verify(
    recordings: &[Recording],
    pano_size_px: &[(u32, u32)],
    control: &[AerialControlPoint],
    config: &VerifyConfig,
) -> Result<Verification, String> {
    verify_with_detail_levels(recordings, pano_size_px, &[], &[], control, config)
}

/// [`verify`] with the detail level of each recording's panorama (`pano_detail_level`, one per recording, or
/// empty for 0 everywhere): a panorama observation's σ is `pano_sigma_px` pixels of that level, i.e.
/// `pano_sigma_px · 2^level` full-resolution pixels, so a panorama enlarged by pixel repetition weighs its
/// observations like the panorama it was enlarged from; and with the stated horizontal σ of each verified
/// pose (`stated_sigma_xy_m`, m, one per recording, or empty when the poses state none: the recorded
/// trajectory), which a segment's pass must be able to support (module documentation).
pub fn verify_with_detail_levels(
    recordings: &[Recording],
    pano_size_px: &[(u32, u32)],
    pano_detail_level: &[usize],
    stated_sigma_xy_m: &[f64],
    control: &[AerialControlPoint],
    config: &VerifyConfig,
) -> Result<Verification, String> {
    if let Err(problems) = config.validate() {
        return Err(format!("verify parameters: {}", describe(&problems)));
    }
    if pano_size_px.len() != recordings.len() {
        return Err(format!(
            "{} panorama sizes for {} recordings; pass one (width, height) per recording",
            pano_size_px.len(),
            recordings.len()
        ));
    }
    for (what, len) in [
        ("panorama detail levels", pano_detail_level.len()),
        ("stated σ", stated_sigma_xy_m.len()),
    ] {
        if !(len == 0 || len == recordings.len()) {
            return Err(format!(
                "{len} {what} for {} recordings; pass one per recording, or none",
                recordings.len()
            ));
        }
    }
    let stated = (!stated_sigma_xy_m.is_empty()).then_some(stated_sigma_xy_m);
    let cameras: Vec<PanoramaCamera> = recordings
        .iter()
        .zip(pano_size_px)
        .map(|(r, &(w, h))| PanoramaCamera::from_recording(r, w, h))
        .collect();
    // σ of each recording's panorama observations, radians.
    let angular_sigma_rad: Vec<f64> = cameras
        .iter()
        .enumerate()
        .map(|(r, cam)| {
            let level = pano_detail_level.get(r).copied().unwrap_or(0).min(30);
            cam.angular_sigma_rad(config.pano_sigma_px * (1u64 << level) as f64)
        })
        .collect();
    let index = index_by_id(recordings, |r| r.image_id.as_str());
    let segment_of = segment_of_recordings(recordings, config);
    let n_segments = segment_of.last().map_or(0, |&s| s + 1);
    let mut points = Vec::new();
    let (mut skipped_single_aerial, mut skipped_mm) = (0, 0);
    let mut rays = Vec::new();
    let mut sigmas = Vec::new();
    for cp in control {
        // Triangulated from ≥ 2 aerial images, or measured in the orthophoto; else one image's ray.
        let usable = cp.aerial.len() >= 2 || cp.map.is_some();
        let aerial = match (cp.point_world, usable, &cp.ray_ground) {
            (Some(xyz), true, _) => AerialPosition::Point(Vector3::from(xyz)),
            (_, _, Some(ray)) if config.single_image_points && cp.aerial.len() == 1 => {
                AerialPosition::Ray(ray)
            }
            _ => {
                skipped_single_aerial += 1;
                continue;
            }
        };
        let near = aerial.near_world();
        rays.clear();
        sigmas.clear();
        let mut observed_from = Vec::with_capacity(cp.mm.len());
        let mut nearest: Option<(f64, usize)> = None;
        for o in &cp.mm {
            if let Some(&r) = index.get(o.image_id.as_str()) {
                rays.push(cameras[r].pixel_ray(o.u_px, o.v_px));
                sigmas.push(angular_sigma_rad[r]);
                observed_from.push(r);
                let d = (cameras[r].center_world - near).norm();
                if nearest.is_none_or(|(best, _)| d < best) {
                    nearest = Some((d, r));
                }
            }
        }
        let (Ok(t), Some((_, r))) = (triangulate_rays(&rays, &sigmas), nearest) else {
            skipped_mm += 1;
            continue;
        };
        let mm = &t.point_world;
        let mm_var = &t.covariance_m2;
        let (offset_m, variance_m2) = match aerial {
            AerialPosition::Point(aerial) => {
                let aerial_cov = cp
                    .covariance_m2
                    .map(|c| Matrix3::from_fn(|i, j| c[i][j]))
                    .unwrap_or_else(Matrix3::zeros);
                let cov = mm_var + aerial_cov;
                (
                    (mm - aerial).into(),
                    [cov[(0, 0)], cov[(1, 1)], cov[(2, 2)]],
                )
            }
            AerialPosition::Ray(ray) => {
                let [ax, ay] = ray.xy_at(mm.z);
                let [vx, vy] = ray.xy_variance_m2(mm_var[(2, 2)]);
                (
                    [mm.x - ax, mm.y - ay, 0.0],
                    [mm_var[(0, 0)] + vx, mm_var[(1, 1)] + vy, 0.0],
                )
            }
        };
        points.push(VerifiedPoint {
            tie_point_id: cp.tie_point_id.clone(),
            segment: segment_of[r],
            observed_from,
            offset_m,
            variance_m2,
            mm_views: rays.len(),
            aerial_height: matches!(aerial, AerialPosition::Point(_)),
        });
    }
    // Members of every segment in one pass over the recordings and one over the points (in their order).
    let mut span: Vec<Option<(usize, usize, usize)>> = vec![None; n_segments];
    // (A non-finite position makes a later recording's index fall back to 0: segments are those up to the
    // last recording's, as they always were.)
    for (i, &s) in segment_of.iter().enumerate() {
        if let Some(slot) = span.get_mut(s) {
            let e = slot.get_or_insert((0, i, i));
            e.0 += 1;
            e.2 = i;
        }
    }
    let mut members: Vec<Vec<&VerifiedPoint>> = vec![Vec::new(); n_segments];
    for p in &points {
        if let Some(m) = members.get_mut(p.segment) {
            m.push(p);
        }
    }
    let segments: Vec<VerificationSegment> = span
        .iter()
        .zip(&members)
        .enumerate()
        .filter_map(|(s, (span, members))| {
            let &(n_rec, a, b) = span.as_ref()?;
            let (first, last) = (
                recordings[a].image_id.clone(),
                recordings[b].image_id.clone(),
            );
            Some(statistics(
                s,
                n_rec,
                first,
                last,
                a..=b,
                members,
                stated,
                config,
            ))
        })
        .collect();
    let all: Vec<&VerifiedPoint> = points.iter().collect();
    let overall = statistics(
        n_segments,
        recordings.len(),
        recordings
            .first()
            .map(|r| r.image_id.clone())
            .unwrap_or_default(),
        recordings
            .last()
            .map(|r| r.image_id.clone())
            .unwrap_or_default(),
        0..=recordings.len().saturating_sub(1),
        &all,
        stated,
        config,
    );
    Ok(Verification {
        segments,
        points,
        overall,
        skipped_single_aerial,
        skipped_mm,
        config: config.clone(),
    })
}

/// Where the aerial data put a compared point.
enum AerialPosition<'a> {
    /// Triangulated from ≥ 2 aerial images or measured in an orthophoto (world, m).
    Point(Vector3<f64>),
    /// One aerial image's ray, horizontal only.
    Ray(&'a AerialRayGround),
}

impl AerialPosition<'_> {
    /// A world point near the control point (to find the recording that saw it from closest).
    fn near_world(&self) -> Vector3<f64> {
        match self {
            AerialPosition::Point(p) => *p,
            AerialPosition::Ray(r) => Vector3::from(r.point_world),
        }
    }
}

/// Table 5-13 statistics of a set of points.
#[allow(clippy::too_many_arguments)]
fn statistics(
    index: usize,
    recordings: usize,
    first_image_id: String,
    last_image_id: String,
    span: RangeInclusive<usize>,
    points: &[&VerifiedPoint],
    stated_sigma_xy_m: Option<&[f64]>,
    config: &VerifyConfig,
) -> VerificationSegment {
    let n = points.len();
    let with_height: Vec<&VerifiedPoint> =
        points.iter().copied().filter(|p| p.aerial_height).collect();
    let mut mean = [0.0; 3];
    let mut sd = [0.0; 3];
    let mut sigma_mean = [0.0; 3];
    for k in 0..3 {
        // Horizontal axes from every point, the vertical one from those with an aerial height.
        let axis_points = if k == 2 { &with_height[..] } else { points };
        (mean[k], sd[k]) = mean_and_sd(axis_points.iter().map(|p| p.offset_m[k]));
        if !axis_points.is_empty() {
            let nf = axis_points.len() as f64;
            let propagated = axis_points
                .iter()
                .map(|p| p.variance_m2[k])
                .sum::<f64>()
                .sqrt()
                / nf;
            sigma_mean[k] = (sd[k] / nf.sqrt()).max(propagated);
        }
    }
    let (mean_3d, sd_3d) =
        mean_and_sd(with_height.iter().map(|p| Vector3::from(p.offset_m).norm()));
    let offset_2d = mean[0].hypot(mean[1]);
    let by_recording = points_by_recording(points);
    let points_off = points
        .iter()
        .filter(|p| {
            point_significantly_off(p, config)
                && neighbours_agree_off(p, points, &by_recording, config)
        })
        .count();
    let stated_sigma_xy_m = stated_sigma_xy_m
        .and_then(|s| s.get(span.clone()))
        .filter(|s| !s.is_empty())
        .map(|s| (s.iter().map(|v| v * v).sum::<f64>() / s.len() as f64).sqrt());
    let unobserved_run = if recordings == 0 {
        0
    } else {
        longest_unobserved_run(span, points)
    };
    let status = if points_off >= config.min_points_off {
        VerifyStatus::Fail
    } else if n < config.min_points
        || unobserved_run as f64 >= config.max_unobserved_share * recordings as f64
    {
        VerifyStatus::Insufficient
    } else if offset_2d - config.confidence_k * sigma_mean[0].max(sigma_mean[1])
        > config.tolerance_xy_m
        || (config.check_height
            && mean[2].abs() - config.confidence_k * sigma_mean[2] > config.tolerance_z_m)
    {
        VerifyStatus::Fail
    } else if stated_sigma_xy_m.is_some_and(|s| !(config.confidence_k * s <= config.tolerance_xy_m))
    {
        VerifyStatus::Insufficient
    } else {
        VerifyStatus::Pass
    };
    VerificationSegment {
        index,
        first_image_id,
        last_image_id,
        recordings,
        points: n,
        points_3d: with_height.len(),
        mean_m: mean,
        sd_m: sd,
        mean_3d_m: mean_3d,
        sd_3d_m: sd_3d,
        sigma_mean_m: sigma_mean,
        offset_2d_m: offset_2d,
        points_off,
        unobserved_run,
        stated_sigma_xy_m,
        status,
    }
}

/// Mean and sample SD of `values` (0, 0 when empty; SD 0 with one value).
fn mean_and_sd(values: impl Iterator<Item = f64> + Clone) -> (f64, f64) {
    let n = values.clone().count();
    if n == 0 {
        return (0.0, 0.0);
    }
    let nf = n as f64;
    let mean = values.clone().sum::<f64>() / nf;
    let sd = if n > 1 {
        (values.map(|v| (v - mean).powi(2)).sum::<f64>() / (nf - 1.0)).sqrt()
    } else {
        0.0
    };
    (mean, sd)
}

/// Longest run of consecutive recordings in `span` (indices into the verified recordings) from which none of
/// `points` was observed; the whole span when there are no points.
fn longest_unobserved_run(span: RangeInclusive<usize>, points: &[&VerifiedPoint]) -> usize {
    let (first, last) = (*span.start(), *span.end());
    let mut observed: Vec<usize> = points
        .iter()
        .flat_map(|p| p.observed_from.iter().copied())
        .filter(|r| span.contains(r))
        .collect();
    observed.sort_unstable();
    observed.dedup();
    let mut longest = 0;
    let mut next_unobserved = first;
    for &r in &observed {
        longest = longest.max(r - next_unobserved);
        next_unobserved = r + 1;
    }
    longest.max((last + 1).saturating_sub(next_unobserved))
}

/// True when the point's horizontal offset exceeds `tolerance_xy_m` by more than `confidence_k` of its own
/// horizontal σ (the root of the two variances, a bound on the σ in any horizontal direction).
fn point_significantly_off(p: &VerifiedPoint, config: &VerifyConfig) -> bool {
    significantly_off([p.offset_m[0], p.offset_m[1]], p, config)
}

/// True when the horizontal offset `offset_xy_m` exceeds `tolerance_xy_m` by more than `confidence_k` of `p`'s
/// horizontal σ.
fn significantly_off(offset_xy_m: [f64; 2], p: &VerifiedPoint, config: &VerifyConfig) -> bool {
    let sigma_2d = (p.variance_m2[0] + p.variance_m2[1]).max(0.0).sqrt();
    offset_xy_m[0].hypot(offset_xy_m[1]) - config.confidence_k * sigma_2d > config.tolerance_xy_m
}

/// For each recording index, the positions in `points` of the points observed from it.
fn points_by_recording(points: &[&VerifiedPoint]) -> BTreeMap<usize, Vec<usize>> {
    let mut by_recording: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for (k, p) in points.iter().enumerate() {
        for &r in &p.observed_from {
            by_recording.entry(r).or_default().push(k);
        }
    }
    by_recording
}

/// With `min_neighbours` > 0: whether the points of `points` that share a recording with `p` (itself included;
/// found through `by_recording`, [`points_by_recording`]) are off as a whole — their component-wise median
/// horizontal offset beyond `tolerance_xy_m` by more than `confidence_k` of `p`'s σ; `true` when fewer than
/// `min_neighbours` share one (too few to outvote it).
fn neighbours_agree_off(
    p: &VerifiedPoint,
    points: &[&VerifiedPoint],
    by_recording: &BTreeMap<usize, Vec<usize>>,
    config: &VerifyConfig,
) -> bool {
    if config.min_neighbours == 0 {
        return true;
    }
    let mut sharing: Vec<usize> = p
        .observed_from
        .iter()
        .filter_map(|r| by_recording.get(r))
        .flatten()
        .copied()
        .collect();
    sharing.sort_unstable();
    sharing.dedup();
    if sharing.len() < config.min_neighbours {
        return true;
    }
    let mut xs: Vec<f64> = sharing.iter().map(|&k| points[k].offset_m[0]).collect();
    let mut ys: Vec<f64> = sharing.iter().map(|&k| points[k].offset_m[1]).collect();
    let (Some(mx), Some(my)) = (median_in_place(&mut xs), median_in_place(&mut ys)) else {
        return true;
    };
    significantly_off([mx, my], p, config)
}

/// Column names of `verification.csv`.
pub const VERIFICATION_CSV_HEADER: [&str; 21] = [
    "segment",
    "first_image_id",
    "last_image_id",
    "recordings",
    "points",
    "mean_x",
    "mean_y",
    "mean_z",
    "sd_x",
    "sd_y",
    "sd_z",
    "mean_3d",
    "sd_3d",
    "sigma_mean_x",
    "sigma_mean_y",
    "sigma_mean_z",
    "points_off",
    "status",
    "unobserved_run",
    "stated_sigma_xy",
    "points_3d",
];

/// `verification.csv`: one row per segment (metres; floats in shortest round-trip form), then a row
/// `segment = all` with the overall statistics. Written atomically.
pub fn write_verification_csv(path: &Path, v: &Verification) -> io::Result<()> {
    write_csv(path, &VERIFICATION_CSV_HEADER, |w| {
        for s in v.segments.iter().chain(std::iter::once(&v.overall)) {
            let label = if std::ptr::eq(s, &v.overall) {
                "all".to_string()
            } else {
                s.index.to_string()
            };
            let nums = [
                s.mean_m[0],
                s.mean_m[1],
                s.mean_m[2],
                s.sd_m[0],
                s.sd_m[1],
                s.sd_m[2],
                s.mean_3d_m,
                s.sd_3d_m,
                s.sigma_mean_m[0],
                s.sigma_mean_m[1],
                s.sigma_mean_m[2],
            ]
            .map(|x| format!("{x}"));
            writeln!(
                w,
                "{label},{},{},{},{},{},{},{},{},{},{}",
                quote(&s.first_image_id),
                quote(&s.last_image_id),
                s.recordings,
                s.points,
                nums.join(","),
                s.points_off,
                s.status.label(),
                s.unobserved_run,
                s.stated_sigma_xy_m
                    .map_or(String::new(), |v| format!("{v}")),
                s.points_3d
            )?;
        }
        Ok(())
    })
}

/// A short fixed-width table for stdout (Table 5-13 layout per segment, centimetres).
pub fn render_verification_table(v: &Verification) -> String {
    let mut out = String::new();
    out.push_str(&format!(
        "verification: MM (recorded poses) − aerial control, per segment [cm]; tolerance {:.0} cm horizontal, \
         {:.0} cm vertical\n",
        v.config.tolerance_xy_m * 100.0,
        v.config.tolerance_z_m * 100.0
    ));
    out.push_str(&format!(
        "{:>4} {:<14} {:<14} {:>4} {:>4} {:>7} {:>7} {:>7} {:>6} {:>6} {:>6} {:>7} {:>6} {:>7}  {}\n",
        "seg",
        "first",
        "last",
        "pts",
        "off",
        "mean X",
        "mean Y",
        "mean Z",
        "SD X",
        "SD Y",
        "SD Z",
        "mean 3D",
        "±2D",
        "2D",
        "status"
    ));
    for s in v.segments.iter().chain(std::iter::once(&v.overall)) {
        let label = if std::ptr::eq(s, &v.overall) {
            "all".to_string()
        } else {
            s.index.to_string()
        };
        let cm = |x: f64| x * 100.0;
        out.push_str(&format!(
            "{:>4} {:<14} {:<14} {:>4} {:>4} {:>7.1} {:>7.1} {:>7.1} {:>6.1} {:>6.1} {:>6.1} {:>7.1} {:>6.1} {:>7.1}  {}\n",
            label,
            truncate(&s.first_image_id, 14),
            truncate(&s.last_image_id, 14),
            s.points,
            s.points_off,
            cm(s.mean_m[0]),
            cm(s.mean_m[1]),
            cm(s.mean_m[2]),
            cm(s.sd_m[0]),
            cm(s.sd_m[1]),
            cm(s.sd_m[2]),
            cm(s.mean_3d_m),
            cm(s.sigma_mean_m[0].hypot(s.sigma_mean_m[1])),
            cm(s.offset_2d_m),
            s.status.label()
        ));
    }
    if v.skipped_single_aerial + v.skipped_mm > 0 {
        out.push_str(&format!(
            "skipped: {} control points seen in one aerial image and not compared, {} without an MM \
             triangulation\n",
            v.skipped_single_aerial, v.skipped_mm
        ));
    }
    out
}

fn truncate(s: &str, n: usize) -> String {
    s.chars().take(n).collect()
}
