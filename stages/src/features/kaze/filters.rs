//! Fast paths of the KAZE scale space's filters, each giving exactly the values of the general
//! `imaging::convolve` / `imaging::gradient` code it replaces (same taps, same summation order per pixel,
//! reflective border), only without the zero taps of the spaced Scharr kernels, without per-row allocation
//! and with the derivative images fused where they are only needed for the det(Hessian).
//!
//! The Scharr kernels with tap spacing s (`imaging::gradient::scharr_kernels`) have three non-zero taps at
//! offsets −s, 0, +s: derivative (−1, 0, +1)/(2s), smoothing (3, 10, 3)/16. `convolve_rows` / `convolve_cols`
//! sum `0 + k₀·p₀ + k₁·p₁ + …` over all 2s + 1 taps in order; a zero tap adds ±0, which leaves every sum
//! unchanged (up to the sign of an exact zero), so summing the non-zero taps in the same order is the same.

use rayon::prelude::*;

use crate::imaging::border::reflect_index;
use crate::imaging::gradient::Gradient;
use crate::imaging::GrayImage;

/// Taps of a Scharr-type kernel at offsets (−s, 0, +s); the middle tap is skipped when zero.
#[derive(Clone, Copy, Debug)]
pub struct Taps3 {
    pub step: usize,
    pub k: [f32; 3],
}

impl Taps3 {
    /// (derivative, smoothing) with tap spacing `step_px` (≥ 1), the values of `scharr_kernels`.
    pub fn scharr(step_px: usize) -> (Taps3, Taps3) {
        let s = step_px.max(1);
        let d = 1.0 / (2 * s) as f32;
        (
            Taps3 {
                step: s,
                k: [-d, 0.0, d],
            },
            Taps3 {
                step: s,
                k: [3.0 / 16.0, 10.0 / 16.0, 3.0 / 16.0],
            },
        )
    }

    #[inline(always)]
    fn apply(&self, l: f32, m: f32, r: f32) -> f32 {
        let a = 0.0 + self.k[0] * l;
        let a = if self.k[1] != 0.0 {
            a + self.k[1] * m
        } else {
            a
        };
        a + self.k[2] * r
    }
}

/// `convolve_rows` with a [`Taps3`] kernel on one row.
fn row_pass(src: &[f32], out: &mut [f32], t: Taps3) {
    let w = src.len();
    let s = t.step;
    let at = |c: isize| src[reflect_index(c, w)];
    let edge = |c: usize| at(c as isize - s as isize);
    let edge_pixel = |c: usize, out: &mut [f32]| {
        out[c] = t.apply(edge(c), src[c], at((c + s) as isize));
    };
    if w > 2 * s {
        let n = w - 2 * s;
        let (l, m, r) = (&src[..n], &src[s..s + n], &src[2 * s..2 * s + n]);
        taps3_line([l, m, r], &mut out[s..s + n], t);
        for c in (0..s).chain(w - s..w) {
            edge_pixel(c, out);
        }
    } else {
        for c in 0..w {
            edge_pixel(c, out);
        }
    }
}

/// `convolve_rows` with a [`Taps3`] kernel over a whole `width`-wide buffer.
fn rows(src: &[f32], out: &mut [f32], width: usize, t: Taps3) {
    out.par_chunks_mut(width)
        .zip(src.par_chunks(width))
        .for_each(|(o, s)| row_pass(s, o, t));
}

/// The three source rows (−s, 0, +s, reflected) of output row `row` of a column pass.
#[inline]
fn col_rows(src: &[f32], width: usize, height: usize, row: usize, s: usize) -> [&[f32]; 3] {
    let r = |k: isize| {
        let i = reflect_index(row as isize + k, height);
        &src[i * width..(i + 1) * width]
    };
    [r(-(s as isize)), r(0), r(s as isize)]
}

