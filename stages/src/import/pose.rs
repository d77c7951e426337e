//! Panorama attitude algebra of the import: the IMU body attitude (roll, pitch, heading to north-east-down),
//! the boresight of the panorama frame on the body, the lever arm, and the campaign's panorama angles
//! `d_world = Rz(−yaw)·Rx(pitch)·Ry(roll)·d_pano` (campaign-format.md) in both directions.
//!
//! Frames: body x forward, y right, z down; panorama frame x right, y forward (the centre column), z up;
//! with a zero boresight the panorama's centre column looks along the body's x axis and its zenith is −z.

use crate::crs::Ellipsoid;
use crate::formats::angles::swap_xy_flip_z;
use crate::geometry::{panorama_rotation, rot_x, rot_y, rot_z};
use nalgebra::{Matrix3, Vector3};

/// Body → north-east-down: `Rz(heading)·Ry(pitch)·Rx(roll)` (degrees).
pub fn body_to_ned(roll_deg: f64, pitch_deg: f64, heading_deg: f64) -> Matrix3<f64> {
    rot_z(heading_deg.to_radians()) * rot_y(pitch_deg.to_radians()) * rot_x(roll_deg.to_radians())
}

/// Roll, pitch, heading (degrees, heading in [0, 360)) of a body → NED rotation.
pub fn ned_angles(r: &Matrix3<f64>) -> (f64, f64, f64) {
    let pitch = (-r[(2, 0)]).clamp(-1.0, 1.0).asin();
    let heading = r[(1, 0)].atan2(r[(0, 0)]);
    let roll = r[(2, 1)].atan2(r[(2, 2)]);
    (
        roll.to_degrees(),
        pitch.to_degrees(),
        heading.to_degrees().rem_euclid(360.0),
    )
}

/// Panorama → body with boresight angles roll, pitch, yaw (degrees, about the body axes x, y, z).
pub fn panorama_to_body(boresight_deg: [f64; 3]) -> Matrix3<f64> {
    let [r, p, y] = boresight_deg;
    body_to_ned(r, p, y) * swap_xy_flip_z()
}

/// Panorama → east-north-up of a panorama rigid on the body.
pub fn panorama_to_enu(body_to_ned: &Matrix3<f64>, boresight_deg: [f64; 3]) -> Matrix3<f64> {
    swap_xy_flip_z() * body_to_ned * panorama_to_body(boresight_deg)
}

/// The campaign's panorama angles (yaw, pitch, roll in degrees) of a panorama → world rotation, the inverse
/// of [`panorama_rotation`]: `R = Rz(−yaw)·Rx(pitch)·Ry(roll)` has `R[2][1] = sin pitch`,
/// `R[2][0] = −cos pitch sin roll`, `R[2][2] = cos pitch cos roll`, `R[0][1] = sin yaw cos pitch`,
/// `R[1][1] = cos yaw cos pitch`.
pub fn panorama_angles(r: &Matrix3<f64>) -> (f64, f64, f64) {
    let pitch = r[(2, 1)].clamp(-1.0, 1.0).asin();
    let roll = (-r[(2, 0)]).atan2(r[(2, 2)]);
    let yaw = r[(0, 1)].atan2(r[(1, 1)]);
    (yaw.to_degrees(), pitch.to_degrees(), roll.to_degrees())
}

/// Campaign angles → rotation (re-exported for symmetry).
pub fn panorama_matrix(yaw_deg: f64, pitch_deg: f64, roll_deg: f64) -> Matrix3<f64> {
    panorama_rotation(yaw_deg, pitch_deg, roll_deg)
}

/// A lever arm: the point `lever_body_m` (body frame) from the IMU, whose attitude is `body_to_ned`.
/// Geodetic positions are (latitude °, longitude °, ellipsoidal height m) on `ellipsoid`.
pub struct LeverArm<'a> {
    pub ellipsoid: &'a Ellipsoid,
    pub body_to_ned: &'a Matrix3<f64>,
    pub lever_body_m: [f64; 3],
}

impl LeverArm<'_> {
    /// The lever arm in earth-centred axes at (lat, lon), m.
    fn offset_ecef(&self, lat_deg: f64, lon_deg: f64) -> Vector3<f64> {
        Ellipsoid::enu_to_ecef(lat_deg, lon_deg)
            * swap_xy_flip_z()
            * self.body_to_ned
            * Vector3::from(self.lever_body_m)
    }

    /// The geodetic position of the lever arm's end for the IMU at `imu`, exact through earth-centred
    /// coordinates.
    pub fn apply(&self, imu: (f64, f64, f64)) -> (f64, f64, f64) {
        if Vector3::from(self.lever_body_m) == Vector3::zeros() {
            return imu;
        }
        let (lat_deg, lon_deg, h_m) = imu;
        let offset_ecef = self.offset_ecef(lat_deg, lon_deg);
        let e = self.ellipsoid;
        e.from_ecef(&(e.to_ecef(lat_deg, lon_deg, h_m) + offset_ecef))
    }

    /// The IMU position whose lever arm ends at `end` (the inverse of [`LeverArm::apply`], by fixed-point
    /// iteration: the attitude's ECEF axes depend on the IMU position, changing by < 1e-6 per m).
    pub fn remove(&self, end: (f64, f64, f64)) -> (f64, f64, f64) {
        let target = self.ellipsoid.to_ecef(end.0, end.1, end.2);
        let mut imu = end;
        for _ in 0..5 {
            imu = self
                .ellipsoid
                .from_ecef(&(target - self.offset_ecef(imu.0, imu.1)));
        }
        imu
    }
}
