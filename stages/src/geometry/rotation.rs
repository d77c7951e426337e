//! Rotation matrices of the campaign contract (docs/campaign-format.md).
//!
//! - Elementary right-handed rotations `Rx`, `Ry`, `Rz` about the world axes X (east), Y (north), Z (up).
//! - Aerial attitude ω-φ-κ: `R = Rx(ω)·Ry(φ)·Rz(κ)` maps camera-frame vectors to world-frame vectors.
//! - Panorama residual rotation: `d_world = Rz(−yaw)·Rx(pitch)·Ry(roll)·d_pano`.
//!
//! All matrices are f64; angles are radians in the `rot_*` functions and degrees elsewhere (`_deg`).

use nalgebra::{Matrix3, Vector3};

/// Right-handed rotation by `a_rad` about the X axis: `[[1,0,0],[0,cos,−sin],[0,sin,cos]]`.
pub fn rot_x(a_rad: f64) -> Matrix3<f64> {
    let (s, c) = a_rad.sin_cos();
    Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
}

/// Right-handed rotation by `a_rad` about the Y axis: `[[cos,0,sin],[0,1,0],[−sin,0,cos]]`.
pub fn rot_y(a_rad: f64) -> Matrix3<f64> {
    let (s, c) = a_rad.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

/// Right-handed rotation by `a_rad` about the Z axis: `[[cos,−sin,0],[sin,cos,0],[0,0,1]]`.
pub fn rot_z(a_rad: f64) -> Matrix3<f64> {
    let (s, c) = a_rad.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

/// Camera→world rotation of an aerial frame camera: `R = Rx(ω)·Ry(φ)·Rz(κ)` (angles in degrees).
///
/// `P_world = C + R·p_cam`; with ω = φ = κ = 0 the camera looks straight down (−z) with the image top north.
pub fn opk_to_matrix(omega_deg: f64, phi_deg: f64, kappa_deg: f64) -> Matrix3<f64> {
    rot_x(omega_deg.to_radians()) * rot_y(phi_deg.to_radians()) * rot_z(kappa_deg.to_radians())
}

/// Inverse of [`opk_to_matrix`]: (ω, φ, κ) in degrees with φ ∈ [−90°, 90°], ω, κ ∈ (−180°, 180°].
///
/// Expanding `Rx(ω)·Ry(φ)·Rz(κ)` gives `R[0][2] = sin φ`, `R[1][2] = −sin ω cos φ`, `R[2][2] = cos ω cos φ`,
/// `R[0][0] = cos φ cos κ`, `R[0][1] = −cos φ sin κ`. At gimbal lock (|φ| = 90°) only ω ± κ is defined:
/// κ is then set to 0 and ω taken from `R[1][0] = sin ω sin φ`, `R[1][1] = cos ω`.
/// The input should be a rotation matrix; it is not re-orthogonalised.
pub fn matrix_to_opk(r: &Matrix3<f64>) -> (f64, f64, f64) {
    let sin_phi = r[(0, 2)].clamp(-1.0, 1.0);
    let cos_phi = r[(0, 0)].hypot(r[(0, 1)]);
    let phi = sin_phi.atan2(cos_phi);
    if cos_phi > 1e-12 {
        let omega = (-r[(1, 2)]).atan2(r[(2, 2)]);
        let kappa = (-r[(0, 1)]).atan2(r[(0, 0)]);
        (omega.to_degrees(), phi.to_degrees(), kappa.to_degrees())
    } else {
        // Gimbal lock: with κ = 0, R[1][0] = sin ω · sin φ and R[1][1] = cos ω.
        let omega = (r[(1, 0)] * sin_phi.signum()).atan2(r[(1, 1)]);
        (omega.to_degrees(), phi.to_degrees(), 0.0)
    }
}

/// Panorama→world rotation for the optional residual rotation of a panorama (degrees):
/// `d_world = Rz(−yaw)·Rx(pitch)·Ry(roll)·d_pano`.
///
/// Positive yaw turns the panorama clockwise seen from above, positive pitch raises the direction of the centre
/// column (north), positive roll lowers the direction shown at u = 3W/4 (east).
pub fn panorama_rotation(yaw_deg: f64, pitch_deg: f64, roll_deg: f64) -> Matrix3<f64> {
    rot_z(-yaw_deg.to_radians()) * rot_x(pitch_deg.to_radians()) * rot_y(roll_deg.to_radians())
}

/// Camera-to-world rotation of a frame camera at `centre_world` whose viewing direction (camera −z) points at
/// `target_world`, with the camera x axis horizontal (`Z_world × back`). Undefined for a vertical view.
pub fn look_at_matrix(centre_world: &Vector3<f64>, target_world: &Vector3<f64>) -> Matrix3<f64> {
    let back = (centre_world - target_world).normalize();
    let x = Vector3::z().cross(&back).normalize();
    let y = back.cross(&x);
    Matrix3::from_columns(&[x, y, back])
}
