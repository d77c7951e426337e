//! Residuals and analytic Jacobians of the adjustment's observations, and the parameterisation of the
//! unknowns (thesis 5.4: recording positions, optional yaw, tie-point coordinates).
//!
//! Unknowns per recording (local frame, see [`State`]): centre x, y, z (metres) and a yaw correction ψ
//! (radians); horizontal-only fixes z, `estimate_yaw = false` fixes ψ = 0. The corrected panorama rotation
//! is `R = Rz(−ψ)·R0` with `R0 = Rz(−yaw)·Rx(pitch)·Ry(roll)` the recorded one, i.e. the panorama's yaw
//! becomes `yaw + ψ`.
//!
//! Panorama observation residual (radians): with `p = Rᵀ(X − C)` the point in the panorama frame,
//! azimuth `A = atan2(p_x, p_y)` and elevation `E = atan2(p_z, ‖p_xy‖)`, the residual is
//! `(wrap(A − A_obs), E − E_obs)`, i.e. the reprojection error d(x, x̂) of thesis 5.7 in equirectangular pixels
//! times the pixel angle 2π/W (the two image axes have the same angular pitch when W = 2H). It is whitened by
//! σ_θ = σ_px·2π/W: matching noise is isotropic in pixels, so the azimuth component is deliberately not scaled
//! by cos E (which would model noise isotropic on the sphere and under-weight rays far from the horizon).

use super::problem::{AdjustOptions, Block};
use crate::geometry::{rot_z, LocalOrigin};
use nalgebra::{Matrix2x3, Matrix3, SMatrix, Vector2, Vector3, Vector4};
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// Number of recording parameters before masking: x, y, z, ψ.
pub const FULL_CAMERA_PARAMS: usize = 4;

/// 2 × 4 Jacobian of a panorama residual with respect to (x, y, z, ψ) of its recording.
pub type CameraJacobian2 = SMatrix<f64, 2, FULL_CAMERA_PARAMS>;

/// Which of (x, y, z, ψ) are free.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Parameterization {
    /// Free full-parameter indices in order (subset of 0..4).
    pub active: Vec<usize>,
}

impl Parameterization {
    /// The free parameters of a configuration.
    pub fn from_options(options: &AdjustOptions) -> Self {
        let mut active = vec![0, 1];
        if !options.horizontal_only {
            active.push(2);
        }
        if options.estimate_yaw {
            active.push(3);
        }
        Self { active }
    }

    /// Free parameters per recording.
    pub fn per_recording(&self) -> usize {
        self.active.len()
    }
}

/// The current estimate, in the local frame.
#[derive(Clone, Debug, PartialEq)]
pub struct State {
    pub origin: LocalOrigin,
    /// Recording centres, local frame, metres.
    pub centers_local: Vec<Vector3<f64>>,
    /// Yaw corrections ψ, radians.
    pub yaw_correction_rad: Vec<f64>,
    /// Tie points, local frame, metres.
    pub points_local: Vec<Vector3<f64>>,
}

impl State {
    /// The state the adjustment starts from: a local origin at the mean recorded centre, the recorded
    /// centres, no yaw corrections and the initial tie points; `None` for a block without recordings.
    pub fn initial(block: &Block) -> Option<State> {
        let origin = LocalOrigin::at_mean(block.recordings.iter().map(|r| &r.camera.center_world))?;
        Some(State {
            origin,
            centers_local: block
                .recordings
                .iter()
                .map(|r| origin.to_local(&r.camera.center_world))
                .collect(),
            yaw_correction_rad: vec![0.0; block.recordings.len()],
            points_local: block
                .points_initial_world
                .iter()
                .map(|p| origin.to_local(p))
                .collect(),
        })
    }

    /// Adds an update of the camera parameters (per recording over (x, y, z, ψ); fixed ones are zero) and of
    /// the points (3 per point; undetermined points get zero).
    pub fn apply(&self, camera_step: &[Vector4<f64>], point_step: &[Vector3<f64>]) -> State {
        let mut next = self.clone();
        for ((center, yaw), step) in next
            .centers_local
            .iter_mut()
            .zip(next.yaw_correction_rad.iter_mut())
            .zip(camera_step)
        {
            *center += step.xyz();
            *yaw += step.w;
        }
        for (p, step) in next.points_local.iter_mut().zip(point_step) {
            *p += step;
        }
        next
    }
}

/// Observed azimuth and elevation (radians) of a continuous panorama pixel (campaign-format.md).
pub fn observed_angles_rad(u_px: f64, v_px: f64, width_px: u32, height_px: u32) -> (f64, f64) {
    let azimuth = TAU * u_px / f64::from(width_px) - PI;
    let elevation = FRAC_PI_2 - PI * v_px / f64::from(height_px);
    (azimuth, elevation)
}

