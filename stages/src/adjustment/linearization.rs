//! Gauss–Newton blocks of the normal equations at one state (thesis 5.4), robust IRLS weights included:
//! per recording `U = Jᵀ·J` over (x, y, z, ψ) and its right-hand side, per tie point `V = Jᵀ·J` over its
//! coordinates and its right-hand side, and per panorama observation the coupling `W = J_cᵀ·J_p`.
//!
//! Evaluated in parallel — tie points in fixed chunks, then recordings in fixed chunks — with every sum
//! taken in the same order whatever the thread count: a point's panorama rays (ascending observation
//! index), then its control point and aerial rays; a recording's rays, its priors, then its relative
//! constraints.

use super::parallel::{chunks, split_at_ends};
use super::prepared::Prepared;
use super::problem::RelativeConstraint;
use super::residuals::{CameraJacobian2, State};
use nalgebra::{Matrix3, Matrix4, SMatrix, Vector2, Vector3, Vector4};
use rayon::prelude::*;

/// 4 × 3 coupling block Jᵀ_camera·J_point of one panorama observation.
pub type Coupling = SMatrix<f64, 4, 3>;

/// The normal-equation blocks at one state.
#[derive(Clone, Debug)]
pub struct Linearization {
    /// Per recording: Jᵀ·J over (x, y, z, ψ).
    pub camera_diag: Vec<Matrix4<f64>>,
    /// Per recording: −Jᵀ·r.
    pub camera_rhs: Vec<Vector4<f64>>,
    /// Per relative constraint: its off-diagonal block (symmetric).
    pub camera_off: Vec<Matrix4<f64>>,
    /// Per point: Jᵀ·J.
    pub point_diag: Vec<Matrix3<f64>>,
    /// Per point: −Jᵀ·r.
    pub point_rhs: Vec<Vector3<f64>>,
    /// Per observation position ([`super::layout::ObservationLayout`]): Jᵀ_camera·J_point.
    pub couplings: Vec<Coupling>,
}

/// What a recording needs of one of its rays: whitened camera Jacobian, residual and IRLS weight.
type CameraTerm = (CameraJacobian2, Vector2<f64>, f64);

/// The blocks at `state`; degenerate observations (rare, only far from the solution) contribute nothing.
pub fn linearize(prep: &Prepared, state: &State) -> Linearization {
    let layout = &prep.layout;
    let n_pts = prep.point_active.len();
    let n_pos = layout.recording_of.len();
    let mut point_diag = vec![Matrix3::zeros(); n_pts];
    let mut point_rhs = vec![Vector3::zeros(); n_pts];
    let mut couplings = vec![Coupling::zeros(); n_pos];
    let mut camera_terms: Vec<CameraTerm> =
        vec![(CameraJacobian2::zeros(), Vector2::zeros(), 0.0); n_pos];
    let point_chunks = chunks(n_pts);
    let point_ends: Vec<usize> = point_chunks.iter().map(|&(_, e)| e).collect();
    let position_ends: Vec<usize> = point_chunks
        .iter()
        .map(|&(_, e)| layout.by_point.row_start(e))
        .collect();
    point_chunks
        .iter()
        .zip(split_at_ends(&mut point_diag, &point_ends))
        .zip(split_at_ends(&mut point_rhs, &point_ends))
        .zip(split_at_ends(&mut couplings, &position_ends))
        .zip(split_at_ends(&mut camera_terms, &position_ends))
        .collect::<Vec<_>>()
        .into_par_iter()
        .for_each(|((((&(first, end), diag), rhs), coupling), terms)| {
            let base = layout.by_point.row_start(first);
            for p in first..end {
                for pos in layout.positions_of_point(p) {
                    let i = layout.by_point.values()[pos];
                    let Some((r, jc, jp)) = prep.pano_whitened(i, state) else {
                        continue;
                    };
                    let w = prep.loss.weight(r.norm_squared());
                    diag[p - first] += w * jp.transpose() * jp;
                    rhs[p - first] -= w * jp.transpose() * r;
                    coupling[pos - base] = w * jc.transpose() * jp;
                    terms[pos - base] = (jc, r, w);
                }
            }
        });
    add_point_terms(prep, state, &mut point_diag, &mut point_rhs);
    let (mut camera_diag, mut camera_rhs) = camera_blocks(prep, state, &camera_terms);
    drop(camera_terms);
    let camera_off = add_relative_terms(prep, state, &mut camera_diag, &mut camera_rhs);
    Linearization {
        camera_diag,
        camera_rhs,
        camera_off,
        point_diag,
        point_rhs,
        couplings,
    }
}

