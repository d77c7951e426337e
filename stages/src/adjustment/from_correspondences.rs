//! From the registration stages' correspondences to an adjustment block and back to per-recording results
//! (thesis 5.4.3): MM tie points become tie-point unknowns with their panorama
//! observations; aerial control points either tie their point to the aerial triangulation (thesis scheme:
//! ≥ 2 aerial observations, σ = 0.10 m or the triangulation covariance) or, with `aerial_observations`, put
//! their aerial pixels into the bundle with the aerial orientation fixed (single-aerial points
//! count). Recorded positions are weak priors (σ from the config, else `sigma_xy`/`sigma_z`, else the
//! documented defaults); consecutive recordings optionally keep their recorded differences (3.4.2).
//!
//! Recordings are used in the order given (the campaign sorts them by time, which the relative constraints
//! rely on). Everything an adjust node reports is in [`AdjustmentRun`] (serde, so it can be cached).

use super::adjust::{adjust, ObservationCounts};
pub use super::block_point::{BlockPoint, PointKind};
use super::config::{AdjustConfig, ControlWeighting};
use super::control_consistency::select_control;
use super::error::AdjustError;
use super::extrapolation_anchor::tail_anchors;
use super::height_observation::{HeightObservations, HeightSource};
use super::in_frame::{adjustment_to_map, block_to_local};
use super::problem::{
    AdjustOptions, AerialImageObservation, Block, BlockRecording, ControlPoint, HeightObservation,
    PanoObservation, RelativeConstraint,
};
use super::relative_noise::RelativeSigma;
use super::tie_point_heights::{controlled_recordings, tie_point_heights};
use super::weak_control::ControlEvidence;
use super::weak_control_sigma::{self, WeakSigmaEstimate};
use crate::campaign::{AerialImage, AerialKind, Recording};
use crate::correspondence::{AerialControlPoint, MmTiePoint};
use crate::crs::MapFrame;
use crate::geometry::{triangulate_rays, FrameCamera, PanoramaCamera};
use crate::params::{describe, Params, StageId};
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("adjust", "11");

/// The inputs of one adjustment.
#[derive(Clone, Copy, Debug)]
pub struct AdjustInputs<'a> {
    /// `mm/recordings.csv` rows, sorted by time (the recorded poses).
    pub recordings: &'a [Recording],
    /// Panorama (width, height) in pixels, one per recording.
    pub pano_size_px: &'a [(u32, u32)],
    /// The detail level of each recording's panorama (`PyramidLayout::detail_level`: 0 unless it was enlarged
    /// by pixel repetition), one per recording, or empty for 0 everywhere. `pano_sigma_px` is in pixels of
    /// that level, so a panorama enlarged 2^l times is weighted like the original.
    pub pano_detail_level: &'a [usize],
    /// MM–MM tie points (nadir matching and/or the oblique sparse cloud).
    pub tie_points: &'a [MmTiePoint],
    /// Aerial control points (nadir and/or oblique).
    pub control: &'a [AerialControlPoint],
    /// `aerial/nadir/cameras.csv` and `aerial/oblique/cameras.csv` rows (fixed orientations).
    pub nadir: &'a [AerialImage],
    pub oblique: &'a [AerialImage],
    /// Observed heights of the recordings (one per recording, `None` where there is none) from the campaign's
    /// terrain model ([`super::height_observation::terrain_heights`]), used with `dtm_height`; `None` when the
    /// campaign has no terrain model.
    pub heights: Option<&'a [Option<HeightObservation>]>,
    /// Observed heights of the tie points (one per entry of `tie_points`, `None` where there is none: no
    /// terrain there, or not a ground point) from the campaign's terrain model
    /// ([`super::tie_point_heights::terrain_under_tie_points`]), used with `dtm_tie_heights`; `None` when the
    /// campaign has no terrain model.
    pub tie_point_heights: Option<&'a [Option<HeightObservation>]>,
}

/// An aerial image referenced by the block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AerialImageRef {
    pub kind: AerialKind,
    pub image_id: String,
}

