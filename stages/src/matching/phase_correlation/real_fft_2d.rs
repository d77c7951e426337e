//! 2-D FFT of a real `pw × ph` image through its half spectrum, with the rustfft plans and every buffer
//! allocated once (phase correlation runs thousands of times per nadir stage; thesis 3.4.5.3).
//!
//! Forward: rows are transformed two at a time (row 2r in the real part, row 2r + 1 in the imaginary part of
//! one complex FFT; the two real spectra are separated by Hermitian symmetry), only the `pw/2 + 1`
//! non-redundant column frequencies are kept, then each of those columns is transformed. The half spectrum is
//! stored TRANSPOSED: `spec[kx·ph + ky]`, `kx ∈ [0, pw/2]`, `ky ∈ [0, ph)`. The inverse undoes this for a
//! Hermitian spectrum (that of a real image), packing two output rows into one complex inverse FFT again.
//! Work is about half of a complex 2-D FFT; no allocation after [`RealFft2d::new`].

use std::sync::Arc;

use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};

/// Floating-point type of the spectra. f64: with f32 (tried) the rounding moved the log-quadratic peak by ~2e-5 px
/// between radiometrically equivalent inputs, and the FFTs are not the dominant cost at 32²–128².
pub(crate) type Real = f64;
pub(crate) type Cplx = Complex<Real>;

const ZERO: Cplx = Complex::new(0.0, 0.0);

/// Row pairs handled together when converting between the packed rows and the transposed half spectrum.
const PAIR_BLOCK: usize = 4;

pub(crate) struct RealFft2d {
    pw: usize,
    ph: usize,
    row_forward: Arc<dyn Fft<Real>>,
    row_inverse: Arc<dyn Fft<Real>>,
    col_forward: Arc<dyn Fft<Real>>,
    col_inverse: Arc<dyn Fft<Real>>,
    /// Row pairs packed as complex rows: `ceil(ph/2)` rows of `pw` values.
    packed: Vec<Cplx>,
    scratch: Vec<Cplx>,
}

impl RealFft2d {
    /// Plans for a `pw × ph` real image (both ≥ 1).
    pub(crate) fn new(pw: usize, ph: usize, planner: &mut FftPlanner<Real>) -> Self {
        let row_forward = planner.plan_fft_forward(pw);
        let row_inverse = planner.plan_fft_inverse(pw);
        let col_forward = planner.plan_fft_forward(ph);
        let col_inverse = planner.plan_fft_inverse(ph);
        let scratch_len = [&row_forward, &row_inverse, &col_forward, &col_inverse]
            .iter()
            .map(|f| f.get_inplace_scratch_len())
            .max()
            .unwrap_or(0);
        Self {
            pw,
            ph,
            row_forward,
            row_inverse,
            col_forward,
            col_inverse,
            packed: vec![ZERO; ph.div_ceil(2) * pw],
            scratch: vec![ZERO; scratch_len],
        }
    }

    /// Canvas width `pw`.
    pub(crate) fn width(&self) -> usize {
        self.pw
    }

    /// Canvas height `ph`.
    pub(crate) fn height(&self) -> usize {
        self.ph
    }

    /// Number of stored column frequencies, `pw/2 + 1`.
    pub(crate) fn half_width(&self) -> usize {
        self.pw / 2 + 1
    }

    /// Length of a half spectrum, `(pw/2 + 1)·ph`.
    pub(crate) fn spectrum_len(&self) -> usize {
        self.half_width() * self.ph
    }

    /// Zeroes the input canvas (see [`Self::set_row`]).
    #[cfg(test)]
    pub(crate) fn clear_input(&mut self) {
        self.packed.fill(ZERO);
    }

