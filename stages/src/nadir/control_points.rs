//! Aerial control points: the observations of one MM tie point across all overlapping aerial nadir images,
//! checked for consistency and triangulated from the aerial images alone (thesis 3.4.5.4).
//!
//! The aerial images need no registration with each other: all observations of a tie point come from the same
//! MM corner, so they are linked indirectly (3.4.5.4). Their locations still have to be verified before
//! triangulation.
//!
//! **Consistency check (object space, chosen over a reprojection-residual test).** Nadir images of one strip
//! intersect at well under 1° (baseline ≈ 20–60 m at ≈ 4500 m), so a mislocated observation that is off
//! *along* the baseline only changes the triangulated height: its reprojection residual stays small. We
//! therefore intersect every aerial ray with the horizontal plane at the tie point's MM height (known to
//! decimetres; a height error δz moves a ray's ground point only by δz·tan(tilt) ≤ a few mm) and compare the
//! ground points, each with σ = σ_px·GSD (⊕ δz·tan(tilt)): with ≥ 3 observations the one farthest from the
//! weighted mean of the others is dropped while that distance exceeds `k_sigma`; two observations must agree
//! within `k_sigma` of their combined σ, else the point is dropped (the wrong one cannot be told). The MM height
//! serves only this test; the point itself comes from the aerial rays alone, so it does not inherit the MM
//! positioning error (3.4.5.4). After the least-squares triangulation (`triangulate_rays`, σ of each ray from
//! the aerial row's `sigma_px`) the reprojection residuals must also stay within `k_sigma`·`sigma_px`.
//!
//! **Frame.** Rays from an aerial camera hundreds of metres up are intersected in the campaign's Cartesian frame
//! ([`MapFrame`]: the tangent frame of a projected CRS, or the coordinates themselves when they are Cartesian)
//! and the point and its covariance are converted back to map coordinates, so the map projection's scale and
//! the earth's curvature do not enter the control point (`crs::error_budget`).
//!
//! **Precision at the working level.** An observation is as precise as the pixels it was located in: the
//! refinement locates a tie point at a level of the aerial image's pyramid (`AerialMatch::level`; a 2.5 cm
//! frame at its 10 cm level), so its σ is the row's `sigma_px` in pixels of that level, `sigma_px · 2^level`
//! full-resolution pixels — σ on the ground is `sigma_px` times the GSD actually used, whatever the frame's
//! pixel count.
//!
//! Points seen in one aerial image are kept with `point_world: None` (a bundle with fixed aerial orientation
//! can still use them) and with their ray where it crosses the MM height (`ray_ground`, map coordinates, σ =
//! σ_px·GSD): the horizontal position the verification compares with. Output order: the window's tie-point order; observations sorted by aerial `image_id`.

use super::registration::{AerialRefinement, MmWindowMatch};
use crate::campaign::AerialImage;
use crate::correspondence::{AerialControlPoint, AerialObservation, AerialRayGround};
use crate::crs::MapFrame;
use crate::geometry::{
    intersect_ray_plane, triangulate_rays, FrameCamera, Plane, Ray, Triangulation,
};
use crate::params::{Params, StageId};
use crate::positions::positions_by;
use nalgebra::{Matrix3, Vector2, Vector3};

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("control", "5");

