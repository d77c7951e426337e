//! The trifocal tensor of three cameras with known projection matrices, and point transfer (thesis 4.4.1;
//! Hartley & Zisserman 2004, ch. 15–16; Hartley 1997 eq. 8; Hartley & Zisserman 2004 §15.1–15.3).
//!
//! Index convention: `t[i][j][k]` = T_i^(jk), where i is the covariant index of the view-1 point, j pairs
//! with a line in view 2 and k gives the view-3 point: `x''^k = Σ_i Σ_j x^i · l'_j · T_i^(jk)`.
//! The tensor is computed with the determinant form, valid for any three cameras (no canonical frame needed):
//! `T_i^(qr) = (−1)^(i+1) · det[ P1 without row i ; row q of P2 ; row r of P3 ]` (rows of P1 kept in order,
//! 1-based i), then normalised to unit Frobenius norm (the scale is irrelevant for transfer). The canonical
//! form `T_i = a_i·b4ᵀ − a4·b_iᵀ` for P1 = [I | 0] is [`TrifocalTensor::from_canonical`] (tests compare them).
//!
//! Projection matrices must be formed in a local frame ([`super::LocalOrigin`]), never in raw world
//! coordinates of ≈ 10⁵ m.

use nalgebra::{Matrix3, Matrix3x4, Matrix4, Vector3};

/// A trifocal tensor `t[i][j][k]` (see the module documentation), unit Frobenius norm.
#[derive(Clone, Debug, PartialEq)]
pub struct TrifocalTensor {
    pub t: [[[f64; 3]; 3]; 3],
    /// Fundamental matrix of views 1 → 2 (`l' = F21·x`), used to choose the transfer line.
    pub f21: Matrix3<f64>,
}

/// Why a point could not be transferred.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TransferError {
    #[error("the view-1 point lies at (or numerically at) the epipole: transfer is undefined")]
    AtEpipole,
    #[error("the transferred point lies at infinity in view 3")]
    AtInfinity,
}

/// Determinant of the 4×4 matrix made of rows `r0..r3`.
fn det4(r0: [f64; 4], r1: [f64; 4], r2: [f64; 4], r3: [f64; 4]) -> f64 {
    Matrix4::from_rows(&[r0.into(), r1.into(), r2.into(), r3.into()]).determinant()
}

fn row(p: &Matrix3x4<f64>, r: usize) -> [f64; 4] {
    [p[(r, 0)], p[(r, 1)], p[(r, 2)], p[(r, 3)]]
}

/// Cross-product matrix `[v]_×` (`[v]_×·w = v × w`).
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

fn normalised(mut t: [[[f64; 3]; 3]; 3]) -> [[[f64; 3]; 3]; 3] {
    let norm = t
        .iter()
        .flatten()
        .flatten()
        .map(|v| v * v)
        .sum::<f64>()
        .sqrt();
    if norm > 0.0 {
        t.iter_mut().flatten().flatten().for_each(|v| *v /= norm);
    }
    t
}

/// The fundamental matrix F21 with `x'ᵀ·F21·x = 0` from two projection matrices: `F21 = [e']_× P2 P1⁺`,
/// `e' = P2·C1` (C1 the null vector of P1). Unit Frobenius norm.
fn fundamental_21(p1: &Matrix3x4<f64>, p2: &Matrix3x4<f64>) -> Matrix3<f64> {
    // Camera centre of P1 (its null vector) by cofactors: C^c = (−1)^c·det(P1 without column c).
    let mut c1 = nalgebra::Vector4::zeros();
    for c in 0..4 {
        let cols: Vec<usize> = (0..4).filter(|&k| k != c).collect();
        let m = Matrix3::from_fn(|r, k| p1[(r, cols[k])]);
        c1[c] = if c % 2 == 0 { 1.0 } else { -1.0 } * m.determinant();
    }
    let e2 = p2 * c1;
    // P1⁺ = P1ᵀ(P1 P1ᵀ)⁻¹ (full row rank).
    let p1t = p1.transpose();
    let pinv = (p1 * p1t)
        .try_inverse()
        .map(|inv| p1t * inv)
        .unwrap_or_else(nalgebra::Matrix4x3::zeros);
    let f = skew(&e2) * p2 * pinv;
    let n = f.norm();
    if n > 0.0 {
        f / n
    } else {
        f
    }
}

