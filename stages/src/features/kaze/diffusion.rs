//! Nonlinear diffusion of the KAZE scale space (Alcantarilla, Bartoli & Davison 2012; KAZE paper §3–4; thesis 3.4.4.2 uses it
//! through KAZE): conductance images, the AOS scheme with a Thomas tridiagonal solver, and Fast Explicit
//! Diffusion (FED) cycles.
//!
//! The operator is `div(g ∇L)` discretised as `Σ_q ½(g_p + g_q)(L_q − L_p)` over the 4-neighbours with
//! Neumann (reflecting) ends: a neighbour outside the image contributes nothing. Both schemes conserve the
//! image sum and keep a constant image constant.

use rayon::prelude::*;

use super::params::Diffusivity;
use crate::imaging::gradient::{scharr_gradient, Gradient};
use crate::imaging::GrayImage;

/// Conductance image g(|∇Lσ|²/k²) from an already smoothed level `smoothed` = Lσ = G(derivative σ) * L,
/// gradient by unit-gain Scharr (same operator as [`super::contrast::contrast_factor`], so k is consistent).
pub fn conductance(smoothed: &GrayImage, k: f32, diffusivity: Diffusivity) -> GrayImage {
    conductance_from_gradient(&scharr_gradient(smoothed), k, diffusivity)
}

/// [`conductance`] from the unit-gain Scharr gradient of Lσ.
pub fn conductance_from_gradient(grad: &Gradient, k: f32, diffusivity: Diffusivity) -> GrayImage {
    let inv_k2 = 1.0 / (k * k);
    super::filters::map_gradient(grad, |m2| conductance_value(m2 * inv_k2, diffusivity))
}

/// g(m) for m = |∇Lσ|²/k² ≥ 0.
#[inline]
pub fn conductance_value(m: f32, diffusivity: Diffusivity) -> f32 {
    match diffusivity {
        Diffusivity::PmG1 => (-m).exp(),
        Diffusivity::PmG2 => 1.0 / (1.0 + m),
        Diffusivity::Weickert => {
            if m <= 0.0 {
                1.0
            } else {
                let m4 = m * m * m * m;
                1.0 - (-3.315 / m4).exp()
            }
        }
        Diffusivity::Charbonnier => 1.0 / (1.0 + m).sqrt(),
    }
}

/// Solve the symmetric tridiagonal system with diagonal `diag` (n), off-diagonal `off` (n − 1, both
/// super- and sub-diagonal) and right-hand side `rhs` (n) by the Thomas algorithm; the solution goes to `x`.
/// `scratch` (n) holds the eliminated pivots. Stable for strictly diagonally dominant systems (AOS's are).
/// Panics only on inconsistent slice lengths (a programming error).
pub fn thomas_solve(diag: &[f64], off: &[f64], rhs: &[f64], x: &mut [f64], scratch: &mut [f64]) {
    let n = diag.len();
    assert!(
        rhs.len() == n && x.len() == n && scratch.len() >= n && off.len() + 1 >= n,
        "thomas_solve: inconsistent slice lengths"
    );
    if n == 0 {
        return;
    }
    let m = scratch;
    m[0] = diag[0];
    x[0] = rhs[0];
    for k in 1..n {
        let l = off[k - 1] / m[k - 1];
        m[k] = diag[k] - l * off[k - 1];
        x[k] = rhs[k] - l * x[k - 1];
    }
    x[n - 1] /= m[n - 1];
    for k in (0..n - 1).rev() {
        x[k] = (x[k] - off[k] * x[k + 1]) / m[k];
    }
}

/// Per-line scratch buffers of the AOS solver (allocated once per thread, reused for every line).
struct LineScratch {
    diag: Vec<f64>,
    off: Vec<f64>,
    rhs: Vec<f64>,
    x: Vec<f64>,
    pivots: Vec<f64>,
}

impl LineScratch {
    fn new(n: usize) -> Self {
        Self {
            diag: vec![0.0; n],
            off: vec![0.0; n.saturating_sub(1)],
            rhs: vec![0.0; n],
            x: vec![0.0; n],
            pivots: vec![0.0; n],
        }
    }
}

/// `(I − 2τ A_x)⁻¹ L` along every row of a `width × height` buffer (A_x: 1-D operator along the row with
/// coefficients ½(g_p + g_q), reflecting ends).
fn implicit_rows(l: &[f32], g: &[f32], width: usize, tau: f64) -> Vec<f32> {
    let mut out = vec![0.0f32; l.len()];
    out.par_chunks_mut(width).enumerate().for_each_init(
        || LineScratch::new(width),
        |s, (row, out_row)| {
            let lr = &l[row * width..(row + 1) * width];
            let gr = &g[row * width..(row + 1) * width];
            for p in 0..width {
                s.diag[p] = 1.0;
                s.rhs[p] = lr[p] as f64;
            }
            for p in 0..width.saturating_sub(1) {
                let c = tau * (gr[p] as f64 + gr[p + 1] as f64);
                s.off[p] = -c;
                s.diag[p] += c;
                s.diag[p + 1] += c;
            }
            thomas_solve(&s.diag, &s.off, &s.rhs, &mut s.x, &mut s.pivots);
            for (o, &v) in out_row.iter_mut().zip(&s.x) {
                *o = v as f32;
            }
        },
    );
    out
}