crate::params! {
    /// Parameters of [`aerial_control_points`].
    pub struct ControlParams {
        /// Rejection threshold in standard deviations (ground-point agreement and reprojection residuals).
        k_sigma: f64 = 3.0, min 1.0, max 100.0;
        /// Standard deviation of the MM tie point's height used by the ground-plane check.
        mm_height_sigma_m: f64 = 1.0, unit "m", min 0.0, max 1000.0;
        /// Observations with a matching score below this are ignored.
        min_score: f64 = 0.0;
        /// Weak peaks only where nothing better exists (`nadir::peak_support`): a location whose correlation
        /// peak is below this is kept only when none of its recording's locations in any nadir image reaches
        /// it (dropped ones count as `nadir.weak_peaks`). 0 = every peak accepted by `[refine] min_peak` is kept.
        strong_peak: f64 = 0.0, min 0.0, below 1.0;
        /// Corroborated tie points only where the recording has them (`nadir::peak_support`): a tie point
        /// located in fewer nadir images than this is left out when another tie point of its recording is
        /// located in at least this many (dropped ones count as `nadir.unconfirmed`). 1 = no check.
        min_aerial_images: usize = 1, min 1, max 20;
    }
    check(p, v) {
        crate::params::check_finite("min_score", &p.min_score, v);
    }
}

/// One aerial observation of a tie point with what the checks need.
struct Candidate {
    observation: AerialObservation,
    ray: Ray,
    /// Angular σ of the ray, rad.
    sigma_rad: f64,
    sigma_px: f64,
    camera: FrameCamera,
    /// Ray ∩ horizontal plane at the MM height (x, y), m; and that point's horizontal σ, m.
    ground_xy: Vector2<f64>,
    ground_sigma_m: f64,
    /// The horizontal σ of that point from the observation alone (σ_px · GSD), m.
    pixel_ground_sigma_m: f64,
}

fn candidate(
    row: &AerialImage,
    (obs, level): (&AerialObservation, usize),
    mm_z: f64,
    p: &ControlParams,
    frame: &MapFrame,
) -> Option<Candidate> {
    let camera = frame.camera_to_local(&FrameCamera::from_aerial(row)).ok()?;
    let sigma_level_px = if row.sigma_px.is_finite() && row.sigma_px > 0.0 {
        row.sigma_px
    } else {
        0.5
    };
    // σ in full-resolution pixels: `sigma_px` pixels of the level the point was located at.
    let sigma_px = sigma_level_px * (1u64 << level.min(30)) as f64;
    let ray = camera.pixel_ray(obs.u_px, obs.v_px);
    if !ray.dir_world.iter().all(|v| v.is_finite()) {
        return None;
    }
    let ground = intersect_ray_plane(&ray, &Plane::horizontal(mm_z))?;
    let gsd_m = camera.gsd_at(&ground);
    if !(gsd_m > 0.0 && gsd_m.is_finite()) {
        return None;
    }
    let d = ray.dir_world;
    let tilt_tan = d.x.hypot(d.y) / d.z.abs().max(1e-9);
    let pixel_ground_sigma_m = sigma_px * gsd_m;
    let ground_sigma_m = pixel_ground_sigma_m.hypot(p.mm_height_sigma_m * tilt_tan);
    Some(Candidate {
        observation: obs.clone(),
        ray,
        sigma_rad: camera.angular_sigma_rad(sigma_px),
        sigma_px,
        camera,
        ground_xy: Vector2::new(ground.x, ground.y),
        ground_sigma_m,
        pixel_ground_sigma_m,
    })
}

/// Weighted mean of the ground points of `c` except index `skip`, with its σ.
fn mean_without(c: &[Candidate], skip: usize) -> (Vector2<f64>, f64) {
    // Local origin: the first other point (world coordinates are ≈ 1e5 m).
    let origin = c
        .iter()
        .enumerate()
        .find(|(k, _)| *k != skip)
        .map(|(_, x)| x.ground_xy)
        .unwrap_or_else(Vector2::zeros);
    let (mut sw, mut acc) = (0.0, Vector2::zeros());
    for (k, x) in c.iter().enumerate() {
        if k == skip {
            continue;
        }
        let w = 1.0 / x.ground_sigma_m.powi(2);
        sw += w;
        acc += (x.ground_xy - origin) * w;
    }
    (origin + acc / sw, (1.0 / sw).sqrt())
}

