//! The drive of a street-network block: a square grid of streets `street_spacing_m` apart, driven row by row
//! (west–east and back, a snake) and then column by column, so every crossing is passed twice, in two
//! directions — the repeated passes a city campaign has. Recordings every `spacing_m` along the drive on a
//! gently undulating terrain, and the recorded positions: the true ones plus a slowly varying GNSS bias
//! (Gaussian knots every `drift_length` recordings, linearly interpolated — multipath and blocked satellites
//! give errors correlated over tens to hundreds of metres) and white noise.

use crate::rng::{mix_seed, SplitMix64};
use nalgebra::Vector3;

/// Camera height above the road, metres.
pub const CAMERA_HEIGHT_M: f64 = 2.5;

/// Ground height of the synthetic terrain at (x, y) relative to the grid origin, metres.
pub fn ground_z(x: f64, y: f64) -> f64 {
    100.0 + 2.0 * (x / 300.0).sin() + 1.5 * (y / 400.0).cos()
}

/// World position of the grid origin (south-west crossing), metres.
pub const ORIGIN: [f64; 2] = [150_000.0, 450_000.0];

/// True recording centres along the drive and the heading of travel at each (degrees clockwise from north).
pub fn drive(
    recordings: usize,
    street_spacing_m: f64,
    spacing_m: f64,
) -> (Vec<Vector3<f64>>, Vec<f64>) {
    let corners = grid_route(recordings, street_spacing_m, spacing_m);
    let mut centers = Vec::with_capacity(recordings);
    let mut headings = Vec::with_capacity(recordings);
    let mut along = 0.0;
    'legs: for leg in corners.windows(2) {
        let (a, b) = (leg[0], leg[1]);
        let d = [b[0] - a[0], b[1] - a[1]];
        let length = d[0].hypot(d[1]);
        let heading = d[0].atan2(d[1]).to_degrees().rem_euclid(360.0);
        while along <= length {
            if centers.len() == recordings {
                break 'legs;
            }
            let t = along / length;
            let (x, y) = (a[0] + t * d[0], a[1] + t * d[1]);
            centers.push(Vector3::new(
                ORIGIN[0] + x,
                ORIGIN[1] + y,
                ground_z(x, y) + CAMERA_HEIGHT_M,
            ));
            headings.push(heading);
            along += spacing_m;
        }
        along -= length;
    }
    (centers, headings)
}

/// Corners (grid coordinates, metres) of a snake over the rows and then the columns of a square grid just
/// large enough for `recordings` recordings.
fn grid_route(recordings: usize, street_spacing_m: f64, spacing_m: f64) -> Vec<[f64; 2]> {
    // Total street length 2·m·(m − 1)·B for m streets each way must hold the drive.
    let needed_m = recordings.max(2) as f64 * spacing_m;
    let mut m = 2usize;
    while 2.0 * (m * (m - 1)) as f64 * street_spacing_m < needed_m {
        m += 1;
    }
    let side = (m - 1) as f64 * street_spacing_m;
    let mut corners = Vec::with_capacity(4 * m);
    for row in 0..m {
        let y = row as f64 * street_spacing_m;
        let (x0, x1) = if row % 2 == 0 {
            (0.0, side)
        } else {
            (side, 0.0)
        };
        corners.push([x0, y]);
        corners.push([x1, y]);
    }
    // From the last row's end, the columns in a snake back south and north again.
    let start_at_east = corners.last().is_some_and(|c| c[0] > 0.0);
    for k in 0..m {
        let col = if start_at_east { m - 1 - k } else { k };
        let x = col as f64 * street_spacing_m;
        let (y0, y1) = if k % 2 == 0 { (side, 0.0) } else { (0.0, side) };
        corners.push([x, y0]);
        corners.push([x, y1]);
    }
    corners.dedup();
    corners
}

/// Recorded positions: `true_centers` + a horizontal bias varying slowly along the drive (knots every
/// `drift_length` recordings with σ `drift_sigma_m` per axis, linear in between) + white noise σ `noise_m`
/// per axis (horizontal) and a tenth of the bias vertically.
pub fn recorded_positions(
    true_centers: &[Vector3<f64>],
    drift_sigma_m: f64,
    drift_length: usize,
    noise_m: f64,
    seed: u64,
) -> Vec<Vector3<f64>> {
    let step = drift_length.max(1);
    let knot = |k: usize| {
        let mut rng = SplitMix64::new(mix_seed(seed ^ 0xD51F_7000, k as u64));
        Vector3::new(
            rng.next_gaussian(),
            rng.next_gaussian(),
            0.1 * rng.next_gaussian(),
        ) * drift_sigma_m
    };
    true_centers
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let (k, t) = (i / step, (i % step) as f64 / step as f64);
            let bias = knot(k) * (1.0 - t) + knot(k + 1) * t;
            let mut rng = SplitMix64::new(mix_seed(seed ^ 0x4015_E000, i as u64));
            let noise = Vector3::new(rng.next_gaussian(), rng.next_gaussian(), 0.0) * noise_m;
            c + bias + noise
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_drive_covers_every_street_twice_at_the_crossings_with_even_spacing() {
        let (centers, headings) = drive(2000, 100.0, 5.0);
        assert_eq!(centers.len(), 2000);
        for w in centers.windows(2) {
            let d = (w[1] - w[0]).xy().norm();
            // Equal spacing along the streets; shorter across a corner.
            assert!(d <= 5.0 + 1e-9 && d > 3.0, "{d}");
        }
        // Headings are axis-aligned.
        assert!(headings.iter().all(|h| (h % 90.0).abs() < 1e-9));
        // The crossing at grid (100, 100) is passed once west–east/east–west and once north–south.
        let near: Vec<usize> = (0..centers.len())
            .filter(|&i| {
                (centers[i].x - ORIGIN[0] - 100.0).hypot(centers[i].y - ORIGIN[1] - 100.0) < 3.0
            })
            .collect();
        assert!(near.len() >= 2);
        assert!(
            near.last().unwrap() - near.first().unwrap() > 100,
            "{near:?}"
        );
    }

    #[test]
    fn recorded_positions_drift_slowly() {
        let (centers, _) = drive(1000, 100.0, 5.0);
        let recorded = recorded_positions(&centers, 0.8, 100, 0.0, 3);
        let errors: Vec<Vector3<f64>> = recorded.iter().zip(&centers).map(|(r, c)| r - c).collect();
        let rms = (errors.iter().map(|e| e.xy().norm_squared()).sum::<f64>() / 1000.0).sqrt();
        assert!(rms > 0.3 && rms < 2.5, "{rms}");
        for w in errors.windows(2) {
            assert!((w[1] - w[0]).norm() < 0.1);
        }
    }
}
