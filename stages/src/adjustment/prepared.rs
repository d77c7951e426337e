//! One solve's fixed setup (local frame, active observations, weights, whitening) and the evaluation of its
//! cost (thesis 5.4: the adjustment model; 5.7: residual weighting).
//!
//! Whitening: every residual is divided by its a-priori standard deviation, so the cost is
//! `½·Σ ρ(‖r_obs‖²)` over panorama, aerial-image and control-point observations (robust loss ρ) plus
//! `½·Σ ρ_rel(‖r‖²)` over the relative constraints (their own loss, Huber by default) and `½·Σ ‖r‖²` over the
//! priors. Panorama residuals are additionally multiplied by the thesis 5.7 weighting
//! factor, fixed per solve from the distances at the start of the solve.

use super::aerial::FixedFrameCamera;
use super::error::AdjustError;
use super::layout::{ObservationLayout, ReducedStructure};
use super::parallel::ordered_sum;
use super::problem::{AdjustOptions, Block, RelativeConstraint};
use super::residuals::{observed_angles_rad, pano_residual, Parameterization, State};
use super::robust::RobustLoss;
use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

/// A panorama observation ready for evaluation.
#[derive(Clone, Copy, Debug)]
pub struct PreparedPano {
    pub recording: usize,
    pub point: usize,
    /// Observed (azimuth, elevation), radians.
    pub observed_rad: (f64, f64),
    /// 1 / σ_θ (radians⁻¹): whitens the angular residual.
    pub whitening: f64,
    /// Thesis 5.7 weighting factor (1 for method 1).
    pub weight_factor: f64,
    pub active: bool,
}

/// A control point ready for evaluation.
#[derive(Clone, Copy, Debug)]
pub struct PreparedControl {
    pub point: usize,
    pub position_local: Vector3<f64>,
    /// L⁻¹ with covariance = L·Lᵀ: whitens the coordinate residual.
    pub whitening: Matrix3<f64>,
    pub active: bool,
}

/// An observed tie-point height ready for evaluation.
#[derive(Clone, Copy, Debug)]
pub struct PreparedPointHeight {
    pub point: usize,
    /// Observed Z, local frame.
    pub z_local: f64,
    /// 1 / σ (m⁻¹): whitens the height residual.
    pub whitening: f64,
    pub active: bool,
}

/// An aerial image observation ready for evaluation (the aerial orientation is fixed).
#[derive(Clone, Copy, Debug)]
pub struct PreparedAerial {
    pub camera: usize,
    pub point: usize,
    pub observed_px: (f64, f64),
    /// 1 / σ_px: whitens the pixel residual.
    pub whitening: f64,
    pub active: bool,
}

/// The fixed setup of one solve.
#[derive(Clone, Debug)]
pub struct Prepared {
    pub parameterization: Parameterization,
    pub loss: RobustLoss,
    /// Loss on the relative constraints.
    pub relative_loss: RobustLoss,
    pub horizontal_only: bool,
    /// Recorded pano→world rotations R0.
    pub rotations0: Vec<Matrix3<f64>>,
    /// Recorded centres, local frame (priors and relative constraints refer to them).
    pub recorded_local: Vec<Vector3<f64>>,
    pub prior_sigma_xy_m: Vec<Option<f64>>,
    pub prior_sigma_z_m: Vec<Option<f64>>,
    /// Per recording: whether a Gauss–Markov relative constraint leads into it in X/Y and in Z, which then
    /// stands for its position prior on those axes ([`RelativeConstraint::is_gauss_markov`]).
    pub prior_in_chain: Vec<[bool; 2]>,
    /// Observed heights of the recordings' centres: (Z in the local frame, σ in metres).
    pub height_observations: Vec<Option<(f64, f64)>>,
    pub yaw_prior_sigma_rad: Option<f64>,
    /// σ of the change of the yaw correction along each relative constraint, radians (with `estimate_yaw`).
    pub yaw_relative_sigma_rad: Option<f64>,
    /// Per recording: whether a relative constraint with a yaw term leads into it, which then stands for its
    /// yaw prior (the prior counts once per chain, not once per recording of a shared bias).
    pub yaw_prior_in_chain: Vec<bool>,
    pub pano: Vec<PreparedPano>,
    pub control: Vec<PreparedControl>,
    /// Observed tie-point heights (inactive for undetermined points and horizontal-only solves).
    pub point_heights: Vec<PreparedPointHeight>,
    /// Fixed aerial cameras in the local frame.
    pub aerial_cameras: Vec<FixedFrameCamera>,
    pub aerial: Vec<PreparedAerial>,
    /// The relative constraints (from ≠ to).
    pub relative: Vec<RelativeConstraint>,
    /// Points with enough active observations to be determined.
    pub point_active: Vec<bool>,
    /// Active panorama observations by point and by recording.
    pub layout: ObservationLayout,
    /// Block structure of the reduced camera matrix and its symbolic factorisation.
    pub structure: ReducedStructure,
}