/// How the correspondences entered the block.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BuildCounts {
    pub tie_points: usize,
    pub control_points: usize,
    /// Control points used as triangulated control (thesis scheme).
    pub control_as_gcp: usize,
    /// Control points whose aerial pixels went into the bundle.
    pub control_as_aerial_observations: usize,
    /// Control points not used: a single aerial observation in the thesis scheme, or no usable point.
    pub control_unused: usize,
    pub aerial_observations: usize,
    /// Aerial observations left out because the point's initial position is not in front of that camera.
    pub aerial_observations_skipped: usize,
    pub relative_constraints: usize,
    /// The recordings' observed heights (`dtm_height`).
    pub heights: HeightObservations,
    /// Weak orthophoto control points not used because they disagree with the strong control along the
    /// trajectory (`weak_control_tolerance_m`).
    pub weak_control_dropped: usize,
    /// Control points not used because their correction disagrees with the control of the neighbouring
    /// recordings (`control_consistency_window`).
    pub inconsistent_control_dropped: usize,
    /// Recordings beyond the first or last recording with control tied to it (`extrapolation_anchor`).
    pub extrapolation_anchors: usize,
    /// Tie points whose height was observed from the terrain model (`dtm_tie_heights`).
    pub tie_point_heights: usize,
    /// The weak control's σ measured against the strong control of the same recordings
    /// (`weak_control_sigma_estimated`; `None` when off).
    pub weak_control_sigma: Option<WeakSigmaEstimate>,
}

/// A block with the names of its unknowns.
#[derive(Clone, Debug)]
pub struct BlockBuild {
    pub block: Block,
    pub options: AdjustOptions,
    pub recording_ids: Vec<String>,
    pub points: Vec<BlockPoint>,
    pub aerial_images: Vec<AerialImageRef>,
    pub counts: BuildCounts,
    /// The σ of the relative constraints (given, or estimated from the recorded trajectory).
    pub relative_sigma: RelativeSigma,
}

/// One adjusted recording.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunRecording {
    pub image_id: String,
    /// Recorded projection centre, world, metres.
    pub recorded_world: [f64; 3],
    /// Adjusted projection centre, world, metres.
    pub adjusted_world: [f64; 3],
    /// Added to the recorded yaw, degrees (0 unless estimated).
    pub yaw_correction_deg: f64,
    /// Posterior σ of x, y, z, metres: a posteriori (scaled by σ̂0) when there is redundancy, else a priori.
    pub sigma_m: [f64; 3],
    /// σ of the yaw correction, degrees, scaled like `sigma_m` (0 when yaw is not estimated).
    pub sigma_yaw_deg: f64,
    pub sigma_is_a_posteriori: bool,
}

/// One adjusted tie point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunPoint {
    pub point: BlockPoint,
    /// Adjusted coordinates (initial ones when undetermined), world, metres.
    pub position_world: [f64; 3],
    /// Determined in the final solve (≥ 2 rays or a control point).
    pub determined: bool,
}

/// Everything the adjust node reports (metrics: iterations, observations, rejected, cost).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AdjustmentRun {
    pub config: AdjustConfig,
    pub recordings: Vec<RunRecording>,
    pub points: Vec<RunPoint>,
    pub aerial_images: Vec<AerialImageRef>,
    /// Accepted LM steps over all rejection rounds.
    pub iterations: usize,
    /// Why the final solve stopped (`StepSize`, `CostChange`, `ZeroCost`, `MaxIterations`, `DampingLimit`).
    pub termination: String,
    pub observations: ObservationCounts,
    pub rejected: ObservationCounts,
    /// Rejected observations of all kinds.
    pub rejected_total: usize,
    /// Final cost ½Σρ (whitened).
    pub final_cost: f64,
    /// σ̂0² (`None` without redundancy).
    pub variance_factor: Option<f64>,
    pub redundancy: i64,
    pub rejection_rounds: usize,
    pub build: BuildCounts,
    /// The σ of the relative constraints between consecutive recordings (used by them when they are on, and
    /// by the corrections' interpolation between recordings always).
    pub relative_sigma: RelativeSigma,
}

