//! Symbolic analysis of a block sparse Cholesky factorisation: the permuted pattern, the elimination tree
//! (Liu's algorithm with path compression) and the block structure of the factor L, computed row by row
//! from the row subtrees of the elimination tree so that every column's rows come out ascending
//! (T. A. Davis, *Direct Methods for Sparse Linear Systems*, SIAM 2006, chapter 4).
//!
//! Numbering: "old" indices are the caller's (recordings); "new" ones are positions in the fill-reducing
//! order (`perm[new] = old`). The factor's strictly lower blocks are stored by column.

use super::csr::Csr;

const NONE: usize = usize::MAX;

/// Where a block (r, c) of the symmetric matrix lives in the factor's storage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slot {
    /// A diagonal block (new index).
    Diagonal(usize),
    /// A strictly lower block at this storage position, in the caller's orientation.
    Lower(usize),
    /// A strictly lower block at this storage position that holds the transpose of the caller's block.
    Upper(usize),
}

/// The structure of L for a pattern and an ordering.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Symbolic {
    /// `perm[new] = old`.
    perm: Vec<usize>,
    /// `inverse[old] = new`.
    inverse: Vec<usize>,
    /// Elimination-tree parent (new numbering), `usize::MAX` for a root.
    parent: Vec<usize>,
    /// Rows (new numbering, ascending) of the strictly lower blocks of each column.
    columns: Csr,
}

impl Symbolic {
    /// Analyses the symmetric block pattern whose strictly lower part is `lower` (row r holds the columns
    /// c < r of its non-zero blocks, old numbering; duplicates allowed) under the ordering `perm`.
    pub fn new(lower: &Csr, perm: Vec<usize>) -> Self {
        let n = lower.rows();
        assert_eq!(perm.len(), n, "the ordering must cover every block row");
        let mut inverse = vec![NONE; n];
        for (new, &old) in perm.iter().enumerate() {
            inverse[old] = new;
        }
        // Row form of the permuted strictly lower pattern: row i holds its columns j < i.
        let rows = Csr::from_pairs(
            n,
            (0..n).flat_map(|r| {
                let inverse = &inverse;
                lower
                    .row(r)
                    .iter()
                    .filter(move |&&c| c != r)
                    .map(move |&c| {
                        let (a, b) = (inverse[r], inverse[c]);
                        (a.max(b), a.min(b))
                    })
            }),
        );
        let parent = elimination_tree(&rows);
        let columns = factor_columns(&rows, &parent);
        Self {
            perm,
            inverse,
            parent,
            columns,
        }
    }

    /// Number of block rows.
    pub fn dim(&self) -> usize {
        self.perm.len()
    }

    /// `perm[new] = old`.
    pub fn perm(&self) -> &[usize] {
        &self.perm
    }

    /// New index of old block `old`.
    pub fn new_index(&self, old: usize) -> usize {
        self.inverse[old]
    }

    /// Elimination-tree parent of new column `j` (`None` for a root).
    pub fn parent(&self, j: usize) -> Option<usize> {
        (self.parent[j] != NONE).then_some(self.parent[j])
    }

    /// Rows (new numbering, ascending) of the strictly lower blocks of new column `j`.
    pub fn column(&self, j: usize) -> &[usize] {
        self.columns.row(j)
    }

    /// Storage position of the first strictly lower block of new column `j`.
    pub fn column_start(&self, j: usize) -> usize {
        self.columns.row_start(j)
    }

    /// (storage position, row) of the strictly lower blocks of new column `j`, rows ascending.
    pub fn column_positions(&self, j: usize) -> impl Iterator<Item = (usize, usize)> + '_ {
        let start = self.column_start(j);
        self.column(j)
            .iter()
            .enumerate()
            .map(move |(k, &row)| (start + k, row))
    }

    /// For the row k = `column(j)[a]` of new column `j`: (b, storage position of the block
    /// (`column(j)[b]`, k)) for every later row b > a of column `j`. Those rows lie in column k's structure
    /// (the rows of a column are a clique of L's structure) and both are ascending: one merge walk finds
    /// them.
    pub fn merge_walk(&self, j: usize, a: usize) -> impl Iterator<Item = (usize, usize)> + '_ {
        let rows = self.column(j);
        let mut column_k = self.column_positions(rows[a]);
        rows.iter().enumerate().skip(a + 1).map(move |(b, &i)| {
            let position = column_k
                .find(|&(_, row)| row == i)
                .expect("a column's structure is a clique of L's structure")
                .0;
            (b, position)
        })
    }

    /// Strictly lower blocks of L.
    pub fn lower_blocks(&self) -> usize {
        self.columns.len()
    }

    /// Storage position of the strictly lower block (i, j), new numbering, i > j; `None` outside L's pattern.
    pub fn position(&self, i: usize, j: usize) -> Option<usize> {
        let rows = self.column(j);
        rows.binary_search(&i)
            .ok()
            .map(|k| self.column_start(j) + k)
    }

    /// Where the block (r, c) of the matrix (old numbering) lives; `None` outside L's pattern.
    pub fn slot(&self, r: usize, c: usize) -> Option<Slot> {
        let (i, j) = (self.inverse[r], self.inverse[c]);
        match i.cmp(&j) {
            std::cmp::Ordering::Equal => Some(Slot::Diagonal(i)),
            std::cmp::Ordering::Greater => self.position(i, j).map(Slot::Lower),
            std::cmp::Ordering::Less => self.position(j, i).map(Slot::Upper),
        }
    }
}

