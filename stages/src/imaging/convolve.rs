//! Separable 2-D filtering (correlation form) with reflective borders, parallel over rows.
//!
//! `out(col, row) = Σ_j Σ_i ky[j]·kx[i]·in(col + i − rx, row + j − ry)` with `rx = kx.len() / 2`,
//! `ry = ky.len() / 2` (odd kernels are centred; an empty kernel means identity along that axis).
//! Out-of-range pixels are mirrored about the image edge ([`Border::Reflect`](super::border::Border)).
//! The summation order is fixed per pixel, so results do not depend on the thread count.

use rayon::prelude::*;

use super::border::reflect_index;
use super::image::GrayImage;

/// Filter `img` with `kernel_x` along rows, then `kernel_y` along columns (both in correlation form).
pub fn convolve_separable(img: &GrayImage, kernel_x: &[f32], kernel_y: &[f32]) -> GrayImage {
    let rows = convolve_rows(img, kernel_x);
    convolve_cols(&rows, kernel_y)
}

/// Filter each row with `kernel` (correlation, centre `kernel.len() / 2`, reflective border).
pub fn convolve_rows(img: &GrayImage, kernel: &[f32]) -> GrayImage {
    let (w, h) = (img.width, img.height);
    if kernel.is_empty() || w == 0 || h == 0 {
        return img.clone();
    }
    let r = kernel.len() / 2;
    let tail = kernel.len() - 1 - r;
    let mut out = GrayImage::filled(w, h, 0.0);
    out.data.par_chunks_mut(w).enumerate().for_each_init(
        || vec![0.0f32; w + kernel.len() - 1],
        |padded, (row, out_row)| {
            let src = img.row(row);
            out_row.fill(0.0);
            // Interior copied as a block; only the 2r border samples need the reflection.
            if r + tail <= w {
                padded[r..r + w].copy_from_slice(src);
                for k in (0..r).chain(r + w..padded.len()) {
                    padded[k] = src[reflect_index(k as isize - r as isize, w)];
                }
            } else {
                for (k, p) in padded.iter_mut().enumerate() {
                    *p = src[reflect_index(k as isize - r as isize, w)];
                }
            }
            debug_assert_eq!(padded.len(), w + r + tail);
            for (i, &kv) in kernel.iter().enumerate() {
                let shifted = &padded[i..i + w];
                for (o, &s) in out_row.iter_mut().zip(shifted) {
                    *o += kv * s;
                }
            }
        },
    );
    out
}

/// Filter each column with `kernel` (correlation, centre `kernel.len() / 2`, reflective border).
pub fn convolve_cols(img: &GrayImage, kernel: &[f32]) -> GrayImage {
    let (w, h) = (img.width, img.height);
    if kernel.is_empty() || w == 0 || h == 0 {
        return img.clone();
    }
    let r = kernel.len() / 2;
    let mut out = GrayImage::filled(w, h, 0.0);
    out.data
        .par_chunks_mut(w)
        .enumerate()
        .for_each(|(row, out_row)| {
            for (j, &kv) in kernel.iter().enumerate() {
                let src_row = reflect_index(row as isize + j as isize - r as isize, h);
                for (o, &s) in out_row.iter_mut().zip(img.row(src_row)) {
                    *o += kv * s;
                }
            }
        });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn naive(img: &GrayImage, kx: &[f32], ky: &[f32]) -> GrayImage {
        let (w, h) = (img.width, img.height);
        let mut out = GrayImage::filled(w, h, 0.0);
        for row in 0..h {
            for col in 0..w {
                let mut acc = 0.0f64;
                for (j, &b) in ky.iter().enumerate() {
                    let rr = reflect_index(row as isize + j as isize - (ky.len() / 2) as isize, h);
                    for (i, &a) in kx.iter().enumerate() {
                        let cc =
                            reflect_index(col as isize + i as isize - (kx.len() / 2) as isize, w);
                        acc += (a * b) as f64 * img.get(cc, rr) as f64;
                    }
                }
                out.set(col, row, acc as f32);
            }
        }
        out
    }

    #[test]
    fn matches_naive_2d_correlation_including_borders() {
        let (w, h) = (9, 6);
        let data = (0..w * h).map(|k| ((k * 37 % 23) as f32) * 0.1).collect();
        let img = GrayImage::from_vec(w, h, data).unwrap();
        let kx = [0.1, -0.4, 0.2, 0.7, 0.05];
        let ky = [-1.0, 0.5, 2.0];
        let fast = convolve_separable(&img, &kx, &ky);
        let slow = naive(&img, &kx, &ky);
        for (a, b) in fast.data.iter().zip(&slow.data) {
            assert!((a - b).abs() < 1e-5, "{a} vs {b}");
        }
    }

    #[test]
    fn kernel_wider_than_image_uses_periodic_reflection() {
        let img = GrayImage::from_vec(2, 1, vec![1.0, 3.0]).unwrap();
        let k = [1.0f32; 7];
        let fast = convolve_rows(&img, &k);
        let slow = naive(&img, &k, &[1.0]);
        assert_eq!(fast.data, slow.data);
    }
}
