//! Sampling a [`GrayImage`] at continuous pixel coordinates: bilinear and bicubic (Keys, a = −0.5).
//!
//! Coordinates follow campaign-format.md: (u, v) in pixels, top-left image corner (0, 0), centre of pixel
//! (col, row) at (col + 0.5, row + 0.5). So sampling at a pixel centre returns that pixel exactly. What lies
//! outside the image is decided by an explicit [`Border`]. An empty image samples as the border constant (or 0).

use super::border::Border;
use super::image::GrayImage;

/// Keys' cubic convolution parameter; −0.5 reproduces quadratics and is the classic "bicubic" (OpenCV: −0.75).
pub const KEYS_A: f64 = -0.5;

#[inline]
fn empty_value(border: Border) -> f32 {
    match border {
        Border::Constant(c) => c,
        _ => 0.0,
    }
}

/// Pixel (col, row) with out-of-range indices resolved by `border`. The image must be non-empty.
#[inline]
pub fn pixel_with_border(img: &GrayImage, col: isize, row: isize, border: Border) -> f32 {
    match (
        border.map_index(col, img.width),
        border.map_index(row, img.height),
    ) {
        (Some(c), Some(r)) => img.data[r * img.width + c],
        _ => empty_value(border),
    }
}

/// `x.floor()` without a libm call for |x| < 2^52 (the default x86-64 target has no rounding instruction, and
/// the samplers floor two coordinates per pixel); identical to `f64::floor` except that −0.0 gives +0.0.
#[inline(always)]
pub fn floor_fast(x: f64) -> f64 {
    if x.abs() < 4.5e15 {
        let t = x as i64 as f64;
        if t > x {
            t - 1.0
        } else {
            t
        }
    } else {
        x.floor()
    }
}

/// Bilinear interpolation at (u_px, v_px).
#[inline]
pub fn sample_bilinear(img: &GrayImage, u_px: f64, v_px: f64, border: Border) -> f32 {
    let x = u_px - 0.5;
    let y = v_px - 0.5;
    // Interior fast path (all four neighbours inside; false for NaN): no border logic, truncation is floor.
    if x >= 0.0 && y >= 0.0 && x < (img.width as f64 - 1.0) && y < (img.height as f64 - 1.0) {
        return bilinear_interior(&img.data, img.width, x, y);
    }
    sample_bilinear_border(img, u_px, v_px, border)
}

/// Bilinear interpolation at pixel-index coordinates (x, y) = (u − 0.5, v − 0.5) with
/// 0 ≤ x < width − 1 and 0 ≤ y < height − 1 (the caller checks). `data` is row-major with `width` columns.
#[inline(always)]
fn bilinear_interior(data: &[f32], width: usize, x: f64, y: f64) -> f32 {
    let (x0, y0) = (x as usize, y as usize);
    let fx = (x - x0 as f64) as f32;
    let fy = (y - y0 as f64) as f32;
    let i = y0 * width + x0;
    let quad = &data[i..i + width + 2];
    let (p00, p10) = (quad[0], quad[1]);
    let (p01, p11) = (quad[width], quad[width + 1]);
    let top = p00 + (p10 - p00) * fx;
    let bottom = p01 + (p11 - p01) * fx;
    top + (bottom - top) * fy
}

/// The pixel-index cell holding (u_px, v_px): its corner (floor of u − 0.5, v − 0.5) and the fractions of the
/// position within it; `None` for an empty image or a non-finite position.
#[inline(always)]
fn cell_of(img: &GrayImage, u_px: f64, v_px: f64) -> Option<((isize, isize), (f64, f64))> {
    if img.width == 0 || img.height == 0 || !u_px.is_finite() || !v_px.is_finite() {
        return None;
    }
    let (x, y) = (u_px - 0.5, v_px - 0.5);
    let (x0f, y0f) = (floor_fast(x), floor_fast(y));
    Some(((x0f as isize, y0f as isize), (x - x0f, y - y0f)))
}

/// [`sample_bilinear`] for positions near or beyond the border (and non-finite ones).
#[cold]
#[inline(never)]
fn sample_bilinear_border(img: &GrayImage, u_px: f64, v_px: f64, border: Border) -> f32 {
    let Some(((x0, y0), (fx, fy))) = cell_of(img, u_px, v_px) else {
        return empty_value(border);
    };
    let (fx, fy) = (fx as f32, fy as f32);
    let w = img.width as isize;
    let h = img.height as isize;
    let (p00, p10, p01, p11) = if x0 >= 0 && y0 >= 0 && x0 + 1 < w && y0 + 1 < h {
        let i = y0 as usize * img.width + x0 as usize;
        (
            img.data[i],
            img.data[i + 1],
            img.data[i + img.width],
            img.data[i + img.width + 1],
        )
    } else {
        (
            pixel_with_border(img, x0, y0, border),
            pixel_with_border(img, x0 + 1, y0, border),
            pixel_with_border(img, x0, y0 + 1, border),
            pixel_with_border(img, x0 + 1, y0 + 1, border),
        )
    };
    let top = p00 + (p10 - p00) * fx;
    let bottom = p01 + (p11 - p01) * fx;
    top + (bottom - top) * fy
}

