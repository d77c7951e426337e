//! The ratio of two counts, the form every inlier ratio, coverage fraction and resolution ratio of the
//! metrics takes.

/// `part / whole` as a number, 0 when `whole` is 0 (nothing to take a share of).
pub fn ratio_or_zero(part: usize, whole: usize) -> f64 {
    if whole == 0 {
        0.0
    } else {
        part as f64 / whole as f64
    }
}