impl Prepared {
    /// Sets up a solve at `state`; `rejected` flags observations removed by earlier rejection rounds.
    pub fn new(
        block: &Block,
        options: &AdjustOptions,
        state: &State,
        rejected: &Rejected,
    ) -> Result<Self, AdjustError> {
        let pano_rejected = &rejected.pano;
        let control_rejected = &rejected.control;
        let n_rec = block.recordings.len();
        let n_pts = block.points_initial_world.len();
        let rotations0: Vec<Matrix3<f64>> = block
            .recordings
            .iter()
            .map(|r| r.camera.rotation_pano_to_world)
            .collect();
        let recorded_local = block
            .recordings
            .iter()
            .map(|r| state.origin.to_local(&r.camera.center_world))
            .collect();
        let mut pano = Vec::with_capacity(block.pano_observations.len());
        for (index, o) in block.pano_observations.iter().enumerate() {
            let cam = &block.recordings[o.recording].camera;
            let observed_rad = observed_angles_rad(o.u_px, o.v_px, cam.width_px, cam.height_px);
            let distance_m =
                (state.points_local[o.point] - state.centers_local[o.recording]).norm();
            let weight_factor = options
                .weighting
                .factor(distance_m, cam.pixel_angle_rad().to_degrees());
            if pano_residual(
                observed_rad,
                &rotations0[o.recording],
                state.yaw_correction_rad[o.recording],
                &state.centers_local[o.recording],
                &state.points_local[o.point],
            )
            .is_none()
            {
                return Err(AdjustError::InvalidPanoObservation {
                    index,
                    problem: "the tie point lies at or straight above/below the recording centre; \
                              check its initial coordinates"
                        .to_string(),
                });
            }
            pano.push(PreparedPano {
                recording: o.recording,
                point: o.point,
                observed_rad,
                whitening: 1.0 / cam.angular_sigma_rad(o.sigma_px),
                weight_factor,
                active: !pano_rejected[index] && weight_factor > 0.0,
            });
        }
        let mut control = Vec::with_capacity(block.control_points.len());
        for (index, cp) in block.control_points.iter().enumerate() {
            let chol =
                cp.covariance_m2
                    .cholesky()
                    .ok_or_else(|| AdjustError::InvalidControlPoint {
                        index,
                        problem: "covariance is not symmetric positive definite".to_string(),
                    })?;
            let whitening =
                chol.l()
                    .try_inverse()
                    .ok_or_else(|| AdjustError::InvalidControlPoint {
                        index,
                        problem: "covariance is singular".to_string(),
                    })?;
            control.push(PreparedControl {
                point: cp.point,
                position_local: state.origin.to_local(&cp.position_world),
                whitening,
                active: !control_rejected[index],
            });
        }
        let aerial_cameras: Vec<FixedFrameCamera> = block
            .aerial_cameras
            .iter()
            .map(|c| FixedFrameCamera::new(c, &state.origin))
            .collect();
        let mut aerial = Vec::with_capacity(block.aerial_observations.len());
        for (index, o) in block.aerial_observations.iter().enumerate() {
            let observed_px = (o.u_px, o.v_px);
            if aerial_cameras[o.camera]
                .residual(observed_px, &state.points_local[o.point])
                .is_none()
            {
                return Err(AdjustError::InvalidAerialObservation {
                    index,
                    problem: "the tie point is not in front of the aerial camera (or far outside its \
                              image); check the point's initial coordinates and the camera orientation"
                        .to_string(),
                });
            }
            aerial.push(PreparedAerial {
                camera: o.camera,
                point: o.point,
                observed_px,
                whitening: 1.0 / o.sigma_px,
                active: !rejected.aerial[index],
            });
        }
        // A point is determined by ≥ 2 active rays (panorama or aerial) or an active control point.
        let mut rays = vec![0usize; n_pts];
        for o in pano.iter().filter(|o| o.active) {
            rays[o.point] += 1;
        }
        for o in aerial.iter().filter(|o| o.active) {
            rays[o.point] += 1;
        }
        let mut controlled = vec![false; n_pts];
        for c in control.iter().filter(|c| c.active) {
            controlled[c.point] = true;
        }
        let point_active: Vec<bool> = (0..n_pts).map(|p| rays[p] >= 2 || controlled[p]).collect();
        for o in pano.iter_mut() {
            o.active &= point_active[o.point];
        }
        for o in aerial.iter_mut() {
            o.active &= point_active[o.point];
        }
        let point_heights = prepare_point_heights(block, state, &point_active, options)?;
        let layout = ObservationLayout::new(
            n_rec,
            n_pts,
            pano.iter()
                .enumerate()
                .filter(|(_, o)| o.active)
                .map(|(i, o)| (i, o.point)),
            |i| pano[i].recording,
        );
        let relative = block.relative_constraints.clone();
        let mut prior_in_chain = vec![[false; 2]; n_rec];
        for rc in &relative {
            prior_in_chain[rc.to][0] |= rc.carry_xy < 1.0;
            prior_in_chain[rc.to][1] |= rc.carry_z < 1.0;
        }
        let yaw_relative_sigma_rad = options
            .estimate_yaw
            .then_some(options.yaw_relative_sigma_deg.map(f64::to_radians))
            .flatten();
        let mut yaw_prior_in_chain = vec![false; n_rec];
        if yaw_relative_sigma_rad.is_some() {
            for rc in relative.iter().filter(|rc| rc.ties_yaw) {
                yaw_prior_in_chain[rc.to] = true;
            }
        }
        let pairs: Vec<(usize, usize)> = relative.iter().map(|r| (r.from, r.to)).collect();
        let structure = ReducedStructure::new(&layout, &pairs);
        Ok(Self {
            parameterization: Parameterization::from_options(options),
            loss: options.loss,
            relative_loss: options.relative_loss,
            horizontal_only: options.horizontal_only,
            rotations0,
            recorded_local,
            prior_sigma_xy_m: block
                .recordings
                .iter()
                .map(|r| r.prior_sigma_xy_m)
                .collect(),
            prior_sigma_z_m: block.recordings.iter().map(|r| r.prior_sigma_z_m).collect(),
            prior_in_chain,
            height_observations: block
                .recordings
                .iter()
                .map(|r| {
                    r.height_observation.map(|h| {
                        let mut c = r.camera.center_world;
                        c.z = h.z_world;
                        (state.origin.to_local(&c).z, h.sigma_m)
                    })
                })
                .collect(),
            yaw_prior_sigma_rad: options
                .estimate_yaw
                .then_some(options.yaw_prior_sigma_deg.map(f64::to_radians))
                .flatten(),
            yaw_relative_sigma_rad,
            yaw_prior_in_chain,
            pano,
            control,
            point_heights,
            aerial_cameras,
            aerial,
            relative,
            point_active,
            layout,
            structure,
        })
    }