/// `(I − 2τ A_y)⁻¹ L` along every column of a `width × height` buffer: the same tridiagonal systems and the
/// same Thomas operations per column as [`implicit_rows`] on the transposed buffer ([`thomas_solve`]: diagonal
/// `(1 + c_{k−1}) + c_k`, off-diagonal `−c_k`, `c_k = τ(g_k + g_{k+1})`), but solved for a block of columns in
/// lockstep, row by row (contiguous, vectorisable, no transposes). Blocks run in parallel.
fn implicit_cols(l: &[f32], g: &[f32], width: usize, height: usize, tau: f64) -> Vec<f32> {
    const BLOCK: usize = 64;
    let blocks: Vec<(usize, Vec<f32>)> = (0..width.div_ceil(BLOCK))
        .into_par_iter()
        .map(|b| {
            let (c0, c1) = (b * BLOCK, ((b + 1) * BLOCK).min(width));
            let bw = c1 - c0;
            let coupling = |k: usize, i: usize| {
                tau * (g[k * width + c0 + i] as f64 + g[(k + 1) * width + c0 + i] as f64)
            };
            // Forward elimination: pivots m_k and eliminated right-hand sides x_k for every row k.
            let mut m = vec![0.0f64; height * bw];
            let mut x = vec![0.0f64; height * bw];
            for k in 0..height {
                for i in 0..bw {
                    let mut diag = 1.0f64;
                    if k > 0 {
                        diag += coupling(k - 1, i);
                    }
                    if k + 1 < height {
                        diag += coupling(k, i);
                    }
                    let rhs = l[k * width + c0 + i] as f64;
                    if k == 0 {
                        m[i] = diag;
                        x[i] = rhs;
                    } else {
                        let off = -coupling(k - 1, i);
                        let lk = off / m[(k - 1) * bw + i];
                        m[k * bw + i] = diag - lk * off;
                        x[k * bw + i] = rhs - lk * x[(k - 1) * bw + i];
                    }
                }
            }
            // Back substitution.
            for i in 0..bw {
                x[(height - 1) * bw + i] /= m[(height - 1) * bw + i];
            }
            for k in (0..height.saturating_sub(1)).rev() {
                for i in 0..bw {
                    let off = -coupling(k, i);
                    x[k * bw + i] = (x[k * bw + i] - off * x[(k + 1) * bw + i]) / m[k * bw + i];
                }
            }
            (c0, x.iter().map(|&v| v as f32).collect())
        })
        .collect();
    let mut out = vec![0.0f32; l.len()];
    for (c0, block) in blocks {
        let bw = block.len() / height.max(1);
        for (row, src) in block.chunks_exact(bw).enumerate() {
            out[row * width + c0..row * width + c0 + bw].copy_from_slice(src);
        }
    }
    out
}

/// One AOS step of time `tau`: L' = ½ Σ_{l∈{x,y}} (I − 2τ A_l(g))⁻¹ L (KAZE paper eq. 8). Unconditionally
/// stable; conserves the image sum.
pub fn aos_step(level: &GrayImage, g: &GrayImage, tau: f32) -> GrayImage {
    let (w, h) = (level.width, level.height);
    if w == 0 || h == 0 {
        return level.clone();
    }
    let tau = tau as f64;
    let along_x = implicit_rows(&level.data, &g.data, w, tau);
    let along_y = implicit_cols(&level.data, &g.data, w, h, tau);
    let data = along_x
        .iter()
        .zip(&along_y)
        .map(|(&a, &b)| 0.5 * (a + b))
        .collect();
    GrayImage {
        width: w,
        height: h,
        data,
    }
}

/// Largest stable explicit step for the 2-D 4-neighbour scheme with g ≤ 1.
pub const FED_TAU_MAX: f64 = 0.25;

/// Step sizes of one FED cycle whose sum is `total_time` (Grewenig, Weickert, Bruhn 2010; OpenCV
/// `fed_tau_by_process_time` with one cycle, τ_max = 0.25, κ-cycle reordering for numerical stability).
pub fn fed_step_sizes(total_time: f64) -> Vec<f64> {
    if !(total_time > 0.0 && total_time.is_finite()) {
        return Vec::new();
    }
    let n = ((3.0 * total_time / FED_TAU_MAX + 0.25).sqrt() - 0.5 - 1e-8)
        .ceil()
        .max(1.0) as usize;
    let scale = 3.0 * total_time / (FED_TAU_MAX * (n * (n + 1)) as f64);
    let c = 1.0 / (4 * n + 2) as f64;
    let d = scale * FED_TAU_MAX / 2.0;
    let taus: Vec<f64> = (0..n)
        .map(|k| {
            let h = (std::f64::consts::PI * (2 * k + 1) as f64 * c).cos();
            d / (h * h)
        })
        .collect();
    let kappa = n / 2;
    if kappa == 0 {
        return taus;
    }
    let mut prime = n + 1;
    while !is_prime(prime) {
        prime += 1;
    }
    let mut out = Vec::with_capacity(n);
    let mut k = 0usize;
    while out.len() < n {
        let index = ((k + 1) * kappa) % prime;
        k += 1;
        if index >= 1 && index - 1 < n {
            out.push(taus[index - 1]);
        }
    }
    out
}