/// Control points, aerial rays and observed point heights: they touch only their point (aerial cameras are fixed), so they enter
/// the Schur complement through V alone.
fn add_point_terms(
    prep: &Prepared,
    state: &State,
    point_diag: &mut [Matrix3<f64>],
    point_rhs: &mut [Vector3<f64>],
) {
    for (i, c) in prep.control.iter().enumerate() {
        if !c.active {
            continue;
        }
        let r = prep.control_whitened(i, state);
        let w = prep.loss.weight(r.norm_squared());
        let j = c.whitening;
        point_diag[c.point] += w * j.transpose() * j;
        point_rhs[c.point] -= w * j.transpose() * r;
    }
    for (i, o) in prep.aerial.iter().enumerate() {
        if !o.active {
            continue;
        }
        let Some((r, j)) = prep.aerial_whitened(i, state) else {
            continue;
        };
        let w = prep.loss.weight(r.norm_squared());
        point_diag[o.point] += w * j.transpose() * j;
        point_rhs[o.point] -= w * j.transpose() * r;
    }
    for (i, h) in prep.point_heights.iter().enumerate() {
        if !h.active {
            continue;
        }
        let r = prep.point_height_whitened(i, state);
        let w = prep.loss.weight(r * r);
        point_diag[h.point][(2, 2)] += w * h.whitening * h.whitening;
        point_rhs[h.point].z -= w * h.whitening * r;
    }
}

/// Per recording: its rays' Jᵀ·J and −Jᵀ·r, then its position and yaw priors.
fn camera_blocks(
    prep: &Prepared,
    state: &State,
    camera_terms: &[CameraTerm],
) -> (Vec<Matrix4<f64>>, Vec<Vector4<f64>>) {
    let n_rec = prep.recorded_local.len();
    let mut camera_diag = vec![Matrix4::zeros(); n_rec];
    let mut camera_rhs = vec![Vector4::zeros(); n_rec];
    let rec_chunks = chunks(n_rec);
    let ends: Vec<usize> = rec_chunks.iter().map(|&(_, e)| e).collect();
    rec_chunks
        .iter()
        .zip(split_at_ends(&mut camera_diag, &ends))
        .zip(split_at_ends(&mut camera_rhs, &ends))
        .collect::<Vec<_>>()
        .into_par_iter()
        .for_each(|((&(first, end), diag), rhs)| {
            for c in first..end {
                let (d, b) = (&mut diag[c - first], &mut rhs[c - first]);
                for &pos in prep.layout.by_recording.row(c) {
                    let (jc, r, w) = &camera_terms[pos];
                    *d += *w * jc.transpose() * jc;
                    *b -= *w * jc.transpose() * r;
                }
                for (axis, r, inv_sigma) in prep.prior_terms(c, state) {
                    if inv_sigma > 0.0 {
                        d[(axis, axis)] += inv_sigma * inv_sigma;
                        b[axis] -= inv_sigma * r;
                    }
                }
                if let Some(s) = prep.yaw_prior_of(c) {
                    d[(3, 3)] += 1.0 / (s * s);
                    b[3] -= state.yaw_correction_rad[c] / (s * s);
                }
            }
        });
    (camera_diag, camera_rhs)
}

/// Relative constraints: diagonal terms of both recordings and the off-diagonal block of each constraint.
fn add_relative_terms(
    prep: &Prepared,
    state: &State,
    camera_diag: &mut [Matrix4<f64>],
    camera_rhs: &mut [Vector4<f64>],
) -> Vec<Matrix4<f64>> {
    let mut camera_off = Vec::with_capacity(prep.relative.len());
    for i in 0..prep.relative.len() {
        let RelativeConstraint {
            from: a,
            to: b,
            sigma_m: sigma,
            ..
        } = prep.relative[i];
        let r = prep.relative_residual(i, state);
        let carry = prep.relative_carry(i);
        // IRLS: residual and Jacobian scaled by √ρ'(s) of the constraint's loss.
        let w = prep.relative_loss_of(i).weight(r.norm_squared());
        let inv2 = w / (sigma * sigma);
        let mut block = Matrix4::zeros();
        for axis in 0..prep.position_axes() {
            // J_a = −carry·I/σ, J_b = I/σ (carry 1: the random walk).
            let phi = carry[axis];
            camera_diag[a][(axis, axis)] += phi * phi * inv2;
            camera_diag[b][(axis, axis)] += inv2;
            block[(axis, axis)] = -phi * inv2;
            camera_rhs[a][axis] += phi * w * r[axis] / sigma;
            camera_rhs[b][axis] -= w * r[axis] / sigma;
        }
        if let (Some(r), Some(s)) = (
            prep.relative_yaw_residual(i, state),
            prep.yaw_relative_sigma_rad,
        ) {
            // Least squares: J_a = −1/σ_ψ, J_b = 1/σ_ψ.
            let inv2 = 1.0 / (s * s);
            camera_diag[a][(3, 3)] += inv2;
            camera_diag[b][(3, 3)] += inv2;
            block[(3, 3)] = -inv2;
            camera_rhs[a][3] += r / s;
            camera_rhs[b][3] -= r / s;
        }
        camera_off.push(block);
    }
    camera_off
}
