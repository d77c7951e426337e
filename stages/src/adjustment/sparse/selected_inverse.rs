//! Selected inversion: the blocks of Z = A⁻¹ on the structure of the Cholesky factor L (in particular every
//! diagonal block), without forming the dense inverse — the Takahashi recursion (K. Takahashi, J. Fagan,
//! M.-S. Chen, "Formation of a sparse bus impedance matrix and its application to short circuit study",
//! 1973; A. M. Erisman, W. F. Tinney, "On computing certain elements of the inverse of a sparse matrix",
//! Comm. ACM 18(3), 1975).
//!
//! From Lᵀ·Z = L⁻¹ (upper triangular on the left, lower triangular on the right), column by column from the
//! last: for i in the structure S_j of column j of L,
//! `Z(i, j) = −(Σ_{k∈S_j} Z(i, k)·L(k, j))·L(j, j)⁻¹` and
//! `Z(j, j) = L(j, j)⁻ᵀ·(L(j, j)⁻¹ − Σ_{k∈S_j} L(k, j)ᵀ·Z(k, j))`.
//! Every Z(i, k) needed lies in L's structure (S_j \ {k} ⊆ structure of the smaller of i, k), so the
//! recursion stays on the factor's blocks: cost Σ_j |S_j|² block products, memory that of L.

use super::block4::{self, Block};
use super::factor::Factor;
use super::symbolic::Symbolic;

/// The blocks of A⁻¹ on the structure of L.
#[derive(Clone, Debug, PartialEq)]
pub struct SelectedInverse {
    /// Diagonal blocks, new numbering.
    diagonal: Vec<Block>,
    /// Strictly lower blocks in the symbolic's storage order.
    lower: Vec<Block>,
}

impl SelectedInverse {
    /// Runs the Takahashi recursion on a factorised `factor`.
    pub fn new(symbolic: &Symbolic, factor: &Factor) -> Self {
        let n = symbolic.dim();
        let mut z = Self {
            diagonal: vec![Block::zeros(); n],
            lower: vec![Block::zeros(); symbolic.lower_blocks()],
        };
        let mut acc: Vec<Block> = Vec::new();
        for j in (0..n).rev() {
            let l_inv = block4::invert_lower(factor.diagonal(j));
            let start = symbolic.column_start(j);
            let rows = symbolic.column(j);
            // acc[a] = Σ_{k∈S_j} Z(rows[a], k)·L(k, j), visiting each pair (i > k) of S_j once through column
            // k of Z (a merge walk, as in the factorisation) and using Z(k, i) = Z(i, k)ᵀ.
            acc.clear();
            acc.resize(rows.len(), Block::zeros());
            for (a, &k) in rows.iter().enumerate() {
                let l_kj = factor.lower(start + a);
                acc[a] += z.diagonal[k] * l_kj;
                for (b, position) in symbolic.merge_walk(j, a) {
                    let z_ik = &z.lower[position];
                    acc[b] += z_ik * l_kj;
                    acc[a] += z_ik.tr_mul(factor.lower(start + b));
                }
            }
            for (a, sum) in acc.iter().enumerate() {
                z.lower[start + a] = -sum * l_inv;
            }
            let mut sum = Block::zeros();
            for a in 0..rows.len() {
                sum += factor.lower(start + a).tr_mul(&z.lower[start + a]);
            }
            let d = l_inv.tr_mul(&(l_inv - sum));
            z.diagonal[j] = (d + d.transpose()) * 0.5;
        }
        z
    }

    /// The diagonal block of A⁻¹ for block row `old` (the caller's numbering).
    pub fn diagonal(&self, symbolic: &Symbolic, old: usize) -> Block {
        self.diagonal[symbolic.new_index(old)]
    }

    /// The block (r, c) of A⁻¹ (the caller's numbering) when it lies on L's structure.
    pub fn get(&self, symbolic: &Symbolic, r: usize, c: usize) -> Option<Block> {
        let (i, j) = (symbolic.new_index(r), symbolic.new_index(c));
        match i.cmp(&j) {
            std::cmp::Ordering::Equal => Some(self.diagonal[i]),
            std::cmp::Ordering::Greater => symbolic.position(i, j).map(|k| self.lower[k]),
            std::cmp::Ordering::Less => symbolic.position(j, i).map(|k| self.lower[k].transpose()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adjustment::sparse::factor::tests::{assemble, random_spd};
    use crate::adjustment::sparse::ordering::fill_reducing;

    #[test]
    fn equals_the_dense_inverse_on_the_factor_structure() {
        for (n, extra, seed) in [(1, 0, 1), (12, 0, 2), (40, 30, 3), (60, 200, 4)] {
            let (lower, blocks, dense) = random_spd(n, extra, seed);
            let inverse = dense.clone().try_inverse().unwrap();
            for perm in [(0..n).collect::<Vec<_>>(), fill_reducing(&lower)] {
                let symbolic = Symbolic::new(&lower, perm);
                let mut f = assemble(&symbolic, &blocks);
                f.factorize(&symbolic).unwrap();
                let z = SelectedInverse::new(&symbolic, &f);
                let mut checked = 0;
                for r in 0..n {
                    for c in 0..n {
                        let Some(block) = z.get(&symbolic, r, c) else {
                            continue;
                        };
                        let expected = inverse.view((4 * r, 4 * c), (4, 4));
                        let scale = expected.amax();
                        let err = (block - expected).amax();
                        assert!(
                            err <= 1e-9 * scale,
                            "n {n} block ({r}, {c}): {err} vs {scale}"
                        );
                        checked += 1;
                    }
                    assert_eq!(z.diagonal(&symbolic, r), z.get(&symbolic, r, r).unwrap());
                }
                assert!(checked >= n + 2 * (n - 1));
            }
        }
    }
}