/// `out[i] = k0·l[i] + k1·m[i] + k2·r[i]` (the middle tap skipped when it is zero), the interior of both
/// passes.
#[inline(always)]
fn taps3_line(src: [&[f32]; 3], out: &mut [f32], t: Taps3) {
    let [l, m, r] = src;
    let n = out.len();
    let (l, m, r) = (&l[..n], &m[..n], &r[..n]);
    if t.k[1] != 0.0 {
        for i in 0..n {
            out[i] = 0.0 + t.k[0] * l[i] + t.k[1] * m[i] + t.k[2] * r[i];
        }
    } else {
        for i in 0..n {
            out[i] = 0.0 + t.k[0] * l[i] + t.k[2] * r[i];
        }
    }
}

/// `convolve_cols` with a [`Taps3`] kernel over a whole buffer.
fn cols(src: &[f32], out: &mut [f32], width: usize, height: usize, t: Taps3) {
    out.par_chunks_mut(width)
        .enumerate()
        .for_each(|(row, o)| taps3_line(col_rows(src, width, height, row, t.step), o, t));
}

/// `convolve_separable(img, kx, ky)` for [`Taps3`] kernels, using `tmp` (same size) for the row pass.
fn separable(
    src: &[f32],
    tmp: &mut [f32],
    out: &mut [f32],
    width: usize,
    height: usize,
    kx: Taps3,
    ky: Taps3,
) {
    rows(src, tmp, width, kx);
    cols(tmp, out, width, height, ky);
}

/// Reusable full-image buffers of the scale-space construction.
#[derive(Default)]
pub struct Scratch {
    a: Vec<f32>,
    b: Vec<f32>,
    c: Vec<f32>,
}

impl Scratch {
    fn ensure(&mut self, n: usize) {
        for v in [&mut self.a, &mut self.b, &mut self.c] {
            if v.len() != n {
                *v = vec![0.0; n];
            }
        }
    }
}

/// `imaging::gradient::scharr_gradient` (step 1), the same values.
pub fn scharr_gradient(img: &GrayImage, scratch: &mut Scratch) -> Gradient {
    let (w, h) = (img.width, img.height);
    if w == 0 || h == 0 {
        return crate::imaging::gradient::scharr_gradient(img);
    }
    scratch.ensure(w * h);
    let (deriv, smooth) = Taps3::scharr(1);
    let mut dx = vec![0.0f32; w * h];
    let mut dy = vec![0.0f32; w * h];
    separable(&img.data, &mut scratch.a, &mut dx, w, h, deriv, smooth);
    separable(&img.data, &mut scratch.a, &mut dy, w, h, smooth, deriv);
    Gradient {
        dx: GrayImage {
            width: w,
            height: h,
            data: dx,
        },
        dy: GrayImage {
            width: w,
            height: h,
            data: dy,
        },
    }
}

/// The derivative images of a level: Lx·s, Ly·s and (Lxx·Lyy − Lxy²)·s⁴, where Lx, Ly, Lxx, Lxy, Lyy are the
/// `convolve_separable` results with `scharr_kernels(step_px)` exactly as `scale_space` defines them
/// (Lxx, Lxy from Lx; Lyy from Ly). Returns (lx, ly, det).
pub fn level_derivatives(
    smoothed: &GrayImage,
    step_px: usize,
    scratch: &mut Scratch,
) -> (GrayImage, GrayImage, GrayImage) {
    let (w, h) = (smoothed.width, smoothed.height);
    let n = w * h;
    let image = |data| GrayImage {
        width: w,
        height: h,
        data,
    };
    if n == 0 {
        return (image(Vec::new()), image(Vec::new()), image(Vec::new()));
    }
    scratch.ensure(n);
    let (deriv, smooth) = Taps3::scharr(step_px);
    let mut lx = vec![0.0f32; n];
    let mut ly = vec![0.0f32; n];
    let mut det = vec![0.0f32; n];
    separable(&smoothed.data, &mut scratch.a, &mut lx, w, h, deriv, smooth);
    separable(&smoothed.data, &mut scratch.a, &mut ly, w, h, smooth, deriv);
    // Row passes of Lxx (deriv on Lx), Lxy (smooth on Lx) and Lyy (smooth on Ly); their column passes are
    // fused into the det(Hessian) row by row.
    rows(&lx, &mut scratch.a, w, deriv);
    rows(&lx, &mut scratch.b, w, smooth);
    rows(&ly, &mut scratch.c, w, smooth);
    let s = step_px as f32;
    let s4 = s * s * s * s;
    let (ta, tb, tc) = (&scratch.a, &scratch.b, &scratch.c);
    det.par_chunks_mut(w).enumerate().for_each_init(
        || (vec![0.0f32; w], vec![0.0f32; w], vec![0.0f32; w]),
        |(xx, xy, yy), (row, out)| {
            taps3_line(col_rows(ta, w, h, row, smooth.step), xx, smooth);
            taps3_line(col_rows(tb, w, h, row, deriv.step), xy, deriv);
            taps3_line(col_rows(tc, w, h, row, deriv.step), yy, deriv);
            for (((o, &xx), &yy), &xy) in out.iter_mut().zip(&*xx).zip(&*yy).zip(&*xy) {
                *o = (xx * yy - xy * xy) * s4;
            }
        },
    );
    lx.par_iter_mut().for_each(|v| *v *= s);
    ly.par_iter_mut().for_each(|v| *v *= s);
    (image(lx), image(ly), image(det))
}

