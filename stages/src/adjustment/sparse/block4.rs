//! Dense 4 × 4 kernels of the block sparse Cholesky: one block per recording, over (x, y, z, ψ). Parameters a
//! configuration does not estimate are kept in the block as decoupled unit rows (identity on the diagonal,
//! zero elsewhere), so every block has the same size and the kernels are fully unrolled.

use nalgebra::{Matrix4, Vector4};

/// One 4 × 4 block.
pub type Block = Matrix4<f64>;
/// One 4-vector block of a right-hand side.
pub type BlockVector = Vector4<f64>;

/// A pivot is accepted when it exceeds this fraction of the diagonal entry it started from: a smaller one is
/// cancellation noise of a singular direction (a few hundred ε), not information.
pub const RELATIVE_PIVOT_TOLERANCE: f64 = 1e-13;

/// Cholesky factor L (lower triangular, A = L·Lᵀ) of the symmetric block `a` (its lower triangle is read).
/// `reference` holds the diagonal of the block before elimination updates; `Err(p)` names the component
/// whose pivot is not positive, not finite, or below [`RELATIVE_PIVOT_TOLERANCE`] of its reference.
pub fn cholesky(a: &Block, reference: &[f64; 4]) -> Result<Block, usize> {
    let mut l = Block::zeros();
    for j in 0..4 {
        let mut d = a[(j, j)];
        for k in 0..j {
            d -= l[(j, k)] * l[(j, k)];
        }
        let floor = RELATIVE_PIVOT_TOLERANCE * reference[j].abs();
        if !(d.is_finite() && d > 0.0 && d > floor) {
            return Err(j);
        }
        let ljj = d.sqrt();
        l[(j, j)] = ljj;
        for i in j + 1..4 {
            let mut s = a[(i, j)];
            for k in 0..j {
                s -= l[(i, k)] * l[(j, k)];
            }
            l[(i, j)] = s / ljj;
        }
    }
    Ok(l)
}

/// Solves L·x = b in place (L lower triangular).
pub fn solve_lower(l: &Block, b: &mut BlockVector) {
    for i in 0..4 {
        let mut s = b[i];
        for k in 0..i {
            s -= l[(i, k)] * b[k];
        }
        b[i] = s / l[(i, i)];
    }
}

/// Solves Lᵀ·x = b in place (L lower triangular).
pub fn solve_lower_transpose(l: &Block, b: &mut BlockVector) {
    for i in (0..4).rev() {
        let mut s = b[i];
        for k in i + 1..4 {
            s -= l[(k, i)] * b[k];
        }
        b[i] = s / l[(i, i)];
    }
}

/// X = A·L⁻ᵀ, i.e. the solution of X·Lᵀ = A (L lower triangular): row i of X solves L·xᵢ = aᵢ.
pub fn right_solve_lower_transpose(a: &Block, l: &Block) -> Block {
    let mut x = *a;
    for r in 0..4 {
        for j in 0..4 {
            let mut s = x[(r, j)];
            for k in 0..j {
                s -= x[(r, k)] * l[(j, k)];
            }
            x[(r, j)] = s / l[(j, j)];
        }
    }
    x
}

/// L⁻¹ of a lower-triangular block.
pub fn invert_lower(l: &Block) -> Block {
    let mut inv = Block::zeros();
    for c in 0..4 {
        let mut e = BlockVector::zeros();
        e[c] = 1.0;
        solve_lower(l, &mut e);
        inv.set_column(c, &e);
    }
    inv
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spd() -> Block {
        let m = Block::from_fn(|i, j| ((i * 4 + j) as f64 * 0.37).sin());
        m * m.transpose() + Block::identity() * 0.5
    }

    fn diagonal(a: &Block) -> [f64; 4] {
        [a[(0, 0)], a[(1, 1)], a[(2, 2)], a[(3, 3)]]
    }

    #[test]
    fn kernels_agree_with_dense_linear_algebra() {
        let a = spd();
        let l = cholesky(&a, &diagonal(&a)).unwrap();
        assert!((l * l.transpose() - a).amax() < 1e-14);
        let b = BlockVector::new(1.0, -2.0, 0.5, 3.0);
        let mut x = b;
        solve_lower(&l, &mut x);
        solve_lower_transpose(&l, &mut x);
        assert!((a * x - b).amax() < 1e-12);
        let m = Block::from_fn(|i, j| (i as f64) - 2.0 * (j as f64));
        let x = right_solve_lower_transpose(&m, &l);
        assert!((x * l.transpose() - m).amax() < 1e-12);
        assert!((invert_lower(&l) * l - Block::identity()).amax() < 1e-13);
    }

    #[test]
    fn singular_and_relatively_tiny_pivots_are_reported() {
        let mut a = Block::identity();
        a[(2, 2)] = 0.0;
        assert_eq!(cholesky(&a, &diagonal(&a)), Err(2));
        // A pivot that cancelled to 1e-15 of where it started is noise.
        let mut b = Block::identity();
        b[(1, 1)] = 1e-15;
        assert_eq!(cholesky(&b, &[1.0, 1.0, 1.0, 1.0]), Err(1));
        assert!(cholesky(&b, &diagonal(&b)).is_ok());
    }
}
