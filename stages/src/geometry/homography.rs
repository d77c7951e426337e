//! 2-D projective transform (homography) estimated by the normalised DLT (Hartley & Zisserman alg. 4.2,
//! Hartley & Zisserman 2004, ch. 4); used between adjacent MM ortho-images (thesis 3.4.4).

use super::point_pair::PointPair;
use super::similarity2::Similarity2;
use nalgebra::{Matrix3, SMatrix, Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// A homography `x' ~ H·x` on homogeneous 2-D points (defined up to scale).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Homography(pub Matrix3<f64>);

impl From<Similarity2> for Homography {
    fn from(sim: Similarity2) -> Self {
        Self(sim.to_matrix())
    }
}

/// Rows of the DLT design matrix are reduced into this 9×9 triangle (Givens QR), so any number of
/// correspondences is handled without allocation and without squaring the condition number.
type Mat9 = SMatrix<f64, 9, 9>;

/// Smallest accepted ratio of the second-smallest to the largest singular value of the normalised DLT system
/// (below it the points do not determine a homography, e.g. all on one line).
const MIN_RANK_RATIO: f64 = 1e-9;

/// Smallest accepted |sin| of the angle at a vertex for three points of a minimal sample not to count as
/// collinear.
const MIN_SIN_COLLINEAR: f64 = 1e-6;

impl Homography {
    /// The identity transform.
    pub fn identity() -> Self {
        Self(Matrix3::identity())
    }

    /// Transforms a point; `None` if it maps to infinity (homogeneous w ≈ 0) or the result is not finite.
    pub fn apply(&self, p: &Vector2<f64>) -> Option<Vector2<f64>> {
        let h = &self.0;
        let x = h[(0, 0)] * p.x + h[(0, 1)] * p.y + h[(0, 2)];
        let y = h[(1, 0)] * p.x + h[(1, 1)] * p.y + h[(1, 2)];
        let w = h[(2, 0)] * p.x + h[(2, 1)] * p.y + h[(2, 2)];
        let w_scale = (h[(2, 0)] * p.x).abs() + (h[(2, 1)] * p.y).abs() + h[(2, 2)].abs();
        if !(w.abs() > 1e-14 * w_scale) {
            return None;
        }
        let out = Vector2::new(x / w, y / w);
        (out.x.is_finite() && out.y.is_finite()).then_some(out)
    }

    /// The inverse transform; `None` if the matrix is singular.
    pub fn inverse(&self) -> Option<Self> {
        self.0.try_inverse().map(|m| Self(m).normalized())
    }

    /// `self ∘ other`: applies `other` first, then `self`.
    pub fn compose(&self, other: &Self) -> Self {
        Self(self.0 * other.0).normalized()
    }

    /// The same transform scaled to unit Frobenius norm, sign chosen so that h33 > 0 (or, if h33 = 0, the
    /// entry of largest magnitude is positive). Two equal homographies have equal normalised matrices.
    pub fn normalized(&self) -> Self {
        let norm = self.0.norm();
        if !(norm > 0.0) {
            return *self;
        }
        let reference = if self.0[(2, 2)] != 0.0 {
            self.0[(2, 2)]
        } else {
            self.0.iter().copied().fold(
                0.0,
                |best: f64, v| if v.abs() > best.abs() { v } else { best },
            )
        };
        Self(self.0 * (reference.signum() / norm))
    }

    /// Distance between `pair.dst` and the transformed `pair.src` (one-way transfer error, destination
    /// units); infinite if `pair.src` maps to infinity.
    pub fn transfer_error(&self, pair: &PointPair) -> f64 {
        match self.apply(&pair.src) {
            Some(p) => (p - pair.dst).norm(),
            None => f64::INFINITY,
        }
    }

    /// Normalised DLT from ≥ 4 correspondences (least squares in the algebraic sense for more than 4);
    /// `None` if degenerate: fewer than 4 pairs, a 4-point sample with 3 collinear points in either image,
    /// points that do not determine a homography (rank test on the DLT system), or a singular result.
    pub fn from_pairs(pairs: &[PointPair]) -> Option<Self> {
        Self::from_pairs_iter(pairs.iter())
    }

    /// [`Self::from_pairs`] over any re-iterable sequence of correspondences (no allocation).
    pub fn from_pairs_iter<'a, I>(pairs: I) -> Option<Self>
    where
        I: Iterator<Item = &'a PointPair> + Clone,
    {
        let n = pairs.clone().count();
        if n < 4 {
            return None;
        }
        if n == 4 {
            let mut src = [Vector2::zeros(); 4];
            let mut dst = [Vector2::zeros(); 4];
            for (i, p) in pairs.clone().enumerate() {
                src[i] = p.src;
                dst[i] = p.dst;
            }
            if has_three_collinear(&src) || has_three_collinear(&dst) {
                return None;
            }
        }
        let t_src = hartley_normalisation(pairs.clone().map(|p| &p.src))?;
        let t_dst = hartley_normalisation(pairs.clone().map(|p| &p.dst))?;

        let mut r = Mat9::zeros();
        for p in pairs {
            let s = t_src * Vector3::new(p.src.x, p.src.y, 1.0);
            let d = t_dst * Vector3::new(p.dst.x, p.dst.y, 1.0);
            let (x, y, w) = (s.x, s.y, s.z);
            let (xp, yp, wp) = (d.x, d.y, d.z);
            givens_add_row(
                &mut r,
                [
                    0.0,
                    0.0,
                    0.0,
                    -wp * x,
                    -wp * y,
                    -wp * w,
                    yp * x,
                    yp * y,
                    yp * w,
                ],
            );
            givens_add_row(
                &mut r,
                [
                    wp * x,
                    wp * y,
                    wp * w,
                    0.0,
                    0.0,
                    0.0,
                    -xp * x,
                    -xp * y,
                    -xp * w,
                ],
            );
        }
        let svd = r.svd(false, true);
        let v_t = svd.v_t?;
        let sv = svd.singular_values;
        let (mut i_min, mut i_max) = (0, 0);
        for i in 1..9 {
            if sv[i] < sv[i_min] {
                i_min = i;
            }
            if sv[i] > sv[i_max] {
                i_max = i;
            }
        }
        let second_smallest = (0..9)
            .filter(|&i| i != i_min)
            .map(|i| sv[i])
            .fold(f64::INFINITY, f64::min);
        if !(second_smallest > MIN_RANK_RATIO * sv[i_max]) {
            return None;
        }
        let h = v_t.row(i_min);
        let h_norm = Matrix3::new(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8]);
        // A (near-)singular homography maps the plane onto a line: degenerate.
        if !(h_norm.determinant().abs() > 1e-12 * h_norm.norm().powi(3)) {
            return None;
        }
        let t_dst_inv = t_dst.try_inverse()?;
        let out = Self(t_dst_inv * h_norm * t_src).normalized();
        out.0.iter().all(|v| v.is_finite()).then_some(out)
    }
}

