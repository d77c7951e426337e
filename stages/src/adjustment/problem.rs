//! The adjustment block (unknowns and observations) and the options of one adjustment configuration
//! (thesis 5.4 and 5.7), with validation that names the offending item.
//!
//! Frames and units: world coordinates are f64 metres (X east, Y north, Z up); the solver works in a local
//! frame shifted to the mean recording centre. Pixel coordinates follow campaign-format.md (continuous, first
//! pixel centre at 0.5). Angles carry their unit in the name.

use super::error::AdjustError;
use super::robust::RobustLoss;
use super::weighting::ResidualWeighting;
use crate::geometry::{FrameCamera, PanoramaCamera};
use nalgebra::{Matrix3, Vector3};

/// Default σ of an aerial control point, metres (thesis 5.4.3).
pub const DEFAULT_CONTROL_SIGMA_M: f64 = 0.10;

/// One mobile-mapping recording: its recorded pose (the initial value and the prior) and prior weights.
#[derive(Clone, Debug)]
pub struct BlockRecording {
    /// Recorded pose: projection centre (world, m), residual rotation and image size.
    pub camera: PanoramaCamera,
    /// σ of the recorded X and Y as a weak prior, metres; `None` = no horizontal prior.
    pub prior_sigma_xy_m: Option<f64>,
    /// σ of the recorded Z as a weak prior, metres; `None` = no vertical prior.
    pub prior_sigma_z_m: Option<f64>,
    /// An observation of the projection centre's height independent of the recorded one (e.g. a terrain
    /// model's height under the recording plus the camera height); `None` = none.
    pub height_observation: Option<HeightObservation>,
}

/// An observed height of a recording's projection centre with its standard deviation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeightObservation {
    /// Observed Z of the projection centre, world frame, metres.
    pub z_world: f64,
    /// Standard deviation of `z_world`, metres.
    pub sigma_m: f64,
}

/// An observed height of a tie point independent of the panoramas' rays (e.g. a terrain model's height under a
/// point on the ground), with its standard deviation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointHeight {
    pub point: usize,
    /// Observed Z of the point, world frame, metres.
    pub z_world: f64,
    /// Standard deviation of `z_world`, metres.
    pub sigma_m: f64,
}

/// A panorama observation of a tie point: continuous pixel (u, v) in recording `recording`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PanoObservation {
    pub recording: usize,
    pub point: usize,
    pub u_px: f64,
    pub v_px: f64,
    /// Standard deviation of the pixel measurement, pixels (both directions).
    pub sigma_px: f64,
}

/// An aerial control point: tie point `point` is tied to a known 3-D position (triangulated from ≥ 2 aerial
/// images) with the given covariance (thesis 5.4.3: σ = 0.10 m isotropic by default).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControlPoint {
    pub point: usize,
    /// Known position, world frame, metres.
    pub position_world: Vector3<f64>,
    /// Covariance of the known position, m² (symmetric positive definite).
    pub covariance_m2: Matrix3<f64>,
}

impl ControlPoint {
    /// A control point with isotropic standard deviation `sigma_m` in X, Y and Z.
    pub fn isotropic(point: usize, position_world: Vector3<f64>, sigma_m: f64) -> Self {
        Self {
            point,
            position_world,
            covariance_m2: Matrix3::identity() * (sigma_m * sigma_m),
        }
    }
}

/// An observation of tie point `point` in aerial image `camera` (an index into [`Block::aerial_cameras`],
/// whose orientation is held fixed): continuous pixel (u, v) of the original aerial image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AerialImageObservation {
    pub camera: usize,
    pub point: usize,
    pub u_px: f64,
    pub v_px: f64,
    /// Standard deviation of the pixel measurement, pixels (the aerial row's `sigma_px`).
    pub sigma_px: f64,
}

/// A relative constraint between two recordings (thesis 3.4.2: the trajectory's high relative accuracy).
///
/// With `c = adjusted − recorded` the correction of a recording's centre, the constraint keeps
/// `c_to − carry ∘ c_from` at zero with standard deviation `sigma_m` per axis. A carry of 1 keeps the recorded
/// difference of the two positions (the error is a random walk); a carry below 1 is the step of a first-order
/// Gauss–Markov error, which also stands for `to`'s position prior ([`super::gauss_markov`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RelativeConstraint {
    pub from: usize,
    pub to: usize,
    pub sigma_m: f64,
    /// Fraction of `from`'s correction expected at `to` in X and Y, in [0, 1].
    pub carry_xy: f64,
    /// Fraction of `from`'s correction expected at `to` in Z, in [0, 1].
    pub carry_z: f64,
    /// Held by least squares whatever [`AdjustOptions::relative_loss`] says: a step of a chain of
    /// recordings without aerial evidence of their own, whose σ already covers what the chain's anchors
    /// show ([`super::relative_bridge`]).
    pub held: bool,
    /// Whether the constraint also ties the yaw corrections of `from` and `to` when
    /// [`AdjustOptions::yaw_relative_sigma_deg`] is given; a chain whose common yaw correction the evidence
    /// does not support is untied ([`super::yaw_support`]).
    pub ties_yaw: bool,
}

