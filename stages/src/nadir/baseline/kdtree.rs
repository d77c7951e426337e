//! A static 2-D kd-tree for box-neighbourhood counting: the chapter-2 baseline keeps only isolated aerial
//! keypoints, i.e. those with few neighbours inside a square box (thesis 2.2.3.2, "a kd-tree is used to
//! identify isolated keypoints").
//!
//! The tree is an implicit balanced tree over a permutation of the points: the node of a slice is its median
//! element along the split axis (x at even depth, y at odd depth), left/right halves are the sub-trees. Building
//! is O(n log² n) with deterministic `sort_by` (ties by index), a box query O(√n + k).

/// A kd-tree over 2-D points (any unit; the caller's pixels or metres).
pub struct KdTree2 {
    points: Vec<[f64; 2]>,
    /// Indices into `points`, arranged as the implicit tree.
    order: Vec<usize>,
}

impl KdTree2 {
    /// Build the tree; non-finite points are kept but never found by queries.
    pub fn build(points: &[[f64; 2]]) -> Self {
        let mut order: Vec<usize> = (0..points.len()).collect();
        build_rec(points, &mut order, 0);
        Self {
            points: points.to_vec(),
            order,
        }
    }

    /// Number of points p with |p.x − c.x| ≤ half_x and |p.y − c.y| ≤ half_y (including a point at `c`).
    pub fn count_in_box(&self, c: [f64; 2], half: [f64; 2]) -> usize {
        let lo = [c[0] - half[0], c[1] - half[1]];
        let hi = [c[0] + half[0], c[1] + half[1]];
        self.count_rec(&self.order, 0, lo, hi)
    }

    fn count_rec(&self, slice: &[usize], depth: usize, lo: [f64; 2], hi: [f64; 2]) -> usize {
        if slice.is_empty() {
            return 0;
        }
        let mid = slice.len() / 2;
        let p = self.points[slice[mid]];
        let axis = depth % 2;
        let inside = (lo[0]..=hi[0]).contains(&p[0]) && (lo[1]..=hi[1]).contains(&p[1]);
        let mut n = usize::from(inside);
        // Left sub-tree holds values ≤ p[axis], right ≥ p[axis] (ties may sit on both sides).
        if lo[axis] <= p[axis] {
            n += self.count_rec(&slice[..mid], depth + 1, lo, hi);
        }
        if hi[axis] >= p[axis] {
            n += self.count_rec(&slice[mid + 1..], depth + 1, lo, hi);
        }
        n
    }
}

fn build_rec(points: &[[f64; 2]], slice: &mut [usize], depth: usize) {
    if slice.len() <= 1 {
        return;
    }
    let axis = depth % 2;
    slice.sort_by(|&a, &b| points[a][axis].total_cmp(&points[b][axis]).then(a.cmp(&b)));
    let mid = slice.len() / 2;
    let (left, right) = slice.split_at_mut(mid);
    build_rec(points, left, depth + 1);
    build_rec(points, &mut right[1..], depth + 1);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimators::rng::SplitMix64;

    #[test]
    fn box_counts_equal_brute_force() {
        let mut rng = SplitMix64::new(7);
        let mut pts: Vec<[f64; 2]> = (0..500)
            .map(|_| [rng.next_f64() * 100.0, rng.next_f64() * 80.0])
            .collect();
        // Duplicates and ties on the split axes.
        pts.push(pts[3]);
        pts.push([pts[10][0], 5.0]);
        let tree = KdTree2::build(&pts);
        for (k, &c) in pts.iter().enumerate() {
            let half = [3.0 + (k % 5) as f64, 2.0 + (k % 3) as f64];
            let brute = pts
                .iter()
                .filter(|p| (p[0] - c[0]).abs() <= half[0] && (p[1] - c[1]).abs() <= half[1])
                .count();
            assert_eq!(tree.count_in_box(c, half), brute, "point {k}");
        }
        assert_eq!(KdTree2::build(&[]).count_in_box([0.0, 0.0], [1.0, 1.0]), 0);
    }
}
