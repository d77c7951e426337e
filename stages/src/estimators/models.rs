//! [`Model`] implementations of the 2-D transforms for [`super::ransac`] (ALGORITHMS.md §11): the datum is a
//! [`PointPair`], the residual the one-way transfer error in the destination image.

use super::ransac::Model;
use crate::geometry::{Homography, PointPair, Similarity2};

/// Similarity (4 DoF) from 2 pairs (exact) or more (least squares, Umeyama).
impl Model for Similarity2 {
    const MIN_SAMPLES: usize = 2;
    type Datum = PointPair;

    fn fit(data: &[&PointPair]) -> Option<Self> {
        Similarity2::least_squares_iter(data.iter().copied())
    }

    fn residual(&self, d: &PointPair) -> f64 {
        self.transfer_error(d)
    }
}

/// Homography from 4 pairs (exact; rejected if 3 are collinear) or more (normalised DLT).
impl Model for Homography {
    const MIN_SAMPLES: usize = 4;
    type Datum = PointPair;

    fn fit(data: &[&PointPair]) -> Option<Self> {
        Homography::from_pairs_iter(data.iter().copied())
    }

    fn residual(&self, d: &PointPair) -> f64 {
        self.transfer_error(d)
    }
}