/// Builds the block of one configuration.
pub fn build_block(
    inputs: &AdjustInputs,
    config: &AdjustConfig,
) -> Result<BlockBuild, AdjustError> {
    if let Err(problems) = config.validate() {
        return Err(AdjustError::InvalidInput {
            item: "adjust parameters".to_string(),
            problem: describe(&problems),
        });
    }
    let (recording_index, recordings, heights) = block_recordings(inputs, config)?;
    let mut block = Block {
        recordings,
        ..Block::default()
    };
    let mut points: Vec<BlockPoint> = Vec::new();
    let mut point_index: HashMap<String, usize> = HashMap::new();
    let mut counts = BuildCounts {
        heights,
        ..BuildCounts::default()
    };
    // σ of each recording's panorama observations, full-resolution pixels (pixels of its detail level).
    let sigma_px: Vec<f64> = (0..block.recordings.len())
        .map(|r| {
            let level = inputs
                .pano_detail_level
                .get(r)
                .copied()
                .unwrap_or(0)
                .min(30);
            config.pano_sigma_px * (1u64 << level) as f64
        })
        .collect();
    let sigma_px = sigma_px.as_slice();
    let resolve =
        |owner: &str, image_id: &str| resolve_recording(&recording_index, owner, image_id);

    for tp in inputs.tie_points {
        add_tie_point(
            tp,
            &resolve,
            sigma_px,
            &mut block,
            &mut points,
            &mut point_index,
        )?;
        counts.tie_points += 1;
    }

    let mut cameras = AerialCameras::default();
    // Per control point of the block: the correction it implies, its recordings and whether it is weak.
    let mut evidence: Vec<ControlEvidence> = Vec::new();
    for cp in inputs.control {
        counts.control_points += 1;
        let owner = format!("aerial control point '{}'", cp.tie_point_id);
        // Resolve the aerial images (in order of first use, so the numbering is deterministic).
        let mut aerial = Vec::with_capacity(cp.aerial.len());
        for a in &cp.aerial {
            let idx = cameras.index_of(inputs, a.kind, &a.image_id, &owner)?;
            aerial.push((idx, a.u_px, a.v_px, a.sigma_px));
        }
        let p = match point_index.get(&cp.tie_point_id) {
            Some(&p) => p,
            None => {
                // A control point whose tie point was not passed: its own point from its MM observations.
                let mut pano = Vec::with_capacity(cp.mm.len());
                for o in &cp.mm {
                    pano.push((resolve(&owner, &o.image_id)?, o.u_px, o.v_px));
                }
                let Some(initial) = initial_point(&block, &pano, cp.point_world, sigma_px) else {
                    counts.control_unused += 1;
                    continue;
                };
                let p = points.len();
                add_point(
                    &mut block,
                    &mut points,
                    &cp.tie_point_id,
                    initial,
                    pano,
                    sigma_px,
                );
                point_index.insert(cp.tie_point_id.clone(), p);
                p
            }
        };
        // An orthophoto control point (`map`) is control like a point triangulated from ≥ 2 aerial images.
        let kind = if cp.aerial.len() >= 2 || cp.map.is_some() {
            PointKind::Control
        } else {
            PointKind::SingleAerial
        };
        if points[p].kind != PointKind::Control {
            points[p].kind = kind;
        }
        points[p]
            .aerial
            .extend(aerial.iter().map(|&(camera, u, v, _)| (camera, u, v)));
        if config.aerial_observations && cp.map.is_none() {
            add_aerial_observations(&mut block, &cameras.rows, p, &aerial, &mut counts);
        } else if let Some(xyz) = cp
            .point_world
            .filter(|_| cp.aerial.len() >= 2 || cp.map.is_some())
        {
            let covariance_m2 = control_covariance(config, cp, &owner)?;
            block.control_points.push(ControlPoint {
                point: p,
                position_world: Vector3::from(xyz),
                covariance_m2,
            });
            counts.control_as_gcp += 1;
            let initial = block.points_initial_world[p];
            let mut recordings: Vec<usize> = points[p].pano.iter().map(|o| o.0).collect();
            recordings.sort_unstable();
            recordings.dedup();
            evidence.push(ControlEvidence {
                correction_m: nalgebra::Vector2::new(xyz[0] - initial.x, xyz[1] - initial.y),
                recordings,
                weak: cp
                    .map
                    .as_ref()
                    .is_some_and(|m| m.score < config.weak_control_below),
                spread: recording_spread(&block, &points[p].pano, sigma_px),
            });
        } else {
            counts.control_unused += 1;
        }
    }
    let relative_sigma = RelativeSigma::resolve(
        config.relative_sigma_m,
        inputs.recordings,
        config.relative_max_gap_m,
    );
    let selection = select_control(
        &evidence,
        block.recordings.len(),
        config,
        relative_sigma.sigma_m,
    );
    counts.weak_control_dropped = selection.weak;
    counts.inconsistent_control_dropped = selection.inconsistent;
    if config.weak_control_sigma_estimated {
        let estimate = weak_control_sigma::estimate(&evidence, &selection.keep);
        if let Some(sigma_m) = estimate.sigma_m {
            let given: Vec<Matrix3<f64>> = block
                .control_points
                .iter()
                .map(|c| c.covariance_m2)
                .collect();
            let raised =
                weak_control_sigma::weak_covariances(&evidence, &selection.keep, &given, sigma_m);
            for (c, cov) in block.control_points.iter_mut().zip(raised) {
                c.covariance_m2 = cov;
            }
        }
        counts.weak_control_sigma = Some(estimate);
    }
    if selection.keep.contains(&false) {
        drop_control(&mut block, &mut points, &selection.keep, &mut counts);
    }
    if let (true, Some(heights)) = (config.dtm_tie_heights, inputs.tie_point_heights) {
        let controlled = controlled_recordings(&block);
        block.point_heights = tie_point_heights(
            inputs.tie_points,
            heights,
            &point_index,
            &points,
            &controlled,
        );
        counts.tie_point_heights = block.point_heights.len();
    }
    block.aerial_cameras = cameras
        .rows
        .iter()
        .map(|r| FrameCamera::from_aerial(r))
        .collect();

    if config.relative_constraints {
        block.relative_constraints =
            relative_constraints(inputs.recordings, config, relative_sigma.sigma_m);
        counts.relative_constraints = block.relative_constraints.len();
    }
    if config.extrapolation_anchor {
        let anchors = tail_anchors(&block, inputs.recordings, config, relative_sigma.sigma_m);
        counts.extrapolation_anchors = anchors.len();
        block.relative_constraints.extend(anchors);
    }
    block.validate()?;
    Ok(BlockBuild {
        block,
        options: config.options(),
        recording_ids: inputs
            .recordings
            .iter()
            .map(|r| r.image_id.clone())
            .collect(),
        points,
        aerial_images: cameras.images,
        counts,
        relative_sigma,
    })
}

