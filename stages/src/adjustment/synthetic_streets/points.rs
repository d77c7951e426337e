//! Tie points of a street-network block and their panorama observations: points beside the road seen by 2–4
//! consecutive recordings (what matching along a trajectory gives), and at every crossing passed more than
//! once, road-marking points seen from each pass (what ties repeated passes together). Every item draws from
//! its own random stream, so the block is the same whatever the thread count.

use super::route::{ground_z, ORIGIN};
use crate::geometry::PanoramaCamera;
use crate::rng::{mix_seed, SplitMix64};
use nalgebra::Vector3;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// A tie point with the recordings that see it.
#[derive(Clone, Debug, PartialEq)]
pub struct TiePoint {
    pub true_world: Vector3<f64>,
    pub recordings: Vec<usize>,
}

/// Points anchored at each recording: `per_recording` on average (a fraction is rounded at random), each
/// seen by 2–4 consecutive recordings starting at its anchor, 4–12 m left or right of the road, 0–6 m up.
pub fn roadside_points(centers: &[Vector3<f64>], per_recording: f64, seed: u64) -> Vec<TiePoint> {
    let n = centers.len();
    (0..n)
        .into_par_iter()
        .with_min_len(256)
        .map(|i| {
            let mut rng = SplitMix64::new(mix_seed(seed ^ 0x7E1E_0000, i as u64));
            let count = per_recording.floor() as usize
                + usize::from(rng.next_f64() < per_recording - per_recording.floor());
            (0..count)
                .filter_map(|_| {
                    let v = (2 + rng.below(3) as usize).min(n);
                    let s = i.min(n - v);
                    let (first, last) = (centers[s], centers[s + v - 1]);
                    let mut dir = last - first;
                    dir.z = 0.0;
                    let dir = dir.try_normalize(1e-9)?;
                    let normal = Vector3::new(-dir.y, dir.x, 0.0);
                    let side = if rng.next_f64() < 0.5 { -1.0 } else { 1.0 };
                    let mid = (first + last) * 0.5;
                    let mut p = mid
                        + normal * (side * (4.0 + 8.0 * rng.next_f64()))
                        + dir * ((rng.next_f64() - 0.5) * 5.0);
                    p.z = ground_z(p.x - ORIGIN[0], p.y - ORIGIN[1]) + rng.next_f64() * 6.0;
                    Some(TiePoint {
                        true_world: p,
                        recordings: (s..s + v).collect(),
                    })
                })
                .collect::<Vec<_>>()
        })
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .collect()
}

/// At each crossing of the grid (spacing `street_spacing_m`) passed more than once, `per_crossing`
/// road-marking points within 5 m of its centre, each seen by the two recordings of every pass nearest to
/// the crossing. A pass is a run of consecutive recordings within 8 m of the crossing.
pub fn crossing_points(
    centers: &[Vector3<f64>],
    street_spacing_m: f64,
    per_crossing: usize,
    seed: u64,
) -> Vec<TiePoint> {
    let node_of = |c: &Vector3<f64>| {
        let (x, y) = (c.x - ORIGIN[0], c.y - ORIGIN[1]);
        let (i, j) = (
            (x / street_spacing_m).round(),
            (y / street_spacing_m).round(),
        );
        let d = (x - i * street_spacing_m).hypot(y - j * street_spacing_m);
        (d < 8.0).then_some((i as i64, j as i64))
    };
    let mut near: BTreeMap<(i64, i64), Vec<usize>> = BTreeMap::new();
    for (r, c) in centers.iter().enumerate() {
        if let Some(node) = node_of(c) {
            near.entry(node).or_default().push(r);
        }
    }
    let mut points = Vec::new();
    for (&(i, j), recordings) in &near {
        let centre = [i as f64 * street_spacing_m, j as f64 * street_spacing_m];
        let distance = |r: usize| {
            (centers[r].x - ORIGIN[0] - centre[0]).hypot(centers[r].y - ORIGIN[1] - centre[1])
        };
        let mut seen_by = Vec::new();
        let mut passes = 0;
        for pass in recordings.chunk_by(|a, b| b - a == 1) {
            let mut sorted = pass.to_vec();
            sorted.sort_by(|&a, &b| distance(a).total_cmp(&distance(b)).then(a.cmp(&b)));
            seen_by.extend(sorted.into_iter().take(2));
            passes += 1;
        }
        if passes < 2 {
            continue;
        }
        seen_by.sort_unstable();
        let node_key = ((i as u64) << 32) ^ (j as u64 & 0xFFFF_FFFF);
        let mut rng = SplitMix64::new(mix_seed(seed ^ 0xC205_5000, node_key));
        for _ in 0..per_crossing {
            let (dx, dy) = ((rng.next_f64() - 0.5) * 10.0, (rng.next_f64() - 0.5) * 10.0);
            let (x, y) = (centre[0] + dx, centre[1] + dy);
            points.push(TiePoint {
                true_world: Vector3::new(ORIGIN[0] + x, ORIGIN[1] + y, ground_z(x, y)),
                recordings: seen_by.clone(),
            });
        }
    }
    points
}

/// Observed pixels (u, v) of each point in each of its recordings' true cameras, with Gaussian pixel noise
/// of σ `noise_px`; an observation that does not project (never for these geometries) is left out.
pub fn observe(
    points: &[TiePoint],
    cameras: &[PanoramaCamera],
    noise_px: f64,
    seed: u64,
) -> Vec<Vec<(usize, f64, f64)>> {
    points
        .par_iter()
        .enumerate()
        .with_min_len(1024)
        .map(|(p, point)| {
            let mut rng = SplitMix64::new(mix_seed(seed ^ 0x0B5E_0000, p as u64));
            point
                .recordings
                .iter()
                .filter_map(|&r| {
                    let cam = &cameras[r];
                    let (u, v) = cam.project_world(&point.true_world)?;
                    let width = f64::from(cam.width_px);
                    let u = (u + noise_px * rng.next_gaussian()).rem_euclid(width);
                    let v = (v + noise_px * rng.next_gaussian())
                        .clamp(1e-3, f64::from(cam.height_px) - 1e-3);
                    Some((r, u, v))
                })
                .collect()
        })
        .collect()
}
