//! Resampling by a per-pixel coordinate map (`remap`), and the scale/affine warps built on it.
//!
//! `remap` is the workhorse of the ortho-projection: for every output pixel (col, row) the caller's map returns
//! the continuous source position (u, v) (campaign-format.md convention: pixel centre at +0.5) or `None` (no
//! source → fill value). Rows are processed in parallel; each output pixel depends only on its own map value,
//! so results are identical for any thread count.

use rayon::prelude::*;

use super::bilinear_many::sample_bilinear_many;
use super::border::Border;
use super::image::GrayImage;
use super::sample::{sample_bicubic, sample_bilinear};

/// Interpolation used by [`remap`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// The pixel containing (u, v).
    Nearest,
    Bilinear,
    /// Keys cubic convolution, a = −0.5.
    Bicubic,
}

/// Sample `img` at (u_px, v_px) with `interp` and `border`.
#[inline]
pub fn sample(img: &GrayImage, u_px: f64, v_px: f64, interp: Interpolation, border: Border) -> f32 {
    match interp {
        Interpolation::Nearest => {
            if img.width == 0 || img.height == 0 || !u_px.is_finite() || !v_px.is_finite() {
                return match border {
                    Border::Constant(c) => c,
                    _ => 0.0,
                };
            }
            super::sample::pixel_with_border(
                img,
                u_px.floor() as isize,
                v_px.floor() as isize,
                border,
            )
        }
        Interpolation::Bilinear => sample_bilinear(img, u_px, v_px, border),
        Interpolation::Bicubic => sample_bicubic(img, u_px, v_px, border),
    }
}

/// Build an `out_width × out_height` image: pixel (col, row) = `src` sampled at `map(col, row)`, or
/// `fill_value` where the map returns `None` (with bilinear interpolation also where it returns a NaN u).
/// Samples near the source edge use `border`.
pub fn remap<F>(
    src: &GrayImage,
    out_width: usize,
    out_height: usize,
    interp: Interpolation,
    border: Border,
    fill_value: f32,
    map: F,
) -> GrayImage
where
    F: Fn(usize, usize) -> Option<(f64, f64)> + Sync,
{
    let mut out = GrayImage::filled(out_width, out_height, fill_value);
    if out_width == 0 {
        return out;
    }
    if interp == Interpolation::Bilinear {
        // The row's positions first (NaN: no source), then the row sampler.
        out.data
            .par_chunks_mut(out_width)
            .enumerate()
            .for_each_init(
                || (vec![0.0; out_width], vec![0.0; out_width]),
                |(us, vs), (row, out_row)| {
                    for (col, (u, v)) in us.iter_mut().zip(vs.iter_mut()).enumerate() {
                        (*u, *v) = map(col, row).unwrap_or((f64::NAN, f64::NAN));
                    }
                    sample_bilinear_many(src, us, vs, out_row, fill_value, |_, u, v| {
                        sample_bilinear(src, u, v, border)
                    });
                },
            );
        return out;
    }
    out.data
        .par_chunks_mut(out_width)
        .enumerate()
        .for_each(|(row, out_row)| {
            for (col, o) in out_row.iter_mut().enumerate() {
                if let Some((u, v)) = map(col, row) {
                    *o = sample(src, u, v, interp, border);
                }
            }
        });
    out
}

/// A precomputed sampling map, the form `cv2.remap` takes (two `CV_32FC1` maps): output pixel (col, row) takes
/// the source at (`u_px[i]`, `v_px[i]`), i = row · width + col, in the campaign pixel convention (pixel centres
/// at +0.5, not OpenCV's integer centres); NaN in `u_px` means "no source" (fill value). f32 positions resolve
/// ≤ 1e-3 px up to 16 384 px.
#[derive(Clone, Debug, PartialEq)]
pub struct SourceMap {
    pub width: usize,
    pub height: usize,
    pub u_px: Vec<f32>,
    pub v_px: Vec<f32>,
}

