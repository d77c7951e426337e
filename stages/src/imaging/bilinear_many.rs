//! Bilinear sampling of a row of positions at once, in two passes as OpenCV's `remap` does: first every
//! position is split into integer pixel, fractions and an "inside" flag (branch-free, so the compiler vectorises
//! it), then the four neighbours are gathered and blended in a loop whose iterations do not depend on each other.
//! The values are exactly those of [`super::sample::sample_bilinear`]; positions without all four neighbours
//! inside the image (and NaN) are handed to the caller's edge rule. Used by the ortho-projection (thesis 3.4.3)
//! and by [`super::resample::remap`]'s bilinear case.

use super::image::GrayImage;

/// Per-thread scratch of [`sample_bilinear_many`] (reuse it across rows: no allocation per row).
#[derive(Clone, Debug, Default)]
pub struct BilinearScratch {
    /// Row-major index of the top-left neighbour (0 where not all neighbours are inside).
    top_left: Vec<i32>,
    fx: Vec<f32>,
    fy: Vec<f32>,
    inside: Vec<bool>,
}

/// `out[i]` = `img` sampled bilinearly at `(us[i], vs[i])` (campaign pixel convention: pixel centres at +0.5)
/// where the four neighbours lie inside the image; elsewhere (and for NaN) `out[i] = edge(i, us[i], vs[i])`.
/// Images of 2³¹ pixels or more, or less than 2 × 2, send every position to `edge`, which must therefore be a
/// complete sampler. `us`, `vs` and `out` must have the same length.
pub fn sample_bilinear_many(
    img: &GrayImage,
    us: &[f64],
    vs: &[f64],
    out: &mut [f32],
    scratch: &mut BilinearScratch,
    mut edge: impl FnMut(usize, f64, f64) -> f32,
) {
    let n = out.len();
    assert!(
        us.len() == n && vs.len() == n,
        "sample_bilinear_many: lengths differ"
    );
    let (w, h) = (img.width, img.height);
    if w < 2 || h < 2 || img.data.len() >= i32::MAX as usize {
        for (i, ((o, &u), &v)) in out.iter_mut().zip(us).zip(vs).enumerate() {
            *o = edge(i, u, v);
        }
        return;
    }
    let s = scratch;
    s.top_left.clear();
    s.top_left.resize(n, 0);
    for buf in [&mut s.fx, &mut s.fy] {
        buf.clear();
        buf.resize(n, 0.0);
    }
    s.inside.clear();
    s.inside.resize(n, false);

    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2 (checked just above).
        unsafe { split_and_blend_avx2(img, us, vs, s, out) };
    } else {
        split_and_blend(img, us, vs, s, out);
    }
    #[cfg(not(target_arch = "x86_64"))]
    split_and_blend(img, us, vs, s, out);

    for (i, o) in out.iter_mut().enumerate() {
        if !s.inside[i] {
            *o = edge(i, us[i], vs[i]);
        }
    }
}

/// Pass 1 (branch-free, vectorisable): integer pixel, fractions and the inside flag of every position.
/// x ∈ [0, w − 1) and y ∈ [0, h − 1) ⇔ all four neighbours inside; outside positions get index 0 (a valid one).
/// The caller guarantees w, h ≥ 2 and w·h < 2³¹.
#[inline(always)]
fn split(img: &GrayImage, us: &[f64], vs: &[f64], s: &mut BilinearScratch) {
    let (x_max, y_max) = ((img.width - 1) as f64, (img.height - 1) as f64);
    let w = img.width as i32;
    let cols = s
        .top_left
        .iter_mut()
        .zip(s.fx.iter_mut())
        .zip(s.fy.iter_mut());
    for (((k, fx), fy), (inside, (&u, &v))) in cols.zip(s.inside.iter_mut().zip(us.iter().zip(vs)))
    {
        let (x, y) = (u - 0.5, v - 0.5);
        let ok = x >= 0.0 && y >= 0.0 && x < x_max && y < y_max;
        let (x, y) = if ok { (x, y) } else { (0.0, 0.0) };
        // Truncation is floor for non-negative values.
        let (x0, y0) = (x as i32, y as i32);
        *k = y0 * w + x0;
        *fx = (x - f64::from(x0)) as f32;
        *fy = (y - f64::from(y0)) as f32;
        *inside = ok;
    }
}

/// Pass 2, scalar: gather the four neighbours and blend (the same operations, in the same order, as
/// [`super::sample::sample_bilinear`]).
#[inline(always)]
fn blend(data: &[f32], w: usize, top_left: &[i32], fx: &[f32], fy: &[f32], out: &mut [f32]) {
    for (((o, &k), &fx), &fy) in out.iter_mut().zip(top_left).zip(fx).zip(fy) {
        let k = k as usize;
        let quad = &data[k..k + w + 2];
        let top = quad[0] + (quad[1] - quad[0]) * fx;
        let bottom = quad[w] + (quad[w + 1] - quad[w]) * fx;
        *o = top + (bottom - top) * fy;
    }
}

#[inline(always)]
fn split_and_blend(
    img: &GrayImage,
    us: &[f64],
    vs: &[f64],
    s: &mut BilinearScratch,
    out: &mut [f32],
) {
    split(img, us, vs, s);
    blend(&img.data, img.width, &s.top_left, &s.fx, &s.fy, out);
}