/// Elimination tree of the pattern given by rows of strictly lower columns (Liu 1986; Davis 2006, 4.1).
fn elimination_tree(rows: &Csr) -> Vec<usize> {
    let n = rows.rows();
    let mut parent = vec![NONE; n];
    let mut ancestor = vec![NONE; n];
    for i in 0..n {
        for &j in rows.row(i) {
            let mut k = j;
            while ancestor[k] != NONE && ancestor[k] != i {
                let next = ancestor[k];
                ancestor[k] = i;
                k = next;
            }
            if ancestor[k] == NONE {
                ancestor[k] = i;
                parent[k] = i;
            }
        }
    }
    parent
}

/// Strictly lower structure of L by column: row i of L is the union of the elimination-tree paths from each
/// j of row i of A up to i (the row subtree, Davis 2006, 4.2); visiting rows in order fills each column
/// ascending.
fn factor_columns(rows: &Csr, parent: &[usize]) -> Csr {
    let n = rows.rows();
    let mut mark = vec![NONE; n];
    let mut start = vec![0usize; n + 1];
    for i in 0..n {
        row_subtree(rows, parent, &mut mark, i, |k| start[k + 1] += 1);
    }
    for j in 0..n {
        start[j + 1] += start[j];
    }
    let mut next = start.clone();
    let mut index = vec![0usize; start[n]];
    mark.iter_mut().for_each(|m| *m = NONE);
    for i in 0..n {
        row_subtree(rows, parent, &mut mark, i, |k| {
            index[next[k]] = i;
            next[k] += 1;
        });
    }
    Csr::from_parts(start, index)
}

/// Visits the columns k < i of row i of L: the elimination-tree paths from each column of row i of A up to
/// (excluding) i; `mark` remembers the visited nodes of row i.
fn row_subtree(
    rows: &Csr,
    parent: &[usize],
    mark: &mut [usize],
    i: usize,
    mut visit: impl FnMut(usize),
) {
    mark[i] = i;
    for &j in rows.row(i) {
        let mut k = j;
        while mark[k] != i {
            visit(k);
            mark[k] = i;
            k = parent[k];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lower pattern of an arrow matrix: every row couples with row 0.
    fn arrow(n: usize) -> Csr {
        Csr::from_pairs(n, (1..n).map(|r| (r, 0)))
    }

    #[test]
    fn arrow_fills_completely_in_natural_order_and_not_at_all_reversed() {
        let n = 5;
        let natural = Symbolic::new(&arrow(n), (0..n).collect());
        // Eliminating the hub first couples everything: L is full.
        assert_eq!(natural.lower_blocks(), n * (n - 1) / 2);
        assert_eq!(natural.column(0), &[1, 2, 3, 4]);
        assert_eq!(natural.column(1), &[2, 3, 4]);
        // Hub last: no fill.
        let reversed = Symbolic::new(&arrow(n), (0..n).rev().collect());
        assert_eq!(reversed.lower_blocks(), n - 1);
        for j in 0..n - 1 {
            assert_eq!(reversed.column(j), &[n - 1]);
            assert_eq!(reversed.parent(j), Some(n - 1));
        }
        assert_eq!(reversed.parent(n - 1), None);
        assert_eq!(reversed.slot(0, 0), Some(Slot::Diagonal(n - 1)));
        // Old (1, 0) is new (3, 4): stored transposed at (4, 3).
        assert_eq!(reversed.slot(1, 0), Some(Slot::Upper(3)));
        assert_eq!(reversed.slot(0, 1), Some(Slot::Lower(3)));
        assert_eq!(reversed.slot(1, 2), None);
    }

    #[test]
    fn a_chain_has_no_fill() {
        let n = 6;
        let chain = Csr::from_pairs(n, (1..n).map(|r| (r, r - 1)));
        let s = Symbolic::new(&chain, (0..n).collect());
        assert_eq!(s.lower_blocks(), n - 1);
        for j in 0..n - 1 {
            assert_eq!(s.column(j), &[j + 1]);
        }
    }
}