    /// Number of axes (of x, y, z) that are free: 2 horizontal-only, else 3.
    pub(super) fn position_axes(&self) -> usize {
        if self.horizontal_only {
            2
        } else {
            3
        }
    }

    /// Whitened, weighted residual of panorama observation `i` and its Jacobians (before the robust scaling);
    /// `None` for a degenerate geometry.
    pub fn pano_whitened(
        &self,
        i: usize,
        state: &State,
    ) -> Option<(
        nalgebra::Vector2<f64>,
        super::residuals::CameraJacobian2,
        nalgebra::Matrix2x3<f64>,
    )> {
        let o = &self.pano[i];
        let (r, jc, jp) = pano_residual(
            o.observed_rad,
            &self.rotations0[o.recording],
            state.yaw_correction_rad[o.recording],
            &state.centers_local[o.recording],
            &state.points_local[o.point],
        )?;
        let s = o.whitening * o.weight_factor;
        Some((r * s, jc * s, jp * s))
    }

    /// Whitened residual (pixels / σ_px) of aerial observation `i` and its Jacobian with respect to the point;
    /// `None` when the point is behind the camera.
    pub fn aerial_whitened(
        &self,
        i: usize,
        state: &State,
    ) -> Option<(nalgebra::Vector2<f64>, nalgebra::Matrix2x3<f64>)> {
        let o = &self.aerial[i];
        let (r, j) =
            self.aerial_cameras[o.camera].residual(o.observed_px, &state.points_local[o.point])?;
        Some((r * o.whitening, j * o.whitening))
    }

    /// Whitened residual of control point `i`.
    pub fn control_whitened(&self, i: usize, state: &State) -> Vector3<f64> {
        let c = &self.control[i];
        c.whitening * (state.points_local[c.point] - c.position_local)
    }

    /// Whitened residual of observed point height `i`.
    pub fn point_height_whitened(&self, i: usize, state: &State) -> f64 {
        let h = &self.point_heights[i];
        (state.points_local[h.point].z - h.z_local) * h.whitening
    }

