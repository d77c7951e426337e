//! Geometric refinement of a homography: Levenberg–Marquardt on the one-way transfer error
//! Σ‖x'_i − π(H x_i)‖² (Hartley & Zisserman 2004, ch. 4: OpenCV's `findHomography` likewise LM-refines the DLT result on the
//! inliers). The DLT minimises an algebraic error; with noisy points this refinement gives the
//! maximum-likelihood estimate for Gaussian noise in the destination image.
//!
//! Works in Hartley-normalised coordinates (isotropic scaling, so the cost is the original one times a
//! constant) with h33 fixed to 1 there (h33 = 0 would send the source centroid to infinity).

use super::homography::{hartley_normalisation, Homography};
use super::point_pair::PointPair;
use nalgebra::{Matrix3, SMatrix, SVector};

type Params = SVector<f64, 8>;

/// Largest number of damping increases tried within one LM iteration.
const MAX_DAMPING_TRIES: usize = 12;

impl Homography {
    /// LM refinement of `self` on the transfer error of `pairs` (≥ 5 pairs; otherwise, or if the
    /// normalisation is degenerate, `self` is returned unchanged). Never returns a worse fit than `self`.
    pub fn refine_transfer_error<'a, I>(&self, pairs: I, max_iterations: usize) -> Self
    where
        I: Iterator<Item = &'a PointPair> + Clone,
    {
        self.try_refine(pairs, max_iterations).unwrap_or(*self)
    }

    fn try_refine<'a, I>(&self, pairs: I, max_iterations: usize) -> Option<Self>
    where
        I: Iterator<Item = &'a PointPair> + Clone,
    {
        if pairs.clone().count() < 5 {
            return None;
        }
        let t_src = hartley_normalisation(pairs.clone().map(|p| &p.src))?;
        let t_dst = hartley_normalisation(pairs.clone().map(|p| &p.dst))?;
        let h_n = t_dst * self.0 * t_src.try_inverse()?;
        if !(h_n[(2, 2)].abs() > 1e-8 * h_n.norm()) {
            return None;
        }
        let h_n = h_n / h_n[(2, 2)];
        let mut params = Params::from_iterator(h_n.transpose().iter().copied().take(8));
        let normalised = |p: &PointPair| {
            let s = t_src * nalgebra::Vector3::new(p.src.x, p.src.y, 1.0);
            let d = t_dst * nalgebra::Vector3::new(p.dst.x, p.dst.y, 1.0);
            (s.x, s.y, d.x, d.y)
        };
        let cost = |h: &Params| -> f64 {
            let mut sum = 0.0;
            for p in pairs.clone() {
                let (x, y, xp, yp) = normalised(p);
                let w = h[6] * x + h[7] * y + 1.0;
                if !(w > 1e-9) {
                    return f64::INFINITY;
                }
                let u = (h[0] * x + h[1] * y + h[2]) / w;
                let v = (h[3] * x + h[4] * y + h[5]) / w;
                sum += (u - xp).powi(2) + (v - yp).powi(2);
            }
            sum
        };
        let mut current = cost(&params);
        if !current.is_finite() {
            return None;
        }
        let mut lambda = 1e-3;
        for _ in 0..max_iterations {
            let mut jtj = SMatrix::<f64, 8, 8>::zeros();
            let mut jtr = Params::zeros();
            for p in pairs.clone() {
                let (x, y, xp, yp) = normalised(p);
                let h = &params;
                let w = h[6] * x + h[7] * y + 1.0;
                let u = (h[0] * x + h[1] * y + h[2]) / w;
                let v = (h[3] * x + h[4] * y + h[5]) / w;
                let ju =
                    Params::from([x / w, y / w, 1.0 / w, 0.0, 0.0, 0.0, -u * x / w, -u * y / w]);
                let jv =
                    Params::from([0.0, 0.0, 0.0, x / w, y / w, 1.0 / w, -v * x / w, -v * y / w]);
                jtj += ju * ju.transpose() + jv * jv.transpose();
                jtr += ju * (u - xp) + jv * (v - yp);
            }
            let mut improved = false;
            for _ in 0..MAX_DAMPING_TRIES {
                let mut a = jtj;
                for i in 0..8 {
                    a[(i, i)] += lambda * (jtj[(i, i)] + 1e-12);
                }
                let Some(chol) = a.cholesky() else {
                    lambda *= 10.0;
                    continue;
                };
                let candidate = params - chol.solve(&jtr);
                let c = cost(&candidate);
                if c < current {
                    let gain = (current - c) / current.max(f64::MIN_POSITIVE);
                    params = candidate;
                    current = c;
                    lambda = (lambda * 0.1).max(1e-12);
                    improved = gain > 1e-14;
                    break;
                }
                lambda *= 10.0;
            }
            if !improved {
                break;
            }
        }
        let h_n = Matrix3::new(
            params[0], params[1], params[2], params[3], params[4], params[5], params[6], params[7],
            1.0,
        );
        let out = Self(t_dst.try_inverse()? * h_n * t_src).normalized();
        out.0.iter().all(|v| v.is_finite()).then_some(out)
    }
}