/// Ground-plane consistency check (see the module documentation); returns the surviving candidates.
fn consistent_subset(mut c: Vec<Candidate>, k_sigma: f64) -> Vec<Candidate> {
    while c.len() >= 3 {
        let mut worst = (0usize, 0.0f64);
        for k in 0..c.len() {
            let (mean, sigma_mean) = mean_without(&c, k);
            let z = (c[k].ground_xy - mean).norm() / c[k].ground_sigma_m.hypot(sigma_mean);
            if z > worst.1 {
                worst = (k, z);
            }
        }
        if worst.1 <= k_sigma {
            return c;
        }
        c.remove(worst.0);
    }
    if c.len() == 2 {
        let z = (c[0].ground_xy - c[1].ground_xy).norm()
            / c[0].ground_sigma_m.hypot(c[1].ground_sigma_m);
        if z > k_sigma {
            c.clear();
        }
    }
    c
}

/// Largest reprojection residual of `t` in the candidates' images, in units of each image's σ_px.
fn max_reprojection_sigma(c: &[&Candidate], t: &Triangulation) -> f64 {
    c.iter()
        .map(|x| match x.camera.project_world(&t.point_world) {
            Some((u, v)) => (u - x.observation.u_px).hypot(v - x.observation.v_px) / x.sigma_px,
            None => f64::INFINITY,
        })
        .fold(0.0, f64::max)
}

/// Least-squares triangulation of the candidates' rays and its largest reprojection residual (σ units).
fn triangulate(c: &[&Candidate]) -> Option<(Triangulation, f64)> {
    let rays: Vec<Ray> = c.iter().map(|x| x.ray).collect();
    let sigmas: Vec<f64> = c.iter().map(|x| x.sigma_rad).collect();
    let t = triangulate_rays(&rays, &sigmas).ok()?;
    let r = max_reprojection_sigma(c, &t);
    Some((t, r))
}

