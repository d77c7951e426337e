//! The numeric block Cholesky factorisation, left-looking and parallel over the levels of the elimination
//! tree: column j of L is its column of A minus the contributions `L(i, k)·L(j, k)ᵀ` of the earlier columns
//! k of row j of L, subtracted in ascending k, then divided by its diagonal factor. Column j reads only its
//! descendants in the elimination tree, so the columns of one level (equal height, see
//! [`Symbolic::levels`]) are computed at the same time, and a long column is cut into row ranges computed
//! at the same time. Every block receives the same products in the same order whatever the thread count —
//! and the same as in a sequential right-looking factorisation — so the factor is bit-identical in all cases.

use super::block4::{self, Block};
use super::factor::Pivot;
use super::symbolic::Symbolic;
use rayon::prelude::*;
use std::cell::RefCell;
use std::ops::Range;

/// Strictly lower blocks of one column computed by one task.
const ROWS_PER_TASK: usize = 48;

thread_local! {
    /// Row → place in the task's range of column j (only the entries of that range are valid).
    static PLACE: RefCell<Vec<u32>> = const { RefCell::new(Vec::new()) };
}

/// One unit of work: a range of the rows of column `column` (indices into its structure), and whether the
/// task also updates the diagonal block.
struct Task {
    column: usize,
    rows: Range<usize>,
    diagonal: bool,
}

/// What a task computed: the updated diagonal block (if asked) and the updated strictly lower blocks.
type Updated = (Option<Block>, Vec<Block>);

/// Replaces the matrix values `diagonal` / `lower` (on the structure of `symbolic`) by the Cholesky factor.
/// On failure the first failing pivot of the sequential column order is named, in the caller's numbering
/// (columns that depend on a failed one are not computed).
pub fn factorize(
    symbolic: &Symbolic,
    diagonal: &mut [Block],
    lower: &mut [Block],
) -> Result<(), Pivot> {
    let n = symbolic.dim();
    let levels = symbolic.levels();
    let mut spoiled = vec![false; n];
    let mut failure: Option<(usize, usize)> = None;
    for level in 0..levels.rows() {
        let columns: Vec<usize> = levels
            .row(level)
            .iter()
            .copied()
            .filter(|&j| !spoiled[j])
            .collect();
        let tasks = level_tasks(symbolic, &columns);
        let run = |task: &Task| updated(symbolic, diagonal, lower, task);
        let results: Vec<Updated> = if tasks.len() > 1 {
            tasks.par_iter().map(run).collect()
        } else {
            tasks.iter().map(run).collect()
        };
        let mut results = results.into_iter();
        for &j in &columns {
            let (diag, mut blocks) = results.next().expect("one task per column at least");
            for _ in 1..symbolic.column(j).len().div_ceil(ROWS_PER_TASK) {
                blocks.extend(results.next().expect("a task per row range").1);
            }
            let d = &diagonal[j];
            let reference = [d[(0, 0)], d[(1, 1)], d[(2, 2)], d[(3, 3)]];
            let diag = diag.expect("the first task of a column updates its diagonal");
            match block4::cholesky(&diag, &reference) {
                Ok(ljj) => {
                    diagonal[j] = ljj;
                    let start = symbolic.column_start(j);
                    for (a, block) in blocks.iter().enumerate() {
                        lower[start + a] = block4::right_solve_lower_transpose(block, &ljj);
                    }
                }
                Err(component) => {
                    spoiled[j] = true;
                    if failure.is_none_or(|(f, _)| j < f) {
                        failure = Some((j, component));
                    }
                }
            }
        }
        for &j in levels.row(level) {
            if let Some(p) = symbolic.parent(j).filter(|_| spoiled[j]) {
                spoiled[p] = true;
            }
        }
    }
    match failure {
        Some((j, component)) => Err(Pivot {
            block: symbolic.perm()[j],
            component,
        }),
        None => Ok(()),
    }
}

