//! The correlation peak: the integer maximum of the surface, the sub-pixel vertex fitted to its 3 × 3
//! neighbourhood, and the direct evaluation of the surface at those 3 × 3 pixels that the refinement passes use
//! instead of a full inverse FFT.

use super::real_fft_2d::{Cplx, Real};
use super::PhaseShift;
use crate::matching::subpixel::{refine_peak, PeakFit};
use rustfft::num_complex::Complex;

/// Direct evaluation of the (unnormalised, real) inverse DFT of a Hermitian half spectrum at 3 × 3 pixels:
/// `r(x, y) = Σ_kx c_kx·Re(e^{2πi·kx·x/pw}·Σ_ky S[kx, ky]·e^{2πi·ky·y/ph})`, c = 1 for the columns without a
/// mirror (kx = 0, pw/2), else 2. Costs three complex multiply-adds per bin, against a full inverse FFT, its
/// unpacking and a scan of the whole surface (the matrix-multiply DFT of Guizar-Sicairos et al. 2008 at
/// upsampling 1).
pub(super) struct LocalSurface {
    pw: usize,
    ph: usize,
    /// `e^{2πi·j/pw}`, `e^{2πi·j/ph}`.
    twiddle_x: Vec<Cplx>,
    twiddle_y: Vec<Cplx>,
    /// `e^{2πi·ky·y/ph}` for the three rows y of the current evaluation.
    rows: [Vec<Cplx>; 3],
    /// Column sums per kx for the three rows.
    columns: Vec<[Cplx; 3]>,
}

impl LocalSurface {
    pub(super) fn new(pw: usize, ph: usize, hw: usize) -> Self {
        let twiddles = |n: usize| -> Vec<Cplx> {
            (0..n)
                .map(|j| {
                    let (s, c) = (2.0 * std::f64::consts::PI * j as f64 / n as f64).sin_cos();
                    Complex::new(c as Real, s as Real)
                })
                .collect()
        };
        let zero = Complex::new(0.0, 0.0);
        Self {
            pw,
            ph,
            twiddle_x: twiddles(pw),
            twiddle_y: twiddles(ph),
            rows: std::array::from_fn(|_| vec![zero; ph]),
            columns: vec![[zero; 3]; hw],
        }
    }

    /// `n[j][i]` = surface at ((cx + i − 1) mod pw, (cy + j − 1) mod ph) of the half spectrum `spec`
    /// (transposed layout, see `real_fft_2d`).
    #[inline(always)]
    pub(super) fn surface_3x3(&mut self, spec: &[Cplx], cx: usize, cy: usize) -> [[f64; 3]; 3] {
        let (pw, ph) = (self.pw, self.ph);
        for (j, row) in self.rows.iter_mut().enumerate() {
            let y = (cy + ph + j - 1) % ph;
            for (ky, e) in row.iter_mut().enumerate() {
                *e = self.twiddle_y[(ky * y) % ph];
            }
        }
        let [r0, r1, r2] = &self.rows;
        for (column, sums) in spec.chunks_exact(ph).zip(self.columns.iter_mut()) {
            let zero = Complex::new(0.0, 0.0);
            let mut acc = [zero; 3];
            for (((&s, &e0), &e1), &e2) in column.iter().zip(r0).zip(r1).zip(r2) {
                acc[0] += s * e0;
                acc[1] += s * e1;
                acc[2] += s * e2;
            }
            *sums = acc;
        }
        let mut n = [[0.0f64; 3]; 3];
        for i in 0..3 {
            let x = (cx + pw + i - 1) % pw;
            for (kx, sums) in self.columns.iter().enumerate() {
                let e = self.twiddle_x[(kx * x) % pw];
                let mirrored = if kx == 0 || 2 * kx == pw { 1.0 } else { 2.0 };
                for (j, s) in sums.iter().enumerate() {
                    n[j][i] += mirrored * (s.re * e.re - s.im * e.im);
                }
            }
        }
        n
    }
}

/// Index of the first maximum in raster order (the maximum found with four partial maxima, which vectorises).
#[inline(always)]
pub(super) fn first_max_index(r: &[Real]) -> usize {
    let chunks = r.chunks_exact(4);
    let mut top = chunks
        .remainder()
        .iter()
        .fold(Real::NEG_INFINITY, |m, &v| if v > m { v } else { m });
    let mut lanes = [Real::NEG_INFINITY; 4];
    for c in chunks {
        for i in 0..4 {
            lanes[i] = if c[i] > lanes[i] { c[i] } else { lanes[i] };
        }
    }
    for v in lanes {
        top = if v > top { v } else { top };
    }
    r.iter().position(|&v| v == top).unwrap_or(0)
}

/// Integer peak (first maximum in raster order) and its sub-pixel refinement, wrapped to `[−N/2, N/2)`.
#[inline(always)]
pub(super) fn find_peak(r: &[Real], pw: usize, ph: usize, fit: PeakFit) -> PhaseShift {
    let best = first_max_index(r);
    let (px, py) = (best % pw, best / pw);
    let mut n = [[0.0f64; 3]; 3];
    for (j, row) in n.iter_mut().enumerate() {
        let y = (py + ph + j - 1) % ph;
        for (i, v) in row.iter_mut().enumerate() {
            let x = (px + pw + i - 1) % pw;
            *v = r[y * pw + x];
        }
    }
    peak_from_neighbourhood(&n, px, py, pw, ph, fit)
}

/// Sub-pixel peak from the 3 × 3 neighbourhood `n` of the integer peak (px, py), wrapped to `[−N/2, N/2)`.
#[inline(always)]
pub(super) fn peak_from_neighbourhood(
    n: &[[f64; 3]; 3],
    px: usize,
    py: usize,
    pw: usize,
    ph: usize,
    fit: PeakFit,
) -> PhaseShift {
    let (dx, dy) = refine_peak(n, fit);
    let wrap = |p: usize, n: usize| {
        if 2 * p >= n {
            p as f64 - n as f64
        } else {
            p as f64
        }
    };
    PhaseShift {
        dx_px: wrap(px, pw) + dx,
        dy_px: wrap(py, ph) + dy,
        peak: n[1][1],
    }
}