/// Squared-gradient conductance map helper: `f(dx² + dy²)` per pixel of a gradient.
pub fn map_gradient(g: &Gradient, f: impl Fn(f32) -> f32 + Sync) -> GrayImage {
    let mut data = vec![0.0f32; g.dx.data.len()];
    data.par_iter_mut()
        .zip(g.dx.data.par_iter().zip(&g.dy.data))
        .for_each(|(o, (&dx, &dy))| *o = f(dx * dx + dy * dy));
    GrayImage {
        width: g.dx.width,
        height: g.dx.height,
        data,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imaging::convolve::convolve_separable;
    use crate::imaging::gradient::scharr_kernels;

    fn image(w: usize, h: usize, seed: u64) -> GrayImage {
        let data = crate::rng::mmix_states(seed)
            .take(w * h)
            .map(|state| (state >> 40) as f32 / (1u64 << 24) as f32)
            .collect();
        GrayImage::from_vec(w, h, data).unwrap()
    }

    fn same(a: &[f32], b: &[f32]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x == y)
    }

    #[test]
    fn derivatives_equal_the_general_separable_convolution() {
        for (w, h) in [(37, 23), (5, 9), (2, 3), (64, 1)] {
            let img = image(w, h, (w * h) as u64);
            let mut scratch = Scratch::default();
            for step in 1..=4 {
                let (deriv, smooth) = scharr_kernels(step);
                let lx = convolve_separable(&img, &deriv, &smooth);
                let ly = convolve_separable(&img, &smooth, &deriv);
                let lxx = convolve_separable(&lx, &deriv, &smooth);
                let lxy = convolve_separable(&lx, &smooth, &deriv);
                let lyy = convolve_separable(&ly, &smooth, &deriv);
                let s = step as f32;
                let s4 = s * s * s * s;
                let det: Vec<f32> = (0..w * h)
                    .map(|i| (lxx.data[i] * lyy.data[i] - lxy.data[i] * lxy.data[i]) * s4)
                    .collect();
                let (fx, fy, fdet) = level_derivatives(&img, step, &mut scratch);
                let sx: Vec<f32> = lx.data.iter().map(|v| v * s).collect();
                let sy: Vec<f32> = ly.data.iter().map(|v| v * s).collect();
                assert!(same(&fx.data, &sx), "lx {w}x{h} step {step}");
                assert!(same(&fy.data, &sy), "ly {w}x{h} step {step}");
                assert!(same(&fdet.data, &det), "det {w}x{h} step {step}");
            }
            let g = crate::imaging::gradient::scharr_gradient(&img);
            let f = scharr_gradient(&img, &mut scratch);
            assert!(same(&f.dx.data, &g.dx.data) && same(&f.dy.data, &g.dy.data));
        }
    }
}