/// [`remap`] with a precomputed [`SourceMap`] (the output has the map's size).
///
/// # Panics
/// If `u_px` or `v_px` does not hold `width · height` values (a programming error, not user data).
pub fn remap_with_map(
    src: &GrayImage,
    map: &SourceMap,
    interp: Interpolation,
    border: Border,
    fill_value: f32,
) -> GrayImage {
    let (w, h) = (map.width, map.height);
    assert!(
        map.u_px.len() == w * h && map.v_px.len() == w * h,
        "SourceMap: {w} x {h} needs {} values per coordinate, has {} and {}",
        w * h,
        map.u_px.len(),
        map.v_px.len()
    );
    if interp != Interpolation::Bilinear || w == 0 {
        return remap(src, w, h, interp, border, fill_value, |col, row| {
            let i = row * w + col;
            let u = map.u_px[i];
            (!u.is_nan()).then(|| (f64::from(u), f64::from(map.v_px[i])))
        });
    }
    let mut out = GrayImage::filled(w, h, fill_value);
    out.data
        .par_chunks_mut(w)
        .zip(map.u_px.par_chunks(w).zip(map.v_px.par_chunks(w)))
        .for_each(|(out_row, (us, vs))| {
            sample_bilinear_many(src, us, vs, out_row, fill_value, |_, u, v| {
                sample_bilinear(src, u, v, border)
            });
        });
    out
}

/// Resize `src` to `out_width × out_height` by pure scaling (pixel-area aligned: the image rectangles coincide).
/// No anti-alias prefilter: blur first when shrinking by more than ~1.5×.
pub fn resize(
    src: &GrayImage,
    out_width: usize,
    out_height: usize,
    interp: Interpolation,
) -> GrayImage {
    let sx = src.width as f64 / out_width.max(1) as f64;
    let sy = src.height as f64 / out_height.max(1) as f64;
    // Every output pixel centre maps inside the source rectangle, so the fill value is never used.
    warp_affine(
        src,
        [sx, 0.0, 0.0, 0.0, sy, 0.0],
        out_width,
        out_height,
        interp,
        0.0,
    )
}

/// 2× up-sampling with bicubic interpolation: fine pixel (i, j) samples the source at ((i + 0.5)/2, (j + 0.5)/2),
/// so a fine coordinate maps back as `u_src = u_fine / 2`.
pub fn upsample_2x(src: &GrayImage) -> GrayImage {
    resize(src, src.width * 2, src.height * 2, Interpolation::Bicubic)
}

