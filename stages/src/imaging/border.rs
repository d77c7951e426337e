//! Border handling for filters and samplers: how an out-of-range pixel index is mapped into the image.
//!
//! Pixel index `i` covers the continuous interval `[i, i + 1)` (centre `i + 0.5`, campaign-format.md), so the
//! image edge sits at coordinate 0 and at `n`. [`Border::Reflect`] mirrors about those edges
//! (`… 1 0 | 0 1 2 … n-1 | n-1 n-2 …`, OpenCV's `BORDER_REFLECT`), which keeps a smooth image smooth and makes
//! filters symmetric about the edge.

/// What a filter or sampler sees outside the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Border {
    /// Mirror about the image edge: index −1 → 0, −2 → 1, n → n − 1 (`BORDER_REFLECT`).
    Reflect,
    /// Repeat the edge pixel (`BORDER_REPLICATE`).
    Clamp,
    /// A constant value outside the image (`BORDER_CONSTANT`).
    Constant(f32),
}

/// Mirror index `i` into `0..n` about the edges at 0 and `n` (period `2n`, valid for any `i`). `n` must be > 0.
#[inline]
pub fn reflect_index(i: isize, n: usize) -> usize {
    let n = n as isize;
    let m = i.rem_euclid(2 * n);
    (if m < n { m } else { 2 * n - 1 - m }) as usize
}

/// Clamp index `i` into `0..n`. `n` must be > 0.
#[inline]
pub fn clamp_index(i: isize, n: usize) -> usize {
    i.clamp(0, n as isize - 1) as usize
}

impl Border {
    /// Index into `0..n` for `i`, or `None` for [`Border::Constant`] when `i` is outside. `n` must be > 0.
    #[inline]
    pub fn map_index(self, i: isize, n: usize) -> Option<usize> {
        if i >= 0 && (i as usize) < n {
            return Some(i as usize);
        }
        match self {
            Border::Reflect => Some(reflect_index(i, n)),
            Border::Clamp => Some(clamp_index(i, n)),
            Border::Constant(_) => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reflect_mirrors_about_edges() {
        let got: Vec<usize> = (-4..8).map(|i| reflect_index(i, 4)).collect();
        assert_eq!(got, vec![3, 2, 1, 0, 0, 1, 2, 3, 3, 2, 1, 0]);
        assert_eq!(reflect_index(-1, 1), 0);
        assert_eq!(reflect_index(17, 1), 0);
    }

    #[test]
    fn clamp_and_constant() {
        assert_eq!(Border::Clamp.map_index(-3, 5), Some(0));
        assert_eq!(Border::Clamp.map_index(9, 5), Some(4));
        assert_eq!(Border::Constant(0.0).map_index(5, 5), None);
        assert_eq!(Border::Constant(0.0).map_index(2, 5), Some(2));
    }
}