    /// Whitened prior residuals of recording `c`: (axis, residual, 1/σ) for each prior axis, then its height
    /// observation (axis 2); unused entries have 1/σ = 0. An axis whose prior a Gauss–Markov chain carries
    /// has none here.
    pub(super) fn prior_terms(&self, c: usize, state: &State) -> [(usize, f64, f64); 4] {
        let d = state.centers_local[c] - self.recorded_local[c];
        let mut out = [(0, 0.0, 0.0); 4];
        let [chain_xy, chain_z] = self.prior_in_chain[c];
        if let Some(s) = self.prior_sigma_xy_m[c].filter(|_| !chain_xy) {
            out[0] = (0, d.x / s, 1.0 / s);
            out[1] = (1, d.y / s, 1.0 / s);
        }
        if !self.horizontal_only {
            if let Some(s) = self.prior_sigma_z_m[c].filter(|_| !chain_z) {
                out[2] = (2, d.z / s, 1.0 / s);
            }
            if let Some((z_local, s)) = self.height_observations[c] {
                out[3] = (2, (state.centers_local[c].z - z_local) / s, 1.0 / s);
            }
        }
        out
    }

    /// The loss of relative constraint `i`: least squares when it is held, else `relative_loss`.
    pub(super) fn relative_loss_of(&self, i: usize) -> RobustLoss {
        if self.relative[i].held {
            RobustLoss::Squared
        } else {
            self.relative_loss
        }
    }

    /// Relative-constraint residual (whitened) of constraint `i`, per free axis:
    /// `(c_to − carry ∘ c_from) / σ` with `c` the correction of a centre.
    pub(super) fn relative_residual(&self, i: usize, state: &State) -> Vector3<f64> {
        let rc = &self.relative[i];
        let (a, b, sigma) = (rc.from, rc.to, rc.sigma_m);
        let mut r = if rc.is_gauss_markov() {
            let carry = self.relative_carry(i);
            let ca = state.centers_local[a] - self.recorded_local[a];
            let cb = state.centers_local[b] - self.recorded_local[b];
            (cb - ca.component_mul(&carry)) / sigma
        } else {
            let kept = self.recorded_local[b] - self.recorded_local[a];
            (state.centers_local[b] - state.centers_local[a] - kept) / sigma
        };
        if self.horizontal_only {
            r.z = 0.0;
        }
        r
    }

    /// σ of recording `c`'s zero yaw prior, radians; `None` without a prior or when a relative yaw term
    /// leads into `c` ([`Self::yaw_prior_in_chain`]).
    pub(super) fn yaw_prior_of(&self, c: usize) -> Option<f64> {
        self.yaw_prior_sigma_rad
            .filter(|_| !self.yaw_prior_in_chain[c])
    }

    /// Whitened change of the yaw correction along relative constraint `i`, `(ψ_to − ψ_from) / σ_ψ`; `None`
    /// without [`Self::yaw_relative_sigma_rad`] or when the constraint does not tie the yaw
    /// ([`RelativeConstraint::ties_yaw`]).
    pub(super) fn relative_yaw_residual(&self, i: usize, state: &State) -> Option<f64> {
        let s = self.yaw_relative_sigma_rad?;
        let rc = &self.relative[i];
        if !rc.ties_yaw {
            return None;
        }
        Some((state.yaw_correction_rad[rc.to] - state.yaw_correction_rad[rc.from]) / s)
    }

    /// The carry of relative constraint `i` per axis (x, y, z).
    pub(super) fn relative_carry(&self, i: usize) -> Vector3<f64> {
        let rc = &self.relative[i];
        Vector3::new(rc.carry_xy, rc.carry_xy, rc.carry_z)
    }

    /// The cost ½·Σρ at `state`; +∞ if some observation is geometrically degenerate there.
    pub fn cost(&self, state: &State) -> f64 {
        let mut total = ordered_sum(self.pano.len(), |i| {
            if !self.pano[i].active {
                return 0.0;
            }
            match self.pano_whitened(i, state) {
                Some((r, _, _)) => self.loss.rho(r.norm_squared()),
                None => f64::INFINITY,
            }
        });
        if total == f64::INFINITY {
            return total;
        }
        for (i, c) in self.control.iter().enumerate() {
            if c.active {
                total += self
                    .loss
                    .rho(self.control_whitened(i, state).norm_squared());
            }
        }
        for (i, o) in self.aerial.iter().enumerate() {
            if !o.active {
                continue;
            }
            match self.aerial_whitened(i, state) {
                Some((r, _)) => total += self.loss.rho(r.norm_squared()),
                None => return f64::INFINITY,
            }
        }
        for (i, h) in self.point_heights.iter().enumerate() {
            if h.active {
                total += self.loss.rho(self.point_height_whitened(i, state).powi(2));
            }
        }
        total += self.prior_terms_sum(state);
        for i in 0..self.relative.len() {
            total += self
                .relative_loss_of(i)
                .rho(self.relative_residual(i, state).norm_squared());
        }
        0.5 * total
    }