fn is_prime(n: usize) -> bool {
    n >= 2
        && (2..)
            .take_while(|d| d * d <= n)
            .all(|d| !n.is_multiple_of(d))
}

/// One explicit step L ← L + τ · Σ_q ½(g_p + g_q)(L_q − L_p), written into `out`. Per pixel the flux sums
/// the left, right, upper and lower neighbour in that order, starting from 0 (neighbours outside the image
/// are left out); interior pixels run through a branch-free loop with the same order.
fn explicit_step(level: &[f32], g: &[f32], width: usize, height: usize, tau: f32, out: &mut [f32]) {
    let half_tau = tau * 0.5;
    out.par_chunks_mut(width)
        .enumerate()
        .for_each(|(row, out_row)| {
            let base = row * width;
            let pixel = |col: usize| {
                let p = base + col;
                let (lp, gp) = (level[p], g[p]);
                let mut flux = 0.0f32;
                if col > 0 {
                    flux += (gp + g[p - 1]) * (level[p - 1] - lp);
                }
                if col + 1 < width {
                    flux += (gp + g[p + 1]) * (level[p + 1] - lp);
                }
                if row > 0 {
                    flux += (gp + g[p - width]) * (level[p - width] - lp);
                }
                if row + 1 < height {
                    flux += (gp + g[p + width]) * (level[p + width] - lp);
                }
                lp + half_tau * flux
            };
            if row == 0 || row + 1 >= height || width < 3 {
                for (col, o) in out_row.iter_mut().enumerate() {
                    *o = pixel(col);
                }
                return;
            }
            out_row[0] = pixel(0);
            out_row[width - 1] = pixel(width - 1);
            let n = width - 2;
            let lc = &level[base..base + width];
            let gc = &g[base..base + width];
            let (lu, gu) = (&level[base - width + 1..][..n], &g[base - width + 1..][..n]);
            let (ld, gd) = (&level[base + width + 1..][..n], &g[base + width + 1..][..n]);
            let (ll, gl) = (&lc[..n], &gc[..n]);
            let (lm, gm) = (&lc[1..n + 1], &gc[1..n + 1]);
            let (lr, gr) = (&lc[2..n + 2], &gc[2..n + 2]);
            let o = &mut out_row[1..n + 1];
            for i in 0..n {
                let (lp, gp) = (lm[i], gm[i]);
                let flux = 0.0f32
                    + (gp + gl[i]) * (ll[i] - lp)
                    + (gp + gr[i]) * (lr[i] - lp)
                    + (gp + gu[i]) * (lu[i] - lp)
                    + (gp + gd[i]) * (ld[i] - lp);
                o[i] = lp + half_tau * flux;
            }
        });
}

/// Diffuse `level` for time `total_time` with one FED cycle ([`fed_step_sizes`]) and fixed conductance `g`.
pub fn fed_diffuse(level: &GrayImage, g: &GrayImage, total_time: f32) -> GrayImage {
    let (w, h) = (level.width, level.height);
    let mut cur = level.data.clone();
    let mut next = vec![0.0f32; cur.len()];
    if w > 0 && h > 0 {
        for tau in fed_step_sizes(total_time as f64) {
            explicit_step(&cur, &g.data, w, h, tau as f32, &mut next);
            std::mem::swap(&mut cur, &mut next);
        }
    }
    GrayImage {
        width: w,
        height: h,
        data: cur,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn transpose(data: &[f32], width: usize, height: usize) -> Vec<f32> {
        (0..width * height)
            .map(|k| data[(k % height) * width + k / height])
            .collect()
    }

    #[test]
    fn column_solve_equals_the_row_solve_of_the_transpose() {
        for (w, h) in [(70, 33), (1, 5), (5, 1), (130, 2)] {
            let l: Vec<f32> = (0..w * h).map(|k| ((k * 37 % 101) as f32) * 0.01).collect();
            let g: Vec<f32> = (0..w * h)
                .map(|k| 0.05 + ((k * 53 % 97) as f32) * 0.009)
                .collect();
            let cols = implicit_cols(&l, &g, w, h, 0.7);
            let rows_t = implicit_rows(&transpose(&l, w, h), &transpose(&g, w, h), h, 0.7);
            assert_eq!(cols, transpose(&rows_t, h, w), "{w}x{h}");
        }
    }
}
