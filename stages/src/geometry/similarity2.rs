//! 2-D similarity transform (4 DoF: uniform scale, rotation, translation), Hartley & Zisserman 2004, ch. 4; used to register
//! MM ortho-image patches onto aerial patches (thesis 3.4.5.2).
//!
//! `x' = s·R(θ)·x + t = [a −b; b a]·x + (tx, ty)` with `a = s cos θ`, `b = s sin θ`.

use super::point_pair::PointPair;
use nalgebra::{Matrix3, Vector2};
use serde::{Deserialize, Serialize};

/// A 2-D similarity: `apply(p) = scale·R(rotation_rad)·p + (tx, ty)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Similarity2 {
    pub scale: f64,
    /// Counter-clockwise rotation in a frame with y up (clockwise on screen when y points down), radians.
    pub rotation_rad: f64,
    pub tx: f64,
    pub ty: f64,
}

impl Similarity2 {
    /// The similarity with this scale, counter-clockwise rotation (radians) and translation.
    pub fn new(scale: f64, rotation_rad: f64, tx: f64, ty: f64) -> Self {
        Self {
            scale,
            rotation_rad,
            tx,
            ty,
        }
    }

    /// The identity transform.
    pub fn identity() -> Self {
        Self::new(1.0, 0.0, 0.0, 0.0)
    }

    /// Whether the transform can map points: every parameter finite and the scale positive (above 1e-6).
    pub fn is_usable(&self) -> bool {
        [self.scale, self.rotation_rad, self.tx, self.ty]
            .iter()
            .all(|v| v.is_finite())
            && self.scale > 1e-6
    }

    /// From the linear parameters `a = s cos θ`, `b = s sin θ` and the translation.
    pub fn from_ab(a: f64, b: f64, tx: f64, ty: f64) -> Self {
        Self {
            scale: a.hypot(b),
            rotation_rad: b.atan2(a),
            tx,
            ty,
        }
    }

    /// The linear parameters (a, b) = (s cos θ, s sin θ).
    pub fn ab(&self) -> (f64, f64) {
        let (sin, cos) = self.rotation_rad.sin_cos();
        (self.scale * cos, self.scale * sin)
    }

    /// Transforms a point.
    pub fn apply(&self, p: &Vector2<f64>) -> Vector2<f64> {
        let (a, b) = self.ab();
        Vector2::new(a * p.x - b * p.y + self.tx, b * p.x + a * p.y + self.ty)
    }

    /// The inverse transform (the scale must be non-zero).
    pub fn inverse(&self) -> Self {
        let scale = 1.0 / self.scale;
        let rotation_rad = -self.rotation_rad;
        let rotated = Self {
            scale,
            rotation_rad,
            tx: 0.0,
            ty: 0.0,
        }
        .apply(&Vector2::new(self.tx, self.ty));
        Self {
            scale,
            rotation_rad,
            tx: -rotated.x,
            ty: -rotated.y,
        }
    }

    /// `self ∘ other`: applies `other` first, then `self`.
    pub fn compose(&self, other: &Self) -> Self {
        let t = self.apply(&Vector2::new(other.tx, other.ty));
        Self {
            scale: self.scale * other.scale,
            rotation_rad: wrap_angle_rad(self.rotation_rad + other.rotation_rad),
            tx: t.x,
            ty: t.y,
        }
    }

    /// The transform as a 3×3 homogeneous matrix.
    pub fn to_matrix(&self) -> Matrix3<f64> {
        let (a, b) = self.ab();
        Matrix3::new(a, -b, self.tx, b, a, self.ty, 0.0, 0.0, 1.0)
    }

    /// The exact transform mapping `src1 → dst1` and `src2 → dst2` (complex form `z' = α·z + β`);
    /// `None` if the two source points (numerically) coincide or the destination points do.
    pub fn from_two_pairs(
        src1: &Vector2<f64>,
        dst1: &Vector2<f64>,
        src2: &Vector2<f64>,
        dst2: &Vector2<f64>,
    ) -> Option<Self> {
        let pairs = [
            PointPair {
                src: *src1,
                dst: *dst1,
            },
            PointPair {
                src: *src2,
                dst: *dst2,
            },
        ];
        Self::least_squares_iter(pairs.iter())
    }

    /// Least-squares similarity from ≥ 2 correspondences (Umeyama 1991 specialised to 2-D, where it has the
    /// closed form below); `None` if fewer than 2 pairs or all source (or all destination) points coincide.
    pub fn least_squares(pairs: &[PointPair]) -> Option<Self> {
        Self::least_squares_iter(pairs.iter())
    }

    /// [`Self::least_squares`] over any re-iterable sequence of correspondences (no allocation).
    ///
    /// With centred coordinates (x, y) → (x', y'), minimising Σ‖x' − [a −b; b a] x‖² over (a, b) gives
    /// `a = Σ(x x' + y y') / Σ‖x‖²`, `b = Σ(x y' − y x') / Σ‖x‖²`; every (a, b) is a scaled rotation, so this
    /// equals Umeyama's SVD solution (no reflection can arise in 2-D). Then `t = μ' − [a −b; b a] μ`.
    pub fn least_squares_iter<'a, I>(pairs: I) -> Option<Self>
    where
        I: Iterator<Item = &'a PointPair> + Clone,
    {
        let mut n = 0usize;
        let mut mean_src = Vector2::zeros();
        let mut mean_dst = Vector2::zeros();
        for p in pairs.clone() {
            n += 1;
            mean_src += p.src;
            mean_dst += p.dst;
        }
        if n < 2 {
            return None;
        }
        mean_src /= n as f64;
        mean_dst /= n as f64;
        let (mut sxx, mut syy, mut sa, mut sb) = (0.0, 0.0, 0.0, 0.0);
        for p in pairs {
            let s = p.src - mean_src;
            let d = p.dst - mean_dst;
            sxx += s.norm_squared();
            syy += d.norm_squared();
            sa += s.x * d.x + s.y * d.y;
            sb += s.x * d.y - s.y * d.x;
        }
        // Spread must exceed the rounding level of the coordinates (world coordinates are ≈ 1e5).
        let min_spread_src = (1e-12 * (1.0 + mean_src.norm())).powi(2) * n as f64;
        let min_spread_dst = (1e-12 * (1.0 + mean_dst.norm())).powi(2) * n as f64;
        if !(sxx > min_spread_src && syy > min_spread_dst) {
            return None;
        }
        let a = sa / sxx;
        let b = sb / sxx;
        let tx = mean_dst.x - (a * mean_src.x - b * mean_src.y);
        let ty = mean_dst.y - (b * mean_src.x + a * mean_src.y);
        let sim = Self::from_ab(a, b, tx, ty);
        (sim.scale > 0.0 && sim.scale.is_finite() && tx.is_finite() && ty.is_finite())
            .then_some(sim)
    }

    /// Distance between `pair.dst` and the transformed `pair.src` (destination units).
    pub fn transfer_error(&self, pair: &PointPair) -> f64 {
        (self.apply(&pair.src) - pair.dst).norm()
    }
}

/// Wraps an angle into (−π, π].
fn wrap_angle_rad(a: f64) -> f64 {
    let w = a.sin().atan2(a.cos());
    if w == -std::f64::consts::PI {
        std::f64::consts::PI
    } else {
        w
    }
}
