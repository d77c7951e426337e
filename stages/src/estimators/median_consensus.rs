//! Median consensus (thesis 4.4.6.3 for the 2-D patch shifts, 4.4.7 for the 3-D translations): the
//! component-wise median of a set of N-dimensional vectors is the consensus, each vector's Euclidean distance
//! to it is its deviation, and vectors within a threshold of the median are inliers.
//!
//! The median tolerates up to half of the set being outliers, which is why the thesis prefers it to RANSAC
//! for the small sets of translations one panorama × one aerial image yields.

/// The result of [`median_consensus`].
#[derive(Clone, Debug, PartialEq)]
pub struct MedianConsensus<const N: usize> {
    /// Component-wise median of the finite input vectors (even counts: mean of the two middle values).
    pub median: [f64; N],
    /// Euclidean distance of each input vector to `median`, in input order (`f64::INFINITY` for a vector
    /// with a non-finite component).
    pub deviations: Vec<f64>,
    /// `deviations[i] <= threshold`, in input order (a non-finite vector is never an inlier).
    pub inliers: Vec<bool>,
}

impl<const N: usize> MedianConsensus<N> {
    /// Number of inliers.
    pub fn inlier_count(&self) -> usize {
        self.inliers.iter().filter(|&&b| b).count()
    }
}

/// Median of a slice (sorted in place; even counts: mean of the two middle values). `None` when empty.
/// The values must be finite (callers filter).
pub fn median_in_place(values: &mut [f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    Some(if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    })
}

/// Component-wise median consensus of `values` with inlier `threshold` (same unit as the values).
///
/// Vectors with a non-finite component do not take part in the median, get an infinite deviation and are
/// outliers. Returns `None` when no vector is finite (in particular for an empty input).
/// Deterministic: the result does not depend on the input order (except that the per-vector outputs follow it).
pub fn median_consensus<const N: usize>(
    values: &[[f64; N]],
    threshold: f64,
) -> Option<MedianConsensus<N>> {
    let finite = |v: &[f64; N]| v.iter().all(|c| c.is_finite());
    let mut column: Vec<f64> = Vec::with_capacity(values.len());
    let mut median = [0.0; N];
    for (k, m) in median.iter_mut().enumerate() {
        column.clear();
        column.extend(values.iter().filter(|v| finite(v)).map(|v| v[k]));
        *m = median_in_place(&mut column)?;
    }
    let deviations: Vec<f64> = values
        .iter()
        .map(|v| {
            if finite(v) {
                v.iter()
                    .zip(median.iter())
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum::<f64>()
                    .sqrt()
            } else {
                f64::INFINITY
            }
        })
        .collect();
    let inliers = deviations.iter().map(|&d| d <= threshold).collect();
    Some(MedianConsensus {
        median,
        deviations,
        inliers,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    #[test]
    fn empty_input_gives_none() {
        assert!(median_consensus::<3>(&[], 0.5).is_none());
        assert!(median_consensus::<2>(&[[f64::NAN, 0.0]], 0.5).is_none());
    }

    #[test]
    fn odd_and_even_medians() {
        let r = median_consensus(&[[1.0], [5.0], [3.0]], 1.0).unwrap();
        assert_eq!(r.median, [3.0]);
        assert_eq!(r.deviations, vec![2.0, 2.0, 0.0]);
        assert_eq!(r.inliers, vec![false, false, true]);
        let r =
            median_consensus(&[[1.0, 10.0], [4.0, 0.0], [2.0, 20.0], [3.0, 30.0]], 10.0).unwrap();
        assert_eq!(r.median, [2.5, 15.0]);
        assert!((r.deviations[0] - (1.5f64 * 1.5 + 25.0).sqrt()).abs() < 1e-12);
        assert_eq!(r.inliers, vec![true, false, true, false]);
    }

    #[test]
    fn threshold_is_inclusive_and_nan_is_outlier() {
        let r =
            median_consensus(&[[0.0, 0.0], [0.0, 0.0], [3.0, 4.0], [f64::NAN, 0.0]], 5.0).unwrap();
        assert_eq!(r.median, [0.0, 0.0]);
        assert_eq!(r.deviations[2], 5.0);
        assert_eq!(r.inliers, vec![true, true, true, false]);
        assert!(r.deviations[3].is_infinite());
    }

    #[test]
    fn injected_outliers_are_rejected_and_inliers_kept() {
        let mut rng = SplitMix64::new(42);
        let truth = [0.8, -0.3, 0.1];
        let mut values = Vec::new();
        let mut expected = Vec::new();
        for i in 0..40 {
            let noise = |r: &mut SplitMix64| (r.next_f64() - 0.5) * 0.1; // ±5 cm
            if i % 4 == 3 {
                // 10 outliers 2 m away in varying directions.
                let a = i as f64;
                values.push([truth[0] + 2.0 * a.cos(), truth[1] + 2.0 * a.sin(), truth[2]]);
                expected.push(false);
            } else {
                values.push([
                    truth[0] + noise(&mut rng),
                    truth[1] + noise(&mut rng),
                    truth[2] + noise(&mut rng),
                ]);
                expected.push(true);
            }
        }
        let r = median_consensus(&values, 0.5).unwrap();
        assert_eq!(r.inliers, expected);
        for (m, t) in r.median.iter().zip(truth) {
            assert!((m - t).abs() < 0.05, "{:?}", r.median);
        }
        assert_eq!(r.inlier_count(), 30);
    }
}