impl RelativeConstraint {
    /// A constraint between recordings `from` and `to` with σ `sigma_m` per axis, under the relative loss.
    pub fn new(from: usize, to: usize, sigma_m: f64) -> Self {
        Self {
            from,
            to,
            sigma_m,
            carry_xy: 1.0,
            carry_z: 1.0,
            held: false,
            ties_yaw: true,
        }
    }

    /// Whether the constraint is a Gauss–Markov step (some carry below 1): it then replaces `to`'s position
    /// prior on the axes where it is.
    pub fn is_gauss_markov(&self) -> bool {
        self.carry_xy < 1.0 || self.carry_z < 1.0
    }
}

/// Everything the adjustment estimates from: recordings (initial poses and priors), initial tie-point
/// coordinates and the observations.
#[derive(Clone, Debug, Default)]
pub struct Block {
    pub recordings: Vec<BlockRecording>,
    /// Initial tie-point coordinates, world frame, metres (e.g. triangulated with the recorded poses).
    pub points_initial_world: Vec<Vector3<f64>>,
    pub pano_observations: Vec<PanoObservation>,
    pub control_points: Vec<ControlPoint>,
    pub relative_constraints: Vec<RelativeConstraint>,
    /// Fixed aerial cameras referenced by `aerial_observations`.
    pub aerial_cameras: Vec<FrameCamera>,
    /// Observations of tie points in the fixed aerial images.
    pub aerial_observations: Vec<AerialImageObservation>,
    /// Observed heights of tie points (under the observations' robust loss; they do not determine a point).
    pub point_heights: Vec<PointHeight>,
}

/// Levenberg–Marquardt settings and convergence criteria.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LmOptions {
    /// Largest number of accepted linearisations per solve.
    pub max_iterations: usize,
    /// Converged when an accepted step lowers the cost by less than this fraction of it.
    pub relative_cost_tolerance: f64,
    /// Converged when the largest parameter update is below this (metres / radians).
    pub step_tolerance: f64,
    /// Initial Marquardt damping λ (the normal matrix diagonal is scaled by 1 + λ).
    pub initial_lambda: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        Self {
            max_iterations: 100,
            relative_cost_tolerance: 1e-12,
            step_tolerance: 1e-10,
            initial_lambda: 1e-4,
        }
    }
}

/// One adjustment configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdjustOptions {
    /// Horizontal-only adjustment (thesis 5.7): recording Z is fixed at its recorded value.
    pub horizontal_only: bool,
    /// Estimate a yaw correction per recording (added to the recorded yaw).
    pub estimate_yaw: bool,
    /// σ of a zero prior on each yaw correction, degrees (`None` = no prior).
    pub yaw_prior_sigma_deg: Option<f64>,
    /// σ of the change of the yaw correction along each relative constraint, degrees (least squares; `None`
    /// = no such term). Used only with `estimate_yaw`.
    pub yaw_relative_sigma_deg: Option<f64>,
    /// k of the significance test of a chain's common yaw correction, `|ψ̄| ≥ k·σ_ψ̄`, with relative yaw
    /// terms: a chain that fails it is solved with per-recording yaw priors ([`super::yaw_support`]); 0 keeps
    /// every chain tied.
    pub yaw_tie_significance: f64,
    /// Residual weighting of panorama observations (thesis 5.7 methods 1–4).
    pub weighting: ResidualWeighting,
    /// Loss on panorama and control-point residuals (IRLS inside LM).
    pub loss: RobustLoss,
    /// Loss on the relative constraints between consecutive recordings (IRLS inside LM): Huber releases a
    /// step of the recorded trajectory that the aerial evidence contradicts (a jump when GNSS is re-acquired,
    /// drift during an outage) linearly instead of quadratically.
    pub relative_loss: RobustLoss,
    /// Widen the relative constraints whose step the solution without them contradicts, by a χ² statistic
    /// (2 degrees of freedom) above this ([`super::relative_release`]); `None` = keep every σ.
    pub relative_release_threshold: Option<f64>,
    /// Reject observations whose |normalised residual| exceeds this and re-solve (`None` = no rejection).
    pub rejection_threshold: Option<f64>,
    /// Largest number of rejection rounds (re-solves after rejections).
    pub max_rejection_rounds: usize,
    pub lm: LmOptions,
}

