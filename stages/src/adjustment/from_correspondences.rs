//! The adjust stage (thesis 5.4.3): the block of one configuration, built from the registration stages'
//! correspondences ([`super::block_build`]), is adjusted — in the campaign's tangent frame when aerial rays are
//! in the bundle — and its results are reported per recording and per point.
//!
//! Recordings are used in the order given (the campaign sorts them by time, which the relative constraints
//! rely on). Everything an adjust node reports is in [`AdjustmentRun`] (serde, so it can be cached).

use super::adjust::{adjust, ObservationCounts};
pub use super::block_point::{BlockPoint, PointKind};
use super::config::AdjustConfig;
use super::error::AdjustError;
use super::in_frame::{adjustment_to_map, block_to_local};
use super::relative_noise::RelativeSigma;
use super::yaw_support::ChainYaw;
use crate::crs::MapFrame;
use crate::params::StageId;
use serde::{Deserialize, Serialize};

pub use super::block_build::{
    build_block, prior_sigmas_m, AdjustInputs, AerialImageRef, BlockBuild, BuildCounts,
};

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("adjust", "22");

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
    /// The components of the correction not applied because no significant correction was near
    /// (`correction::significance`): the recording keeps its recorded value of them.
    #[serde(default)]
    pub held: HeldComponents,
}

/// Which components of a recording's correction were held at the recorded value.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct HeldComponents {
    pub horizontal: bool,
    pub height: bool,
    pub yaw: bool,
}

impl HeldComponents {
    /// Horizontal, height, yaw: in the order of `correction::significance::COMPONENTS`.
    pub fn as_array(&self) -> [bool; 3] {
        [self.horizontal, self.height, self.yaw]
    }

    /// The held components as written in the outputs: `xy`, `z`, `yaw` joined by `+`; empty when none is.
    pub fn label(&self) -> String {
        self.as_array()
            .iter()
            .zip(["xy", "z", "yaw"])
            .filter(|(held, _)| **held)
            .map(|(_, name)| name)
            .collect::<Vec<_>>()
            .join("+")
    }
}

/// One adjusted tie point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunPoint {
    pub point: BlockPoint,
    /// Adjusted coordinates (initial ones when undetermined), world, metres.
    pub position_world: [f64; 3],
    /// Determined in the final solve (≥ 2 rays or a control point).
    pub determined: bool,
    /// The adjustment rejected one of the point's aerial observations or its ground control as a gross
    /// error (its control is then not to be trusted).
    #[serde(default)]
    pub control_rejected: bool,
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
    /// With relative yaw terms: each chain's common yaw correction and whether the evidence supported it
    /// ([`super::yaw_support`]).
    pub yaw_chains: Vec<ChainYaw>,
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
                held: HeldComponents::default(),
            }
        })
        .collect();
    let mut control_rejected = vec![false; build.points.len()];
    for &i in &adj.rejected_aerial {
        control_rejected[build.block.aerial_observations[i].point] = true;
    }
    for &i in &adj.rejected_control {
        control_rejected[build.block.control_points[i].point] = true;
    }
    let points = build
        .points
        .into_iter()
        .enumerate()
        .map(|(i, point)| RunPoint {
            point,
            position_world: adj.points_world[i].into(),
            determined: adj.point_determined[i],
            control_rejected: control_rejected[i],
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
        yaw_chains: adj.yaw_chains,
    })
}