/// Keys' cubic convolution weights for the 4 taps at offsets −1, 0, 1, 2 from `floor(x)`, fraction `t`.
#[inline]
pub fn keys_weights(t: f64) -> [f64; 4] {
    let a = KEYS_A;
    let near = |d: f64| ((a + 2.0) * d - (a + 3.0)) * d * d + 1.0; // |d| <= 1
    let far = |d: f64| ((a * d - 5.0 * a) * d + 8.0 * a) * d - 4.0 * a; // 1 < |d| < 2
    [far(1.0 + t), near(t), near(1.0 - t), far(2.0 - t)]
}

/// Bicubic (Keys, a = −0.5) interpolation at (u_px, v_px). Not bounded by the neighbours (may overshoot).
pub fn sample_bicubic(img: &GrayImage, u_px: f64, v_px: f64, border: Border) -> f32 {
    let Some(((x0, y0), (fx, fy))) = cell_of(img, u_px, v_px) else {
        return empty_value(border);
    };
    let wx = keys_weights(fx);
    let wy = keys_weights(fy);
    let inside = x0 >= 1 && y0 >= 1 && x0 + 2 < img.width as isize && y0 + 2 < img.height as isize;
    let mut acc = 0.0f64;
    for (j, wyj) in wy.iter().enumerate() {
        let row = y0 - 1 + j as isize;
        let mut row_acc = 0.0f64;
        for (i, wxi) in wx.iter().enumerate() {
            let col = x0 - 1 + i as isize;
            let p = if inside {
                img.data[row as usize * img.width + col as usize]
            } else {
                pixel_with_border(img, col, row, border)
            };
            row_acc += wxi * p as f64;
        }
        acc += wyj * row_acc;
    }
    acc as f32
}

/// True if (u_px, v_px) lies inside the image rectangle `[0, W] × [0, H]`.
#[inline]
pub fn contains(img: &GrayImage, u_px: f64, v_px: f64) -> bool {
    u_px >= 0.0 && v_px >= 0.0 && u_px <= img.width as f64 && v_px <= img.height as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_fast_equals_floor() {
        let mut values = vec![
            0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            1.0 - 1e-16,
            -1e-300,
            2.5,
            -2.5,
            4_095.999_999,
            -3999.5,
            1e15,
            -1e15,
            4.6e15,
            -4.6e15,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for state in crate::rng::mmix_states(12345).take(10_000) {
            values.push(((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 20_000.0);
        }
        for x in values {
            assert_eq!(floor_fast(x), x.floor(), "{x}");
        }
        assert!(floor_fast(f64::NAN).is_nan());
    }

    fn ramp(w: usize, h: usize) -> GrayImage {
        let data = (0..w * h)
            .map(|k| (k % w) as f32 * 2.0 + (k / w) as f32 * 3.0)
            .collect();
        GrayImage::from_vec(w, h, data).unwrap()
    }

    #[test]
    fn pixel_centres_are_exact() {
        let img = ramp(7, 5);
        for row in 0..5 {
            for col in 0..7 {
                let (u, v) = (col as f64 + 0.5, row as f64 + 0.5);
                assert_eq!(
                    sample_bilinear(&img, u, v, Border::Reflect),
                    img.get(col, row)
                );
                assert!(
                    (sample_bicubic(&img, u, v, Border::Reflect) - img.get(col, row)).abs() < 1e-5
                );
            }
        }
    }

    #[test]
    fn linear_ramp_is_reproduced_between_centres() {
        // value = 2·(u − 0.5) + 3·(v − 0.5); both interpolators reproduce linear functions inside.
        let img = ramp(9, 8);
        for &(u, v) in &[(2.3, 3.7), (4.75, 1.5), (6.01, 5.99)] {
            let truth = 2.0 * (u - 0.5) + 3.0 * (v - 0.5);
            assert!((sample_bilinear(&img, u, v, Border::Clamp) as f64 - truth).abs() < 1e-5);
            assert!((sample_bicubic(&img, u, v, Border::Clamp) as f64 - truth).abs() < 1e-4);
        }
    }

    #[test]
    fn bicubic_reproduces_quadratics() {
        let (w, h) = (12, 12);
        let f = |x: f64, y: f64| 0.1 * x * x - 0.05 * x * y + 0.2 * y * y + x;
        let data = (0..w * h)
            .map(|k| f((k % w) as f64, (k / w) as f64) as f32)
            .collect();
        let img = GrayImage::from_vec(w, h, data).unwrap();
        let (x, y) = (5.37, 6.81);
        let got = sample_bicubic(&img, x + 0.5, y + 0.5, Border::Reflect) as f64;
        assert!((got - f(x, y)).abs() < 1e-4, "{got} vs {}", f(x, y));
    }

    #[test]
    fn borders_are_explicit() {
        let img = ramp(4, 3);
        // Outside by half a pixel to the left: reflect/clamp see the edge pixel twice → edge value.
        assert_eq!(sample_bilinear(&img, 0.0, 0.5, Border::Reflect), 0.0);
        assert_eq!(sample_bilinear(&img, -0.5, 0.5, Border::Clamp), 0.0);
        // Constant border blends toward the constant.
        assert_eq!(sample_bilinear(&img, 0.0, 0.5, Border::Constant(8.0)), 4.0);
        assert_eq!(sample_bilinear(&img, -3.0, 0.5, Border::Constant(8.0)), 8.0);
        let empty = GrayImage::filled(0, 0, 0.0);
        assert_eq!(sample_bicubic(&empty, 1.0, 1.0, Border::Constant(2.0)), 2.0);
        assert_eq!(sample_bilinear(&img, f64::NAN, 1.0, Border::Reflect), 0.0);
    }
}