impl Default for AdjustOptions {
    fn default() -> Self {
        Self {
            horizontal_only: false,
            estimate_yaw: false,
            yaw_prior_sigma_deg: None,
            yaw_relative_sigma_deg: None,
            yaw_tie_significance: 0.0,
            weighting: ResidualWeighting::default(),
            loss: RobustLoss::Squared,
            relative_loss: RobustLoss::Squared,
            relative_release_threshold: None,
            rejection_threshold: None,
            max_rejection_rounds: 10,
            lm: LmOptions::default(),
        }
    }
}

impl AdjustOptions {
    /// The robust variant: Huber loss (threshold 2σ) and rejection of |normalised residual| > 3.
    pub fn robust() -> Self {
        Self {
            loss: RobustLoss::Huber { threshold: 2.0 },
            rejection_threshold: Some(3.0),
            ..Self::default()
        }
    }
}

/// What is wrong with an image observation, if anything: `image` = (kind, plural, index, count) of the image
/// it is in, `point` = (index, count) of its point, its pixel coordinates and σ.
fn observation_problem(
    image: (&str, &str, usize, usize),
    point: (usize, usize),
    uv_px: [f64; 2],
    sigma_px: f64,
) -> Option<String> {
    let (kind, plural, index, count) = image;
    let (point, n_pts) = point;
    if index >= count {
        Some(format!("{kind} index {index} ≥ {count} {plural}"))
    } else if point >= n_pts {
        Some(format!("point index {point} ≥ {n_pts} points"))
    } else if !uv_px.iter().all(|v| v.is_finite()) {
        Some("pixel coordinates are not finite".to_string())
    } else if !positive_finite(sigma_px) {
        Some(format!("sigma_px = {sigma_px} must be finite and > 0"))
    } else {
        None
    }
}

fn positive_finite(x: f64) -> bool {
    x.is_finite() && x > 0.0
}

/// An option that is absent or finite and > 0; otherwise the error naming `field` with `hint`.
fn optional_positive(
    field: &'static str,
    value: Option<f64>,
    hint: &'static str,
) -> Result<(), AdjustError> {
    match value {
        Some(v) if !positive_finite(v) => Err(AdjustError::InvalidOption {
            field,
            value: v,
            hint,
        }),
        _ => Ok(()),
    }
}

