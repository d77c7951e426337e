//! Index structures of one solve: the active panorama observations grouped by tie point and by recording,
//! and the block structure of the reduced camera matrix `S = U − W·V⁻¹·Wᵀ` (thesis 5.4; the points are
//! eliminated by a Schur complement, see [`super::schur`]) with its fill-reducing symbolic factorisation.
//!
//! Recordings i and j are coupled in S when they observe a common tie point or share a relative
//! constraint. Observation "positions" number the active panorama observations point by point; every
//! per-observation array of a linearisation is indexed by position, so a point's observations are
//! contiguous and a recording's are listed in `by_recording`.

use super::sparse::csr::sort_unique_tail;
use super::sparse::ordering::fill_reducing;
use super::sparse::{Csr, Slot, Symbolic};

/// Active panorama observations by point and by recording.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObservationLayout {
    /// Row p: indices into `Prepared::pano` of point p's active observations (ascending); their positions are
    /// `by_point.row_start(p)..`.
    pub by_point: Csr,
    /// Recording of each position.
    pub recording_of: Vec<usize>,
    /// Point of each position.
    pub point_of: Vec<usize>,
    /// Row r: positions of recording r's active observations (ascending).
    pub by_recording: Csr,
}

impl ObservationLayout {
    /// Groups the active observations, given as `(pano index, point)` in ascending pano index, with
    /// `recording(i)` the recording of pano observation i.
    pub fn new(
        n_recordings: usize,
        n_points: usize,
        active: impl Iterator<Item = (usize, usize)> + Clone,
        recording: impl Fn(usize) -> usize,
    ) -> Self {
        let by_point = Csr::from_pairs(n_points, active.map(|(i, p)| (p, i)));
        let mut recording_of = vec![0usize; by_point.len()];
        let mut point_of = vec![0usize; by_point.len()];
        for p in 0..n_points {
            let start = by_point.row_start(p);
            for (k, &i) in by_point.row(p).iter().enumerate() {
                recording_of[start + k] = recording(i);
                point_of[start + k] = p;
            }
        }
        let by_recording = Csr::from_pairs(
            n_recordings,
            recording_of.iter().enumerate().map(|(pos, &r)| (r, pos)),
        );
        Self {
            by_point,
            recording_of,
            point_of,
            by_recording,
        }
    }

    /// Positions of point p's observations.
    pub fn positions_of_point(&self, p: usize) -> std::ops::Range<usize> {
        let start = self.by_point.row_start(p);
        start..start + self.by_point.row(p).len()
    }
}

/// The block structure of the reduced camera matrix and its symbolic factorisation.
#[derive(Clone, Debug, PartialEq)]
pub struct ReducedStructure {
    /// Row r: the columns c ≤ r of its non-zero blocks, ascending (the last one is r itself).
    pub rows: Csr,
    /// Row r: the relative constraints whose larger recording index is r.
    pub relative_by_row: Csr,
    pub symbolic: Symbolic,
    /// Where each block of `rows` goes in the factor (same order as `rows`' values).
    pub slots: Vec<Slot>,
}

impl ReducedStructure {
    /// The structure for the observation layout and the relative constraints `(from, to)`.
    pub fn new(layout: &ObservationLayout, relative: &[(usize, usize)]) -> Self {
        let n = layout.by_recording.rows();
        let mut start = Vec::with_capacity(n + 1);
        let mut index = Vec::new();
        start.push(0);
        let relative_by_row = Csr::from_pairs(
            n,
            relative
                .iter()
                .enumerate()
                .map(|(k, &(a, b))| (a.max(b), k)),
        );
        for r in 0..n {
            let first = index.len();
            for &pos in layout.by_recording.row(r) {
                for other in layout.positions_of_point(layout.point_of[pos]) {
                    let c = layout.recording_of[other];
                    if c < r {
                        index.push(c);
                    }
                }
            }
            for &k in relative_by_row.row(r) {
                let (a, b) = relative[k];
                index.push(a.min(b));
            }
            sort_unique_tail(&mut index, first);
            index.push(r);
            start.push(index.len());
        }
        let rows = Csr::from_parts(start, index);
        let symbolic = Symbolic::new(&rows, fill_reducing(&rows));
        let slots = (0..n)
            .flat_map(|r| rows.row(r).iter().map(move |&c| (r, c)))
            .map(|(r, c)| {
                symbolic
                    .slot(r, c)
                    .expect("every block of the matrix lies in its factor's structure")
            })
            .collect();
        Self {
            rows,
            relative_by_row,
            symbolic,
            slots,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn couples_recordings_that_share_a_point_or_a_constraint() {
        // Point 0 seen by recordings 0, 1, 2; point 1 by 2 and 3 (observation 5 of point 1 by 3 inactive);
        // a relative constraint 4 → 3.
        let recording = [0, 1, 2, 2, 3];
        let active = [(0, 0), (1, 0), (2, 0), (3, 1), (4, 1)];
        let layout = ObservationLayout::new(5, 2, active.iter().copied(), |i| recording[i]);
        assert_eq!(layout.by_point.row(0), &[0, 1, 2]);
        assert_eq!(layout.by_point.row(1), &[3, 4]);
        assert_eq!(layout.recording_of, vec![0, 1, 2, 2, 3]);
        assert_eq!(layout.by_recording.row(2), &[2, 3]);
        assert_eq!(layout.positions_of_point(1), 3..5);
        let s = ReducedStructure::new(&layout, &[(4, 3)]);
        assert_eq!(s.rows.row(0), &[0]);
        assert_eq!(s.rows.row(1), &[0, 1]);
        assert_eq!(s.rows.row(2), &[0, 1, 2]);
        assert_eq!(s.rows.row(3), &[2, 3]);
        assert_eq!(s.rows.row(4), &[3, 4]);
        assert_eq!(s.relative_by_row.row(4), &[0]);
        assert_eq!(s.slots.len(), s.rows.len());
    }
}
