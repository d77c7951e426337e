//! Sub-pixel peak location by a second-order polynomial fit to the 3 × 3 neighbourhood of an integer peak
//! (thesis 3.4.5.3, eq. 3/1 and the text after it; Kuglin & Hines 1975; Reddy & Chatterji 1996 gives the least-squares formulas).
//!
//! `n[dy + 1][dx + 1]` holds the value at offset (dx, dy) ∈ {−1, 0, 1}² from the integer peak. The fit
//! `r ≈ a + b·x + c·y + d·x² + e·xy + g·y²` is the least-squares solution on the 9 samples; its vertex is the
//! sub-pixel offset. Fitting to `ln r` instead ([`PeakFit::LogQuadratic`]) is exact for Gaussian-shaped peaks
//! (such as a low-pass weighted phase-correlation surface) and removes the bias a parabola has on them.

/// Which surface the quadratic is fitted to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PeakFit {
    /// Quadratic fitted to the values themselves.
    Quadratic,
    /// Quadratic fitted to their logarithm (falls back to [`PeakFit::Quadratic`] if any value is ≤ 0).
    LogQuadratic,
}

/// Vertex offset (dx, dy) of the least-squares quadratic through the 3 × 3 samples, or `None` if the fitted
/// surface has no maximum there (not negative definite) or the vertex lies more than 1 px away on an axis.
pub fn quadratic_peak_2d(n: &[[f64; 3]; 3]) -> Option<(f64, f64)> {
    let col = |x: usize| n[0][x] + n[1][x] + n[2][x];
    let row = |y: usize| n[y][0] + n[y][1] + n[y][2];
    let b = (col(2) - col(0)) / 6.0;
    let c = (row(2) - row(0)) / 6.0;
    let e = (n[2][2] + n[0][0] - n[0][2] - n[2][0]) / 4.0;
    let d = (col(0) + col(2) - 2.0 * col(1)) / 6.0;
    let g = (row(0) + row(2) - 2.0 * row(1)) / 6.0;
    // Solve [2d e; e 2g]·δ = −[b; c].
    let det = 4.0 * d * g - e * e;
    if !(d < 0.0 && g < 0.0 && det > 0.0 && det.is_finite()) {
        return None;
    }
    let dx = (-b * 2.0 * g + c * e) / det;
    let dy = (-c * 2.0 * d + b * e) / det;
    (dx.abs() <= 1.0 && dy.abs() <= 1.0).then_some((dx, dy))
}

/// Vertex of the parabola through (−1, r_minus), (0, r_0), (1, r_plus); `None` unless it is a maximum within
/// half a pixel.
pub fn parabola_peak_1d(r_minus: f64, r_0: f64, r_plus: f64) -> Option<f64> {
    let curvature = r_minus - 2.0 * r_0 + r_plus;
    if !(curvature < 0.0) {
        return None;
    }
    let delta = (r_minus - r_plus) / (2.0 * curvature);
    (delta.abs() <= 0.5).then_some(delta)
}

/// Sub-pixel offset of the peak at the centre of `n`: the 2-D fit, else per-axis parabolas, else 0 on an axis
/// where neither gives a maximum. With [`PeakFit::LogQuadratic`] the logarithm is fitted when all 9 values
/// are > 0.
pub fn refine_peak(n: &[[f64; 3]; 3], fit: PeakFit) -> (f64, f64) {
    let mut m = *n;
    if fit == PeakFit::LogQuadratic && n.iter().flatten().all(|&v| v > 0.0) {
        for v in m.iter_mut().flatten() {
            *v = v.ln();
        }
    }
    if let Some(d) = quadratic_peak_2d(&m) {
        return d;
    }
    let dx = parabola_peak_1d(m[1][0], m[1][1], m[1][2]).unwrap_or(0.0);
    let dy = parabola_peak_1d(m[0][1], m[1][1], m[2][1]).unwrap_or(0.0);
    (dx, dy)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample<F: Fn(f64, f64) -> f64>(f: F) -> [[f64; 3]; 3] {
        let mut n = [[0.0; 3]; 3];
        for (j, row) in n.iter_mut().enumerate() {
            for (i, v) in row.iter_mut().enumerate() {
                *v = f(i as f64 - 1.0, j as f64 - 1.0);
            }
        }
        n
    }

    #[test]
    fn recovers_exact_vertex_of_a_sampled_quadratic() {
        // r = 5 − 2(x − 0.31)² − 1.5(y + 0.22)² + 0.7(x − 0.31)(y + 0.22): vertex (0.31, −0.22).
        let n = sample(|x, y| {
            let (a, b) = (x - 0.31, y + 0.22);
            5.0 - 2.0 * a * a - 1.5 * b * b + 0.7 * a * b
        });
        let (dx, dy) = quadratic_peak_2d(&n).unwrap();
        assert!(
            (dx - 0.31).abs() < 1e-12 && (dy + 0.22).abs() < 1e-12,
            "{dx} {dy}"
        );
    }

    #[test]
    fn log_fit_is_exact_for_gaussian_peaks() {
        let n = sample(|x, y| {
            (-((x - 0.4).powi(2) + (y + 0.15).powi(2)) / (2.0 * 1.1f64.powi(2))).exp()
        });
        let (dx, dy) = refine_peak(&n, PeakFit::LogQuadratic);
        assert!((dx - 0.4).abs() < 1e-12 && (dy + 0.15).abs() < 1e-12);
        // The plain quadratic is biased on the same peak.
        let (qx, _) = refine_peak(&n, PeakFit::Quadratic);
        assert!((qx - 0.4).abs() > 0.01);
    }

    #[test]
    fn rejects_saddles_and_minima() {
        assert!(quadratic_peak_2d(&sample(|x, y| x * x - y * y)).is_none());
        assert!(quadratic_peak_2d(&sample(|x, y| x * x + y * y)).is_none());
        assert_eq!(parabola_peak_1d(1.0, 0.0, 1.0), None);
        assert_eq!(parabola_peak_1d(0.0, 1.0, 0.0), Some(0.0));
        // Flat neighbourhood: no refinement, no NaN.
        assert_eq!(
            refine_peak(&[[1.0; 3]; 3], PeakFit::LogQuadratic),
            (0.0, 0.0)
        );
    }
}
