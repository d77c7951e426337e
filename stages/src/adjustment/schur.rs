//! The reduced camera system (thesis 5.4): with the normal equations
//! `[U W; Wᵀ V]·[δc; δp] = [b_c; b_p]` and V block-diagonal (3 × 3 per tie point), the points are eliminated
//! by the Schur complement `S = U − W·V⁻¹·Wᵀ`, `S·δc = b_c − W·V⁻¹·b_p`, and recovered afterwards as
//! `δp_j = V_j⁻¹·(b_p,j − W_jᵀ·δc)`. Marquardt damping scales the diagonals of U and V by 1 + λ.
//!
//! S is assembled block row by block row in parallel (row r sums, in a fixed order, the products
//! `W_a·V_p⁻¹·W_bᵀ` of its rays a with the rays b of the same point p in recordings ≤ r), scattered into
//! the sparse factor's storage and factorised there ([`super::sparse`]). Parameters a configuration does
//! not estimate are decoupled unit rows (zero step).

use super::layout::ReducedStructure;
use super::linearization::Linearization;
use super::parallel::{chunks, split_at_ends};
use super::prepared::Prepared;
use super::sparse::{Block, BlockVector, Factor, Pivot};
use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

/// Why a damped system could not be factorised.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReduceError {
    /// The 3 × 3 normal block of this tie point is not positive definite.
    Point(usize),
    /// The reduced camera matrix is not positive definite at this pivot.
    Pivot(Pivot),
}

/// Per point: V⁻¹ and V⁻¹·b_p (zero for undetermined points).
pub type PointElimination = (Matrix3<f64>, Vector3<f64>);

/// A factorised reduced camera system and what back-substitution needs. Its buffers are reused from one
/// damping trial to the next (no page faults for every trial on big blocks).
pub struct ReducedSystem {
    pub factor: Factor,
    /// b_c − W·V⁻¹·b_p per recording (zero for fixed parameters).
    pub rhs: Vec<BlockVector>,
    pub points: Vec<PointElimination>,
    /// The blocks of S row by row (the order of `ReducedStructure::rows`).
    values: Vec<Block>,
}

impl ReducedSystem {
    /// Buffers for the systems of `prep`.
    pub fn new(prep: &Prepared) -> Self {
        let structure = &prep.structure;
        Self {
            factor: Factor::zeros(&structure.symbolic),
            rhs: vec![BlockVector::zeros(); structure.rows.rows()],
            points: vec![(Matrix3::zeros(), Vector3::zeros()); prep.point_active.len()],
            values: vec![Block::zeros(); structure.rows.len()],
        }
    }

    /// Forms and factorises the system damped by `lambda`.
    pub fn reduce(
        &mut self,
        prep: &Prepared,
        lin: &Linearization,
        lambda: f64,
    ) -> Result<(), ReduceError> {
        point_inverses(prep, lin, lambda, &mut self.points)?;
        let structure = &prep.structure;
        let n_rec = structure.rows.rows();
        let row_chunks = chunks(n_rec);
        let row_ends: Vec<usize> = row_chunks.iter().map(|&(_, e)| e).collect();
        let value_ends: Vec<usize> = row_ends
            .iter()
            .map(|&e| structure.rows.row_start(e))
            .collect();
        let active = active_mask(prep);
        let points = &self.points;
        row_chunks
            .iter()
            .zip(split_at_ends(&mut self.values, &value_ends))
            .zip(split_at_ends(&mut self.rhs, &row_ends))
            .collect::<Vec<_>>()
            .into_par_iter()
            .for_each(|((&(first, end), values), rhs)| {
                let base = structure.rows.row_start(first);
                for r in first..end {
                    let start = structure.rows.row_start(r) - base;
                    let row = &mut values[start..start + structure.rows.row(r).len()];
                    rhs[r - first] = reduced_row(prep, lin, points, lambda, r, row);
                    mask_row(&active, row, &mut rhs[r - first]);
                }
            });
        self.factor.clear();
        for (slot, value) in structure.slots.iter().zip(&self.values) {
            self.factor.add(*slot, value);
        }
        self.factor
            .factorize(&structure.symbolic)
            .map_err(ReduceError::Pivot)
    }

