//! An image into the FFT canvas: the separable window (Hann or Blackman, its tables kept per taper slot),
//! the window-weighted mean removed, the canvas energy summed on independent lanes so that it vectorises.

use super::real_fft_2d::{Real, RealFft2d};
use super::Taper;
use crate::imaging::window::{window_value, WindowKind};
use crate::imaging::GrayImage;
use rustfft::num_complex::Complex;

/// Window tables of one taper slot (x and y) and two scratch rows for [`load`].
#[derive(Default)]
pub(super) struct TaperTables {
    x: WindowTable,
    y: WindowTable,
    row_a: Vec<f64>,
    row_b: Vec<f64>,
}

impl TaperTables {
    pub(super) fn new(width: usize) -> Self {
        Self {
            row_a: vec![0.0; width],
            row_b: vec![0.0; width],
            ..Self::default()
        }
    }
}

/// Writes the windowed copy of `img` with the window-weighted mean removed at (x0, y0) into the FFT canvas
/// (everything else 0); returns the canvas energy Σ v² (= the mean squared bin magnitude of its spectrum).
#[inline(always)]
pub(super) fn load(
    fft: &mut RealFft2d,
    tables: &mut TaperTables,
    img: &GrayImage,
    taper: Taper,
    x0: usize,
    y0: usize,
) -> Real {
    tables
        .x
        .fill(img.width, taper.kind, taper.size.0, taper.origin.0);
    tables
        .y
        .fill(img.height, taper.kind, taper.size.1, taper.origin.1);
    let (wx, wy) = (&tables.x.values, &tables.y.values);
    let sum_w = tables.x.sum * tables.y.sum;
    let mut sum_wg = 0.0f64;
    for (row, &ky) in wy.iter().enumerate() {
        if ky != 0.0 {
            sum_wg += ky * weighted_sum(img.row(row), wx);
        }
    }
    let mean = if sum_w > 0.0 { sum_wg / sum_w } else { 0.0 };
    let (w, h) = (img.width, img.height);
    let covers_rows = x0 == 0 && w == fft.width();
    // Image row `y` of the canvas row `cy` with its weight (weight 0 if outside: the value is then 0).
    let image_row = |cy: usize| {
        if cy >= y0 && cy - y0 < h && wy[cy - y0] != 0.0 {
            Some((img.row(cy - y0), wy[cy - y0]))
        } else {
            None
        }
    };
    let mut energy = 0.0;
    for pair in 0..fft.height().div_ceil(2) {
        let (a, b) = (image_row(2 * pair), image_row(2 * pair + 1));
        let dst = fft.input_pair_mut(pair);
        if a.is_none() && b.is_none() {
            dst.fill(Complex::new(0.0, 0.0));
            continue;
        }
        if !covers_rows {
            dst.fill(Complex::new(0.0, 0.0));
        }
        // Each row into its own real scratch row (plain loops that vectorise), then interleaved.
        let (ta, tb) = (&mut tables.row_a[..w], &mut tables.row_b[..w]);
        for (t, row) in [(&mut *ta, a), (&mut *tb, b)] {
            match row {
                Some((g, ky)) => {
                    for ((v, &g), &kx) in t.iter_mut().zip(g).zip(wx) {
                        *v = (g as f64 - mean) * (kx * ky);
                    }
                    energy += sum_of_squares(t);
                }
                None => t.fill(0.0),
            }
        }
        for ((c, &re), &im) in dst[x0..x0 + w].iter_mut().zip(&*ta).zip(&*tb) {
            *c = Complex::new(re, im);
        }
    }
    energy
}

/// Partial sums of [`sum_of_squares`] and [`weighted_sum`]: 16 independent lanes, so that the additions do not
/// wait on each other (four AVX / eight SSE2 registers); the lanes are added pairwise at the end.
pub(super) const LANES: usize = 16;