impl TrifocalTensor {
    /// The tensor of three general cameras (determinant form, see the module documentation).
    pub fn from_cameras(p1: &Matrix3x4<f64>, p2: &Matrix3x4<f64>, p3: &Matrix3x4<f64>) -> Self {
        let mut t = [[[0.0; 3]; 3]; 3];
        for (i, ti) in t.iter_mut().enumerate() {
            // P1 without row i, remaining rows in order.
            let kept: Vec<[f64; 4]> = (0..3).filter(|&r| r != i).map(|r| row(p1, r)).collect();
            let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
            for (q, tq) in ti.iter_mut().enumerate() {
                for (r, v) in tq.iter_mut().enumerate() {
                    *v = sign * det4(kept[0], kept[1], row(p2, q), row(p3, r));
                }
            }
        }
        Self {
            t: normalised(t),
            f21: fundamental_21(p1, p2),
        }
    }

    /// The tensor for canonical cameras P1 = [I | 0], P2 = [A | a4], P3 = [B | b4]:
    /// `T_i^(jk) = a_i^j·b4^k − a4^j·b_i^k`. (`p1` is implied.)
    pub fn from_canonical(p2: &Matrix3x4<f64>, p3: &Matrix3x4<f64>) -> Self {
        let mut t = [[[0.0; 3]; 3]; 3];
        for (i, ti) in t.iter_mut().enumerate() {
            for (j, tj) in ti.iter_mut().enumerate() {
                for (k, v) in tj.iter_mut().enumerate() {
                    *v = p2[(j, i)] * p3[(k, 3)] - p2[(j, 3)] * p3[(k, i)];
                }
            }
        }
        let mut p1 = Matrix3x4::zeros();
        p1.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&Matrix3::identity());
        Self {
            t: normalised(t),
            f21: fundamental_21(&p1, p2),
        }
    }

    /// `Σ_i x^i·T_i` (a 3×3 matrix indexed `[j][k]`).
    pub fn contract_point(&self, x: &Vector3<f64>) -> Matrix3<f64> {
        let mut m = Matrix3::zeros();
        for i in 0..3 {
            for j in 0..3 {
                for k in 0..3 {
                    m[(j, k)] += x[i] * self.t[i][j][k];
                }
            }
        }
        m
    }

    /// Incidence residual `‖[x']_× (Σ_i x^i T_i) [x'']_×‖_F` for pixel points (homogeneous w = 1); 0 for an
    /// exact triple (scale: the tensor's unit norm times pixel coordinates squared).
    pub fn incidence_residual(&self, x1: [f64; 2], x2: [f64; 2], x3: [f64; 2]) -> f64 {
        let h = |p: [f64; 2]| Vector3::new(p[0], p[1], 1.0);
        (skew(&h(x2)).transpose() * self.contract_point(&h(x1)) * skew(&h(x3))).norm()
    }

    /// Point transfer (Hartley & Zisserman 2004, ch. 15–16 steps 1, 3, 4): the view-3 pixel of the point seen at `x1` in view 1
    /// and `x2` in view 2, through the line in view 2 that passes `x2` perpendicular to the epipolar line of
    /// `x1`.
    pub fn transfer(&self, x1: [f64; 2], x2: [f64; 2]) -> Result<[f64; 2], TransferError> {
        let x = Vector3::new(x1[0], x1[1], 1.0);
        let le = self.f21 * x;
        // Numerically at the epipole: the epipolar line is undefined (relative to the size of F·x).
        let scale = self.f21.norm() * x.norm();
        if !(le.x.hypot(le.y) > 1e-14 * scale) {
            return Err(TransferError::AtEpipole);
        }
        let (l1, l2) = (le.x, le.y);
        let lp = Vector3::new(l2, -l1, -x2[0] * l2 + x2[1] * l1);
        let mut out = Vector3::<f64>::zeros();
        for i in 0..3 {
            for j in 0..3 {
                let a = x[i] * lp[j];
                for (k, o) in out.iter_mut().enumerate() {
                    *o += a * self.t[i][j][k];
                }
            }
        }
        let s = out.norm();
        if !(out.z.abs() > 1e-14 * s) {
            return Err(TransferError::AtInfinity);
        }
        Ok([out.x / out.z, out.y / out.z])
    }

    /// Transfer error: distance in view 3 between the transferred point and the measured `x3`, pixels
    /// (infinite when the transfer is undefined).
    pub fn transfer_error(&self, x1: [f64; 2], x2: [f64; 2], x3: [f64; 2]) -> f64 {
        match self.transfer(x1, x2) {
            Ok(p) => (p[0] - x3[0]).hypot(p[1] - x3[1]),
            Err(_) => f64::INFINITY,
        }
    }
}
