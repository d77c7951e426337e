//! Check points and their simulated manual measurements (thesis 3.5.3): distinct ground features of the scene
//! with exact coordinates, about one per 15–20 m of route, each observed in the nearby panoramas where it is
//! visible (no occluder, not behind the recording vehicle), at its true projection plus N(0, σ) pixel noise.

use super::rng::{hash_str, Stream};
use super::scene::{Epoch, Scene};
use super::vehicle::VehicleBody;
use crate::campaign::{CheckPoint, Observation, Recording};
use crate::geometry::PanoramaCamera;
use nalgebra::Vector3;

/// A check-point candidate: position along the route (m), id, world position, and its observations as
/// (recording index, (u, v) px).
type ScoredCandidate = (f64, String, Vector3<f64>, Vec<(usize, (f64, f64))>);

/// Largest gap (m) between the distance to the first hit and to the point for it to count as visible.
const VISIBILITY_TOLERANCE_M: f64 = 0.05;

/// Where `point_world` is seen in the panorama of `rec` (true pose), if it is within `max_distance_m`,
/// visible and not behind the vehicle body; noise-free continuous pixel (u, v).
pub fn visible_projection(
    scene: &Scene,
    rec: &Recording,
    width_px: u32,
    point_world: &Vector3<f64>,
    max_distance_m: f64,
) -> Option<(f64, f64)> {
    let centre = Vector3::new(rec.x, rec.y, rec.z);
    let delta = point_world - centre;
    let dist = delta.norm();
    if dist > max_distance_m || dist < 1e-6 {
        return None;
    }
    let dir = delta / dist;
    if VehicleBody::standard(rec.heading_deg, rec.camera_height_m)
        .hit(&dir)
        .is_some()
    {
        return None;
    }
    let hit = scene.first_hit(&centre, &dir, Epoch::MobileMapping)?;
    if (hit.distance_m - dist).abs() > VISIBILITY_TOLERANCE_M {
        return None;
    }
    let camera = PanoramaCamera::new(
        width_px,
        width_px / 2,
        centre,
        rec.yaw_deg,
        rec.pitch_deg,
        rec.roll_deg,
    );
    camera.project_world(point_world)
}

/// Check points and their observations for one route.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ControlSet {
    pub checkpoints: Vec<CheckPoint>,
    pub observations: Vec<Observation>,
}

/// Parameters of [`plan_control`].
#[derive(Clone, Debug, PartialEq)]
pub struct ControlParams {
    /// One check point per this many metres of route.
    pub spacing_m: f64,
    /// Candidates farther than this from the nearest panorama are ignored, m.
    pub max_route_distance_m: f64,
    /// Observations only in panoramas within this distance, m.
    pub max_observation_distance_m: f64,
    /// SD of the measurement noise per pixel axis.
    pub sigma_px: f64,
    /// Panorama width (height = width / 2).
    pub panorama_width_px: u32,
    /// Point ids are `<prefix>_<nn>`.
    pub id_prefix: String,
}

/// Choose check points among `scene.checkpoint_candidates()` and observe them in `recordings` (true poses,
/// in driving order with `along_m[i]` the distance of recording i along the route). The route is cut into
/// bins of `spacing_m`; in each bin the candidate observed in ≥ 2 panoramas closest to the bin's middle is
/// taken. Measurement noise depends only on (seed, point id, image id).
pub fn plan_control(
    scene: &Scene,
    recordings: &[Recording],
    along_m: &[f64],
    params: &ControlParams,
    seed: u64,
) -> ControlSet {
    if recordings.is_empty() {
        return ControlSet::default();
    }
    // Candidates with their position along the route (that of the nearest panorama) and observations.
    let mut scored: Vec<ScoredCandidate> = Vec::new();
    for (kind, p) in scene.checkpoint_candidates() {
        let (nearest, d2) = recordings
            .iter()
            .enumerate()
            .map(|(i, r)| (i, (r.x - p.x).powi(2) + (r.y - p.y).powi(2)))
            .fold(
                (0, f64::INFINITY),
                |best, c| if c.1 < best.1 { c } else { best },
            );
        if d2.sqrt() > params.max_route_distance_m {
            continue;
        }
        let seen: Vec<(usize, (f64, f64))> = recordings
            .iter()
            .enumerate()
            .filter_map(|(i, r)| {
                visible_projection(
                    scene,
                    r,
                    params.panorama_width_px,
                    &p,
                    params.max_observation_distance_m,
                )
                .map(|uv| (i, uv))
            })
            .collect();
        if seen.len() >= 2 {
            scored.push((along_m.get(nearest).copied().unwrap_or(0.0), kind, p, seen));
        }
    }
    let total_m = along_m.iter().copied().fold(0.0, f64::max);
    let bins = ((total_m / params.spacing_m).round() as usize).max(1);
    let bin_m = (total_m / bins as f64).max(1e-9);
    let mut set = ControlSet::default();
    let (w, h) = (
        f64::from(params.panorama_width_px),
        f64::from(params.panorama_width_px / 2),
    );
    for b in 0..bins {
        let mid = (b as f64 + 0.5) * bin_m;
        let lo = b as f64 * bin_m;
        let hi = if b + 1 == bins {
            f64::INFINITY
        } else {
            lo + bin_m
        };
        // Closest to the bin middle; ties broken by kind and coordinates for determinism.
        let best = scored
            .iter()
            .filter(|c| c.0 >= lo && c.0 < hi)
            .min_by(|a, c| {
                (a.0 - mid)
                    .abs()
                    .total_cmp(&(c.0 - mid).abs())
                    .then_with(|| a.1.cmp(&c.1))
                    .then_with(|| a.2.x.total_cmp(&c.2.x))
                    .then_with(|| a.2.y.total_cmp(&c.2.y))
            });
        let Some((_, _, p, seen)) = best else {
            continue;
        };
        let point_id = format!("{}_{:02}", params.id_prefix, set.checkpoints.len());
        set.checkpoints.push(CheckPoint {
            point_id: point_id.clone(),
            x: p.x,
            y: p.y,
            z: p.z,
            sigma_xy_m: Some(0.01),
            sigma_z_m: Some(0.01),
        });
        for (i, (u, v)) in seen {
            let rec = &recordings[*i];
            let mut r = Stream::new(&[
                seed,
                hash_str("observation"),
                hash_str(&point_id),
                hash_str(&rec.image_id),
            ]);
            let u_px = (u + params.sigma_px * r.normal()).rem_euclid(w);
            let v_px = (v + params.sigma_px * r.normal()).clamp(0.0, h);
            set.observations.push(Observation {
                point_id: point_id.clone(),
                image_id: rec.image_id.clone(),
                u_px,
                v_px,
            });
        }
    }
    set
}
