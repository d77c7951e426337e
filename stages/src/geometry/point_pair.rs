//! A 2-D point correspondence (source image → destination image), the datum of the 2-D transform
//! estimators ([`super::Similarity2`], [`super::Homography`]) and of RANSAC.

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

/// One correspondence: `src` in the source image/plane maps to `dst` in the destination.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointPair {
    pub src: Vector2<f64>,
    pub dst: Vector2<f64>,
}

impl PointPair {
    /// A correspondence from coordinates.
    pub fn new(src_x: f64, src_y: f64, dst_x: f64, dst_y: f64) -> Self {
        Self {
            src: Vector2::new(src_x, src_y),
            dst: Vector2::new(dst_x, dst_y),
        }
    }
}
