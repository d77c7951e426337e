//! M-SURF descriptor of KAZE (Alcantarilla, Bartoli & Davison 2012 "Descriptor"; Agrawal et al. 2008 as used by KAZE; thesis
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

use std::sync::OnceLock;

use super::scale_space::Level;
use crate::imaging::sample::sample_bilinear;
use crate::imaging::{Border, GrayImage};

const GRID: usize = 4;
const SAMPLES_PER_SIDE: i32 = 9;
const SIGMA1_STEPS: f32 = 2.5;
const SIGMA2_CELLS: f32 = 1.5;
/// Sample positions per side of the whole window: sub-region centres 5 steps apart, 9 samples each, so the
/// 4 × 9 samples of a row fall on 24 distinct offsets (−11.5 … 11.5 steps).
const WINDOW_SAMPLES: usize = 24;
const HALF: i32 = SAMPLES_PER_SIDE / 2;

/// Gaussian weights exp(−(i² + j²)/(2σ1²)) of the 9 × 9 samples of a sub-region (row j, column i).
fn sample_weights() -> &'static [f32; 81] {
    static WEIGHTS: OnceLock<[f32; 81]> = OnceLock::new();
    WEIGHTS.get_or_init(|| {
        let inv_two_var1 = 1.0 / (2.0 * SIGMA1_STEPS * SIGMA1_STEPS);
        let mut w = [0.0f32; 81];
        for j in -HALF..=HALF {
            for i in -HALF..=HALF {
                w[((j + HALF) * SAMPLES_PER_SIDE + i + HALF) as usize] =
                    (-((i * i + j * j) as f32) * inv_two_var1).exp();
            }
        }
        w
    })
}

/// Add one weighted, rotated sample (rx, ry) to a sub-region's sums. The sign splits are written as selects
/// (adding +0.0 leaves a sum unchanged), so the sums equal the branching form exactly.
#[inline(always)]
fn accumulate(acc: &mut [f32; 8], rx: f32, ry: f32, extended: bool) {
    if extended {
        let (ry_pos, rx_pos) = (ry >= 0.0, rx >= 0.0);
        acc[0] += if ry_pos { rx } else { 0.0 };
        acc[1] += if ry_pos { 0.0 } else { rx };
        acc[2] += if ry_pos { rx.abs() } else { 0.0 };
        acc[3] += if ry_pos { 0.0 } else { rx.abs() };
        acc[4] += if rx_pos { ry } else { 0.0 };
        acc[5] += if rx_pos { 0.0 } else { ry };
        acc[6] += if rx_pos { ry.abs() } else { 0.0 };
        acc[7] += if rx_pos { 0.0 } else { ry.abs() };
    } else {
        acc[0] += rx;
        acc[1] += ry;
        acc[2] += rx.abs();
        acc[3] += ry.abs();
    }
}

/// Bilinear (Lx, Ly) at the 24 × 24 window offsets of an upright keypoint (u + a_x·s, v + a_y·s with
/// a ∈ −11.5 … 11.5): the same values as [`sample_bilinear`] with [`Border::Clamp`] at each position (the
/// position, floor and fraction are computed exactly as there; interior samples read the 4 pixels
/// directly, samples near the border go through `sample_bilinear`).
fn upright_window(
    lx: &GrayImage,
    ly: &GrayImage,
    u_px: f32,
    v_px: f32,
    s: f64,
) -> [[(f32, f32); WINDOW_SAMPLES]; WINDOW_SAMPLES] {
    let offset = |a: usize| -11.5 + a as f32;
    let (w, h) = (lx.width as isize, lx.height as isize);
    let mut cols = [(0.0f64, 0isize, 0.0f32); WINDOW_SAMPLES];
    for (a, c) in cols.iter_mut().enumerate() {
        let su = u_px as f64 + offset(a) as f64 * s;
        let x = su - 0.5;
        let x0f = x.floor();
        *c = (su, x0f as isize, (x - x0f) as f32);
    }
    let mut out = [[(0.0f32, 0.0f32); WINDOW_SAMPLES]; WINDOW_SAMPLES];
    for (b, out_row) in out.iter_mut().enumerate() {
        let sv = v_px as f64 + offset(b) as f64 * s;
        let y = sv - 0.5;
        let y0f = y.floor();
        let (y0, fy) = (y0f as isize, (y - y0f) as f32);
        let row_inside = sv.is_finite() && y0 >= 0 && y0 + 1 < h;
        for (o, &(su, x0, fx)) in out_row.iter_mut().zip(&cols) {
            *o = if row_inside && su.is_finite() && x0 >= 0 && x0 + 1 < w {
                let i = y0 as usize * lx.width + x0 as usize;
                (
                    bilinear_at(&lx.data, i, lx.width, fx, fy),
                    bilinear_at(&ly.data, i, lx.width, fx, fy),
                )
            } else {
                (
                    sample_bilinear(lx, su, sv, Border::Clamp),
                    sample_bilinear(ly, su, sv, Border::Clamp),
                )
            };
        }
    }
    out
}

/// [`sample_bilinear`]'s interior formula with the top-left pixel at flat index `i`.
#[inline(always)]
fn bilinear_at(data: &[f32], i: usize, width: usize, fx: f32, fy: f32) -> f32 {
    let (p00, p10, p01, p11) = (data[i], data[i + 1], data[i + width], data[i + width + 1]);
    let top = p00 + (p10 - p00) * fx;
    let bottom = p01 + (p11 - p01) * fx;
    top + (bottom - top) * fy
}

