//! Heights of the ground tie points from a terrain model: a tie point of the nadir matching is a point of the
//! road surface, so a digital terrain model (DTM) gives its height independently of the panoramas' rays —
//! Z = DTM(x, y), σ = the DTM's stated σ.
//!
//! Why: the panoramas' orientations are held (only the positions are estimated), so two panoramas that see the
//! same ground points fix the direction of the baseline between them, not its length — scaling the pair and
//! its points about one centre leaves every ray as it is, and with both centres at the same height (a road)
//! their heights do not tell either. Where a recording has no control of its own, nothing but the relative
//! constraints then holds its position along the trajectory, and it keeps its own along-track error (demo
//! seed 29: recordings 2–10 between control, 0.05–0.34 m off, the error along the trajectory). A point's
//! height fixes where along each ray it lies — a ray that falls by `h` over `r` metres puts a height error δ
//! at r·δ/h along the ground — so with the recordings' own heights (`dtm_height`) it fixes the baseline's
//! length too.
//!
//! The DTM is sampled at the tie point's position triangulated with the recorded poses, like the recordings'
//! heights at their recorded positions: both are off by the recordings' error alike, and on a 2 % slope a
//! 0.8 m offset changes the terrain by 0.016 m. A tie point that is not on the ground (a kerb's edge) is
//! reduced by the observations' robust loss. Points that are control already have the DTM's height in their
//! control position and get no second one; the oblique sparse cloud's points (façades) get none.

use super::from_correspondences::{BlockPoint, PointKind};
use super::problem::{HeightObservation, PointHeight};
use crate::correspondence::MmTiePoint;
use std::collections::HashMap;

/// The observed heights of the block's tie points: `heights[k]` (the terrain height under `tie_points[k]`,
/// `None` where there is none or the point is not a ground point) for every tie point that is a block point
/// (`point_index` by id) of kind [`PointKind::Tie`].
pub fn tie_point_heights(
    tie_points: &[MmTiePoint],
    heights: &[Option<HeightObservation>],
    point_index: &HashMap<String, usize>,
    points: &[BlockPoint],
) -> Vec<PointHeight> {
    tie_points
        .iter()
        .zip(heights)
        .filter_map(|(tp, h)| {
            let h = (*h)?;
            let &point = point_index.get(&tp.id)?;
            (points.get(point)?.kind == PointKind::Tie).then_some(PointHeight {
                point,
                z_world: h.z_world,
                sigma_m: h.sigma_m,
            })
        })
        .collect()
}

/// Per tie point of `tie_points`, the terrain's height under it (`terrain_z_m` at its triangulated XY,
/// `None` where the terrain has none) with σ `sigma_m`, for the points `on_ground` says are ground points.
pub fn terrain_under_tie_points(
    tie_points: &[MmTiePoint],
    on_ground: impl Fn(usize) -> bool,
    terrain_z_m: impl Fn(f64, f64) -> Option<f64>,
    sigma_m: f64,
) -> Vec<Option<HeightObservation>> {
    tie_points
        .iter()
        .enumerate()
        .map(|(k, tp)| {
            if !on_ground(k) {
                return None;
            }
            let [x, y, _] = tp.point_world;
            terrain_z_m(x, y)
                .filter(|z| z.is_finite())
                .map(|z| HeightObservation {
                    z_world: z,
                    sigma_m,
                })
        })
        .collect()
}
