//! Dominant orientation of a KAZE keypoint (Alcantarilla, Bartoli & Davison 2012 "Orientation"; SURF-style, KAZE paper §4.3).
//!
//! With s = round(σ): derivative samples (Lx, Ly) of the keypoint's level at the pixels containing
//! (u + i·s, v + j·s), integer i, j with i² + j² < 36 (109 samples), Gaussian-weighted (σ = 2.5·s) by the
//! distance of the sampled pixel's centre from the keypoint. A π/3 sector slides around the circle; the
//! sector with the longest summed vector gives θ = atan2(ΣLy, ΣLx) ∈ [0, 2π). Samples outside the image are
//! skipped. Deviation from OpenCV (which steps the sector start by 0.15 rad): the sector starts at every
//! sample angle, i.e. the exact maximum over all sector positions, which also makes θ follow image
//! rotations exactly (OpenCV's fixed 0.15 rad grid does not rotate with the image). θ is measured in the image frame (+x right, +y down), i.e. clockwise on screen.

use std::f32::consts::PI;

use super::scale_space::Level;

const SAMPLE_RADIUS: i32 = 6;
const SECTOR_WIDTH_RAD: f32 = PI / 3.0;
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
    // Sectors anchored at every sample angle: the exact maximum over all sector positions (the 0.15 rad
    // sweep of OpenCV samples these positions coarsely), and equivariant under image rotations.
    let mut order = [0usize; MAX_SAMPLES];
    for (k, o) in order.iter_mut().enumerate().take(n) {
        *o = k;
    }
    let order = &mut order[..n];
    order.sort_by(|&a, &b| angles[a].total_cmp(&angles[b]).then(a.cmp(&b)));
    let angle_at = |j: usize| {
        let a = angles[order[j % n]];
        if j >= n {
            a + 2.0 * PI
        } else {
            a
        }
    };
    let mut best_norm = 0.0f32;
    let mut best_angle = 0.0f32;
    let mut end = 0usize;
    for start in 0..n {
        end = end.max(start);
        while end < start + n && angle_at(end) < angle_at(start) + SECTOR_WIDTH_RAD {
            end += 1;
        }
        // Sum in a fixed order (start..end) so the result does not depend on earlier windows.
        let (mut sx, mut sy) = (0.0f32, 0.0f32);
        for j in start..end {
            let k = order[j % n];
            sx += xs[k];
            sy += ys[k];
        }
        let norm = sx * sx + sy * sy;
        if norm > best_norm {
            best_norm = norm;
            best_angle = angle_0_2pi(sx, sy);
        }
    }
    best_angle
}
