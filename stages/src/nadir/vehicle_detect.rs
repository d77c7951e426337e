//! The recording vehicle found in the panoramas themselves (thesis 3.4.3 masks the car's roof and bonnet in the
//! ortho images; campaign-format.md leaves the vehicle's extent out of the format). The car is the part of the
//! panorama that stays the same relative to the driving direction from one recording to the next, while the
//! street moves past: sampled on a grid of directions fixed to the vehicle (azimuth relative to the heading,
//! depression below the horizon), a direction that shows the car has nearly the same grey value in every
//! recording, one that shows the ground does not.
//!
//! Steps: (1) per recording, the mean grey value of every grid cell (a 3 × 3 sub-sample average), divided by the
//! recording's mean over the grid (exposure); (2) per cell, the standard deviation over the recordings; (3) the
//! threshold between "stable" and "varying" by Otsu's method on the logarithm of the deviations; (4) per
//! azimuth, the stable run of cells that reaches down to the nadir gives the depression where the car begins;
//! (5) the box model of [`VehicleMask`] fitted to those boundaries: with the top face at `roof_drop_m`, the
//! boundary at azimuth α lies `roof_drop / tan(depression)` from the camera, and the front, rear and half width
//! are the medians of the boundary points' coordinates in 30°–40° sectors around ahead, behind and the sides,
//! enlarged by a margin.

use super::vehicle_mask::VehicleMask;
use crate::campaign::Recording;
use crate::geometry::PanoramaCamera;
use crate::imaging::border::Border;
use crate::imaging::pyramid::PyramidLayout;
use crate::imaging::sample::sample_bilinear;
use crate::imaging::GrayImage;
use crate::params::{describe, Params, StageId, Violation};
use nalgebra::Vector3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("vehicle", "3");

crate::params! {
    /// Parameters of [`detect_vehicle`].
    pub struct VehicleDetectParams {
        /// Use at most this many recordings, evenly spread over the campaign.
        max_recordings: usize = 24, min 3;
        /// Fewer usable recordings than this: no detection.
        min_recordings: usize = 5, min 3;
        /// Grid step in azimuth (relative to the driving direction).
        azimuth_step_deg: f64 = 2.0, unit "deg", min 0.25, max 20.0;
        /// Grid step in depression below the horizon.
        depression_step_deg: f64 = 1.0, unit "deg", min 0.1, max 10.0;
        /// The car is searched below this depression only (the horizon is never the car).
        min_depression_deg: f64 = 10.0, unit "deg", min 0.0, max 80.0;
        /// Relative enlargement of the fitted box (edges blurred by the grid and the images).
        margin: f64 = 0.08, min 0.0, max 1.0;
    }
    check(p, v) {
        if p.max_recordings < p.min_recordings {
            v.push(Violation::new(
                "min_recordings",
                format!(
                    "must be ≤ max_recordings, got {} and {}",
                    p.min_recordings, p.max_recordings
                ),
            ));
        }
    }
}

/// The detection's result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DetectedVehicle {
    /// The fitted box (enabled).
    pub mask: VehicleMask,
    pub recordings_used: usize,
    /// Otsu threshold on the cells' grey-value deviation (relative to the recordings' mean grey value).
    pub threshold: f64,
    /// Per azimuth step (0 = ahead, clockwise seen from above): depression where the car begins, degrees
    /// (`None`: no car found towards that azimuth).
    pub boundary_depression_deg: Vec<Option<f64>>,
}

/// The sampling grid.
struct Grid {
    azimuths: usize,
    depressions: usize,
    az_step: f64,
    dep_step: f64,
    dep0: f64,
}

impl Grid {
    fn new(p: &VehicleDetectParams) -> Self {
        Self {
            azimuths: (360.0 / p.azimuth_step_deg).round() as usize,
            depressions: ((90.0 - p.min_depression_deg) / p.depression_step_deg).floor() as usize,
            az_step: 360.0 / (360.0 / p.azimuth_step_deg).round(),
            dep_step: p.depression_step_deg,
            dep0: p.min_depression_deg,
        }
    }

    /// Direction in the vehicle frame (x ahead, y right, z up) for azimuth α and depression δ, degrees.
    fn direction(alpha_deg: f64, depression_deg: f64) -> [f64; 3] {
        let (sa, ca) = alpha_deg.to_radians().sin_cos();
        let (sd, cd) = depression_deg.to_radians().sin_cos();
        [cd * ca, cd * sa, -sd]
    }
}

