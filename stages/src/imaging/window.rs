//! Tapering windows (Hann, Blackman) and their separable 2-D application, used before Fourier-domain matching
//! to suppress the wrap-around edge (Kuglin & Hines 1975; Reddy & Chatterji 1996).

use super::image::GrayImage;

/// Which taper to apply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WindowKind {
    /// No taper (all ones).
    Rectangular,
    /// `w(n) = 0.5·(1 − cos(2πn/(N − 1)))` (symmetric, zero at both ends).
    Hann,
    /// `w(n) = 0.42 − 0.5·cos(2πn/(N − 1)) + 0.08·cos(4πn/(N − 1))` (symmetric).
    Blackman,
}

/// Value of the length-`n` window at continuous sample position `x` (sample k of [`window_1d`] is at x = k);
/// 0 outside `[0, n − 1]`. Used to place a window at a sub-pixel offset.
pub fn window_value(kind: WindowKind, n: usize, x: f64) -> f64 {
    if n == 0 || !(x >= 0.0 && x <= (n - 1) as f64) {
        return 0.0;
    }
    if n == 1 {
        return 1.0;
    }
    let t = 2.0 * std::f64::consts::PI * x / (n - 1) as f64;
    match kind {
        WindowKind::Rectangular => 1.0,
        WindowKind::Hann => 0.5 * (1.0 - t.cos()),
        WindowKind::Blackman => (0.42 - 0.5 * t.cos() + 0.08 * (2.0 * t).cos()).max(0.0),
    }
}

/// The 1-D window of length `n` (f64). Length 1 gives `[1.0]`, length 0 an empty vector.
pub fn window_1d(kind: WindowKind, n: usize) -> Vec<f64> {
    (0..n).map(|i| window_value(kind, n, i as f64)).collect()
}

/// Separable 2-D window `w(col)·w(row)` of size `width × height` (row-major, f64).
pub fn window_2d(kind: WindowKind, width: usize, height: usize) -> Vec<f64> {
    let wx = window_1d(kind, width);
    let wy = window_1d(kind, height);
    let mut out = Vec::with_capacity(width * height);
    for &a in &wy {
        out.extend(wx.iter().map(|&b| a * b));
    }
    out
}

/// `img` multiplied by the separable window (a new image).
pub fn apply_window(img: &GrayImage, kind: WindowKind) -> GrayImage {
    let w = window_2d(kind, img.width, img.height);
    let data = img
        .data
        .iter()
        .zip(&w)
        .map(|(&p, &k)| (p as f64 * k) as f32)
        .collect();
    GrayImage {
        width: img.width,
        height: img.height,
        data,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hann_and_blackman_known_values() {
        let h = window_1d(WindowKind::Hann, 5);
        let expect = [0.0, 0.5, 1.0, 0.5, 0.0];
        for (a, b) in h.iter().zip(expect) {
            assert!((a - b).abs() < 1e-12);
        }
        let b = window_1d(WindowKind::Blackman, 5);
        let expect = [0.0, 0.34, 1.0, 0.34, 0.0];
        for (a, e) in b.iter().zip(expect) {
            assert!((a - e).abs() < 1e-12, "{a} vs {e}");
        }
        assert_eq!(window_1d(WindowKind::Hann, 1), vec![1.0]);
        assert!(window_1d(WindowKind::Hann, 0).is_empty());
        assert!(
            (window_value(WindowKind::Hann, 5, 1.5)
                - 0.5 * (1.0 - (0.75 * std::f64::consts::PI).cos()))
            .abs()
                < 1e-12
        );
        assert_eq!(window_value(WindowKind::Hann, 5, -0.1), 0.0);
        assert_eq!(window_value(WindowKind::Rectangular, 5, 4.1), 0.0);
    }

    #[test]
    fn two_d_is_outer_product() {
        let w = window_2d(WindowKind::Hann, 5, 3);
        assert_eq!(w.len(), 15);
        assert!((w[5 + 2] - 1.0).abs() < 1e-12);
        assert_eq!(w[0], 0.0);
        let img = apply_window(&GrayImage::filled(5, 3, 2.0), WindowKind::Hann);
        assert!((img.get(1, 1) - 1.0).abs() < 1e-6);
    }
}