/// Triangulate the consistent candidates; with ≥ 3 and a reprojection residual above `k_sigma`, drop the one
/// observation whose removal leaves the smallest residual (once). Returns the kept candidates and the point,
/// or nothing.
fn triangulate_checked(
    kept: Vec<Candidate>,
    k_sigma: f64,
) -> Option<(Vec<Candidate>, Triangulation)> {
    let all: Vec<&Candidate> = kept.iter().collect();
    let (t, r) = triangulate(&all)?;
    if r <= k_sigma {
        return Some((kept, t));
    }
    if kept.len() < 3 {
        return None;
    }
    let best = (0..kept.len())
        .filter_map(|k| {
            let rest: Vec<&Candidate> = kept
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != k)
                .map(|(_, c)| c)
                .collect();
            let (t, r) = triangulate(&rest)?;
            (r <= k_sigma).then_some((k, r, t))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    let mut kept = kept;
    kept.remove(best.0);
    Some((kept, best.2))
}

/// Aerial control points of one MM window from its refinements in all overlapping aerial images
/// (thesis 3.4.5.4), for coordinates that are Cartesian. `refinements` pairs each aerial row with its
/// refinement; refinements of other recordings, unknown tie points and repeated images (the best score is
/// kept) are ignored.
pub fn aerial_control_points(
    window: &MmWindowMatch,
    refinements: &[(&AerialImage, &AerialRefinement)],
    p: &ControlParams,
) -> Vec<AerialControlPoint> {
    aerial_control_points_in(window, refinements, p, &MapFrame::Cartesian)
}

/// [`aerial_control_points`] with the rays intersected in `frame` (see the module documentation).
pub fn aerial_control_points_in(
    window: &MmWindowMatch,
    refinements: &[(&AerialImage, &AerialRefinement)],
    p: &ControlParams,
    frame: &MapFrame,
) -> Vec<AerialControlPoint> {
    if p.validate().is_err() {
        return Vec::new();
    }
    let index = positions_by(&window.tie_points, |tp| tp.id.as_str());
    // Per tie point: (aerial row, observation, level located at), at most one per aerial image (best score).
    let mut per_point: Vec<Vec<(&AerialImage, &AerialObservation, usize)>> =
        vec![Vec::new(); window.tie_points.len()];
    for (row, refinement) in refinements {
        if refinement.recording_id != window.recording_id {
            continue;
        }
        for m in &refinement.matches {
            let Some(&i) = index.get(m.tie_point_id.as_str()) else {
                continue;
            };
            let obs = &m.observation;
            if !(obs.score >= p.min_score && obs.u_px.is_finite() && obs.v_px.is_finite()) {
                continue;
            }
            let list = &mut per_point[i];
            match list.iter_mut().find(|(r, _, _)| r.image_id == row.image_id) {
                Some(slot) if obs.score > slot.1.score => *slot = (*row, obs, m.level),
                Some(_) => {}
                None => list.push((*row, obs, m.level)),
            }
        }
    }
    let mut out = Vec::new();
    for (tp, mut list) in window.tie_points.iter().zip(per_point) {
        list.sort_by(|a, b| a.0.image_id.cmp(&b.0.image_id));
        let Ok(mm_local) = frame.point_to_local(&Vector3::from(tp.point_world)) else {
            continue;
        };
        let candidates: Vec<Candidate> = list
            .iter()
            .filter_map(|(row, obs, level)| candidate(row, (*obs, *level), mm_local.z, p, frame))
            .collect();
        let kept = consistent_subset(candidates, p.k_sigma);
        let ray_ground = match kept.as_slice() {
            [single] => ray_ground_in_map(frame, single, mm_local.z),
            _ => None,
        };
        let (kept, point) = match kept.len() {
            0 => continue,
            1 => (kept, None),
            _ => match triangulate_checked(kept, p.k_sigma).map(|(k, t)| (k, in_map(frame, &t))) {
                Some((kept, Some(point))) => (kept, Some(point)),
                _ => continue,
            },
        };
        out.push(AerialControlPoint {
            map: None,
            tie_point_id: tp.id.clone(),
            mm: tp.observations.clone(),
            aerial: kept
                .into_iter()
                .map(|c| AerialObservation {
                    sigma_px: Some(c.sigma_px),
                    ..c.observation
                })
                .collect(),
            point_world: point.as_ref().map(|(x, _)| to_array(x)),
            covariance_m2: point.as_ref().map(|(_, c)| {
                [
                    [c[(0, 0)], c[(0, 1)], c[(0, 2)]],
                    [c[(1, 0)], c[(1, 1)], c[(1, 2)]],
                    [c[(2, 0)], c[(2, 1)], c[(2, 2)]],
                ]
            }),
            ray_ground,
        });
    }
    out
}

/// A single observation's ray where it crosses height `z_local` (the MM height, local frame), in map
/// coordinates (`None` when the frame cannot convert it or the ray is horizontal).
fn ray_ground_in_map(frame: &MapFrame, c: &Candidate, z_local: f64) -> Option<AerialRayGround> {
    let local = AerialRayGround::from_ray(&c.ray, z_local, c.pixel_ground_sigma_m)?;
    let at = Vector3::from(local.point_world);
    let above = at + Vector3::new(local.xy_per_z[0], local.xy_per_z[1], 1.0);
    let (at, above) = (
        frame.point_to_map(&at).ok()?,
        frame.point_to_map(&above).ok()?,
    );
    AerialRayGround::through(&at, &above, c.pixel_ground_sigma_m)
}

/// The triangulated point and its covariance in map coordinates (`None` when the frame cannot convert it).
fn in_map(frame: &MapFrame, t: &Triangulation) -> Option<(Vector3<f64>, Matrix3<f64>)> {
    let point = frame.point_to_map(&t.point_world).ok()?;
    let covariance = frame.covariance_to_map(&point, &t.covariance_m2).ok()?;
    Some((point, covariance))
}

fn to_array(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}