    /// Solves the system formed by the last successful [`Self::reduce`]: (camera step per recording over
    /// (x, y, z, ψ), point steps).
    pub fn step(
        &self,
        prep: &Prepared,
        lin: &Linearization,
    ) -> (Vec<BlockVector>, Vec<Vector3<f64>>) {
        let mut camera_step = self.rhs.clone();
        self.factor
            .solve_in_place(&prep.structure.symbolic, &mut camera_step);
        let layout = &prep.layout;
        let point_step = (0..prep.point_active.len())
            .into_par_iter()
            .with_min_len(super::parallel::CHUNK)
            .map(|p| {
                if !prep.point_active[p] {
                    return Vector3::zeros();
                }
                let mut b = lin.point_rhs[p];
                for pos in layout.positions_of_point(p) {
                    b -= lin.couplings[pos].tr_mul(&camera_step[layout.recording_of[pos]]);
                }
                self.points[p].0 * b
            })
            .collect();
        (camera_step, point_step)
    }
}

/// Which of (x, y, z, ψ) are estimated.
fn active_mask(prep: &Prepared) -> [bool; 4] {
    let mut active = [false; 4];
    for &f in &prep.parameterization.active {
        active[f] = true;
    }
    active
}

/// V_p(λ)⁻¹ and V_p(λ)⁻¹·b_p of every determined point, into `out` (one per point).
fn point_inverses(
    prep: &Prepared,
    lin: &Linearization,
    lambda: f64,
    out: &mut [PointElimination],
) -> Result<(), ReduceError> {
    out.par_iter_mut()
        .enumerate()
        .with_min_len(super::parallel::CHUNK)
        .try_for_each(|(p, slot)| {
            if !prep.point_active[p] {
                *slot = (Matrix3::zeros(), Vector3::zeros());
                return Ok(());
            }
            let mut v = lin.point_diag[p];
            for d in 0..3 {
                v[(d, d)] *= 1.0 + lambda;
            }
            let inv = v.cholesky().ok_or(ReduceError::Point(p))?.inverse();
            *slot = (inv, inv * lin.point_rhs[p]);
            Ok(())
        })
}

/// Row r of S (blocks for the columns of `structure.rows.row(r)`, written to `out`) and its right-hand side.
fn reduced_row(
    prep: &Prepared,
    lin: &Linearization,
    points: &[PointElimination],
    lambda: f64,
    r: usize,
    out: &mut [Block],
) -> BlockVector {
    let structure: &ReducedStructure = &prep.structure;
    let layout = &prep.layout;
    let cols = structure.rows.row(r);
    out.iter_mut().for_each(|b| *b = Block::zeros());
    let mut diag = lin.camera_diag[r];
    for d in 0..4 {
        diag[(d, d)] *= 1.0 + lambda;
    }
    out[cols.len() - 1] = diag;
    let mut rhs = lin.camera_rhs[r];
    for &a in layout.by_recording.row(r) {
        let (inv, y) = &points[layout.point_of[a]];
        let w = &lin.couplings[a];
        rhs -= w * y;
        let w_vinv = w * inv;
        for b in layout.positions_of_point(layout.point_of[a]) {
            let c = layout.recording_of[b];
            if c > r {
                continue;
            }
            let k = cols
                .binary_search(&c)
                .expect("coupled recordings are in the row");
            out[k] -= w_vinv * lin.couplings[b].transpose();
        }
    }
    for &k in structure.relative_by_row.row(r) {
        let (a, b) = (prep.relative[k].from, prep.relative[k].to);
        let col = cols
            .binary_search(&a.min(b))
            .expect("constrained recordings are in the row");
        out[col] += lin.camera_off[k];
    }
    rhs
}

/// Fixed parameters become decoupled unit rows with a zero right-hand side.
fn mask_row(active: &[bool; 4], out: &mut [Block], rhs: &mut BlockVector) {
    let last = out.len() - 1;
    for (k, block) in out.iter_mut().enumerate() {
        for f in (0..4).filter(|&f| !active[f]) {
            block.row_mut(f).fill(0.0);
            block.column_mut(f).fill(0.0);
            if k == last {
                block[(f, f)] = 1.0;
            }
        }
    }
    for f in (0..4).filter(|&f| !active[f]) {
        rhs[f] = 0.0;
    }
}
