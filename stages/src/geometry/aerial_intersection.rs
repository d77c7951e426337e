//! Forward intersection of pixel observations in oriented aerial frame images (thesis 3.4.5.4 for nadir,
//! 4.4.7 for oblique control points): the pixels become rays of their [`FrameCamera`]s with an angular σ
//! from each image's `sigma_px`, the rays are intersected by [`triangulate_rays`] (weighted least squares,
//! a-priori covariance with σ0 = 1), and the result reports what a caller needs to accept or reject it: the
//! reprojection error of every observation in units of its σ_px and the largest intersection angle.
//!
//! [`intersect_pixel_rays`] only computes; [`intersect_checked`] also applies [`IntersectionLimits`] (a
//! minimum intersection angle and a maximum reprojection error) and says which one failed.

use super::frame::FrameCamera;
use super::ray::Ray;
use super::triangulation::{triangulate_rays, Triangulation, TriangulationError};
use serde::{Deserialize, Serialize};

/// One pixel measurement in an oriented frame image.
#[derive(Clone, Copy, Debug)]
pub struct PixelObservation<'a> {
    pub camera: &'a FrameCamera,
    /// Continuous pixel of the original image (campaign-format.md: first pixel centre at (0.5, 0.5)).
    pub u_px: f64,
    pub v_px: f64,
    /// Standard deviation of the measurement, pixels (> 0; the image row's `sigma_px`).
    pub sigma_px: f64,
}

/// The intersection of ≥ 2 pixel observations.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AerialIntersection {
    /// The weighted intersection of the observations' rays: the point (world frame), its a-priori covariance
    /// (σ0 = 1, from the observations' σ_px), the largest angle between two rays and the variance factor.
    pub triangulation: Triangulation,
    /// Per observation (input order): ‖reprojection − observation‖ / σ_px (∞ when the point does not
    /// project into that camera, e.g. behind it).
    pub reprojection_sigma: Vec<f64>,
    /// Largest of `reprojection_sigma`.
    pub max_reprojection_sigma: f64,
}

impl AerialIntersection {
    /// `point_world` as an array (the form the correspondence types store).
    pub fn point_array(&self) -> [f64; 3] {
        let p = &self.triangulation.point_world;
        [p.x, p.y, p.z]
    }

    /// `covariance_m2` as row-major nested arrays (the form the correspondence types store).
    pub fn covariance_rows(&self) -> [[f64; 3]; 3] {
        let c = &self.triangulation.covariance_m2;
        [
            [c[(0, 0)], c[(0, 1)], c[(0, 2)]],
            [c[(1, 0)], c[(1, 1)], c[(1, 2)]],
            [c[(2, 0)], c[(2, 1)], c[(2, 2)]],
        ]
    }
}

/// Intersects the rays of `observations` (≥ 2). Errors are those of [`triangulate_rays`] (too few rays,
/// σ_px not finite and > 0, non-finite pixels, parallel rays, point behind a camera).
pub fn intersect_pixel_rays(
    observations: &[PixelObservation],
) -> Result<AerialIntersection, TriangulationError> {
    let rays: Vec<Ray> = observations
        .iter()
        .map(|o| o.camera.pixel_ray(o.u_px, o.v_px))
        .collect();
    let sigmas: Vec<f64> = observations
        .iter()
        .map(|o| o.camera.angular_sigma_rad(o.sigma_px))
        .collect();
    let t = triangulate_rays(&rays, &sigmas)?;
    let reprojection_sigma: Vec<f64> = observations
        .iter()
        .map(|o| match o.camera.project_world(&t.point_world) {
            Some((u, v)) => (u - o.u_px).hypot(v - o.v_px) / o.sigma_px,
            None => f64::INFINITY,
        })
        .collect();
    let max_reprojection_sigma = reprojection_sigma.iter().copied().fold(0.0, f64::max);
    Ok(AerialIntersection {
        triangulation: t,
        reprojection_sigma,
        max_reprojection_sigma,
    })
}

/// Acceptance limits of [`intersect_checked`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct IntersectionLimits {
    /// Smallest accepted largest-intersection-angle, degrees (rays closer to parallel give no height).
    pub min_angle_deg: f64,
    /// Largest accepted reprojection error of any observation, in units of its σ_px.
    pub max_reprojection_sigma: f64,
}

/// Why [`intersect_checked`] rejected an intersection.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum IntersectionRejection {
    #[error("{0}")]
    Triangulation(#[from] TriangulationError),
    #[error("intersection angle {angle_deg:.3}° is below the minimum {min_deg}°")]
    SmallAngle { angle_deg: f64, min_deg: f64 },
    #[error("reprojection error {sigma:.2} σ exceeds the limit {limit} σ")]
    LargeResidual { sigma: f64, limit: f64 },
}