/// Mean grey value of every grid cell in one recording's panorama, divided by the mean over the grid.
fn cell_values(rec: &Recording, img: &GrayImage, g: &Grid) -> Vec<f64> {
    let cam = PanoramaCamera::from_recording(rec, img.width as u32, img.height as u32);
    let (sh, ch) = rec.heading_deg.to_radians().sin_cos();
    // Vehicle frame → world: ahead = (sin h, cos h), right = (cos h, −sin h).
    let to_world = |d: [f64; 3]| Vector3::new(d[0] * sh + d[1] * ch, d[0] * ch - d[1] * sh, d[2]);
    let mut out = Vec::with_capacity(g.azimuths * g.depressions);
    for j in 0..g.azimuths {
        for k in 0..g.depressions {
            let mut sum = 0.0;
            for a in 0..3 {
                for b in 0..3 {
                    let alpha = (j as f64 + (a as f64 + 0.5) / 3.0) * g.az_step;
                    let dep = g.dep0 + (k as f64 + (b as f64 + 0.5) / 3.0) * g.dep_step;
                    let (u, v) = cam.ray_world_to_pixel(&to_world(Grid::direction(alpha, dep)));
                    sum += f64::from(sample_bilinear(img, u, v, Border::Clamp));
                }
            }
            out.push(sum / 9.0);
        }
    }
    let mean = out.iter().sum::<f64>() / out.len().max(1) as f64;
    if mean > 0.0 {
        out.iter_mut().for_each(|v| *v /= mean);
    }
    out
}

/// Otsu's threshold of `values` (a 256-bin histogram between their extremes).
fn otsu(values: &[f64]) -> f64 {
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if !(hi > lo) {
        return lo;
    }
    let bins = 256;
    let mut hist = vec![0usize; bins];
    for &v in values {
        hist[(((v - lo) / (hi - lo)) * (bins - 1) as f64).round() as usize] += 1;
    }
    let total = values.len() as f64;
    let sum_all: f64 = hist
        .iter()
        .enumerate()
        .map(|(i, &c)| i as f64 * c as f64)
        .sum();
    let (mut w0, mut sum0, mut best, mut best_i) = (0.0, 0.0, -1.0, 0usize);
    for (i, &c) in hist.iter().enumerate() {
        w0 += c as f64;
        sum0 += i as f64 * c as f64;
        let w1 = total - w0;
        if w0 == 0.0 || w1 == 0.0 {
            continue;
        }
        let (m0, m1) = (sum0 / w0, (sum_all - sum0) / w1);
        let between = w0 * w1 * (m0 - m1).powi(2);
        if between > best {
            best = between;
            best_i = i;
        }
    }
    lo + (best_i as f64 + 0.5) / (bins - 1) as f64 * (hi - lo)
}

/// Median of `v` (`None` when empty).
fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

/// The box of `VehicleMask` (top face `roof_drop_m` below the camera) through the boundary depressions.
fn fit_box(
    boundary: &[Option<f64>],
    az_step: f64,
    roof_drop_m: f64,
    margin: f64,
) -> Option<VehicleMask> {
    let points: Vec<(f64, [f64; 2])> = boundary
        .iter()
        .enumerate()
        .filter_map(|(j, d)| {
            let d = (*d)?;
            let alpha = (j as f64 + 0.5) * az_step;
            let r = roof_drop_m / d.to_radians().tan();
            let (s, c) = alpha.to_radians().sin_cos();
            Some((alpha, [r * c, r * s]))
        })
        .collect();
    let near = |centre: f64, half: f64| {
        move |a: f64| ((a - centre + 540.0).rem_euclid(360.0) - 180.0).abs() <= half
    };
    let pick = |sector: &dyn Fn(f64) -> bool, f: &dyn Fn([f64; 2]) -> f64| {
        median(
            points
                .iter()
                .filter(|(a, _)| sector(*a))
                .map(|(_, p)| f(*p))
                .collect(),
        )
    };
    let ahead = near(0.0, 15.0);
    let behind = near(180.0, 15.0);
    let sides = |a: f64| near(90.0, 20.0)(a) || near(270.0, 20.0)(a);
    let front = pick(&ahead, &|p| p[0])?;
    let rear = pick(&behind, &|p| -p[0])?;
    let half_width = pick(&sides, &|p| p[1].abs())?;
    (front > 0.0 && rear > 0.0 && half_width > 0.0).then_some(VehicleMask {
        enabled: true,
        detect: true,
        roof_drop_m,
        front_m: front * (1.0 + margin),
        rear_m: rear * (1.0 + margin),
        half_width_m: half_width * (1.0 + margin),
    })
}

/// The pyramid level of a panorama (pyramid `layout`) that the detection reads: the coarsest whose pixel is at
/// most a third of the finer grid step (each grid cell averages 3 × 3 samples), but never finer than the
/// panorama's detail level (`PyramidLayout::detail_level`): the levels below it only repeat its pixels, and
/// sampled bilinearly they would give other values than the panorama that was enlarged, so an enlarged copy
/// would find another vehicle box than its original.
pub fn detection_level(layout: &PyramidLayout, p: &VehicleDetectParams) -> usize {
    let levels = layout.levels();
    let pixel_deg = p.azimuth_step_deg.min(p.depression_step_deg) / 3.0;
    let needed_width_px = 360.0 / pixel_deg;
    let mut level = 0;
    while level + 1 < levels && (layout.width >> (level + 1)) as f64 >= needed_width_px {
        level += 1;
    }
    level.max(layout.detail_level.min(levels.saturating_sub(1)))
}