/// Write the descriptor of the keypoint (u_px, v_px, sigma_px, angle_rad) on `level` into `out`
/// (length 64, or 128 if `extended`). `out` must have that length.
///
/// Upright keypoints (angle 0) sample the 24 × 24 distinct window positions once (neighbouring sub-regions
/// share samples) and give exactly the values of the general rotated path with θ = 0.
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
    let inv_two_var2 = 1.0 / (2.0 * SIGMA2_CELLS * SIGMA2_CELLS);
    let weights = sample_weights();
    let upright = angle_rad == 0.0;
    let window = upright.then(|| upright_window(&level.lx, &level.ly, u_px, v_px, s));
    let mut sum_sq = 0.0f64;
    for cy in 0..GRID {
        for cx in 0..GRID {
            // Sub-region centre in keypoint-frame units of s, and its index offset from the grid centre.
            let centre_x = -7.5 + 5.0 * cx as f32;
            let centre_y = -7.5 + 5.0 * cy as f32;
            let mut acc = [0.0f32; 8];
            if let Some(window) = &window {
                // θ = 0: rx = weight·Lx, ry = weight·Ly (the rotation by cos 0 = 1, sin 0 = 0 is exact).
                for (jw, wrow) in weights.chunks_exact(SAMPLES_PER_SIDE as usize).enumerate() {
                    let row = &window[5 * cy + jw][5 * cx..5 * cx + SAMPLES_PER_SIDE as usize];
                    for (&weight, &(gx, gy)) in wrow.iter().zip(row) {
                        accumulate(&mut acc, weight * gx, weight * gy, extended);
                    }
                }
            } else {
                for j in -HALF..=HALF {
                    for i in -HALF..=HALF {
                        let ox = centre_x + i as f32;
                        let oy = centre_y + j as f32;
                        let weight = weights[((j + HALF) * SAMPLES_PER_SIDE + i + HALF) as usize];
                        let su = u_px as f64 + (ox as f64 * co - oy as f64 * si) * s;
                        let sv = v_px as f64 + (ox as f64 * si + oy as f64 * co) * s;
                        let gx = sample_bilinear(&level.lx, su, sv, Border::Clamp);
                        let gy = sample_bilinear(&level.ly, su, sv, Border::Clamp);
                        // Into the keypoint frame (x' along θ, y' along θ + π/2).
                        let rx = weight * (gx * co as f32 + gy * si as f32);
                        let ry = weight * (-gx * si as f32 + gy * co as f32);
                        accumulate(&mut acc, rx, ry, extended);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The per-sample form (every sub-region sample bilinear-sampled on its own, weights by `exp`).
    fn reference(level: &Level, u_px: f32, v_px: f32, sigma_px: f32, extended: bool) -> Vec<f32> {
        let per_cell = if extended { 8 } else { 4 };
        let mut out = vec![0.0f32; GRID * GRID * per_cell];
        let s = sigma_px.round().max(1.0) as f64;
        let inv_two_var1 = 1.0 / (2.0 * SIGMA1_STEPS * SIGMA1_STEPS);
        let inv_two_var2 = 1.0 / (2.0 * SIGMA2_CELLS * SIGMA2_CELLS);
        let mut sum_sq = 0.0f64;
        for cy in 0..GRID {
            for cx in 0..GRID {
                let centre_x = -7.5 + 5.0 * cx as f32;
                let centre_y = -7.5 + 5.0 * cy as f32;
                let mut acc = [0.0f32; 8];
                for j in -HALF..=HALF {
                    for i in -HALF..=HALF {
                        let weight = (-((i * i + j * j) as f32) * inv_two_var1).exp();
                        let su = u_px as f64 + (centre_x + i as f32) as f64 * s;
                        let sv = v_px as f64 + (centre_y + j as f32) as f64 * s;
                        let gx = sample_bilinear(&level.lx, su, sv, Border::Clamp);
                        let gy = sample_bilinear(&level.ly, su, sv, Border::Clamp);
                        let (rx, ry) = (weight * gx, weight * gy);
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
                let (gx2, gy2) = (cx as f32 - 1.5, cy as f32 - 1.5);
                let weight2 = (-(gx2 * gx2 + gy2 * gy2) * inv_two_var2).exp();
                for k in 0..per_cell {
                    let v = acc[k] * weight2;
                    out[(cy * GRID + cx) * per_cell + k] = v;
                    sum_sq += (v as f64) * (v as f64);
                }
            }
        }
        let inv = (1.0 / sum_sq.sqrt()) as f32;
        out.iter_mut().for_each(|v| *v *= inv);
        out
    }

    #[test]
    fn upright_window_path_equals_per_sample_sampling_inside_and_at_the_border() {
        let (w, h) = (80, 70);
        let field = |seed: f32| {
            let data = (0..w * h)
                .map(|k| {
                    ((k % w) as f32 * 0.37 + seed).sin() * ((k / w) as f32 * 0.23 - seed).cos()
                })
                .collect();
            GrayImage::from_vec(w, h, data).unwrap()
        };
        let level = Level {
            octave: 0,
            sublevel: 0,
            sigma_px: 2.0,
            step_px: 2,
            lx: field(0.3),
            ly: field(1.7),
            det: GrayImage::filled(w, h, 0.0),
        };
        for &(u, v, sigma) in &[
            (40.3f32, 35.8f32, 1.6f32),
            (40.71, 33.2, 2.4),
            (3.2, 5.9, 1.9),
            (77.5, 66.1, 3.1),
            (12.0, 60.25, 1.0),
        ] {
            for extended in [false, true] {
                let mut out = vec![0.0f32; if extended { 128 } else { 64 }];
                describe(&level, u, v, sigma, 0.0, extended, &mut out);
                let r = reference(&level, u, v, sigma, extended);
                assert!(
                    out.iter().zip(&r).all(|(a, b)| a == b),
                    "({u}, {v}, {sigma}, {extended})"
                );
            }
        }
    }
}
