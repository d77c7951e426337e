//! The planimetric σ of one orthophoto control point from the precision of its correlation peak. A strong peak
//! (≥ `min_peak`) is located to `match_sigma_px`; a weak one — a template partly hidden in the orthophoto by a
//! tree crown, kept because it agrees with the recording's correction ([`super::corroborate`]) — is less
//! precise the weaker it is: its σ can grow with a power of the missing correlation, `match_sigma_px` ·
//! ((1 − peak) / (1 − min_peak))^`weak_sigma_exponent`; with exponent 2, a peak of 0.6 is located to about
//! 2.6 × and 0.5 to 4 × the strong peaks' σ at `min_peak` 0.75. The default exponent is 0 (every peak the
//! same σ): a recording whose only control is weak peaks then keeps its full weight. Optionally
//! (`weak_peaks_correlated`) the weak peaks of one recording are taken as one: the same crowns can displace
//! them alike, so each one's σ is multiplied by √(number of weak peaks the recording keeps), which gives their
//! mean the σ of a single weak peak.

/// How a weak peak's σ grows ([`match_sigma_px`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeakPeakSigma {
    /// Smallest peak located to `match_sigma_px`.
    pub min_peak: f64,
    /// A strong peak's matching σ, working pixels.
    pub match_sigma_px: f64,
    /// Power of the missing correlation (1 − peak) / (1 − min_peak) that multiplies a weak peak's σ.
    pub exponent: f64,
    /// Weak peaks of one recording taken as one (σ × √count).
    pub correlated: bool,
}

/// The matching σ of a control point whose correlation peak is `peak`, working pixels, among
/// `weak_in_recording` weak peaks kept for its recording (see the module documentation). A non-finite peak
/// counts as 0.
pub fn match_sigma_px(peak: f64, w: &WeakPeakSigma, weak_in_recording: usize) -> f64 {
    if peak >= w.min_peak {
        return w.match_sigma_px;
    }
    let peak = if peak.is_finite() { peak.max(0.0) } else { 0.0 };
    let missing = (1.0 - peak) / (1.0 - w.min_peak).max(1e-6);
    let shared = if w.correlated {
        (weak_in_recording.max(1) as f64).sqrt()
    } else {
        1.0
    };
    w.match_sigma_px * missing.powf(w.exponent) * shared
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strong_peaks_keep_the_stated_sigma_and_weak_ones_grow_with_the_missing_correlation() {
        let mut w = WeakPeakSigma {
            min_peak: 0.75,
            match_sigma_px: 0.3,
            exponent: 2.0,
            correlated: false,
        };
        assert_eq!(match_sigma_px(0.9, &w, 4), 0.3);
        assert_eq!(match_sigma_px(0.75, &w, 1), 0.3);
        // (1 − 0.5) / 0.25 = 2: 4 × 0.3.
        assert!((match_sigma_px(0.5, &w, 4) - 1.2).abs() < 1e-12);
        // 0.6: (0.4 / 0.25)² = 2.56.
        assert!((match_sigma_px(0.6, &w, 1) - 0.768).abs() < 1e-12);
        assert!((match_sigma_px(f64::NAN, &w, 1) - 0.3 * 16.0).abs() < 1e-12);
        // Never smaller for a weaker peak.
        let mut last = 0.0;
        for k in 0..=75 {
            let s = match_sigma_px(0.75 - k as f64 * 0.01, &w, 3);
            assert!(s >= last, "{s} < {last}");
            last = s;
        }
        // Correlated: × √4 among four weak peaks; exponent 0: the strong peaks' σ.
        w.correlated = true;
        assert!((match_sigma_px(0.5, &w, 4) - 2.4).abs() < 1e-12);
        w.correlated = false;
        w.exponent = 0.0;
        assert_eq!(match_sigma_px(0.55, &w, 4), 0.3);
    }
}
