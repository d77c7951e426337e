//! The adjustment block of one configuration, built from the registration stages' correspondences (thesis
//! 5.4.3): MM tie points become point unknowns with their panorama observations; aerial control points tie
//! their point to the aerial triangulation or put their aerial pixels into the bundle; recorded positions
//! become weak priors, consecutive recordings optionally keep their recorded differences (3.4.2). Control
//! points are screened here (weak and inconsistent control) before the block is handed to the solver.

pub use super::block_point::{BlockPoint, PointKind};
pub use super::build_counts::BuildCounts;
use super::chain_end_evidence::drop_lone_chain_end_evidence;
use super::config::{AdjustConfig, ControlWeighting};
use super::control_screen::{
    aerial_observation_evidence, screen_control, EvidenceSource, SourcedEvidence,
};
use super::error::AdjustError;
use super::extrapolation_anchor::tail_anchors;
use super::problem::{AdjustOptions, AerialImageObservation, Block, ControlPoint, PanoObservation};
use super::relative_noise::RelativeSigma;
use super::tie_point_heights::{controlled_recordings, tie_point_heights};
use super::weak_control::ControlEvidence;
use crate::campaign::{AerialImage, AerialKind};
use crate::correspondence::{AerialControlPoint, MmTiePoint};
use crate::geometry::{triangulate_rays, FrameCamera};
use crate::params::{describe, Params};
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

pub use super::adjust_inputs::AdjustInputs;
pub use super::block_recordings::prior_sigmas_m;
use super::block_recordings::{
    block_recordings, pano_sigmas_px, relative_constraints, resolve_recording,
};

/// An aerial image referenced by the block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AerialImageRef {
    pub kind: AerialKind,
    pub image_id: String,
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
    let mut asm = Assembly {
        block: Block {
            recordings,
            ..Block::default()
        },
        points: Vec::new(),
        point_index: HashMap::new(),
        cameras: AerialCameras::default(),
        counts: BuildCounts {
            heights,
            ..BuildCounts::default()
        },
    };
    let sigma_px = pano_sigmas_px(inputs, config, asm.block.recordings.len());
    let sigma_px = sigma_px.as_slice();
    let resolve =
        |owner: &str, image_id: &str| resolve_recording(&recording_index, owner, image_id);

    for tp in inputs.tie_points {
        add_tie_point(
            tp,
            &resolve,
            sigma_px,
            &mut asm.block,
            &mut asm.points,
            &mut asm.point_index,
        )?;
        asm.counts.tie_points += 1;
    }

    // Per control point of the block: the correction it implies, its recordings and whether it is weak.
    let mut evidence: Vec<SourcedEvidence> = Vec::new();
    for cp in inputs.control {
        if let Some(e) = asm.add_control_point(cp, inputs, config, &resolve, sigma_px)? {
            evidence.push(e);
        }
    }
    let relative_sigma = RelativeSigma::resolve(
        config.relative_sigma_m,
        inputs.recordings,
        config.relative_max_gap_m,
    );
    screen_control(
        &mut asm.block,
        &mut asm.points,
        &evidence,
        config,
        relative_sigma.sigma_m,
        &mut asm.counts,
    );
    let Assembly {
        mut block,
        mut points,
        point_index,
        cameras,
        mut counts,
    } = asm;
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
    drop_lone_chain_end_evidence(
        &mut block,
        &mut points,
        config.chain_end_min_aerial_observations,
        &mut counts,
    );
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

/// The block while it is being built, with the names of its points and aerial images and the counts of what
/// went in.
struct Assembly<'a> {
    block: Block,
    points: Vec<BlockPoint>,
    point_index: HashMap<String, usize>,
    cameras: AerialCameras<'a>,
    counts: BuildCounts,
}

