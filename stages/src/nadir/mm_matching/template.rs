//! Template matching of one corner between two ortho images (thesis 3.4.4.4): normalised cross-correlation
//! (OpenCV `TM_CCOEFF_NORMED` semantics, OpenCV TM_CCOEFF_NORMED) of a square template around a corner in the
//! detecting image over a small square search range in the neighbour, with a sub-pixel peak from the 3 × 3
//! quadratic fit (`matching::subpixel`). Also the validity index that tells whether a box of an ortho image is
//! free of masked (vehicle) pixels.
//!
//! Unlike [`crate::matching::ncc::match_template`] this works in place on the full images with caller-owned
//! scratch buffers, so matching hundreds of corners allocates nothing per corner.

use crate::imaging::GrayImage;
use crate::matching::subpixel::{refine_peak, PeakFit};

/// Integral image of the masked pixels of an ortho image: answers "is every pixel of this box valid?" in O(1).
pub struct ValidIndex {
    width: usize,
    height: usize,
    /// (width + 1) × (height + 1) counts of invalid pixels above-left of each grid corner.
    invalid_sum: Vec<u32>,
}

impl ValidIndex {
    /// Index of `valid` (row-major, 1 = valid) for a `width × height` image. A mask of the wrong length counts
    /// as all-invalid.
    pub fn new(valid: &[u8], width: usize, height: usize) -> Self {
        let stride = width + 1;
        let mut invalid_sum = vec![0u32; stride * (height + 1)];
        let ok = valid.len() == width * height;
        for row in 0..height {
            let mut acc = 0u32;
            for col in 0..width {
                acc += u32::from(!ok || valid[row * width + col] == 0);
                let i = (row + 1) * stride + col + 1;
                invalid_sum[i] = invalid_sum[i - stride] + acc;
            }
        }
        Self {
            width,
            height,
            invalid_sum,
        }
    }

    /// Whether pixels `col0..=col1` × `row0..=row1` all lie inside the image and are all valid.
    pub fn all_valid(&self, col0: i64, row0: i64, col1: i64, row1: i64) -> bool {
        if col0 < 0 || row0 < 0 || col1 >= self.width as i64 || row1 >= self.height as i64 {
            return false;
        }
        if col1 < col0 || row1 < row0 {
            return true;
        }
        let stride = self.width + 1;
        let (c0, r0, c1, r1) = (
            col0 as usize,
            row0 as usize,
            col1 as usize + 1,
            row1 as usize + 1,
        );
        let s = &self.invalid_sum;
        s[r1 * stride + c1] + s[r0 * stride + c0] - s[r0 * stride + c1] - s[r1 * stride + c0] == 0
    }

    /// Whether the square of half size `half` around pixel (col, row) is inside and valid.
    pub fn square_valid(&self, col: i64, row: i64, half: i64) -> bool {
        self.all_valid(col - half, row - half, col + half, row + half)
    }
}

/// Reusable buffers of [`match_corner`] (one per worker thread).
#[derive(Default)]
pub struct TemplateScratch {
    /// Zero-mean template values.
    template: Vec<f64>,
    /// Integral images of the search region's values and squared values.
    sum: Vec<f64>,
    sum_sq: Vec<f64>,
    /// Score map, (2r + 1)².
    scores: Vec<f64>,
}

/// The best match of a template.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TemplatePeak {
    /// Sub-pixel displacement of the best match from the search centre pixel, neighbour px.
    pub offset_u_px: f64,
    pub offset_v_px: f64,
    /// NCC at the integer peak, [−1, 1].
    pub score: f64,
}

