//! A local origin for numerically stable solvers: world coordinates are ≈ 10⁵ m, so every normal equation,
//! SVD or least-squares problem first subtracts a nearby origin (a local origin keeps the normal equations well conditioned).

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// A translation of the world frame: `p_local = p_world − origin`. Axes stay the world axes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LocalOrigin {
    /// The origin of the local frame, world frame, metres.
    pub origin: Vector3<f64>,
}

impl LocalOrigin {
    /// A local frame with the given origin (world frame, metres).
    pub fn new(origin: Vector3<f64>) -> Self {
        Self { origin }
    }

    /// A local frame centred at the mean of `points_world`; `None` if there are no points.
    pub fn at_mean<'a, I>(points_world: I) -> Option<Self>
    where
        I: IntoIterator<Item = &'a Vector3<f64>>,
    {
        let mut sum = Vector3::zeros();
        let mut n = 0usize;
        for p in points_world {
            sum += p;
            n += 1;
        }
        (n > 0).then(|| Self::new(sum / n as f64))
    }

    /// World point → local coordinates (metres).
    pub fn to_local(&self, p_world: &Vector3<f64>) -> Vector3<f64> {
        p_world - self.origin
    }

    /// Local coordinates → world point (metres).
    pub fn to_world(&self, p_local: &Vector3<f64>) -> Vector3<f64> {
        p_local + self.origin
    }
}