/// Removes the control points `keep` rejects (parallel to the block's control points); a point left without
/// control becomes a tie point again.
fn drop_control(
    block: &mut Block,
    points: &mut [BlockPoint],
    keep: &[bool],
    counts: &mut BuildCounts,
) {
    let mut kept = Vec::with_capacity(block.control_points.len());
    for (c, k) in block.control_points.iter().zip(keep) {
        if *k {
            kept.push(*c);
        } else {
            counts.control_as_gcp -= 1;
        }
    }
    block.control_points = kept;
    let mut still_control = vec![false; points.len()];
    for c in &block.control_points {
        still_control[c.point] = true;
    }
    for (p, point) in points.iter_mut().enumerate() {
        if point.kind == PointKind::Control && !still_control[p] && point.aerial.is_empty() {
            point.kind = PointKind::Tie;
        }
    }
}

/// The aerial cameras the control points use, numbered in order of first use.
#[derive(Default)]
struct AerialCameras<'a> {
    index: HashMap<(AerialKind, &'a str), usize>,
    images: Vec<AerialImageRef>,
    rows: Vec<&'a AerialImage>,
}

impl<'a> AerialCameras<'a> {
    /// The number of aerial image `image_id` of `kind` (named by `owner`), added on first use.
    fn index_of(
        &mut self,
        inputs: &AdjustInputs<'a>,
        kind: AerialKind,
        image_id: &'a str,
        owner: &str,
    ) -> Result<usize, AdjustError> {
        if let Some(&i) = self.index.get(&(kind, image_id)) {
            return Ok(i);
        }
        let rows = match kind {
            AerialKind::Nadir => inputs.nadir,
            AerialKind::Oblique => inputs.oblique,
        };
        let row = rows
            .iter()
            .find(|r| r.image_id == image_id)
            .ok_or_else(|| AdjustError::InvalidInput {
                item: owner.to_string(),
                problem: format!(
                    "aerial image '{image_id}' ({kind:?}) is not among the aerial cameras passed; pass \
                     the cameras.csv rows the control points were measured in"
                ),
            })?;
        let i = self.images.len();
        self.index.insert((kind, image_id), i);
        self.images.push(AerialImageRef {
            kind,
            image_id: image_id.to_string(),
        });
        self.rows.push(row);
        Ok(i)
    }
}

