//! M-SURF descriptor of KAZE (ALGORITHMS.md §1 "Descriptor"; Agrawal et al. 2008 as used by KAZE; thesis
//! 3.4.5.2 uses the extended, upright variant).
//!
//! With s = round(σ) and the keypoint frame rotated by θ (θ = 0 when upright): a 4×4 grid of sub-regions
//! centred on the keypoint, sub-region centres at (−7.5, −2.5, 2.5, 7.5)·s, each sampled on 9×9 points at
//! step s around its centre (nominal 5s cell extended by 2s on each side; neighbours overlap), so the whole
//! window spans 24s × 24s and is symmetric about the keypoint (OpenCV's grid is offset by s/2; ours is not).
//! Per sample: bilinear (Lx, Ly) of the level at the continuous position (campaign pixel convention, clamped
//! at the border), rotated into the keypoint frame, weighted by a Gaussian σ1 = 2.5s about the sub-region
//! centre. Per sub-region (ΣLx, ΣLy, Σ|Lx|, Σ|Ly|) — or, extended, the 8 sums split by the sign of the other
//! derivative — weighted by a Gaussian σ2 = 1.5 sub-regions about the grid centre. Finally L2-normalised.

use super::scale_space::Level;
use crate::imaging::sample::sample_bilinear;
use crate::imaging::Border;

const GRID: usize = 4;
const SAMPLES_PER_SIDE: i32 = 9;
const SIGMA1_STEPS: f32 = 2.5;
const SIGMA2_CELLS: f32 = 1.5;

/// Write the descriptor of the keypoint (u_px, v_px, sigma_px, angle_rad) on `level` into `out`
/// (length 64, or 128 if `extended`). `out` must have that length.
pub fn describe(
    level: &Level,
    u_px: f32,
    v_px: f32,
    sigma_px: f32,
    angle_rad: f32,
    extended: bool,
    out: &mut [f32],
) {
    let per_cell = if extended { 8 } else { 4 };
    debug_assert_eq!(out.len(), GRID * GRID * per_cell);
    let s = sigma_px.round().max(1.0) as f64;
    let (co, si) = ((angle_rad as f64).cos(), (angle_rad as f64).sin());
    let inv_two_var1 = 1.0 / (2.0 * SIGMA1_STEPS * SIGMA1_STEPS);
    let inv_two_var2 = 1.0 / (2.0 * SIGMA2_CELLS * SIGMA2_CELLS);
    let mut sum_sq = 0.0f64;
    for cy in 0..GRID {
        for cx in 0..GRID {
            // Sub-region centre in keypoint-frame units of s, and its index offset from the grid centre.
            let centre_x = -7.5 + 5.0 * cx as f32;
            let centre_y = -7.5 + 5.0 * cy as f32;
            let mut acc = [0.0f32; 8];
            for j in -(SAMPLES_PER_SIDE / 2)..=SAMPLES_PER_SIDE / 2 {
                for i in -(SAMPLES_PER_SIDE / 2)..=SAMPLES_PER_SIDE / 2 {
                    let ox = centre_x + i as f32;
                    let oy = centre_y + j as f32;
                    let weight = (-((i * i + j * j) as f32) * inv_two_var1).exp();
                    let su = u_px as f64 + (ox as f64 * co - oy as f64 * si) * s;
                    let sv = v_px as f64 + (ox as f64 * si + oy as f64 * co) * s;
                    let gx = sample_bilinear(&level.lx, su, sv, Border::Clamp);
                    let gy = sample_bilinear(&level.ly, su, sv, Border::Clamp);
                    // Into the keypoint frame (x' along θ, y' along θ + π/2).
                    let rx = weight * (gx * co as f32 + gy * si as f32);
                    let ry = weight * (-gx * si as f32 + gy * co as f32);
                    if extended {
                        if ry >= 0.0 {
                            acc[0] += rx;
                            acc[2] += rx.abs();
                        } else {
                            acc[1] += rx;
                            acc[3] += rx.abs();
                        }
                        if rx >= 0.0 {
                            acc[4] += ry;
                            acc[6] += ry.abs();
                        } else {
                            acc[5] += ry;
                            acc[7] += ry.abs();
                        }
                    } else {
                        acc[0] += rx;
                        acc[1] += ry;
                        acc[2] += rx.abs();
                        acc[3] += ry.abs();
                    }
                }
            }
            let gx2 = cx as f32 - 1.5;
            let gy2 = cy as f32 - 1.5;
            let weight2 = (-(gx2 * gx2 + gy2 * gy2) * inv_two_var2).exp();
            let base = (cy * GRID + cx) * per_cell;
            for k in 0..per_cell {
                let v = acc[k] * weight2;
                out[base + k] = v;
                sum_sq += (v as f64) * (v as f64);
            }
        }
    }
    if sum_sq > 0.0 {
        let inv = (1.0 / sum_sq.sqrt()) as f32;
        out.iter_mut().for_each(|v| *v *= inv);
    }
}
