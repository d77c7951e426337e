//! Brown lens distortion in the convention of campaign-format.md (normalised image y points up):
//! `r² = x² + y²`, `ρ = 1 + k1 r² + k2 r⁴ + k3 r⁶ + k4 r⁸`,
//! `x_b = x ρ + 2 p1 x y + p2 (r² + 2x²)`, `y_b = y ρ + p1 (r² + 2y²) + 2 p2 x y`,
//! then the affinity / non-orthogonality of the pixel axes (Metashape's b1, b2, in units of the focal length):
//! `x_d = x_b (1 + a1) + a2 y_b`, `y_d = y_b`, so that `u = cx + f·x_d = cx + (f + b1)·x_b + b2·y_b` with
//! `a1 = b1 / f`, `a2 = b2 / f`.

use serde::{Deserialize, Serialize};

/// Brown radial (k1…k4) and tangential (p1, p2) distortion coefficients plus the pixel-axis affinity (a1, a2);
/// all zero = no distortion.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BrownDistortion {
    pub k1: f64,
    pub k2: f64,
    /// Radial coefficient of r⁶ (optional column `k3`, default 0).
    #[serde(default)]
    pub k3: f64,
    /// Radial coefficient of r⁸ (optional column `k4`, default 0).
    #[serde(default)]
    pub k4: f64,
    pub p1: f64,
    pub p2: f64,
    /// Affinity: scale difference of the u axis, `b1 / focal_px` (dimensionless; column `b1` is in pixels).
    #[serde(default)]
    pub a1: f64,
    /// Non-orthogonality (skew) of the pixel axes, `b2 / focal_px` (dimensionless; column `b2` is in pixels).
    #[serde(default)]
    pub a2: f64,
}

/// Largest residual ‖distort(x, y) − (x_d, y_d)‖ (normalised units) accepted as converged by `undistort`.
pub const UNDISTORT_TOLERANCE: f64 = 1e-12;

const MAX_UNDISTORT_ITERATIONS: usize = 100;

impl BrownDistortion {
    /// No distortion.
    pub const NONE: Self = Self {
        k1: 0.0,
        k2: 0.0,
        k3: 0.0,
        k4: 0.0,
        p1: 0.0,
        p2: 0.0,
        a1: 0.0,
        a2: 0.0,
    };

    /// The classic four-coefficient model (k1, k2, p1, p2), everything else zero.
    pub fn k1k2p1p2(k1: f64, k2: f64, p1: f64, p2: f64) -> Self {
        Self {
            k1,
            k2,
            p1,
            p2,
            ..Self::NONE
        }
    }

    /// True when all coefficients are zero.
    pub fn is_zero(&self) -> bool {
        *self == Self::NONE
    }

    /// Radial factor `ρ(s) = 1 + k1 s + k2 s² + k3 s³ + k4 s⁴` at `s = r²` and its derivative `dρ/ds`.
    fn radial(&self, s: f64) -> (f64, f64) {
        let rho = 1.0 + s * (self.k1 + s * (self.k2 + s * (self.k3 + s * self.k4)));
        let drho = self.k1 + s * (2.0 * self.k2 + s * (3.0 * self.k3 + s * 4.0 * self.k4));
        (rho, drho)
    }

    /// Largest squared ideal radius r² = x² + y² up to which the radial part `r·ρ(r²)` keeps increasing
    /// (infinite if it always does). Beyond it the polynomial folds back, so far-away points would land inside
    /// the image: [`super::FrameCamera::project_world`] rejects them.
    ///
    /// `d(r ρ)/dr = 1 + 3 k1 s + 5 k2 s² + 7 k3 s³ + 9 k4 s⁴` with `s = r²`; the limit is its smallest positive
    /// root (closed form without k3, k4; otherwise bracketed on a geometric grid of s and bisected).
    pub fn max_monotonic_r2(&self) -> f64 {
        if self.k3 == 0.0 && self.k4 == 0.0 {
            return quadratic_limit(self.k1, self.k2);
        }
        let slope = |s: f64| {
            1.0 + s
                * (3.0 * self.k1 + s * (5.0 * self.k2 + s * (7.0 * self.k3 + s * 9.0 * self.k4)))
        };
        let mut lo = 0.0;
        let mut hi = 1e-8;
        while hi < 1e8 {
            if !(slope(hi) > 0.0) {
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if slope(mid) > 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                return lo;
            }
            lo = hi;
            hi *= 1.05;
        }
        f64::INFINITY
    }

