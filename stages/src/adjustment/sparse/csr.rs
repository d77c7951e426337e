//! Compressed rows of indices: row `i` owns `index[start[i]..start[i + 1]]`. The one sparse container of the
//! adjustment (observations per tie point, observations per recording, the block pattern of the reduced
//! camera matrix), so that nothing per item is a separate heap allocation.

/// Rows of indices in one contiguous array.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Csr {
    start: Vec<usize>,
    index: Vec<usize>,
}

impl Csr {
    /// Groups `(row, value)` pairs by row (a counting sort: within a row, values keep the order of `pairs`).
    /// Rows without pairs are empty; every row is `< rows`.
    pub fn from_pairs(rows: usize, pairs: impl Iterator<Item = (usize, usize)> + Clone) -> Self {
        let mut start = vec![0usize; rows + 1];
        for (r, _) in pairs.clone() {
            start[r + 1] += 1;
        }
        for r in 0..rows {
            start[r + 1] += start[r];
        }
        let mut next = start.clone();
        let mut index = vec![0usize; start[rows]];
        for (r, v) in pairs {
            index[next[r]] = v;
            next[r] += 1;
        }
        Self { start, index }
    }

    /// Rows from per-row lengths and the concatenated values.
    pub fn from_parts(start: Vec<usize>, index: Vec<usize>) -> Self {
        debug_assert_eq!(start.last().copied().unwrap_or(0), index.len());
        Self { start, index }
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    /// The values of row `i`.
    pub fn row(&self, i: usize) -> &[usize] {
        &self.index[self.start[i]..self.start[i + 1]]
    }

    /// Position of the first value of row `i` in the concatenated values.
    pub fn row_start(&self, i: usize) -> usize {
        self.start[i]
    }

    /// Total number of values.
    pub fn len(&self) -> usize {
        self.index.len()
    }

    /// True when no row holds a value.
    pub fn is_empty(&self) -> bool {
        self.index.is_empty()
    }

    /// All values, row after row.
    pub fn values(&self) -> &[usize] {
        &self.index
    }

    /// Bytes held (for memory reports).
    pub fn heap_bytes(&self) -> usize {
        (self.start.capacity() + self.index.capacity()) * std::mem::size_of::<usize>()
    }
}

/// Sorts `index[first..]` and removes repeated values from it (the row being assembled at the end of a CSR
/// index array).
pub fn sort_unique_tail(index: &mut Vec<usize>, first: usize) {
    index[first..].sort_unstable();
    let mut kept = first;
    for k in first..index.len() {
        if kept == first || index[k] != index[kept - 1] {
            index[kept] = index[k];
            kept += 1;
        }
    }
    index.truncate(kept);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_pairs_by_row_in_input_order() {
        let pairs = [(2, 7), (0, 1), (2, 3), (0, 5)];
        let c = Csr::from_pairs(4, pairs.iter().copied());
        assert_eq!(c.rows(), 4);
        assert_eq!(c.row(0), &[1, 5]);
        assert!(c.row(1).is_empty());
        assert_eq!(c.row(2), &[7, 3]);
        assert!(c.row(3).is_empty());
        assert_eq!(c.len(), 4);
        assert_eq!(c.row_start(2), 2);
    }
}