    /// Σ‖r‖² of the priors, yaw priors and relative yaw terms (never robustified).
    fn prior_terms_sum(&self, state: &State) -> f64 {
        let mut total = 0.0;
        for c in 0..self.recorded_local.len() {
            for (_, r, _) in self.prior_terms(c, state) {
                total += r * r;
            }
            if let Some(s) = self.yaw_prior_of(c) {
                total += (state.yaw_correction_rad[c] / s).powi(2);
            }
        }
        for i in 0..self.relative.len() {
            if let Some(r) = self.relative_yaw_residual(i, state) {
                total += r * r;
            }
        }
        total
    }

    /// Squared-residual sum Σ‖r‖² of the active observations without robust loss (for σ̂0²), and the number of
    /// residual components.
    pub fn plain_sum_of_squares(&self, state: &State) -> (f64, usize) {
        let mut total = self.prior_terms_sum(state);
        for i in 0..self.relative.len() {
            total += self.relative_residual(i, state).norm_squared();
        }
        let mut count = 0usize;
        total += ordered_sum(self.pano.len(), |i| {
            let r = self.pano[i]
                .active
                .then(|| self.pano_whitened(i, state))
                .flatten();
            r.map_or(0.0, |(r, _, _)| r.norm_squared())
        });
        count += 2
            * (0..self.pano.len())
                .into_par_iter()
                .filter(|&i| self.pano[i].active && self.pano_whitened(i, state).is_some())
                .count();
        for (i, c) in self.control.iter().enumerate() {
            if c.active {
                total += self.control_whitened(i, state).norm_squared();
                count += 3;
            }
        }
        for (i, o) in self.aerial.iter().enumerate() {
            if o.active {
                if let Some((r, _)) = self.aerial_whitened(i, state) {
                    total += r.norm_squared();
                    count += 2;
                }
            }
        }
        for (i, h) in self.point_heights.iter().enumerate() {
            if h.active {
                total += self.point_height_whitened(i, state).powi(2);
                count += 1;
            }
        }
        for c in 0..self.recorded_local.len() {
            count += self
                .prior_terms(c, state)
                .iter()
                .filter(|t| t.2 > 0.0)
                .count();
            if self.yaw_prior_of(c).is_some() {
                count += 1;
            }
        }
        count += self.relative.len() * self.position_axes();
        if self.yaw_relative_sigma_rad.is_some() {
            count += self.relative.iter().filter(|rc| rc.ties_yaw).count();
        }
        (total, count)
    }
}

/// The block's observed point heights in the local frame of `state`, each active when its point is
/// determined by its rays (a height alone does not determine a point) and the solve is not horizontal-only.
fn prepare_point_heights(
    block: &Block,
    state: &State,
    point_active: &[bool],
    options: &AdjustOptions,
) -> Result<Vec<PreparedPointHeight>, AdjustError> {
    block
        .point_heights
        .iter()
        .enumerate()
        .map(|(index, h)| {
            let invalid = |problem: &str| AdjustError::InvalidInput {
                item: format!("point height {index}"),
                problem: problem.to_string(),
            };
            let Some(initial) = block.points_initial_world.get(h.point) else {
                return Err(invalid("names a point the block does not have"));
            };
            if !(h.sigma_m > 0.0 && h.sigma_m.is_finite() && h.z_world.is_finite()) {
                return Err(invalid("height and σ must be finite, σ > 0"));
            }
            let mut p = *initial;
            p.z = h.z_world;
            Ok(PreparedPointHeight {
                point: h.point,
                z_local: state.origin.to_local(&p).z,
                whitening: 1.0 / h.sigma_m,
                active: point_active[h.point] && !options.horizontal_only,
            })
        })
        .collect()
}

/// Observations removed by rejection rounds, per kind (indices as in the [`Block`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Rejected {
    pub pano: Vec<bool>,
    pub control: Vec<bool>,
    pub aerial: Vec<bool>,
}

impl Rejected {
    /// Nothing rejected yet.
    pub fn none(block: &Block) -> Self {
        Self {
            pano: vec![false; block.pano_observations.len()],
            control: vec![false; block.control_points.len()],
            aerial: vec![false; block.aerial_observations.len()],
        }
    }
}