    /// Ideal normalised coordinates → distorted normalised coordinates.
    pub fn distort(&self, x: f64, y: f64) -> (f64, f64) {
        let r2 = x * x + y * y;
        let (radial, _) = self.radial(r2);
        let xb = x * radial + 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x);
        let yb = y * radial + self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y;
        (xb * (1.0 + self.a1) + self.a2 * yb, yb)
    }

    /// Jacobian of [`Self::distort`]: `[[∂xd/∂x, ∂xd/∂y], [∂yd/∂x, ∂yd/∂y]]`.
    pub fn distort_jacobian(&self, x: f64, y: f64) -> [[f64; 2]; 2] {
        let r2 = x * x + y * y;
        // d(radial)/dx = 2x·g, d(radial)/dy = 2y·g
        let (radial, g) = self.radial(r2);
        let dxb_dx = radial + 2.0 * x * x * g + 2.0 * self.p1 * y + 6.0 * self.p2 * x;
        let dxb_dy = 2.0 * x * y * g + 2.0 * self.p1 * x + 2.0 * self.p2 * y;
        let dyb_dx = 2.0 * x * y * g + 2.0 * self.p1 * x + 2.0 * self.p2 * y;
        let dyb_dy = radial + 2.0 * y * y * g + 6.0 * self.p1 * y + 2.0 * self.p2 * x;
        let s = 1.0 + self.a1;
        [
            [s * dxb_dx + self.a2 * dyb_dx, s * dxb_dy + self.a2 * dyb_dy],
            [dyb_dx, dyb_dy],
        ]
    }

    /// Distorted → ideal normalised coordinates by Newton iteration on [`Self::distort`], converged to
    /// [`UNDISTORT_TOLERANCE`]. Outside the region where the distortion is invertible (far beyond any real
    /// image) it returns the best iterate found; use [`Self::try_undistort`] to detect that.
    pub fn undistort(&self, xd: f64, yd: f64) -> (f64, f64) {
        let (x, y, _) = self.undistort_iterate(xd, yd);
        (x, y)
    }

    /// Like [`Self::undistort`], but `None` when the iteration did not reach [`UNDISTORT_TOLERANCE`].
    pub fn try_undistort(&self, xd: f64, yd: f64) -> Option<(f64, f64)> {
        let (x, y, residual) = self.undistort_iterate(xd, yd);
        (residual <= UNDISTORT_TOLERANCE).then_some((x, y))
    }

    /// Newton iteration; returns the best (x, y) and its residual norm.
    fn undistort_iterate(&self, xd: f64, yd: f64) -> (f64, f64, f64) {
        if self.is_zero() {
            return (xd, yd, 0.0);
        }
        let (mut x, mut y) = (xd, yd);
        // Squared residuals (no hypot in the per-pixel path); stop at the rounding level of the coordinates.
        let stop_sq = (1e-16 * (1.0 + xd.abs() + yd.abs())).powi(2);
        let mut best = (x, y, f64::INFINITY);
        for _ in 0..MAX_UNDISTORT_ITERATIONS {
            let (fx, fy) = self.distort(x, y);
            let (ex, ey) = (fx - xd, fy - yd);
            let residual_sq = ex * ex + ey * ey;
            if residual_sq < best.2 {
                best = (x, y, residual_sq);
            }
            if residual_sq <= stop_sq || !residual_sq.is_finite() {
                break;
            }
            let [[a, b], [c, d]] = self.distort_jacobian(x, y);
            let det = a * d - b * c;
            if det.abs() < 1e-300 || !det.is_finite() {
                break;
            }
            let dx = (d * ex - b * ey) / det;
            let dy = (a * ey - c * ex) / det;
            x -= dx;
            y -= dy;
            if dx.abs() + dy.abs() <= 1e-17 * (1.0 + x.abs() + y.abs()) {
                let (fx, fy) = self.distort(x, y);
                let residual_sq = (fx - xd).powi(2) + (fy - yd).powi(2);
                if residual_sq < best.2 {
                    best = (x, y, residual_sq);
                }
                break;
            }
        }
        (best.0, best.1, best.2.sqrt())
    }
}

/// Smallest positive root of `1 + 3 k1 s + 5 k2 s²` (infinite if there is none).
fn quadratic_limit(k1: f64, k2: f64) -> f64 {
    let (a, b, c) = (5.0 * k2, 3.0 * k1, 1.0);
    if a == 0.0 {
        return if b < 0.0 { -c / b } else { f64::INFINITY };
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return f64::INFINITY;
    }
    // Numerically stable roots q/a and c/q.
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    let roots = [if q != 0.0 { c / q } else { f64::NAN }, q / a];
    roots
        .iter()
        .copied()
        .filter(|&s| s > 0.0)
        .fold(f64::INFINITY, f64::min)
}