/// [`intersect_pixel_rays`], then rejects a too-small intersection angle or a too-large reprojection error.
pub fn intersect_checked(
    observations: &[PixelObservation],
    limits: &IntersectionLimits,
) -> Result<AerialIntersection, IntersectionRejection> {
    let x = intersect_pixel_rays(observations)?;
    if !(x.triangulation.max_angle_deg >= limits.min_angle_deg) {
        return Err(IntersectionRejection::SmallAngle {
            angle_deg: x.triangulation.max_angle_deg,
            min_deg: limits.min_angle_deg,
        });
    }
    if !(x.max_reprojection_sigma <= limits.max_reprojection_sigma) {
        return Err(IntersectionRejection::LargeResidual {
            sigma: x.max_reprojection_sigma,
            limit: limits.max_reprojection_sigma,
        });
    }
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::BrownDistortion;
    use nalgebra::Vector3;

    /// An oblique camera 600 m east/west of the origin at 1000 m height, looking at (500 000, 5 400 000, 50).
    fn oblique(east_m: f64, kappa_deg: f64) -> FrameCamera {
        let target = Vector3::new(500_000.0, 5_400_000.0, 50.0);
        let centre = Vector3::new(500_000.0 + east_m, 5_400_000.0 + 30.0, 1000.0);
        let r = crate::geometry::look_at_matrix(&centre, &target);
        let mut cam = FrameCamera::from_opk(
            centre,
            0.0,
            0.0,
            kappa_deg,
            8000.0,
            2000.0,
            1500.0,
            4000,
            3000,
            BrownDistortion {
                k1: -0.02,
                k2: 0.001,
                p1: 1e-5,
                p2: -1e-5,
                ..BrownDistortion::NONE
            },
        );
        cam.rotation_cam_to_world = r;
        cam
    }

    fn observe<'a>(cam: &'a FrameCamera, p: &Vector3<f64>, du: f64) -> PixelObservation<'a> {
        let (u, v) = cam.project_world(p).expect("in front");
        PixelObservation {
            camera: cam,
            u_px: u + du,
            v_px: v,
            sigma_px: 0.5,
        }
    }

    #[test]
    fn exact_projections_intersect_to_the_point() {
        let a = oblique(-600.0, 0.0);
        let b = oblique(650.0, 0.0);
        for p in [
            Vector3::new(500_003.0, 5_400_001.0, 52.5),
            Vector3::new(499_990.0, 5_400_020.0, 40.0),
        ] {
            let x = intersect_pixel_rays(&[observe(&a, &p, 0.0), observe(&b, &p, 0.0)]).unwrap();
            assert!(
                (x.triangulation.point_world - p).norm() < 1e-4,
                "{:?}",
                x.triangulation.point_world - p
            );
            assert!(x.max_reprojection_sigma < 1e-3);
            assert!(
                x.triangulation.max_angle_deg > 60.0 && x.triangulation.max_angle_deg < 90.0,
                "{}",
                x.triangulation.max_angle_deg
            );
            let c = x.covariance_rows();
            assert!(c[0][0] > 0.0 && c[1][1] > 0.0 && c[2][2] > 0.0);
            assert!((c[0][1] - c[1][0]).abs() <= 1e-9 * c[0][0]);
        }
    }

    #[test]
    fn limits_reject_small_angles_and_large_residuals() {
        let a = oblique(-600.0, 0.0);
        let b = oblique(650.0, 0.0);
        let c = oblique(-610.0, 0.0);
        let p = Vector3::new(500_003.0, 5_400_001.0, 52.5);
        let limits = IntersectionLimits {
            min_angle_deg: 2.0,
            max_reprojection_sigma: 3.0,
        };
        // Two nearly identical viewpoints: angle well below 2°.
        let r = intersect_checked(&[observe(&a, &p, 0.0), observe(&c, &p, 0.0)], &limits);
        assert!(
            matches!(r, Err(IntersectionRejection::SmallAngle { .. })),
            "{r:?}"
        );
        // Three views, one observation 20 px off: the residual exceeds 3 σ.
        let r = intersect_checked(
            &[
                observe(&a, &p, 0.0),
                observe(&b, &p, 0.0),
                observe(&c, &p, 20.0),
            ],
            &limits,
        );
        assert!(
            matches!(r, Err(IntersectionRejection::LargeResidual { .. })),
            "{r:?}"
        );
        // 0.5 px noise passes.
        let r = intersect_checked(&[observe(&a, &p, 0.5), observe(&b, &p, -0.5)], &limits);
        assert!(r.is_ok(), "{r:?}");
    }

    #[test]
    fn invalid_sigma_and_single_ray_are_errors() {
        let a = oblique(-600.0, 0.0);
        let p = Vector3::new(500_003.0, 5_400_001.0, 52.5);
        assert!(matches!(
            intersect_pixel_rays(&[observe(&a, &p, 0.0)]),
            Err(TriangulationError::TooFewRays(1))
        ));
        let b = oblique(650.0, 0.0);
        let mut o = observe(&b, &p, 0.0);
        o.sigma_px = 0.0;
        assert!(matches!(
            intersect_pixel_rays(&[observe(&a, &p, 0.0), o]),
            Err(TriangulationError::InvalidSigma { .. })
        ));
    }
}