/// Both passes with AVX2: pass 1 on 4 lanes, pass 2 with 8-lane gathers. No FMA: every value is bit-identical
/// to [`split_and_blend`]'s (test).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn split_and_blend_avx2(
    img: &GrayImage,
    us: &[f64],
    vs: &[f64],
    s: &mut BilinearScratch,
    out: &mut [f32],
) {
    use std::arch::x86_64::*;
    split(img, us, vs, s);
    let (data, w) = (&img.data[..], img.width);
    let n = out.len();
    let lanes = n - n % 8;
    let base = data.as_ptr();
    for i in (0..lanes).step_by(8) {
        // SAFETY: i + 8 ≤ n for the three scratch rows and `out` (all of length n). Every top-left index k
        // satisfies 0 ≤ k and k + w + 1 < w·h = data.len() (`split`: x0 ≤ w − 2, y0 ≤ h − 2, or k = 0 with
        // w, h ≥ 2), so all four gathers read inside `data`.
        unsafe {
            let k = _mm256_loadu_si256(s.top_left.as_ptr().add(i) as *const __m256i);
            let p00 = _mm256_i32gather_ps::<4>(base, k);
            let p10 = _mm256_i32gather_ps::<4>(base.add(1), k);
            let p01 = _mm256_i32gather_ps::<4>(base.add(w), k);
            let p11 = _mm256_i32gather_ps::<4>(base.add(w + 1), k);
            let fx = _mm256_loadu_ps(s.fx.as_ptr().add(i));
            let fy = _mm256_loadu_ps(s.fy.as_ptr().add(i));
            let top = _mm256_add_ps(p00, _mm256_mul_ps(_mm256_sub_ps(p10, p00), fx));
            let bottom = _mm256_add_ps(p01, _mm256_mul_ps(_mm256_sub_ps(p11, p01), fx));
            let value = _mm256_add_ps(top, _mm256_mul_ps(_mm256_sub_ps(bottom, top), fy));
            _mm256_storeu_ps(out.as_mut_ptr().add(i), value);
        }
    }
    blend(
        data,
        w,
        &s.top_left[lanes..],
        &s.fx[lanes..],
        &s.fy[lanes..],
        &mut out[lanes..],
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imaging::border::Border;
    use crate::imaging::sample::sample_bilinear;

    #[test]
    fn equals_sample_bilinear_inside_and_defers_to_the_edge_rule_outside() {
        let (w, h) = (37, 23);
        let data: Vec<f32> = (0..w * h)
            .map(|i| ((i * 7919) % 1000) as f32 / 1000.0)
            .collect();
        let img = GrayImage::from_vec(w, h, data).unwrap();
        // Positions everywhere, including exact pixel centres, the last interior fractions, outside and NaN.
        let mut us = Vec::new();
        let mut vs = Vec::new();
        for i in 0..400 {
            us.push(-2.0 + i as f64 * 0.1037);
            vs.push(-1.5 + (i * 13 % 400) as f64 * 0.0671);
        }
        us.extend([0.5, w as f64 - 0.5, w as f64 - 0.5001, f64::NAN, 3.0]);
        vs.extend([0.5, 3.5, h as f64 - 0.5001, 2.0, f64::NAN]);
        let mut out = vec![0.0f32; us.len()];
        let mut edges = 0;
        sample_bilinear_many(
            &img,
            &us,
            &vs,
            &mut out,
            &mut BilinearScratch::default(),
            |_, u, v| {
                edges += 1;
                sample_bilinear(&img, u, v, Border::Constant(-7.0))
            },
        );
        for i in 0..us.len() {
            let want = sample_bilinear(&img, us[i], vs[i], Border::Constant(-7.0));
            assert!(
                out[i].to_bits() == want.to_bits(),
                "({}, {}): {} vs {want}",
                us[i],
                vs[i],
                out[i]
            );
        }
        assert!(
            edges > 50 && edges < us.len() - 100,
            "{edges} positions took the edge rule"
        );
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_avx2_path_is_bit_identical_to_the_scalar_one() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("no AVX2 on this CPU: nothing to compare");
            return;
        }
        let (w, h) = (61, 29);
        let data: Vec<f32> = (0..w * h)
            .map(|i| ((i * 104_729) % 997) as f32 / 997.0)
            .collect();
        let img = GrayImage::from_vec(w, h, data).unwrap();
        let n = 1003; // not a multiple of 8: the scalar tail runs too
        let us: Vec<f64> = (0..n)
            .map(|i| -1.0 + (i * 37 % n) as f64 * 0.0637)
            .collect();
        let vs: Vec<f64> = (0..n)
            .map(|i| -0.7 + (i * 91 % n) as f64 * 0.0311)
            .collect();
        let run = |avx2: bool| {
            let mut s = BilinearScratch {
                top_left: vec![0; n],
                fx: vec![0.0; n],
                fy: vec![0.0; n],
                inside: vec![false; n],
            };
            let mut out = vec![0.0f32; n];
            if avx2 {
                // SAFETY: AVX2 was detected above.
                unsafe { split_and_blend_avx2(&img, &us, &vs, &mut s, &mut out) };
            } else {
                split_and_blend(&img, &us, &vs, &mut s, &mut out);
            }
            (out, s.inside)
        };
        let (scalar, inside) = run(false);
        let (wide, inside_wide) = run(true);
        assert_eq!(inside, inside_wide);
        assert!(inside.iter().filter(|&&b| b).count() > n / 2);
        for i in (0..n).filter(|&i| inside[i]) {
            assert_eq!(scalar[i].to_bits(), wide[i].to_bits(), "position {i}");
        }
    }
}
