//! The mobile-mapping trajectory: true panorama poses every 5 m along a scene's driving route (thesis 3.5.1.2),
//! with heights from the road surface, heading = driving direction, increasing ISO 8601 times and (on some
//! panoramas) a small residual yaw/pitch/roll.

use super::preset::PresetParams;
use super::rng::{hash_str, Stream};
use crate::campaign::{format_time_iso, Recording};

/// A point sampled along a polyline with the local driving direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RouteSample {
    pub x_world: f64,
    pub y_world: f64,
    /// Distance from the route start, m.
    pub along_m: f64,
    /// Driving direction, degrees clockwise from grid north, in [0, 360).
    pub heading_deg: f64,
}

/// Cumulative lengths of a polyline (first entry 0).
fn cumulative_lengths(route: &[[f64; 2]]) -> Vec<f64> {
    let mut acc = Vec::with_capacity(route.len());
    let mut s = 0.0;
    acc.push(0.0);
    for w in route.windows(2) {
        s += (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
        acc.push(s);
    }
    acc
}

/// Point at distance `s_m` along the polyline (clamped to its ends).
pub fn point_at(route: &[[f64; 2]], cumulative: &[f64], s_m: f64) -> [f64; 2] {
    let total = *cumulative.last().unwrap_or(&0.0);
    let s = s_m.clamp(0.0, total);
    let k = cumulative
        .partition_point(|&c| c <= s)
        .clamp(1, route.len().max(2) - 1);
    let (a, b) = (route[k - 1], route[k]);
    let seg = cumulative[k] - cumulative[k - 1];
    let t = if seg > 0.0 {
        (s - cumulative[k - 1]) / seg
    } else {
        0.0
    };
    [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
}

/// Samples every `spacing_m` along `route` (at most `max_samples`), heading from the chord between the points
/// half a spacing before and after (smooth through bends). Empty if the route has fewer than 2 points.
pub fn sample_route(route: &[[f64; 2]], spacing_m: f64, max_samples: usize) -> Vec<RouteSample> {
    if route.len() < 2 || spacing_m <= 0.0 {
        return Vec::new();
    }
    let cum = cumulative_lengths(route);
    let total = *cum.last().unwrap();
    let count = ((total / spacing_m).floor() as usize + 1).min(max_samples);
    (0..count)
        .map(|i| {
            let s = i as f64 * spacing_m;
            let p = point_at(route, &cum, s);
            let a = point_at(route, &cum, s - spacing_m / 2.0);
            let b = point_at(route, &cum, s + spacing_m / 2.0);
            let heading_deg = (b[0] - a[0])
                .atan2(b[1] - a[1])
                .to_degrees()
                .rem_euclid(360.0);
            RouteSample {
                x_world: p[0],
                y_world: p[1],
                along_m: s,
                heading_deg,
            }
        })
        .collect()
}

/// Acquisition start of the synthetic campaign: 2019-06-14T10:00:00Z, seconds since 1970.
pub const START_TIME_S: f64 = 1_560_506_400.0;

/// True recordings of one route: `route_index` names them (`pano_<route>_<nnn>`) and offsets their times by
/// one hour per route. `ground_height_m(x, y)` gives the road surface height. Returns the recordings and
/// each one's distance along the route.
pub fn true_recordings(
    samples: &[RouteSample],
    route_index: usize,
    params: &PresetParams,
    seed: u64,
    ground_height_m: impl Fn(f64, f64) -> f64,
) -> Vec<Recording> {
    samples
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let image_id = format!("pano_{route_index}_{i:03}");
            let t_s = START_TIME_S + 3600.0 * route_index as f64 + s.along_m / params.speed_m_s;
            let t_s = (t_s * 1000.0).round() / 1000.0;
            let (mut yaw, mut pitch, mut roll) = (0.0, 0.0, 0.0);
            if params.attitude_every > 0 && i % params.attitude_every == 1 {
                let mut r = Stream::new(&[seed, hash_str("attitude"), hash_str(&image_id)]);
                let q = |v: f64| (v * 1e4).round() / 1e4;
                yaw = q(params.attitude_sigma_deg * r.normal());
                pitch = q(params.attitude_sigma_deg * r.normal());
                roll = q(params.attitude_sigma_deg * r.normal());
            }
            let z = ground_height_m(s.x_world, s.y_world) + params.camera_height_m;
            Recording {
                yaw_deg: yaw,
                pitch_deg: pitch,
                roll_deg: roll,
                sigma_xy_m: Some(params.sigma_xy_m),
                sigma_z_m: Some(params.sigma_z_m),
                time: format_time_iso(t_s).unwrap_or_default(),
                ..Recording::new(
                    &image_id,
                    t_s,
                    [s.x_world, s.y_world, z],
                    s.heading_deg,
                    params.camera_height_m,
                )
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_start_at_the_campaign_start_and_increase_by_spacing_over_speed() {
        let samples = sample_route(&[[0.0, 0.0], [0.0, 30.0]], 5.0, 100);
        let params = crate::synth::preset::Preset::Tiny.params();
        let recs = true_recordings(&samples, 1, &params, 3, |_, _| 1.5);
        assert_eq!(recs[0].time, "2019-06-14T11:00:00.000Z");
        assert_eq!(recs[1].time, "2019-06-14T11:00:00.625Z");
        assert_eq!(recs[1].image_id, "pano_1_001");
        assert!((recs[2].z - 3.7).abs() < 1e-12 && recs[2].camera_height_m == 2.2);
        assert!(recs.windows(2).all(|w| w[1].time_s > w[0].time_s));
        assert!(
            recs[1].yaw_deg != 0.0 && recs[0].yaw_deg == 0.0,
            "every 3rd has a residual rotation"
        );
    }

    #[test]
    fn samples_every_spacing_with_driving_heading_through_a_turn() {
        // 20 m north, then 20 m east.
        let route = [[0.0, 0.0], [0.0, 20.0], [20.0, 20.0]];
        let s = sample_route(&route, 5.0, 100);
        assert_eq!(s.len(), 9);
        assert!((s[2].y_world - 10.0).abs() < 1e-12 && s[2].x_world.abs() < 1e-12);
        assert!(s[1].heading_deg.abs() < 1e-9 || (s[1].heading_deg - 360.0).abs() < 1e-9);
        assert!((s[6].heading_deg - 90.0).abs() < 1e-9 && (s[6].x_world - 10.0).abs() < 1e-12);
        assert!(
            (s[4].heading_deg - 45.0).abs() < 1e-9,
            "corner heading {}",
            s[4].heading_deg
        );
        assert_eq!(sample_route(&route, 5.0, 3).len(), 3);
        assert!(sample_route(&route[..1], 5.0, 10).is_empty());
    }
}
