//! From ortho-image measurements back to the panoramas and into object space (thesis 3.4.4.5): each ortho
//! pixel becomes a world point on that ortho's ground plane, which the recording's panorama camera projects
//! to the panorama pixel it was sampled from (the exact inverse of the ortho-projection, 3.4.3); the rays
//! of those pixels from the recorded poses are triangulated with weights from the panorama pixel precision.
//! A point is rejected when a ray misses it by more than `max_ray_residual_m` (with three rays the worst
//! neighbour ray is dropped first) or the rays intersect at too small an angle.

use super::params::MmMatchParams;
use super::OrthoView;
use crate::correspondence::{MmTiePoint, PanoObservation};
use crate::geometry::{triangulate_rays, PanoramaCamera, Ray, Triangulation};

/// The panorama camera of a view's recorded pose.
pub fn camera_of(view: &OrthoView) -> PanoramaCamera {
    PanoramaCamera::from_recording(view.recording, view.pano_width_px, view.pano_height_px)
}

/// The panorama observation of ortho pixel (u, v) of `view` (exact inverse of the ortho-projection).
pub fn pano_observation(
    view: &OrthoView,
    camera: &PanoramaCamera,
    u_px: f64,
    v_px: f64,
) -> Option<PanoObservation> {
    let (u, v) = view
        .ortho
        .georef
        .ortho_to_panorama_pixel(camera, u_px, v_px)?;
    (u.is_finite() && v.is_finite()).then(|| PanoObservation {
        image_id: view.recording.image_id.clone(),
        u_px: u,
        v_px: v,
    })
}

/// The settings of [`triangulate_track`] (shared by the nadir MM matching and the oblique sparse cloud).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackTriangulation {
    /// Standard deviation of a panorama observation, panorama px (ray weights).
    pub pano_sigma_px: f64,
    /// A ray farther than this from the point rejects the track (after dropping the worst of ≥ 3 rays), m.
    pub max_ray_residual_m: f64,
    /// Smallest accepted maximum intersection angle, degrees.
    pub min_intersection_angle_deg: f64,
}

impl From<&MmMatchParams> for TrackTriangulation {
    fn from(p: &MmMatchParams) -> Self {
        Self {
            pano_sigma_px: p.pano_sigma_px,
            max_ray_residual_m: p.max_ray_residual_m,
            min_intersection_angle_deg: p.min_intersection_angle_deg,
        }
    }
}

/// Whether a triangulation passes the residual and angle checks.
fn acceptable(t: &Triangulation, p: &TrackTriangulation) -> bool {
    t.residuals_m.iter().all(|&r| r <= p.max_ray_residual_m)
        && t.max_angle_deg >= p.min_intersection_angle_deg
        && t.point_world.iter().all(|v| v.is_finite())
}

/// Triangulate one track. `members[k]` = (camera, observation) with the detecting panorama first. Returns the
/// tie point with the observations actually used (`members[0]` is never dropped).
pub fn triangulate_track(
    id: String,
    members: &[(&PanoramaCamera, PanoObservation)],
    p: &TrackTriangulation,
) -> Option<MmTiePoint> {
    let solve = |keep: &[usize]| -> Option<Triangulation> {
        let rays: Vec<Ray> = keep
            .iter()
            .map(|&k| {
                let (cam, obs) = &members[k];
                cam.pixel_ray(obs.u_px, obs.v_px)
            })
            .collect();
        let sigmas: Vec<f64> = keep
            .iter()
            .map(|&k| members[k].0.angular_sigma_rad(p.pano_sigma_px))
            .collect();
        triangulate_rays(&rays, &sigmas).ok()
    };
    let mut keep: Vec<usize> = (0..members.len()).collect();
    let mut tri = solve(&keep);
    let failed = tri.as_ref().is_none_or(|t| !acceptable(t, p));
    if failed && keep.len() >= 3 {
        // Drop the neighbour ray that misses most (never the detecting one) and try once more.
        if let Some(t) = &tri {
            let worst = (1..keep.len())
                .max_by(|&a, &b| t.residuals_m[a].total_cmp(&t.residuals_m[b]))
                .unwrap_or(1);
            keep.remove(worst);
            tri = solve(&keep);
        }
    }
    let t = tri.filter(|t| acceptable(t, p))?;
    let c = &t.covariance_m2;
    Some(MmTiePoint {
        id,
        observations: keep.iter().map(|&k| members[k].1.clone()).collect(),
        point_world: [t.point_world.x, t.point_world.y, t.point_world.z],
        covariance_m2: [
            [c[(0, 0)], c[(0, 1)], c[(0, 2)]],
            [c[(1, 0)], c[(1, 1)], c[(1, 2)]],
            [c[(2, 0)], c[(2, 1)], c[(2, 2)]],
        ],
        max_angle_deg: t.max_angle_deg,
    })
}