/// Hartley normalisation: translate the centroid to 0 and scale the mean distance to √2.
/// `None` if the points (numerically) coincide.
pub(super) fn hartley_normalisation<'a, I>(points: I) -> Option<Matrix3<f64>>
where
    I: Iterator<Item = &'a Vector2<f64>> + Clone,
{
    let mut n = 0usize;
    let mut mean = Vector2::zeros();
    for p in points.clone() {
        mean += p;
        n += 1;
    }
    mean /= n as f64;
    let mean_dist = points.map(|p| (p - mean).norm()).sum::<f64>() / n as f64;
    if !(mean_dist > 1e-12 * (1.0 + mean.norm())) {
        return None;
    }
    let s = std::f64::consts::SQRT_2 / mean_dist;
    Some(Matrix3::new(
        s,
        0.0,
        -s * mean.x,
        0.0,
        s,
        -s * mean.y,
        0.0,
        0.0,
        1.0,
    ))
}

/// True if any three of the four points are (numerically) collinear.
fn has_three_collinear(p: &[Vector2<f64>; 4]) -> bool {
    const TRIPLES: [[usize; 3]; 4] = [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]];
    TRIPLES.iter().any(|&[i, j, k]| {
        let a = p[j] - p[i];
        let b = p[k] - p[i];
        let c = p[k] - p[j];
        // |a × b| = 2·area = (two longest sides) · sin(smallest angle): thin triangles are collinear.
        let mut sides = [a.norm(), b.norm(), c.norm()];
        sides.sort_by(f64::total_cmp);
        let cross = (a.x * b.y - a.y * b.x).abs();
        !(cross > MIN_SIN_COLLINEAR * sides[1] * sides[2])
    })
}

/// Adds one row to the upper-triangular factor `r` of the rows seen so far (Givens rotations).
fn givens_add_row(r: &mut Mat9, mut row: [f64; 9]) {
    for i in 0..9 {
        if row[i] == 0.0 {
            continue;
        }
        let a = r[(i, i)];
        let b = row[i];
        let h = a.hypot(b);
        let (c, s) = (a / h, b / h);
        for j in i..9 {
            let rij = r[(i, j)];
            let xj = row[j];
            r[(i, j)] = c * rij + s * xj;
            row[j] = c * xj - s * rij;
        }
    }
}