/// The recordings' index by image id, the block's recordings and what their height observations were.
type BlockRecordings<'a> = (
    HashMap<&'a str, usize>,
    Vec<BlockRecording>,
    HeightObservations,
);

/// The block's recordings (recorded poses as weak priors, thesis 5.4.3, and with `dtm_height` their observed
/// heights) and their index by image id; refuses a size or height list that does not match and duplicate
/// image ids.
fn block_recordings<'a>(
    inputs: &AdjustInputs<'a>,
    config: &AdjustConfig,
) -> Result<BlockRecordings<'a>, AdjustError> {
    let n_rec = inputs.recordings.len();
    for (item, len, what) in [
        (
            "panorama sizes",
            Some(inputs.pano_size_px.len()),
            "(width, height)",
        ),
        (
            "recording heights",
            inputs.heights.map(<[_]>::len),
            "height or none",
        ),
    ] {
        if let Some(len) = len.filter(|&l| l != n_rec) {
            return Err(AdjustError::InvalidInput {
                item: item.to_string(),
                problem: format!(
                    "{len} {item} for {n_rec} recordings; pass one {what} per recording"
                ),
            });
        }
    }
    let (source, heights) = match (config.dtm_height, inputs.heights) {
        (false, _) => (HeightSource::Off, &[][..]),
        (true, None) => (HeightSource::NoDtm, &[][..]),
        (true, Some(h)) => (HeightSource::Dtm, h),
    };
    let mut recording_index: HashMap<&str, usize> = HashMap::with_capacity(n_rec);
    let mut recordings = Vec::with_capacity(n_rec);
    for (i, (rec, &(w, h))) in inputs
        .recordings
        .iter()
        .zip(inputs.pano_size_px)
        .enumerate()
    {
        if recording_index.insert(rec.image_id.as_str(), i).is_some() {
            return Err(AdjustError::InvalidInput {
                item: format!("recording '{}'", rec.image_id),
                problem: "image_id occurs twice; image ids must be unique".to_string(),
            });
        }
        let (prior_xy, prior_z) = prior_sigmas_m(rec, config);
        recordings.push(BlockRecording {
            camera: PanoramaCamera::from_recording(rec, w, h),
            prior_sigma_xy_m: Some(prior_xy),
            prior_sigma_z_m: Some(prior_z),
            height_observation: heights.get(i).copied().flatten(),
        });
    }
    let summary = HeightObservations::of(source, heights);
    Ok((recording_index, recordings, summary))
}

/// The σ of a recording's position prior, m: horizontal, vertical (the workflow's override, else the
/// recording's own `sigma_xy` / `sigma_z`, else the configuration's default).
pub fn prior_sigmas_m(rec: &Recording, config: &AdjustConfig) -> (f64, f64) {
    (
        config
            .prior_sigma_xy_m
            .or(rec.sigma_xy_m)
            .unwrap_or(config.default_prior_sigma_xy_m),
        config
            .prior_sigma_z_m
            .or(rec.sigma_z_m)
            .unwrap_or(config.default_prior_sigma_z_m),
    )
}

