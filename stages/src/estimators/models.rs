//! [`Model`] implementations of the 2-D transforms for [`super::ransac`](mod@super::ransac) (Hartley & Zisserman 2004, ch. 4): the datum is a
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

/// Levenberg–Marquardt iterations of the least-squares refit on more than 4 pairs.
pub const HOMOGRAPHY_REFINE_ITERATIONS: usize = 10;

/// Homography from 4 pairs (exact; rejected if 3 are collinear) or more (normalised DLT, then LM on the
/// transfer error, as OpenCV's `findHomography` does on its inliers).
impl Model for Homography {
    const MIN_SAMPLES: usize = 4;
    type Datum = PointPair;

    fn fit(data: &[&PointPair]) -> Option<Self> {
        let dlt = Homography::from_pairs_iter(data.iter().copied())?;
        if data.len() == Self::MIN_SAMPLES {
            return Some(dlt);
        }
        Some(dlt.refine_transfer_error(data.iter().copied(), HOMOGRAPHY_REFINE_ITERATIONS))
    }

    fn residual(&self, d: &PointPair) -> f64 {
        self.transfer_error(d)
    }
}
