//! Numeric block sparse Cholesky factorisation A = L·Lᵀ on the structure of a [`Symbolic`] analysis
//! (right-looking: each finished column updates the later columns it couples), and solves with the factor.
//! Sequential and in a fixed order, so the result does not depend on the thread count.

use super::block4::{self, Block, BlockVector};
use super::symbolic::{Slot, Symbolic};

/// A non-positive (or relatively vanishing) pivot: the matrix is not positive definite there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pivot {
    /// Block row in the caller's numbering.
    pub block: usize,
    /// Component 0..4 within the block.
    pub component: usize,
}

/// Matrix values on the factor's structure; after [`Factor::factorize`] the factor L itself.
#[derive(Clone, Debug, PartialEq)]
pub struct Factor {
    /// Diagonal blocks (new numbering): A's before, L's (lower triangular) after factorisation.
    diagonal: Vec<Block>,
    /// Strictly lower blocks in the symbolic's column storage order.
    lower: Vec<Block>,
}

impl Factor {
    /// A zero matrix on the structure of `symbolic`.
    pub fn zeros(symbolic: &Symbolic) -> Self {
        Self {
            diagonal: vec![Block::zeros(); symbolic.dim()],
            lower: vec![Block::zeros(); symbolic.lower_blocks()],
        }
    }

    /// Sets every value to zero (for the next assembly).
    pub fn clear(&mut self) {
        self.diagonal.iter_mut().for_each(|b| *b = Block::zeros());
        self.lower.iter_mut().for_each(|b| *b = Block::zeros());
    }

    /// Adds the matrix block `value` at `slot` (for a diagonal slot only its lower triangle is used).
    pub fn add(&mut self, slot: Slot, value: &Block) {
        match slot {
            Slot::Diagonal(j) => self.diagonal[j] += value,
            Slot::Lower(k) => self.lower[k] += value,
            Slot::Upper(k) => self.lower[k] += value.transpose(),
        }
    }

    /// Diagonal block of new column `j`.
    pub fn diagonal(&self, j: usize) -> &Block {
        &self.diagonal[j]
    }

    /// Strictly lower block at storage position `k`.
    pub fn lower(&self, k: usize) -> &Block {
        &self.lower[k]
    }

    /// Replaces the assembled matrix by its Cholesky factor. On a failing pivot the values are left
    /// partially factorised and the pivot is named in the caller's numbering.
    pub fn factorize(&mut self, symbolic: &Symbolic) -> Result<(), Pivot> {
        let reference: Vec<[f64; 4]> = self
            .diagonal
            .iter()
            .map(|d| [d[(0, 0)], d[(1, 1)], d[(2, 2)], d[(3, 3)]])
            .collect();
        for (j, reference) in reference.iter().enumerate() {
            let ljj =
                block4::cholesky(&self.diagonal[j], reference).map_err(|component| Pivot {
                    block: symbolic.perm()[j],
                    component,
                })?;
            self.diagonal[j] = ljj;
            let start = symbolic.column_start(j);
            let rows = symbolic.column(j);
            for k in start..start + rows.len() {
                self.lower[k] = block4::right_solve_lower_transpose(&self.lower[k], &ljj);
            }
            // Update the later columns: A(i1, i2) −= L(i1, j)·L(i2, j)ᵀ for i1 ≥ i2 in column j. The rows
            // after i2 in column j are a subset of column i2's rows, both ascending: one merge walk finds them.
            for (a, &i2) in rows.iter().enumerate() {
                let l2t = self.lower[start + a].transpose();
                let diag_update = self.lower[start + a] * l2t;
                self.diagonal[i2] -= diag_update;
                for (b, k) in symbolic.merge_walk(j, a) {
                    let update = self.lower[start + b] * l2t;
                    self.lower[k] -= update;
                }
            }
        }
        Ok(())
    }