/// The recording a correspondence of `owner` names, by image id.
fn resolve_recording(
    recording_index: &HashMap<&str, usize>,
    owner: &str,
    image_id: &str,
) -> Result<usize, AdjustError> {
    recording_index
        .get(image_id)
        .copied()
        .ok_or_else(|| AdjustError::InvalidInput {
            item: owner.to_string(),
            problem: format!(
                "panorama '{image_id}' is not among the {} recordings of the adjustment; \
                 pass the recordings the correspondences were made with",
                recording_index.len()
            ),
        })
}

/// An MM tie point as a tie-point unknown with its panorama observations (σ `sigma_px`).
fn add_tie_point(
    tp: &MmTiePoint,
    resolve: &impl Fn(&str, &str) -> Result<usize, AdjustError>,
    sigma_px: &[f64],
    block: &mut Block,
    points: &mut Vec<BlockPoint>,
    point_index: &mut HashMap<String, usize>,
) -> Result<(), AdjustError> {
    let owner = format!("tie point '{}'", tp.id);
    if point_index.contains_key(&tp.id) {
        return Err(AdjustError::InvalidInput {
            item: owner,
            problem: "id occurs twice; tie-point ids must be unique".to_string(),
        });
    }
    if !tp.point_world.iter().all(|v| v.is_finite()) {
        return Err(AdjustError::InvalidInput {
            item: owner,
            problem: "point_world is not finite".to_string(),
        });
    }
    let mut pano = Vec::with_capacity(tp.observations.len());
    for o in &tp.observations {
        pano.push((resolve(&owner, &o.image_id)?, o.u_px, o.v_px));
    }
    point_index.insert(tp.id.clone(), points.len());
    let initial = Vector3::from(tp.point_world);
    add_point(block, points, &tp.id, initial, pano, sigma_px);
    Ok(())
}

/// A tie-point unknown `id` at `initial` (world, m) with its panorama observations (recording, u, v in px);
/// `sigma_px` per recording.
fn add_point(
    block: &mut Block,
    points: &mut Vec<BlockPoint>,
    id: &str,
    initial: Vector3<f64>,
    pano: Vec<(usize, f64, f64)>,
    sigma_px: &[f64],
) {
    let p = points.len();
    for &(recording, u_px, v_px) in &pano {
        block.pano_observations.push(PanoObservation {
            recording,
            point: p,
            u_px,
            v_px,
            sigma_px: sigma_px[recording],
        });
    }
    block.points_initial_world.push(initial);
    points.push(BlockPoint {
        id: id.to_string(),
        kind: PointKind::Tie,
        pano,
        aerial: Vec::new(),
    });
}

/// A control point's aerial pixels as observations of point `p` in the bundle (aerial orientations fixed),
/// each with its own σ (the level it was located at) or else its image's `sigma_px`; an observation whose
/// camera does not see the point's initial position is skipped and counted.
fn add_aerial_observations(
    block: &mut Block,
    rows: &[&AerialImage],
    p: usize,
    aerial: &[(usize, f64, f64, Option<f64>)],
    counts: &mut BuildCounts,
) {
    let initial = block.points_initial_world[p];
    for &(camera, u_px, v_px, sigma_px) in aerial {
        if FrameCamera::from_aerial(rows[camera])
            .project_world(&initial)
            .is_none()
        {
            counts.aerial_observations_skipped += 1;
            continue;
        }
        counts.aerial_observations += 1;
        block.aerial_observations.push(AerialImageObservation {
            camera,
            point: p,
            u_px,
            v_px,
            sigma_px: sigma_px
                .filter(|s| s.is_finite() && *s > 0.0)
                .unwrap_or(rows[camera].sigma_px),
        });
    }
    counts.control_as_aerial_observations += usize::from(!aerial.is_empty());
}

