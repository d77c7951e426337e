//! Dominant orientation of a KAZE keypoint (ALGORITHMS.md §1 "Orientation"; SURF-style, KAZE paper §4.3).
//!
//! With s = round(σ): derivative samples (Lx, Ly) of the keypoint's level at the pixels containing
//! (u + i·s, v + j·s), integer i, j with i² + j² < 36 (109 samples), Gaussian-weighted (σ = 2.5·s) by the
//! distance of the sampled pixel's centre from the keypoint. A π/3 sector slides in steps of 0.15 rad; the
//! sector with the longest summed vector gives θ = atan2(ΣLy, ΣLx) ∈ [0, 2π). Samples outside the image are
//! skipped. θ is measured in the image frame (+x right, +y down), i.e. clockwise on screen.

use std::f32::consts::PI;

use super::scale_space::Level;

const SAMPLE_RADIUS: i32 = 6;
const SECTOR_WIDTH_RAD: f32 = PI / 3.0;
const SECTOR_STEP_RAD: f32 = 0.15;
const MAX_SAMPLES: usize = 109;

/// Angle of (x, y) in [0, 2π).
#[inline]
pub fn angle_0_2pi(x: f32, y: f32) -> f32 {
    let a = y.atan2(x);
    if a < 0.0 {
        a + 2.0 * PI
    } else {
        a
    }
}

/// Dominant orientation (rad, [0, 2π)) at (u_px, v_px) with refined scale `sigma_px` on `level`.
pub fn dominant_orientation(level: &Level, u_px: f32, v_px: f32, sigma_px: f32) -> f32 {
    let s = sigma_px.round().max(1.0);
    let (w, h) = (level.lx.width as i64, level.lx.height as i64);
    let mut xs = [0.0f32; MAX_SAMPLES];
    let mut ys = [0.0f32; MAX_SAMPLES];
    let mut angles = [0.0f32; MAX_SAMPLES];
    let mut n = 0usize;
    let inv_two_var = 1.0 / (2.0 * (2.5 * s) * (2.5 * s));
    for j in -SAMPLE_RADIUS..=SAMPLE_RADIUS {
        for i in -SAMPLE_RADIUS..=SAMPLE_RADIUS {
            if i * i + j * j >= SAMPLE_RADIUS * SAMPLE_RADIUS {
                continue;
            }
            let col = (u_px + i as f32 * s).floor() as i64;
            let row = (v_px + j as f32 * s).floor() as i64;
            if col < 0 || row < 0 || col >= w || row >= h {
                continue;
            }
            let du = col as f32 + 0.5 - u_px;
            let dv = row as f32 + 0.5 - v_px;
            let weight = (-(du * du + dv * dv) * inv_two_var).exp();
            let idx = row as usize * w as usize + col as usize;
            xs[n] = weight * level.lx.data[idx];
            ys[n] = weight * level.ly.data[idx];
            angles[n] = angle_0_2pi(xs[n], ys[n]);
            n += 1;
        }
    }
    let mut best_norm = 0.0f32;
    let mut best_angle = 0.0f32;
    let mut start = 0.0f32;
    while start < 2.0 * PI {
        let end = start + SECTOR_WIDTH_RAD;
        let (mut sx, mut sy) = (0.0f32, 0.0f32);
        for k in 0..n {
            let a = angles[k];
            // Sector [start, end) wrapping past 2π.
            let inside = if end <= 2.0 * PI {
                a >= start && a < end
            } else {
                a >= start || a < end - 2.0 * PI
            };
            if inside {
                sx += xs[k];
                sy += ys[k];
            }
        }
        let norm = sx * sx + sy * sy;
        if norm > best_norm {
            best_norm = norm;
            best_angle = angle_0_2pi(sx, sy);
        }
        start += SECTOR_STEP_RAD;
    }
    best_angle
}
