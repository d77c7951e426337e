//! A symmetric matrix in envelope ("skyline") storage and its in-place Cholesky factorisation, for the
//! reduced camera matrix of the adjustment.
//!
//! Why: recordings of a trajectory are ordered in time and tie points are seen by neighbouring recordings,
//! so the reduced camera matrix (after eliminating the points) is banded. The envelope of a row — from its
//! first non-zero column to the diagonal — is preserved by the Cholesky factor, so the factorisation costs
//! O(n·b²) for bandwidth b instead of O(n³) dense (a 3000 × 3000 dense factorisation would be ~9 GFLOP per LM
//! step). Blocks with long-range links (a street driven twice) still factorise exactly, only slower.

/// Lower triangle of a symmetric n × n matrix, row i stored from column `first_col[i]` to i.
#[derive(Clone, Debug, PartialEq)]
pub struct SkylineMatrix {
    first_col: Vec<usize>,
    row_start: Vec<usize>,
    values: Vec<f64>,
}

impl SkylineMatrix {
    /// A zero matrix with the given envelope (`first_col[i] ≤ i`; larger values are clamped to i).
    pub fn zeros(first_col: &[usize]) -> Self {
        let mut row_start = Vec::with_capacity(first_col.len() + 1);
        let mut fc = Vec::with_capacity(first_col.len());
        let mut total = 0usize;
        for (i, &f) in first_col.iter().enumerate() {
            let f = f.min(i);
            fc.push(f);
            row_start.push(total);
            total += i - f + 1;
        }
        row_start.push(total);
        Self {
            first_col: fc,
            row_start,
            values: vec![0.0; total],
        }
    }

    /// Dimension n.
    pub fn dim(&self) -> usize {
        self.first_col.len()
    }

    /// Stored entries (for reporting the fill).
    pub fn stored(&self) -> usize {
        self.values.len()
    }

    /// Sets every entry to zero (the envelope is kept).
    pub fn clear(&mut self) {
        self.values.iter_mut().for_each(|v| *v = 0.0);
    }

    fn index(&self, i: usize, j: usize) -> usize {
        debug_assert!(
            j <= i && j >= self.first_col[i],
            "({i},{j}) outside the envelope"
        );
        self.row_start[i] + (j - self.first_col[i])
    }

    /// Entry (i, j) of the lower triangle (j ≤ i); 0 outside the envelope.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        if j > i || j < self.first_col[i] {
            0.0
        } else {
            self.values[self.index(i, j)]
        }
    }

    /// Adds `v` to entry (i, j), j ≤ i, which must lie inside the envelope.
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        let k = self.index(i, j);
        self.values[k] += v;
    }

    /// Scales the diagonal by (1 + λ) (Marquardt damping).
    pub fn damp_diagonal(&mut self, lambda: f64) {
        for i in 0..self.dim() {
            let k = self.index(i, i);
            self.values[k] *= 1.0 + lambda;
        }
    }

    /// Replaces the matrix by its Cholesky factor L (A = L·Lᵀ). On a non-positive pivot returns its row.
    pub fn factorize(&mut self) -> Result<(), usize> {
        let n = self.dim();
        for i in 0..n {
            let fi = self.first_col[i];
            let ri = self.row_start[i];
            for j in fi..=i {
                let fj = self.first_col[j];
                let rj = self.row_start[j];
                let k0 = fi.max(fj);
                let mut s = self.values[ri + (j - fi)];
                let row_i = &self.values[ri + (k0 - fi)..ri + (j - fi)];
                let row_j = &self.values[rj + (k0 - fj)..rj + (j - fj)];
                s -= row_i.iter().zip(row_j).map(|(a, b)| a * b).sum::<f64>();
                if j < i {
                    let ljj = self.values[rj + (j - fj)];
                    self.values[ri + (j - fi)] = s / ljj;
                } else {
                    if !(s > 0.0 && s.is_finite()) {
                        return Err(i);
                    }
                    self.values[ri + (i - fi)] = s.sqrt();
                }
            }
        }
        Ok(())
    }

    /// Solves A·x = b in place using the factor from [`Self::factorize`].
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let n = self.dim();
        for i in 0..n {
            let fi = self.first_col[i];
            let ri = self.row_start[i];
            let row = &self.values[ri..ri + (i - fi)];
            let s: f64 = row.iter().zip(&b[fi..i]).map(|(l, y)| l * y).sum();
            b[i] = (b[i] - s) / self.values[ri + (i - fi)];
        }
        for i in (0..n).rev() {
            let fi = self.first_col[i];
            let ri = self.row_start[i];
            b[i] /= self.values[ri + (i - fi)];
            let xi = b[i];
            for (k, l) in (fi..i).zip(&self.values[ri..ri + (i - fi)]) {
                b[k] -= l * xi;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    #[test]
    fn solves_a_banded_spd_system_like_a_dense_cholesky() {
        let n = 9;
        let first: Vec<usize> = (0..n).map(|i: usize| i.saturating_sub(2)).collect();
        let mut a = SkylineMatrix::zeros(&first);
        let mut dense = DMatrix::<f64>::zeros(n, n);
        for i in 0..n {
            for j in first[i]..=i {
                let v = if i == j {
                    6.0 + i as f64
                } else {
                    1.0 / (1.0 + (i + 2 * j) as f64)
                };
                a.add(i, j, v);
                dense[(i, j)] = v;
                dense[(j, i)] = v;
            }
        }
        let b = DVector::from_fn(n, |i, _| (i as f64).sin() + 0.5);
        let expected = dense.cholesky().unwrap().solve(&b);
        a.factorize().unwrap();
        let mut x: Vec<f64> = b.iter().copied().collect();
        a.solve_in_place(&mut x);
        for i in 0..n {
            assert!((x[i] - expected[i]).abs() < 1e-13);
        }
    }

    #[test]
    fn reports_a_non_positive_pivot() {
        let mut a = SkylineMatrix::zeros(&[0, 0]);
        a.add(0, 0, 1.0);
        a.add(1, 0, 2.0);
        a.add(1, 1, 1.0);
        assert_eq!(a.factorize(), Err(1));
    }
}