/// Match the (2·half + 1)² template of `src` centred on pixel (`src_col`, `src_row`) against the windows of
/// `dst` centred on (`dst_col` + dx, `dst_row` + dy), |dx|, |dy| ≤ `radius`. Returns the best match, or
/// `None` if any pixel involved lies outside an image, the template is flat, or the best score lies on the
/// border of the search range (the true peak may lie outside it). Ties go to the first candidate in raster
/// order.
#[allow(clippy::too_many_arguments)]
pub fn match_corner(
    src: &GrayImage,
    src_col: i64,
    src_row: i64,
    dst: &GrayImage,
    dst_col: i64,
    dst_row: i64,
    half: usize,
    radius: usize,
    scratch: &mut TemplateScratch,
) -> Option<TemplatePeak> {
    let (h, r) = (half as i64, radius as i64);
    let side = 2 * half + 1;
    let n = (side * side) as f64;
    let inside = |img: &GrayImage, c0: i64, r0: i64, c1: i64, r1: i64| {
        c0 >= 0 && r0 >= 0 && c1 < img.width as i64 && r1 < img.height as i64
    };
    if !inside(src, src_col - h, src_row - h, src_col + h, src_row + h)
        || !inside(
            dst,
            dst_col - h - r,
            dst_row - h - r,
            dst_col + h + r,
            dst_row + h + r,
        )
    {
        return None;
    }

    // Zero-mean template and its norm.
    scratch.template.clear();
    let mut mean = 0.0f64;
    for j in 0..side {
        let row = &src.row((src_row - h) as usize + j)[(src_col - h) as usize..][..side];
        mean += row.iter().map(|&v| v as f64).sum::<f64>();
    }
    mean /= n;
    let mut t_norm_sq = 0.0f64;
    for j in 0..side {
        let row = &src.row((src_row - h) as usize + j)[(src_col - h) as usize..][..side];
        for &v in row {
            let t = v as f64 - mean;
            t_norm_sq += t * t;
            scratch.template.push(t);
        }
    }
    if !(t_norm_sq > 1e-12 * n) {
        return None;
    }
    let t_norm = t_norm_sq.sqrt();

    // Integral images of the search region (values shifted by the template mean for conditioning).
    let region = side + 2 * radius;
    let stride = region + 1;
    scratch.sum.clear();
    scratch.sum.resize(stride * stride, 0.0);
    scratch.sum_sq.clear();
    scratch.sum_sq.resize(stride * stride, 0.0);
    let (rc0, rr0) = ((dst_col - h - r) as usize, (dst_row - h - r) as usize);
    for y in 0..region {
        let row = &dst.row(rr0 + y)[rc0..][..region];
        let (mut a1, mut a2) = (0.0f64, 0.0f64);
        for (x, &g) in row.iter().enumerate() {
            let d = g as f64 - mean;
            a1 += d;
            a2 += d * d;
            let i = (y + 1) * stride + x + 1;
            scratch.sum[i] = scratch.sum[i - stride] + a1;
            scratch.sum_sq[i] = scratch.sum_sq[i - stride] + a2;
        }
    }

    // Score map.
    let m = 2 * radius + 1;
    scratch.scores.clear();
    scratch.scores.resize(m * m, 0.0);
    let mut best = 0usize;
    for y in 0..m {
        for x in 0..m {
            let mut num = 0.0f64;
            for (j, t_row) in scratch.template.chunks_exact(side).enumerate() {
                let i_row = &dst.row(rr0 + y + j)[rc0 + x..][..side];
                for (&t, &g) in t_row.iter().zip(i_row) {
                    num += t * g as f64;
                }
            }
            let (top, bottom) = (y * stride, (y + side) * stride);
            let box_sum =
                |s: &[f64]| s[bottom + x + side] - s[bottom + x] - s[top + x + side] + s[top + x];
            let (d1, d2) = (box_sum(&scratch.sum), box_sum(&scratch.sum_sq));
            let energy = (d2 - d1 * d1 / n).max(0.0);
            let score = if energy > 1e-12 * n {
                (num / (energy.sqrt() * t_norm)).clamp(-1.0, 1.0)
            } else {
                0.0
            };
            let k = y * m + x;
            scratch.scores[k] = score;
            if score > scratch.scores[best] {
                best = k;
            }
        }
    }
    let (bx, by) = (best % m, best / m);
    if bx == 0 || by == 0 || bx + 1 == m || by + 1 == m {
        return None;
    }
    let mut nb = [[0.0f64; 3]; 3];
    for (j, row) in nb.iter_mut().enumerate() {
        for (i, v) in row.iter_mut().enumerate() {
            *v = scratch.scores[(by + j - 1) * m + bx + i - 1];
        }
    }
    let (sx, sy) = refine_peak(&nb, PeakFit::Quadratic);
    Some(TemplatePeak {
        offset_u_px: bx as f64 - radius as f64 + sx,
        offset_v_px: by as f64 - radius as f64 + sy,
        score: scratch.scores[best],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth random-looking texture evaluated at continuous coordinates (so shifted copies are exact).
    fn texture(x: f64, y: f64) -> f32 {
        let v = (0.37 * x).sin() * (0.23 * y).cos()
            + 0.6 * (0.11 * x + 0.29 * y).sin()
            + 0.4 * (0.05 * x * x.cos() - 0.17 * y).cos();
        (0.5 + 0.2 * v) as f32
    }

    fn image(w: usize, h: usize, shift_u: f64, shift_v: f64) -> GrayImage {
        let mut img = GrayImage::filled(w, h, 0.0);
        for row in 0..h {
            for col in 0..w {
                img.set(
                    col,
                    row,
                    texture(col as f64 + 0.5 - shift_u, row as f64 + 0.5 - shift_v),
                );
            }
        }
        img
    }

    #[test]
    fn recovers_integer_and_subpixel_shifts() {
        let src = image(80, 80, 0.0, 0.0);
        let mut scratch = TemplateScratch::default();
        for &(su, sv) in &[(3.0, -2.0), (1.3, 0.4), (-2.25, 3.7), (0.0, 0.0)] {
            let dst = image(80, 80, su, sv);
            let peak =
                match_corner(&src, 40, 38, &dst, 40, 38, 10, 6, &mut scratch).expect("a peak");
            assert!(
                (peak.offset_u_px - su).abs() < 0.1 && (peak.offset_v_px - sv).abs() < 0.1,
                "shift ({su}, {sv}) found ({}, {})",
                peak.offset_u_px,
                peak.offset_v_px
            );
            assert!(peak.score > 0.95, "score {}", peak.score);
            if su.fract() == 0.0 && sv.fract() == 0.0 {
                // The integer peak is exact; the quadratic sub-pixel fit of an asymmetric peak is not.
                assert!((peak.score - 1.0).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn gain_and_offset_do_not_change_the_score_and_flat_or_outside_gives_none() {
        let src = image(60, 60, 0.0, 0.0);
        let mut dst = image(60, 60, 2.0, 1.0);
        for v in &mut dst.data {
            *v = 0.3 + 1.7 * *v;
        }
        let mut scratch = TemplateScratch::default();
        let peak = match_corner(&src, 30, 30, &dst, 30, 30, 8, 4, &mut scratch).unwrap();
        assert!((peak.score - 1.0).abs() < 1e-6);
        assert!((peak.offset_u_px - 2.0).abs() < 0.1 && (peak.offset_v_px - 1.0).abs() < 0.1);
        // Flat template.
        let flat = GrayImage::filled(60, 60, 0.5);
        assert!(match_corner(&flat, 30, 30, &dst, 30, 30, 8, 4, &mut scratch).is_none());
        // Search region leaves the image.
        assert!(match_corner(&src, 30, 30, &dst, 5, 30, 8, 4, &mut scratch).is_none());
        // Shift larger than the radius: the best score lies on the border ⇒ rejected.
        let far = image(60, 60, 7.0, 0.0);
        assert!(match_corner(&src, 30, 30, &far, 30, 30, 8, 4, &mut scratch).is_none());
    }

    #[test]
    fn valid_index_boxes() {
        let (w, h) = (10, 8);
        let mut valid = vec![1u8; w * h];
        valid[3 * w + 6] = 0;
        let idx = ValidIndex::new(&valid, w, h);
        assert!(idx.all_valid(0, 0, 9, 2));
        assert!(!idx.all_valid(0, 0, 9, 3));
        assert!(idx.all_valid(0, 0, 5, 7));
        assert!(!idx.square_valid(6, 3, 0));
        assert!(idx.square_valid(2, 4, 2));
        assert!(!idx.square_valid(1, 4, 2), "leaves the image");
        assert!(!ValidIndex::new(&valid[1..], w, h).all_valid(0, 0, 0, 0));
    }
}