#[inline(always)]
pub(super) fn reduce_lanes(mut acc: [f64; LANES]) -> f64 {
    let mut n = LANES;
    while n > 1 {
        n /= 2;
        for i in 0..n {
            acc[i] += acc[i + n];
        }
    }
    acc[0]
}

/// Σ v² with [`LANES`] partial sums (vectorises).
#[inline(always)]
pub(super) fn sum_of_squares(v: &[f64]) -> f64 {
    let chunks = v.chunks_exact(LANES);
    let tail: f64 = chunks.remainder().iter().map(|x| x * x).sum();
    let mut acc = [0.0f64; LANES];
    for c in chunks {
        for i in 0..LANES {
            acc[i] += c[i] * c[i];
        }
    }
    reduce_lanes(acc) + tail
}

/// Σ g·w in f64 with [`LANES`] partial sums (vectorises).
#[inline(always)]
pub(super) fn weighted_sum(g: &[f32], w: &[f64]) -> f64 {
    let (gc, wc) = (g.chunks_exact(LANES), w.chunks_exact(LANES));
    let tail: f64 = gc
        .remainder()
        .iter()
        .zip(wc.remainder())
        .map(|(&a, &b)| a as f64 * b)
        .sum();
    let mut acc = [0.0f64; LANES];
    for (a, b) in gc.zip(wc) {
        for i in 0..LANES {
            acc[i] += a[i] as f64 * b[i];
        }
    }
    reduce_lanes(acc) + tail
}

/// A 1-D window table `values[c] = window(c − origin)`, `c ∈ [0, n)` (0 outside the window), remembering what it
/// was filled for so that an unchanged taper costs nothing. A shifted Hann/Blackman costs one `sin_cos` per
/// harmonic: `cos(θ(c − o)) = cos θc·cos θo + sin θc·sin θo` with cos θc, sin θc tabulated per (n, size).
#[derive(Default)]
pub(super) struct WindowTable {
    values: Vec<f64>,
    sum: f64,
    key: Option<(usize, WindowKind, usize, u64)>,
    /// `[cos θc, sin θc, cos 2θc, sin 2θc]`, θ = 2π/(size − 1), for `trig_key` = (n, size).
    trig: Vec<[f64; 4]>,
    trig_key: Option<(usize, usize)>,
}

impl WindowTable {
    pub(super) fn fill(&mut self, n: usize, kind: WindowKind, size: usize, origin: f64) {
        let key = Some((n, kind, size, origin.to_bits()));
        if self.key == key {
            return;
        }
        self.values.clear();
        if size < 2 || kind == WindowKind::Rectangular {
            self.values
                .extend((0..n).map(|c| window_value(kind, size, c as f64 - origin)));
        } else {
            let theta = 2.0 * std::f64::consts::PI / (size - 1) as f64;
            if self.trig_key != Some((n, size)) {
                self.trig.clear();
                self.trig.extend((0..n).map(|c| {
                    let (s1, c1) = (theta * c as f64).sin_cos();
                    let (s2, c2) = (2.0 * theta * c as f64).sin_cos();
                    [c1, s1, c2, s2]
                }));
                self.trig_key = Some((n, size));
            }
            let (so1, co1) = (theta * origin).sin_cos();
            let (so2, co2) = (2.0 * theta * origin).sin_cos();
            let last = (size - 1) as f64;
            self.values
                .extend(self.trig.iter().enumerate().map(|(c, t)| {
                    let u = c as f64 - origin;
                    if !(u >= 0.0 && u <= last) {
                        return 0.0;
                    }
                    let cos1 = t[0] * co1 + t[1] * so1;
                    match kind {
                        WindowKind::Hann => 0.5 * (1.0 - cos1),
                        _ => (0.42 - 0.5 * cos1 + 0.08 * (t[2] * co2 + t[3] * so2)).max(0.0),
                    }
                }));
        }
        self.sum = self.values.iter().sum();
        self.key = key;
    }
}
