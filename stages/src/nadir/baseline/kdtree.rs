//! Box-neighbourhood counting over 2-D points for the chapter-2 baseline, which keeps only isolated aerial
//! keypoints, i.e. those with few neighbours inside a square box (thesis 2.2.3.2, "a kd-tree is used to identify
//! isolated keypoints"). The spatial index is the `rstar` crate's R*-tree (bulk-loaded, deterministic);
//! this wrapper only fixes the query the baseline needs.

use rstar::{RTree, AABB};

/// A static spatial index over 2-D points (any unit; the caller's pixels or metres).
pub struct KdTree2 {
    tree: RTree<[f64; 2]>,
}

impl KdTree2 {
    /// Build the index; non-finite points are left out (they are never found by queries).
    pub fn build(points: &[[f64; 2]]) -> Self {
        let finite: Vec<[f64; 2]> = points
            .iter()
            .copied()
            .filter(|p| p[0].is_finite() && p[1].is_finite())
            .collect();
        Self {
            tree: RTree::bulk_load(finite),
        }
    }

    /// Number of points p with |p.x − c.x| ≤ half_x and |p.y − c.y| ≤ half_y (including a point at `c`).
    pub fn count_in_box(&self, c: [f64; 2], half: [f64; 2]) -> usize {
        let lo = [c[0] - half[0], c[1] - half[1]];
        let hi = [c[0] + half[0], c[1] + half[1]];
        self.tree
            .locate_in_envelope(&AABB::from_corners(lo, hi))
            .count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

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
