//! Fill-reducing ordering of the block pattern: approximate minimum degree (P. R. Amestoy, T. A. Davis,
//! I. S. Duff, "An approximate minimum degree ordering algorithm", SIAM J. Matrix Anal. Appl. 17(4), 1996)
//! through the `amd` crate, a translation of SuiteSparse AMD. Working on blocks (one node per recording)
//! keeps the graph small. A trajectory recorded once is a chain and gets no fill in any sensible order; a
//! street driven twice, crossings and loops couple recordings far apart in time, and the natural order
//! would then fill the factor between them.

use super::csr::{sort_unique_tail, Csr};

/// The ordering `perm[new] = old` for the symmetric pattern whose strictly lower part is `lower` (old
/// numbering). Deterministic; falls back to the natural order if AMD rejects the pattern (it cannot for a
/// pattern built here, but an ordering is only a performance choice).
pub fn fill_reducing(lower: &Csr) -> Vec<usize> {
    let n = lower.rows();
    if n <= 2 {
        return (0..n).collect();
    }
    // Both triangles, column-compressed (symmetric, so rows = columns), no diagonal, sorted, no duplicates.
    let mut full = Csr::from_pairs(
        n,
        (0..n).flat_map(|r| {
            lower
                .row(r)
                .iter()
                .filter(move |&&c| c != r)
                .flat_map(move |&c| [(r, c), (c, r)])
        }),
    );
    full = sorted_unique(&full);
    let a_p: Vec<usize> = (0..=n)
        .map(|i| if i < n { full.row_start(i) } else { full.len() })
        .collect();
    match amd::order(n, &a_p, full.values(), &amd::Control::default()) {
        Ok((perm, _, _)) if is_permutation(&perm, n) => perm,
        _ => (0..n).collect(),
    }
}

/// Each row sorted ascending without repeated values.
fn sorted_unique(c: &Csr) -> Csr {
    let mut start = Vec::with_capacity(c.rows() + 1);
    let mut index = Vec::with_capacity(c.len());
    start.push(0);
    for r in 0..c.rows() {
        let first = index.len();
        index.extend_from_slice(c.row(r));
        sort_unique_tail(&mut index, first);
        start.push(index.len());
    }
    Csr::from_parts(start, index)
}

fn is_permutation(perm: &[usize], n: usize) -> bool {
    let mut seen = vec![false; n];
    perm.len() == n
        && perm
            .iter()
            .all(|&p| p < n && !std::mem::replace(&mut seen[p], true))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adjustment::sparse::symbolic::Symbolic;

    #[test]
    fn a_two_dimensional_grid_fills_less_than_in_natural_order() {
        // A 30 × 30 grid graph (a street network's recording graph is grid-like at crossings).
        let side = 30;
        let n = side * side;
        let pairs = (0..n).flat_map(|r| {
            let (x, y) = (r % side, r / side);
            let mut v = Vec::new();
            if x > 0 {
                v.push((r, r - 1));
            }
            if y > 0 {
                v.push((r, r - side));
            }
            v
        });
        let lower = Csr::from_pairs(n, pairs.collect::<Vec<_>>().into_iter());
        let perm = fill_reducing(&lower);
        assert!(is_permutation(&perm, n));
        let natural = Symbolic::new(&lower, (0..n).collect()).lower_blocks();
        let amd = Symbolic::new(&lower, perm).lower_blocks();
        println!("grid {side}²: fill natural {natural}, AMD {amd}");
        assert!(amd * 2 < natural, "{amd} vs {natural}");
        // Deterministic.
        assert_eq!(fill_reducing(&lower), fill_reducing(&lower));
    }
}