/// The vehicle of the panoramas `views` (recording with its recorded heading and orientation, grey image); the
/// error says why none was found (too few views, no stable region at the nadir in every direction).
pub fn detect_vehicle(
    views: &[(&Recording, &GrayImage)],
    p: &VehicleDetectParams,
) -> Result<DetectedVehicle, String> {
    if let Err(e) = p.validate() {
        return Err(format!(
            "invalid vehicle detection parameters: {}",
            describe(&e)
        ));
    }
    if views.len() < p.min_recordings {
        return Err(format!(
            "{} panoramas; at least {} are needed to tell the car from the street",
            views.len(),
            p.min_recordings
        ));
    }
    let g = Grid::new(p);
    let values: Vec<Vec<f64>> = views
        .par_iter()
        .map(|(rec, img)| cell_values(rec, img, &g))
        .collect();
    let n = values.len() as f64;
    let cells = g.azimuths * g.depressions;
    let log_sd: Vec<f64> = (0..cells)
        .map(|c| {
            let mean = values.iter().map(|v| v[c]).sum::<f64>() / n;
            let var = values.iter().map(|v| (v[c] - mean).powi(2)).sum::<f64>() / (n - 1.0);
            (var.sqrt() + 1e-6).ln()
        })
        .collect();
    let threshold = otsu(&log_sd);
    let stable = |j: usize, k: usize| log_sd[j * g.depressions + k] < threshold;
    let boundary: Vec<Option<f64>> = (0..g.azimuths)
        .map(|j| {
            let last = g.depressions.checked_sub(1)?;
            if !stable(j, last) {
                return None;
            }
            let mut k = last;
            while k > 0 && stable(j, k - 1) {
                k -= 1;
            }
            Some(g.dep0 + k as f64 * g.dep_step)
        })
        .collect();
    let roof_drop = VehicleMask::default().roof_drop_m;
    let mask = fit_box(&boundary, g.az_step, roof_drop, p.margin).ok_or_else(|| {
        "no region at the nadir stays the same across the panoramas ahead, behind and to both sides".to_string()
    })?;
    Ok(DetectedVehicle {
        mask,
        recordings_used: views.len(),
        threshold: threshold.exp(),
        boundary_depression_deg: boundary,
    })
}

/// Up to `max` indices spread evenly over `0..n` (all when `n ≤ max`).
pub fn spread_indices(n: usize, max: usize) -> Vec<usize> {
    if n <= max {
        return (0..n).collect();
    }
    (0..max).map(|i| i * (n - 1) / (max - 1).max(1)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_through_exact_boundaries_is_recovered() {
        let truth = VehicleMask {
            enabled: true,
            detect: false,
            roof_drop_m: 0.4,
            front_m: 0.8,
            rear_m: 1.3,
            half_width_m: 0.7,
        };
        // Boundary depression per 2° azimuth: where the ray leaves the rectangle at the roof plane.
        let boundary: Vec<Option<f64>> = (0..180)
            .map(|j| {
                let a = ((j as f64 + 0.5) * 2.0).to_radians();
                let (s, c) = a.sin_cos();
                let tx = if c > 0.0 {
                    truth.front_m / c
                } else {
                    truth.rear_m / -c
                };
                let ty = truth.half_width_m / s.abs().max(1e-12);
                let r = tx.min(ty);
                Some((truth.roof_drop_m / r).atan().to_degrees())
            })
            .collect();
        let m = fit_box(&boundary, 2.0, 0.4, 0.0).unwrap();
        assert!((m.front_m - 0.8).abs() < 0.01, "{m:?}");
        assert!((m.rear_m - 1.3).abs() < 0.01, "{m:?}");
        assert!((m.half_width_m - 0.7).abs() < 0.01, "{m:?}");
        assert!(fit_box(&vec![None; 180], 2.0, 0.4, 0.0).is_none());
    }

    #[test]
    fn the_detection_level_follows_the_grid_step_but_not_below_the_detail_level() {
        let p = VehicleDetectParams::default(); // 1° depression step: pixels of at most 1/3°, 1080 px wide
        let layout = |w: usize, detail_level: usize| {
            let mut l = PyramidLayout::new(w, w / 2, crate::imaging::pyramid::SampleDepth::U8, 256)
                .unwrap();
            l.detail_level = detail_level;
            l
        };
        assert_eq!(detection_level(&layout(1024, 0), &p), 0);
        assert_eq!(detection_level(&layout(8192, 0), &p), 2);
        // A 1024-px panorama enlarged 4× by pixel repetition is read at the level it was enlarged from, not
        // at its 2048-px level, whose pixels only repeat the original's.
        assert_eq!(detection_level(&layout(4096, 0), &p), 1);
        assert_eq!(detection_level(&layout(4096, 2), &p), 2);
    }

    #[test]
    fn otsu_splits_two_clusters_and_indices_spread_evenly() {
        let mut v: Vec<f64> = (0..100).map(|i| -5.0 + 0.001 * i as f64).collect();
        v.extend((0..300).map(|i| -1.0 + 0.001 * i as f64));
        let t = otsu(&v);
        assert!(t > -4.9 && t < -1.0, "{t}");
        assert_eq!(spread_indices(5, 10), vec![0, 1, 2, 3, 4]);
        assert_eq!(spread_indices(40, 4), vec![0, 13, 26, 39]);
    }
}
