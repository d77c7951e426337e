//! Axis-aligned bounding boxes of point sets.

/// The axis-aligned bounding box of `points`: per axis the smallest and the largest coordinate (+∞ and −∞
/// when there are no points).
pub fn bounding_box<'a, const N: usize>(
    points: impl IntoIterator<Item = &'a [f64; N]>,
) -> ([f64; N], [f64; N]) {
    let mut lo = [f64::INFINITY; N];
    let mut hi = [f64::NEG_INFINITY; N];
    for p in points {
        for k in 0..N {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}