/// The tasks of one level: each column cut into ranges of [`ROWS_PER_TASK`] rows (at least one range; the
/// first also updates the diagonal). The cut depends only on the structure.
fn level_tasks(symbolic: &Symbolic, columns: &[usize]) -> Vec<Task> {
    let mut tasks = Vec::with_capacity(columns.len());
    for &j in columns {
        let len = symbolic.column(j).len();
        let pieces = len.div_ceil(ROWS_PER_TASK).max(1);
        for piece in 0..pieces {
            let rows = piece * ROWS_PER_TASK..((piece + 1) * ROWS_PER_TASK).min(len);
            tasks.push(Task {
                column: j,
                rows,
                diagonal: piece == 0,
            });
        }
    }
    tasks
}

/// The blocks of a task after subtracting, in ascending k, the contributions of every column k of row j of
/// L: `L(j, k)·L(j, k)ᵀ` from the diagonal, `L(i, k)·L(j, k)ᵀ` from block (i, j) for the rows i > j of
/// column k that lie in the task's range (they all lie in column j's structure).
fn updated(symbolic: &Symbolic, diagonal: &[Block], lower: &[Block], task: &Task) -> Updated {
    let j = task.column;
    let start = symbolic.column_start(j);
    let rows = &symbolic.column(j)[task.rows.clone()];
    let mut blocks: Vec<Block> = lower[start + task.rows.start..start + task.rows.end].to_vec();
    let mut diag = task.diagonal.then(|| diagonal[j]);
    let (first, end) = match (rows.first(), rows.last()) {
        (Some(&first), Some(&last)) => (first, last + 1),
        _ => (0, 0),
    };
    PLACE.with_borrow_mut(|place| {
        if place.len() < symbolic.dim() {
            place.resize(symbolic.dim(), 0);
        }
        for (a, &i) in rows.iter().enumerate() {
            place[i] = a as u32;
        }
        let (columns, positions) = symbolic.row(j);
        for (&k, &p_jk) in columns.iter().zip(positions) {
            let l_jk_t = lower[p_jk].transpose();
            if let Some(d) = diag.as_mut() {
                *d -= lower[p_jk] * l_jk_t;
            }
            // Column k's rows after j are stored right after L(j, k).
            let tail_start = p_jk + 1;
            let tail = &symbolic.column(k)[tail_start - symbolic.column_start(k)..];
            let skip = tail.partition_point(|&i| i < first);
            for (b, &i) in tail.iter().enumerate().skip(skip) {
                if i >= end {
                    break;
                }
                blocks[place[i] as usize] -= lower[tail_start + b] * l_jk_t;
            }
        }
    });
    (diag, blocks)
}

#[cfg(test)]
mod tests {
    use crate::adjustment::sparse::block4::Block;
    use crate::adjustment::sparse::factor::tests::{assemble, random_spd};
    use crate::adjustment::sparse::factor::Pivot;
    use crate::adjustment::sparse::ordering::fill_reducing;
    use crate::adjustment::sparse::symbolic::Symbolic;

    #[test]
    fn the_factor_is_bit_identical_whatever_the_thread_count() {
        // Long-range couplings give long columns (several row ranges) and wide levels.
        let n = 400;
        let (lower, blocks, _) = random_spd(n, 3000, 11);
        let symbolic = Symbolic::new(&lower, fill_reducing(&lower));
        assert!((0..n).any(|j| symbolic.column(j).len() > 2 * super::ROWS_PER_TASK));
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    let mut f = assemble(&symbolic, &blocks);
                    f.factorize(&symbolic).unwrap();
                    f
                })
        };
        let one = run(1);
        for threads in [2, 3] {
            assert!(run(threads) == one, "{threads} threads");
        }
    }

    #[test]
    fn the_first_failing_column_of_the_sequential_order_is_named() {
        // Independent blocks 0..4 (all leaves of one level); blocks 1 and 3 are indefinite.
        let lower = crate::adjustment::sparse::csr::Csr::from_pairs(4, std::iter::empty());
        let symbolic = Symbolic::new(&lower, vec![2, 3, 1, 0]);
        let mut blocks: Vec<(usize, usize, Block)> =
            (0..4).map(|r| (r, r, Block::identity())).collect();
        blocks[1].2[(2, 2)] = -1.0;
        blocks[3].2[(1, 1)] = -1.0;
        let mut f = assemble(&symbolic, &blocks);
        // New order 2, 3, 1, 0: block 3 comes first.
        assert_eq!(
            f.factorize(&symbolic),
            Err(Pivot {
                block: 3,
                component: 1
            })
        );
    }
}