    /// Solves A·x = b in place with the factor (`b` in the caller's block numbering).
    pub fn solve_in_place(&self, symbolic: &Symbolic, b: &mut [BlockVector]) {
        let n = symbolic.dim();
        let perm = symbolic.perm();
        let mut y: Vec<BlockVector> = perm.iter().map(|&old| b[old]).collect();
        for j in 0..n {
            block4::solve_lower(&self.diagonal[j], &mut y[j]);
            let yj = y[j];
            let start = symbolic.column_start(j);
            for (k, &i) in symbolic.column(j).iter().enumerate() {
                y[i] -= self.lower[start + k] * yj;
            }
        }
        for j in (0..n).rev() {
            let start = symbolic.column_start(j);
            let mut s = y[j];
            for (k, &i) in symbolic.column(j).iter().enumerate() {
                s -= self.lower[start + k].tr_mul(&y[i]);
            }
            block4::solve_lower_transpose(&self.diagonal[j], &mut s);
            y[j] = s;
        }
        for (new, &old) in perm.iter().enumerate() {
            b[old] = y[new];
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::adjustment::sparse::csr::Csr;
    use crate::rng::SplitMix64;
    use nalgebra::DMatrix;

    /// A random symmetric positive definite block matrix: a chain plus random long-range couplings. Returns
    /// the lower pattern, the blocks (r, c, value) with c ≤ r, and the dense matrix.
    pub(crate) fn random_spd(
        n: usize,
        extra: usize,
        seed: u64,
    ) -> (Csr, Vec<(usize, usize, Block)>, DMatrix<f64>) {
        let mut rng = SplitMix64::new(seed);
        let mut pairs: Vec<(usize, usize)> = (1..n).map(|r| (r, r - 1)).collect();
        for _ in 0..extra {
            let a = rng.below(n as u64) as usize;
            let b = rng.below(n as u64) as usize;
            if a != b {
                pairs.push((a.max(b), a.min(b)));
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let mut blocks = Vec::new();
        let mut dense = DMatrix::<f64>::zeros(4 * n, 4 * n);
        for &(r, c) in &pairs {
            let v = Block::from_fn(|_, _| rng.next_f64() - 0.5);
            blocks.push((r, c, v));
            dense.view_mut((4 * r, 4 * c), (4, 4)).copy_from(&v);
            dense
                .view_mut((4 * c, 4 * r), (4, 4))
                .copy_from(&v.transpose());
        }
        // Diagonal dominance makes it positive definite.
        for r in 0..n {
            let m = Block::from_fn(|_, _| rng.next_f64() - 0.5);
            let d = m * m.transpose() + Block::identity() * (4.0 * n as f64).sqrt() * 3.0;
            blocks.push((r, r, d));
            dense.view_mut((4 * r, 4 * r), (4, 4)).copy_from(&d);
        }
        let lower = Csr::from_pairs(n, pairs.iter().copied());
        (lower, blocks, dense)
    }

    pub(crate) fn assemble(symbolic: &Symbolic, blocks: &[(usize, usize, Block)]) -> Factor {
        let mut f = Factor::zeros(symbolic);
        for &(r, c, ref v) in blocks {
            f.add(symbolic.slot(r, c).unwrap(), v);
        }
        f
    }

    #[test]
    fn solves_like_a_dense_cholesky_in_any_order() {
        let n = 30;
        let (lower, blocks, dense) = random_spd(n, 25, 3);
        let b = nalgebra::DVector::from_fn(4 * n, |i, _| (i as f64 * 0.7).cos());
        let expected = dense.clone().cholesky().unwrap().solve(&b);
        let mut rng = SplitMix64::new(9);
        let mut shuffled: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            shuffled.swap(i, rng.below(i as u64 + 1) as usize);
        }
        for perm in [(0..n).collect::<Vec<_>>(), shuffled] {
            let symbolic = Symbolic::new(&lower, perm);
            let mut f = assemble(&symbolic, &blocks);
            f.factorize(&symbolic).unwrap();
            let mut x: Vec<BlockVector> = (0..n)
                .map(|r| BlockVector::from_fn(|k, _| b[4 * r + k]))
                .collect();
            f.solve_in_place(&symbolic, &mut x);
            for r in 0..n {
                for k in 0..4 {
                    let e = expected[4 * r + k];
                    assert!((x[r][k] - e).abs() < 1e-12 * e.abs().max(1.0), "{r} {k}");
                }
            }
        }
    }

    #[test]
    fn an_indefinite_matrix_names_its_pivot() {
        let lower = Csr::from_pairs(2, [(1usize, 0usize)].into_iter());
        let symbolic = Symbolic::new(&lower, vec![0, 1]);
        let mut f = Factor::zeros(&symbolic);
        f.add(Slot::Diagonal(0), &Block::identity());
        f.add(Slot::Diagonal(1), &Block::identity());
        // Block (1, 0) = 2·I makes the Schur complement of block 1 equal to I − 4·I.
        f.add(symbolic.slot(1, 0).unwrap(), &(Block::identity() * 2.0));
        assert_eq!(
            f.factorize(&symbolic),
            Err(Pivot {
                block: 1,
                component: 0
            })
        );
    }
}