impl<'a> Assembly<'a> {
    /// Adds aerial control point `cp`: its point (its own from its MM observations when its tie point was not
    /// passed), the point's kind, and either its aerial observations in the bundle or the point as ground
    /// control. Returns the evidence of ground control (the correction it implies, for its screening).
    fn add_control_point(
        &mut self,
        cp: &'a AerialControlPoint,
        inputs: &AdjustInputs<'a>,
        config: &AdjustConfig,
        resolve: &impl Fn(&str, &str) -> Result<usize, AdjustError>,
        sigma_px: &[f64],
    ) -> Result<Option<SourcedEvidence>, AdjustError> {
        self.counts.control_points += 1;
        let owner = format!("aerial control point '{}'", cp.tie_point_id);
        // Resolve the aerial images (in order of first use, so the numbering is deterministic).
        let mut aerial = Vec::with_capacity(cp.aerial.len());
        for a in &cp.aerial {
            let idx = self.cameras.index_of(inputs, a.kind, &a.image_id, &owner)?;
            aerial.push((idx, a.u_px, a.v_px, a.sigma_px));
        }
        let p = match self.point_index.get(&cp.tie_point_id) {
            Some(&p) => p,
            None => {
                // A control point whose tie point was not passed: its own point from its MM observations.
                let mut pano = Vec::with_capacity(cp.mm.len());
                for o in &cp.mm {
                    pano.push((resolve(&owner, &o.image_id)?, o.u_px, o.v_px));
                }
                let Some(initial) = initial_point(&self.block, &pano, cp.point_world, sigma_px)
                else {
                    self.counts.control_unused += 1;
                    return Ok(None);
                };
                let p = self.points.len();
                add_point(
                    &mut self.block,
                    &mut self.points,
                    &cp.tie_point_id,
                    initial,
                    pano,
                    sigma_px,
                );
                self.point_index.insert(cp.tie_point_id.clone(), p);
                p
            }
        };
        // An orthophoto control point (`map`) is control like a point triangulated from ≥ 2 aerial images.
        let kind = if cp.aerial.len() >= 2 || cp.map.is_some() {
            PointKind::Control
        } else {
            PointKind::SingleAerial
        };
        if self.points[p].kind != PointKind::Control {
            self.points[p].kind = kind;
        }
        self.points[p]
            .aerial
            .extend(aerial.iter().map(|&(camera, u, v, _)| (camera, u, v)));
        if config.aerial_observations && cp.map.is_none() {
            let first = self.block.aerial_observations.len();
            add_aerial_observations(
                &mut self.block,
                &self.cameras.rows,
                p,
                &aerial,
                &mut self.counts,
            );
            // Only the consistency check reads the evidence of aerial pixels (weak control is orthophoto
            // control): its triangulations are not spent without it.
            if config.control_consistency_window.is_none() {
                return Ok(None);
            }
            let rows = &self.cameras.rows;
            return Ok(aerial_observation_evidence(
                &self.block,
                |camera| FrameCamera::from_aerial(rows[camera]),
                p,
                cp.point_world,
                first..self.block.aerial_observations.len(),
                self.points[p].recordings(),
                recording_spread(&self.block, &self.points[p].pano, sigma_px),
            ));
        } else if let Some(xyz) = cp
            .point_world
            .filter(|_| cp.aerial.len() >= 2 || cp.map.is_some())
        {
            let covariance_m2 = control_covariance(config, cp, &owner)?;
            self.block.control_points.push(ControlPoint {
                point: p,
                position_world: Vector3::from(xyz),
                covariance_m2,
            });
            self.counts.control_as_gcp += 1;
            let initial = self.block.points_initial_world[p];
            return Ok(Some(SourcedEvidence {
                evidence: ControlEvidence {
                    correction_m: nalgebra::Vector2::new(xyz[0] - initial.x, xyz[1] - initial.y),
                    recordings: self.points[p].recordings(),
                    weak: cp
                        .map
                        .as_ref()
                        .is_some_and(|m| m.score < config.weak_control_below),
                    spread: recording_spread(&self.block, &self.points[p].pano, sigma_px),
                },
                source: EvidenceSource::Ground(self.block.control_points.len() - 1),
            }));
        } else {
            self.counts.control_unused += 1;
        }
        Ok(None)
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