/// The covariance of a control point tied to the aerial triangulation (thesis 5.4.3): σ = `control_sigma_m`
/// in every axis, or the triangulation's own covariance.
fn control_covariance(
    config: &AdjustConfig,
    cp: &AerialControlPoint,
    owner: &str,
) -> Result<Matrix3<f64>, AdjustError> {
    // Orthophoto points always carry their stated accuracy (the fixed σ describes aerial triangulation).
    let weighting = match cp.map {
        Some(_) => ControlWeighting::Covariance,
        None => config.control_weighting,
    };
    match weighting {
        ControlWeighting::Fixed => {
            Ok(Matrix3::identity() * (config.control_sigma_m * config.control_sigma_m))
        }
        ControlWeighting::Covariance => {
            let c = cp.covariance_m2.ok_or_else(|| AdjustError::InvalidInput {
                item: owner.to_string(),
                problem: "control_weighting = \"covariance\" but the point has no covariance_m2"
                    .to_string(),
            })?;
            Ok(Matrix3::from_row_slice(&[
                c[0][0], c[0][1], c[0][2], c[1][0], c[1][1], c[1][2], c[2][0], c[2][1], c[2][2],
            ]))
        }
    }
}

/// Consecutive recordings at most `relative_max_gap_m` apart keep their recorded difference (thesis 3.4.2).
fn relative_constraints(
    recordings: &[Recording],
    config: &AdjustConfig,
    sigma_m: f64,
) -> Vec<RelativeConstraint> {
    (1..recordings.len())
        .filter(|&i| {
            let (a, b) = (&recordings[i - 1], &recordings[i]);
            (a.x - b.x).hypot(a.y - b.y) <= config.relative_max_gap_m
        })
        .map(|i| RelativeConstraint {
            from: i - 1,
            to: i,
            sigma_m,
        })
        .collect()
}

/// How the recordings' errors spread the horizontal position triangulated from the panorama observations
/// `pano` (recording, u, v) with the recorded poses, relative to one recording's error: Σᵢ JᵢJᵢᵀ,
/// Jᵢ = ∂(x, y)/∂(recording i's x, y) of the triangulated point (finite differences of 1 cm). The identity
/// for a point of one recording (it moves with it) or one that cannot be triangulated.
fn recording_spread(
    block: &Block,
    pano: &[(usize, f64, f64)],
    sigma_px: &[f64],
) -> nalgebra::Matrix2<f64> {
    const STEP_M: f64 = 0.01;
    let one = nalgebra::Matrix2::identity();
    let mut recordings: Vec<usize> = pano.iter().map(|o| o.0).collect();
    recordings.sort_unstable();
    recordings.dedup();
    if recordings.len() < 2 {
        return one;
    }
    let triangulate = |shift: Option<(usize, Vector3<f64>)>| {
        let rays: Vec<_> = pano
            .iter()
            .map(|&(r, u, v)| {
                let mut ray = block.recordings[r].camera.pixel_ray(u, v);
                if let Some((_, d)) = shift.filter(|s| s.0 == r) {
                    ray.origin_world += d;
                }
                ray
            })
            .collect();
        let sigmas: Vec<f64> = pano
            .iter()
            .map(|&(r, _, _)| block.recordings[r].camera.angular_sigma_rad(sigma_px[r]))
            .collect();
        triangulate_rays(&rays, &sigmas).ok().map(|t| t.point_world)
    };
    let Some(base) = triangulate(None) else {
        return one;
    };
    let mut sum = nalgebra::Matrix2::<f64>::zeros();
    for &r in &recordings {
        let mut j = nalgebra::Matrix2::<f64>::zeros();
        for axis in 0..2 {
            let mut d = Vector3::zeros();
            d[axis] = STEP_M;
            let Some(moved) = triangulate(Some((r, d))) else {
                return one;
            };
            j[(0, axis)] = (moved.x - base.x) / STEP_M;
            j[(1, axis)] = (moved.y - base.y) / STEP_M;
        }
        sum += j * j.transpose();
    }
    sum
}