    /// Writes `values` into row `y` of the real input canvas starting at column `x0` (`x0 + len ≤ pw`).
    /// Values yielded beyond the row's end are ignored.
    #[cfg(test)]
    pub(crate) fn set_row(&mut self, y: usize, x0: usize, values: impl Iterator<Item = Real>) {
        let start = (y / 2) * self.pw + x0;
        let row = &mut self.packed[start..(y / 2 + 1) * self.pw];
        if y.is_multiple_of(2) {
            row.iter_mut().zip(values).for_each(|(c, v)| c.re = v);
        } else {
            row.iter_mut().zip(values).for_each(|(c, v)| c.im = v);
        }
    }

    /// Row pair `pair` of the real input canvas as one complex row of `pw` values: row `2·pair` in the real
    /// parts, row `2·pair + 1` (if `< ph`; else keep it 0) in the imaginary parts. Every pair must be written
    /// (or the canvas cleared) before [`Self::forward`].
    pub(crate) fn input_pair_mut(&mut self, pair: usize) -> &mut [Cplx] {
        &mut self.packed[pair * self.pw..(pair + 1) * self.pw]
    }

    /// Half spectrum (transposed layout, see the module doc) of the canvas written with [`Self::set_row`].
    /// The canvas is consumed (left undefined).
    #[inline(always)]
    pub(crate) fn forward(&mut self, spec: &mut [Cplx]) {
        let (pw, ph, hw) = (self.pw, self.ph, self.half_width());
        debug_assert_eq!(spec.len(), hw * ph);
        self.row_forward
            .process_with_scratch(&mut self.packed, &mut self.scratch);
        // Blocks of PAIR_BLOCK row pairs, so that each column of the transposed output is written in runs of
        // 2·PAIR_BLOCK consecutive values instead of one scattered store per row.
        for (block, rows) in self.packed.chunks(PAIR_BLOCK * pw).enumerate() {
            let y_start = 2 * PAIR_BLOCK * block;
            for kx in 0..hw {
                let column = &mut spec[kx * ph..(kx + 1) * ph];
                for (p, z) in rows.chunks_exact(pw).enumerate() {
                    let (y0, y1) = (y_start + 2 * p, y_start + 2 * p + 1);
                    let a = z[kx];
                    let b = z[(pw - kx) % pw].conj();
                    // Spectrum of the real part: (Z[k] + conj Z[−k])/2; of the imaginary part: (Z[k] − conj Z[−k])/2i.
                    column[y0] = (a + b) * 0.5;
                    if y1 < ph {
                        let d = a - b;
                        column[y1] = Complex::new(d.im * 0.5, -d.re * 0.5);
                    }
                }
            }
        }
        self.col_forward
            .process_with_scratch(spec, &mut self.scratch);
    }