impl Block {
    /// Checks indices, finiteness and positivity of all inputs; the error names the first bad item.
    pub fn validate(&self) -> Result<(), AdjustError> {
        if self.recordings.is_empty() {
            return Err(AdjustError::NoRecordings);
        }
        for (index, rec) in self.recordings.iter().enumerate() {
            let c = &rec.camera.center_world;
            for (field, value) in [("x", c.x), ("y", c.y), ("z", c.z)] {
                if !value.is_finite() {
                    return Err(AdjustError::InvalidRecording {
                        index,
                        field,
                        value,
                        hint: "coordinates must be finite metres",
                    });
                }
            }
            if rec.camera.width_px == 0 || rec.camera.height_px == 0 {
                return Err(AdjustError::InvalidRecording {
                    index,
                    field: "width_px",
                    value: f64::from(rec.camera.width_px),
                    hint: "image size must be positive",
                });
            }
            for (field, sigma) in [
                ("sigma_xy_m", rec.prior_sigma_xy_m),
                ("sigma_z_m", rec.prior_sigma_z_m),
            ] {
                if let Some(s) = sigma {
                    if !positive_finite(s) {
                        return Err(AdjustError::InvalidRecording {
                            index,
                            field,
                            value: s,
                            hint: "a prior sigma must be finite and > 0, or absent",
                        });
                    }
                }
            }
            if let Some(h) = rec.height_observation {
                for (field, value, ok) in [
                    (
                        "height_observation.z_world",
                        h.z_world,
                        h.z_world.is_finite(),
                    ),
                    (
                        "height_observation.sigma_m",
                        h.sigma_m,
                        positive_finite(h.sigma_m),
                    ),
                ] {
                    if !ok {
                        return Err(AdjustError::InvalidRecording {
                            index,
                            field,
                            value,
                            hint: "a height observation needs a finite height and a finite σ > 0",
                        });
                    }
                }
            }
        }
        for (index, p) in self.points_initial_world.iter().enumerate() {
            if !p.iter().all(|v| v.is_finite()) {
                return Err(AdjustError::InvalidPoint { index });
            }
        }
        let n_rec = self.recordings.len();
        let n_pts = self.points_initial_world.len();
        for (index, o) in self.pano_observations.iter().enumerate() {
            let image = ("recording", "recordings", o.recording, n_rec);
            let problem =
                observation_problem(image, (o.point, n_pts), [o.u_px, o.v_px], o.sigma_px).or_else(
                    || {
                        let v_max = f64::from(self.recordings[o.recording].camera.height_px);
                        (!(o.v_px > 0.0 && o.v_px < v_max)).then(|| {
                            format!(
                                "v_px = {} outside (0, {v_max}) (the poles have no azimuth)",
                                o.v_px
                            )
                        })
                    },
                );
            if let Some(problem) = problem {
                return Err(AdjustError::InvalidPanoObservation { index, problem });
            }
        }
        for (index, cp) in self.control_points.iter().enumerate() {
            let problem = if cp.point >= n_pts {
                Some(format!("point index {} ≥ {n_pts} points", cp.point))
            } else if !cp.position_world.iter().all(|v| v.is_finite()) {
                Some("position is not finite".to_string())
            } else if cp.covariance_m2.cholesky().is_none()
                || !cp.covariance_m2.iter().all(|v| v.is_finite())
            {
                Some("covariance is not symmetric positive definite".to_string())
            } else {
                None
            };
            if let Some(problem) = problem {
                return Err(AdjustError::InvalidControlPoint { index, problem });
            }
        }
        for (index, cam) in self.aerial_cameras.iter().enumerate() {
            let finite = cam.center_world.iter().all(|v| v.is_finite())
                && cam.rotation_cam_to_world.iter().all(|v| v.is_finite())
                && cam.cx_px.is_finite()
                && cam.cy_px.is_finite();
            if !finite || !positive_finite(cam.focal_px) {
                return Err(AdjustError::InvalidInput {
                    item: format!("aerial camera {index}"),
                    problem: "centre, rotation and principal point must be finite and focal_px > 0"
                        .to_string(),
                });
            }
        }
        let n_cam = self.aerial_cameras.len();
        for (index, o) in self.aerial_observations.iter().enumerate() {
            let image = ("camera", "aerial cameras", o.camera, n_cam);
            let problem =
                observation_problem(image, (o.point, n_pts), [o.u_px, o.v_px], o.sigma_px);
            if let Some(problem) = problem {
                return Err(AdjustError::InvalidAerialObservation { index, problem });
            }
        }
        for (index, rc) in self.relative_constraints.iter().enumerate() {
            let problem = if rc.from >= n_rec || rc.to >= n_rec {
                Some(format!(
                    "recording indices {} / {} must be < {n_rec}",
                    rc.from, rc.to
                ))
            } else if rc.from == rc.to {
                Some("from and to are the same recording".to_string())
            } else if !positive_finite(rc.sigma_m) {
                Some(format!("sigma_m = {} must be finite and > 0", rc.sigma_m))
            } else if !(0.0..=1.0).contains(&rc.carry_xy) || !(0.0..=1.0).contains(&rc.carry_z) {
                Some(format!(
                    "carry_xy = {} and carry_z = {} must lie in [0, 1]",
                    rc.carry_xy, rc.carry_z
                ))
            } else {
                None
            };
            if let Some(problem) = problem {
                return Err(AdjustError::InvalidRelativeConstraint { index, problem });
            }
        }
        Ok(())
    }
}

impl AdjustOptions {
    /// Checks the numeric options.
    pub fn validate(&self) -> Result<(), AdjustError> {
        optional_positive(
            "yaw_prior_sigma_deg",
            self.yaw_prior_sigma_deg,
            "must be finite and > 0, or absent",
        )?;
        optional_positive(
            "yaw_relative_sigma_deg",
            self.yaw_relative_sigma_deg,
            "must be finite and > 0, or absent",
        )?;
        if !(self.yaw_tie_significance.is_finite() && self.yaw_tie_significance >= 0.0) {
            return Err(AdjustError::InvalidOption {
                field: "yaw_tie_significance",
                value: self.yaw_tie_significance,
                hint: "must be finite and ≥ 0 (0 keeps every chain's yaw tied)",
            });
        }
        optional_positive(
            "relative_release_threshold",
            self.relative_release_threshold,
            "must be finite and > 0 (e.g. 9.21, the 99 % quantile of χ² with 2 degrees of freedom), or absent",
        )?;
        optional_positive(
            "rejection_threshold",
            self.rejection_threshold,
            "must be finite and > 0 (e.g. 3), or absent",
        )?;
        self.weighting.validate()?;
        self.loss.validate()?;
        self.relative_loss.validate()?;
        Ok(())
    }
}