/// Initial coordinates of a point from its panorama rays with the recorded poses, else `fallback`.
fn initial_point(
    block: &Block,
    pano: &[(usize, f64, f64)],
    fallback: Option<[f64; 3]>,
    sigma_px: &[f64],
) -> Option<Vector3<f64>> {
    if pano.len() >= 2 {
        let rays: Vec<_> = pano
            .iter()
            .map(|&(r, u, v)| block.recordings[r].camera.pixel_ray(u, v))
            .collect();
        let sigmas: Vec<f64> = pano
            .iter()
            .map(|&(r, _, _)| block.recordings[r].camera.angular_sigma_rad(sigma_px[r]))
            .collect();
        if let Ok(t) = triangulate_rays(&rays, &sigmas) {
            return Some(t.point_world);
        }
    }
    fallback
        .map(Vector3::from)
        .filter(|p| p.iter().all(|v| v.is_finite()))
}

/// Builds and adjusts one configuration, taking the campaign's coordinates as a Cartesian frame.
pub fn run(inputs: &AdjustInputs, config: &AdjustConfig) -> Result<AdjustmentRun, AdjustError> {
    run_in_frame(inputs, config, &MapFrame::Cartesian)
}

/// Builds and adjusts one configuration of a campaign whose intersection frame is `frame`. With aerial
/// observations in the bundle (`aerial_observations`) and a tangent frame, the block is adjusted in that frame
/// and the results are converted back to map coordinates ([`super::in_frame`]): aerial rays hundreds of metres
/// long are then free of the map projection's scale and the earth's curvature. Otherwise every ray of the
/// block is a panorama ray of a few tens of metres, and the block is adjusted in map coordinates.
pub fn run_in_frame(
    inputs: &AdjustInputs,
    config: &AdjustConfig,
    frame: &MapFrame,
) -> Result<AdjustmentRun, AdjustError> {
    let build = build_block(inputs, config)?;
    let adj = if config.aerial_observations && frame.is_tangent() {
        let local = block_to_local(&build.block, frame)?;
        adjustment_to_map(adjust(&local, &build.options)?, frame)?
    } else {
        adjust(&build.block, &build.options)?
    };
    let recordings = build
        .recording_ids
        .iter()
        .zip(&build.block.recordings)
        .zip(&adj.recordings)
        .map(|((id, rec), a)| {
            let (sigma, posterior) = match a.sigma_a_posteriori_m {
                Some(s) => (s, true),
                None => (a.sigma_a_priori_m, false),
            };
            let yaw_scale = match (posterior, adj.variance_factor) {
                (true, Some(f)) => super::adjust::posterior_scale(f),
                _ => 1.0,
            };
            RunRecording {
                image_id: id.clone(),
                recorded_world: rec.camera.center_world.into(),
                adjusted_world: a.position_world.into(),
                yaw_correction_deg: a.yaw_correction_deg,
                sigma_m: sigma.into(),
                sigma_yaw_deg: a.sigma_yaw_a_priori_deg * yaw_scale,
                sigma_is_a_posteriori: posterior,
            }
        })
        .collect();
    let points = build
        .points
        .into_iter()
        .enumerate()
        .map(|(i, point)| RunPoint {
            point,
            position_world: adj.points_world[i].into(),
            determined: adj.point_determined[i],
        })
        .collect();
    let rejected_total = adj.rejected.pano + adj.rejected.control + adj.rejected.aerial;
    Ok(AdjustmentRun {
        config: config.clone(),
        recordings,
        points,
        aerial_images: build.aerial_images,
        iterations: adj.iterations,
        termination: format!("{:?}", adj.termination),
        observations: adj.observations,
        rejected: adj.rejected,
        rejected_total,
        final_cost: adj.final_cost,
        variance_factor: adj.variance_factor,
        redundancy: adj.redundancy,
        rejection_rounds: adj.rounds.len(),
        build: build.counts,
        relative_sigma: RelativeSigma {
            released: adj.released_relative,
            ..build.relative_sigma
        },
    })
}