    /// Unnormalised inverse (no 1/(pw·ph)) of a Hermitian half spectrum; `spec` is consumed, the real
    /// `pw × ph` row-major result goes to `out`.
    #[inline(always)]
    pub(crate) fn inverse(&mut self, spec: &mut [Cplx], out: &mut [Real]) {
        let (pw, ph, hw) = (self.pw, self.ph, self.half_width());
        debug_assert_eq!(spec.len(), hw * ph);
        debug_assert_eq!(out.len(), pw * ph);
        self.col_inverse
            .process_with_scratch(spec, &mut self.scratch);
        // Column-inverse rows y0, y1: A[k], B[k] for k < hw, conj(A[pw − k]) beyond; pack Z = A + iB. Blocks of
        // row pairs as in `forward`, so that each column is read in runs.
        for (block, rows) in self.packed.chunks_mut(PAIR_BLOCK * pw).enumerate() {
            let y_start = 2 * PAIR_BLOCK * block;
            for k in 0..pw {
                let (kk, mirrored) = if k < hw { (k, false) } else { (pw - k, true) };
                let column = &spec[kk * ph..(kk + 1) * ph];
                for (p, z) in rows.chunks_exact_mut(pw).enumerate() {
                    let (y0, y1) = (y_start + 2 * p, y_start + 2 * p + 1);
                    let mut a = column[y0];
                    let mut b = if y1 < ph { column[y1] } else { ZERO };
                    if mirrored {
                        a = a.conj();
                        b = b.conj();
                    }
                    z[k] = Complex::new(a.re - b.im, a.im + b.re);
                }
            }
        }
        self.row_inverse
            .process_with_scratch(&mut self.packed, &mut self.scratch);
        for (pair, z) in self.packed.chunks_exact(pw).enumerate() {
            let y0 = 2 * pair;
            for (o, c) in out[y0 * pw..(y0 + 1) * pw].iter_mut().zip(z) {
                *o = c.re;
            }
            if y0 + 1 < ph {
                for (o, c) in out[(y0 + 1) * pw..(y0 + 2) * pw].iter_mut().zip(z) {
                    *o = c.im;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Direct O(N²) DFT of a real image, full spectrum row-major `[ky·pw + kx]`.
    fn naive_dft(img: &[Real], pw: usize, ph: usize) -> Vec<Complex<f64>> {
        let mut out = vec![Complex::new(0.0, 0.0); pw * ph];
        for ky in 0..ph {
            for kx in 0..pw {
                let mut s = Complex::new(0.0, 0.0);
                for y in 0..ph {
                    for x in 0..pw {
                        let phase = -2.0
                            * std::f64::consts::PI
                            * ((kx * x) as f64 / pw as f64 + (ky * y) as f64 / ph as f64);
                        s += Complex::from_polar(img[y * pw + x], phase);
                    }
                }
                out[ky * pw + kx] = s;
            }
        }
        out
    }

    fn check_size(pw: usize, ph: usize) {
        let img: Vec<Real> = (0..pw * ph)
            .map(|k| ((k * 37 + 11) % 23) as Real - 7.5)
            .collect();
        let mut planner = FftPlanner::new();
        let mut f = RealFft2d::new(pw, ph, &mut planner);
        // Rounding of sums of up to pw·ph terms of magnitude ≤ 16 (the direct DFT's own rounding included).
        let tol = 1e4 * (pw * ph) as f64 * Real::EPSILON;
        f.clear_input();
        for y in 0..ph {
            f.set_row(y, 0, img[y * pw..(y + 1) * pw].iter().copied());
        }
        let mut spec = vec![ZERO; f.spectrum_len()];
        f.forward(&mut spec);
        let truth = naive_dft(&img, pw, ph);
        for kx in 0..f.half_width() {
            for ky in 0..ph {
                let got = spec[kx * ph + ky];
                let d = (Complex::new(got.re as f64, got.im as f64) - truth[ky * pw + kx]).norm();
                assert!(d < tol, "{pw}x{ph} bin ({kx},{ky}): {d}");
            }
        }
        let mut out = vec![0.0; pw * ph];
        f.inverse(&mut spec, &mut out);
        let n = (pw * ph) as Real;
        for (o, i) in out.iter().zip(&img) {
            assert!((o / n - i).abs() < tol, "{pw}x{ph}: {o} vs {i}");
        }
    }

    #[test]
    fn matches_direct_dft_and_round_trips_for_even_and_odd_sizes() {
        for (pw, ph) in [(8, 6), (6, 5), (5, 8), (9, 9), (1, 4), (4, 1), (12, 15)] {
            check_size(pw, ph);
        }
    }

    #[test]
    fn rows_written_with_offset_land_in_place() {
        let (pw, ph) = (8, 5);
        let mut planner = FftPlanner::new();
        let mut f = RealFft2d::new(pw, ph, &mut planner);
        f.clear_input();
        f.set_row(3, 2, [1.0, 2.0, 3.0].into_iter());
        let mut spec = vec![ZERO; f.spectrum_len()];
        f.forward(&mut spec);
        let mut out = vec![0.0; pw * ph];
        f.inverse(&mut spec, &mut out);
        for (k, v) in out.iter().enumerate() {
            let expected = match k {
                26 => 1.0,
                27 => 2.0,
                28 => 3.0,
                _ => 0.0,
            };
            assert!((v / 40.0 - expected).abs() < 1e-5, "index {k}: {v}");
        }
    }
}