/// Wraps an angle difference into [−π, π).
pub fn wrap_pi(a_rad: f64) -> f64 {
    (a_rad + PI).rem_euclid(TAU) - PI
}

/// Generator of rotations about Z: d/dψ Rz(ψ) = Rz(ψ)·K.
fn k_z() -> Matrix3<f64> {
    Matrix3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0)
}

/// Residual (radians, unwhitened) of a panorama observation and its Jacobians with respect to the recording's
/// (x, y, z, ψ) and the point's (x, y, z). `rotation0` is the recorded pano→world rotation R0.
/// `None` if the point coincides with the projection centre or lies on the vertical through it.
pub fn pano_residual(
    observed_rad: (f64, f64),
    rotation0: &Matrix3<f64>,
    yaw_correction_rad: f64,
    center_local: &Vector3<f64>,
    point_local: &Vector3<f64>,
) -> Option<(Vector2<f64>, CameraJacobian2, Matrix2x3<f64>)> {
    let rotation = rot_z(-yaw_correction_rad) * rotation0;
    let rt = rotation.transpose();
    let diff = point_local - center_local;
    let p = rt * diff;
    let h2 = p.x * p.x + p.y * p.y;
    let n2 = h2 + p.z * p.z;
    if !(h2 > 1e-18 && n2.is_finite()) {
        return None;
    }
    let h = h2.sqrt();
    let (az_obs, el_obs) = observed_rad;
    let az = p.x.atan2(p.y);
    let el = p.z.atan2(h);
    let r = Vector2::new(wrap_pi(az - az_obs), el - el_obs);
    // d(az, el)/dp.
    let d_az = [p.y / h2, -p.x / h2, 0.0];
    let d_el = [-p.x * p.z / (h * n2), -p.y * p.z / (h * n2), h / n2];
    let mut d_res_dp = Matrix2x3::zeros();
    for j in 0..3 {
        d_res_dp[(0, j)] = d_az[j];
        d_res_dp[(1, j)] = d_el[j];
    }
    let j_point = d_res_dp * rt;
    let dp_dyaw = rt * (k_z() * diff);
    let mut j_camera = CameraJacobian2::zeros();
    for row in 0..2 {
        for col in 0..3 {
            j_camera[(row, col)] = -j_point[(row, col)];
        }
        j_camera[(row, 3)] = (d_res_dp.row(row) * dp_dyaw)[(0, 0)];
    }
    Some((r, j_camera, j_point))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{panorama_rotation, PanoramaCamera};

    #[test]
    fn residual_is_zero_at_the_true_pose_and_jacobian_matches_finite_differences() {
        let center = Vector3::new(1.0, -2.0, 2.5);
        let point = Vector3::new(7.0, 4.0, 0.3);
        let (yaw, pitch, roll) = (12.0, 1.5, -0.7);
        let psi = 0.01_f64;
        let cam = PanoramaCamera::new(4800, 2400, center, yaw + psi.to_degrees(), pitch, roll);
        let (u, v) = cam.project_world(&point).unwrap();
        let obs = observed_angles_rad(u, v, 4800, 2400);
        let r0 = panorama_rotation(yaw, pitch, roll);
        let (r, jc, jp) = pano_residual(obs, &r0, psi, &center, &point).unwrap();
        assert!(r.norm() < 1e-12, "{r:?}");
        // Move off the solution and compare with central differences.
        let c1 = center + Vector3::new(0.2, -0.1, 0.05);
        let x1 = point + Vector3::new(-0.3, 0.2, 0.1);
        let psi1 = 0.03;
        let (_, jc, jp) = pano_residual(obs, &r0, psi1, &c1, &x1).unwrap_or((r, jc, jp));
        // Central differences over the camera's (x, y, z, ψ) and then the point's (x, y, z).
        let residual_at = |k: usize, step: f64| {
            let (mut c, mut psi, mut x) = (c1, psi1, x1);
            match k {
                0..=2 => c[k] += step,
                3 => psi += step,
                _ => x[k - 4] += step,
            }
            pano_residual(obs, &r0, psi, &c, &x).unwrap().0
        };
        let h = 1e-6;
        for k in 0..7 {
            let numeric = (residual_at(k, h) - residual_at(k, -h)) / (2.0 * h);
            let (analytic, label, column) = match k {
                0..=3 => (jc.column(k).into_owned(), "camera", k),
                _ => (jp.column(k - 4).into_owned(), "point", k - 4),
            };
            for row in 0..2 {
                assert!(
                    (numeric[row] - analytic[row]).abs() < 1e-8,
                    "{label} {column} row {row}"
                );
            }
        }
    }
}
