//! Visibility hypothesis of a façade plane in an oblique image (thesis 4.4.3, eqs. 4/5–4/6, Fig. 4.6).
//!
//! Reading of the (garbled) equations: the viewing vector w = c_obl − p_avg (centroid to camera) is split in
//! the plane's frame into its component along the normal a = w·n (the distance of the camera from the plane,
//! |c_obl − c_f| with c_f the perpendicular foot), a horizontal in-plane component b = w·h (h = ẑ × n,
//! normalised, along the façade) and a vertical in-plane component c = w·(n × h). Then
//! φ = atan2(|b|, a) — how far the camera is off the normal sideways (yaw), and
//! θ = atan2(|c|, a) — how far it is off the normal vertically (the oblique's elevation above the façade
//! normal). A camera straight in front of the plane gives θ = φ = 0°; the thesis admits ≤ 70° for both.
//! The camera must be in front of the plane (a > 0).
//!
//! Theoretical resolution: t = ‖w‖ / focal_px, the pixel footprint on a plane perpendicular to the viewing
//! ray. Thesis 4.4.5 says the theoretical resolution only equals the real one when the grid is parallel to
//! the image plane — i.e. t ignores the façade's obliquity, which the patch stage's real-resolution ratio
//! (≥ 0.6) accounts for later. Criterion 3: the centroid projects inside the image.

use crate::geometry::FrameCamera;
use crate::oblique::types::ObliqueView;
use nalgebra::Vector3;

/// Why an oblique image does not see a plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VisibilityRejection {
    /// The camera is behind (or in) the plane.
    Behind,
    /// θ or φ above the limit (degrees).
    Angle { theta_deg: f64, phi_deg: f64 },
    /// Theoretical resolution coarser than the limit (metres).
    Resolution { resolution_m: f64 },
    /// The centroid does not project into the image.
    Outside,
}

/// In-plane unit axes of a plane with unit normal `normal`: (horizontal h = ẑ × n normalised, up = n × h);
/// for a horizontal plane h = n × x̂ normalised. `(h, up, n)` is right-handed.
pub fn horizontal_axes(normal: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let mut h = Vector3::z().cross(normal);
    if !(h.norm() > 1e-9) {
        h = normal.cross(&Vector3::x());
    }
    let h = h.normalize();
    (h, normal.cross(&h))
}

/// (θ, φ) in degrees of a camera at `camera` seeing a plane with unit normal `normal` at `centroid` (module
/// documentation); `None` if the camera is not in front of the plane.
pub fn view_angles_deg(
    normal: &Vector3<f64>,
    centroid: &Vector3<f64>,
    camera: &Vector3<f64>,
) -> Option<(f64, f64)> {
    let w = camera - centroid;
    let a = w.dot(normal);
    if !(a > 0.0) {
        return None;
    }
    let (h, up) = horizontal_axes(normal);
    let phi = w.dot(&h).abs().atan2(a).to_degrees();
    let theta = w.dot(&up).abs().atan2(a).to_degrees();
    Some((theta, phi))
}

/// The visibility hypothesis of one plane in one oblique image (module documentation).
pub fn check_visibility(
    image_id: &str,
    camera: &FrameCamera,
    normal_world: &Vector3<f64>,
    centroid_world: &Vector3<f64>,
    max_view_angle_deg: f64,
    max_resolution_m: f64,
) -> Result<ObliqueView, VisibilityRejection> {
    let (theta_deg, phi_deg) = view_angles_deg(normal_world, centroid_world, &camera.center_world)
        .ok_or(VisibilityRejection::Behind)?;
    if !(theta_deg <= max_view_angle_deg && phi_deg <= max_view_angle_deg) {
        return Err(VisibilityRejection::Angle { theta_deg, phi_deg });
    }
    let resolution_m = (camera.center_world - centroid_world).norm() / camera.focal_px;
    if !(resolution_m <= max_resolution_m) {
        return Err(VisibilityRejection::Resolution { resolution_m });
    }
    let (u, v) = camera
        .project_world(centroid_world)
        .filter(|&(u, v)| camera.contains(u, v))
        .ok_or(VisibilityRejection::Outside)?;
    Ok(ObliqueView {
        image_id: image_id.to_string(),
        theta_deg,
        phi_deg,
        resolution_m,
        centroid_px: [u, v],
    })
}
