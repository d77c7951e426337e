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

/// The geodetic position of a point `lever_body_m` (body frame) from the IMU at (lat, lon, h) with attitude
/// `body_to_ned`, exact through earth-centred coordinates.
pub fn apply_lever_arm(
    ellipsoid: &Ellipsoid,
    lat_deg: f64,
    lon_deg: f64,
    h_m: f64,
    body_to_ned: &Matrix3<f64>,
    lever_body_m: [f64; 3],
) -> (f64, f64, f64) {
    let lever = Vector3::from(lever_body_m);
    if lever == Vector3::zeros() {
        return (lat_deg, lon_deg, h_m);
    }
    let offset_ecef =
        Ellipsoid::enu_to_ecef(lat_deg, lon_deg) * swap_xy_flip_z() * body_to_ned * lever;
    ellipsoid.from_ecef(&(ellipsoid.to_ecef(lat_deg, lon_deg, h_m) + offset_ecef))
}

/// The IMU position whose lever arm ends at the panorama centre (the inverse of [`apply_lever_arm`], by
/// fixed-point iteration: the attitude's ECEF axes depend on the IMU position, changing by < 1e-6 per m).
pub fn remove_lever_arm(
    ellipsoid: &Ellipsoid,
    lat_deg: f64,
    lon_deg: f64,
    h_m: f64,
    body_to_ned: &Matrix3<f64>,
    lever_body_m: [f64; 3],
) -> (f64, f64, f64) {
    let target = ellipsoid.to_ecef(lat_deg, lon_deg, h_m);
    let lever = Vector3::from(lever_body_m);
    let mut imu = (lat_deg, lon_deg, h_m);
    for _ in 0..5 {
        let offset = Ellipsoid::enu_to_ecef(imu.0, imu.1) * swap_xy_flip_z() * body_to_ned * lever;
        imu = ellipsoid.from_ecef(&(target - offset));
    }
    imu
}