/// Affine warp: output pixel centre (u_out, v_out) samples the source at
/// `(a[0]·u_out + a[1]·v_out + a[2], a[3]·u_out + a[4]·v_out + a[5])` (the map goes output → source, continuous
/// coordinates). Positions outside the source rectangle get `fill_value`.
pub fn warp_affine(
    src: &GrayImage,
    out_to_src: [f64; 6],
    out_width: usize,
    out_height: usize,
    interp: Interpolation,
    fill_value: f32,
) -> GrayImage {
    let (w, h) = (src.width as f64, src.height as f64);
    let a = out_to_src;
    remap(
        src,
        out_width,
        out_height,
        interp,
        Border::Reflect,
        fill_value,
        |c, r| {
            let (uo, vo) = (c as f64 + 0.5, r as f64 + 0.5);
            let u = a[0] * uo + a[1] * vo + a[2];
            let v = a[3] * uo + a[4] * vo + a[5];
            (u >= 0.0 && v >= 0.0 && u <= w && v <= h).then_some((u, v))
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn smooth(w: usize, h: usize) -> GrayImage {
        let f = |u: f64, v: f64| (0.2 * u).sin() + (0.15 * v).cos() + 0.01 * u * v;
        let data = (0..w * h)
            .map(|k| f((k % w) as f64 + 0.5, (k / w) as f64 + 0.5) as f32)
            .collect();
        GrayImage::from_vec(w, h, data).unwrap()
    }

    #[test]
    fn identity_map_is_exact_and_none_fills() {
        let img = smooth(13, 9);
        let out = remap(
            &img,
            13,
            9,
            Interpolation::Bicubic,
            Border::Reflect,
            -1.0,
            |c, r| (c != 3).then_some((c as f64 + 0.5, r as f64 + 0.5)),
        );
        for r in 0..9 {
            for c in 0..13 {
                let want = if c == 3 { -1.0 } else { img.get(c, r) };
                assert!((out.get(c, r) - want).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn integer_translation_by_affine_is_exact() {
        let img = smooth(20, 16);
        let out = warp_affine(
            &img,
            [1.0, 0.0, 3.0, 0.0, 1.0, -2.0],
            20,
            16,
            Interpolation::Bilinear,
            9.0,
        );
        assert_eq!(out.get(0, 5), img.get(3, 3));
        assert_eq!(out.get(16, 15), img.get(19, 13));
        assert_eq!(out.get(5, 0), 9.0); // source v = −1.5 is outside
    }

    #[test]
    fn upsample_maps_coordinates_by_half() {
        let img = smooth(24, 20);
        let up = upsample_2x(&img);
        assert_eq!((up.width, up.height), (48, 40));
        // fine pixel (i, j) centre (i + 0.5, j + 0.5) is source (i + 0.5)/2: compare with the smooth function.
        let f = |u: f64, v: f64| (0.2 * u).sin() + (0.15 * v).cos() + 0.01 * u * v;
        for &(i, j) in &[(10usize, 10usize), (21, 17), (30, 25)] {
            let (u, v) = ((i as f64 + 0.5) / 2.0, (j as f64 + 0.5) / 2.0);
            assert!((up.get(i, j) as f64 - f(u, v)).abs() < 2e-3, "{i},{j}");
        }
    }

    #[test]
    fn remap_with_map_equals_remap_with_the_same_positions() {
        let img = smooth(40, 30);
        let (w, h) = (23, 17);
        // Positions inside, near and beyond the edges, and "no source" (NaN) every seventh pixel.
        let position = |col: usize, row: usize| {
            let u = -1.5 + col as f64 * 1.91 + row as f64 * 0.13;
            let v = -0.8 + row as f64 * 1.87 - col as f64 * 0.07;
            ((row * w + col) % 7 != 3).then_some((u as f32, v as f32))
        };
        let mut map = SourceMap {
            width: w,
            height: h,
            u_px: vec![f32::NAN; w * h],
            v_px: vec![f32::NAN; w * h],
        };
        for row in 0..h {
            for col in 0..w {
                if let Some((u, v)) = position(col, row) {
                    map.u_px[row * w + col] = u;
                    map.v_px[row * w + col] = v;
                }
            }
        }
        for interp in [
            Interpolation::Nearest,
            Interpolation::Bilinear,
            Interpolation::Bicubic,
        ] {
            for border in [Border::Clamp, Border::Reflect, Border::Constant(2.5)] {
                let by_map = remap_with_map(&img, &map, interp, border, -1.0);
                let by_closure = remap(&img, w, h, interp, border, -1.0, |col, row| {
                    position(col, row).map(|(u, v)| (f64::from(u), f64::from(v)))
                });
                assert_eq!((by_map.width, by_map.height), (w, h));
                for (i, (a, b)) in by_map.data.iter().zip(&by_closure.data).enumerate() {
                    assert_eq!(a.to_bits(), b.to_bits(), "{interp:?} {border:?} pixel {i}");
                }
                assert_eq!(by_map.data[3], -1.0, "no source: the fill value");
            }
        }
        // A pixel whose neighbours all lie inside equals sample_bilinear there.
        let (u, v) = (map.u_px[5 * w + 6], map.v_px[5 * w + 6]);
        let out = remap_with_map(&img, &map, Interpolation::Bilinear, Border::Clamp, 0.0);
        let want = sample_bilinear(&img, f64::from(u), f64::from(v), Border::Clamp);
        assert_eq!(out.get(6, 5), want);
    }
}
