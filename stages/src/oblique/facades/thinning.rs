//! Non-uniform box-grid thinning of a plane's inliers (thesis 4.4.4; Pomerleau et al. 2013; Pomerleau et al. 2013).
//!
//! A box holding more than K points is split along its longest dimension — at the median point
//! ([`ThinningSplit::Median`]: left gets n − ⌊n/2⌋ points) or at the spatial midpoint
//! ([`ThinningSplit::Midpoint`]) — and the halves are processed recursively; boxes are the tight bounds of
//! their points. One random point is kept per leaf box. A box is also split, whatever its count, while its
//! longest dimension exceeds `max_box_m` (like an octree's maximum node size): without this cap a box of ≤ K
//! points far apart is a leaf and isolated points are merged — e.g. 10 points 10 m apart beside a dense
//! cluster, split at the midpoint, end in boxes of ≤ K points and only a few survive; with the cap every
//! isolated point gets its own box and is kept while clusters are still thinned (the thesis' "points with
//! high proximity, rather than isolated points, will be removed"). `f64::INFINITY` gives the plain
//! count-based reference behaviour (libpointmatcher). A box whose points all coincide along every axis is a
//! leaf whatever its count. Ties are broken by index (sort by (coordinate, index)), leaves are visited
//! depth-first left to right and the RNG is seeded, so the result is deterministic.

use super::params::ThinningSplit;
use crate::estimators::SplitMix64;
use crate::geometry::bounding_box;

/// Indices (ascending) into `points` of the points kept: one per leaf box of at most
/// `max_points_per_box` points and at most `max_box_m` along its longest dimension (module documentation).
/// Non-finite points are never kept. `max_points_per_box` = 0 is treated as 1.
pub fn box_grid_thin(
    points: &[[f64; 3]],
    max_points_per_box: usize,
    max_box_m: f64,
    split: ThinningSplit,
    seed: u64,
) -> Vec<usize> {
    let k = max_points_per_box.max(1);
    let mut order: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].iter().all(|c| c.is_finite()))
        .collect();
    let mut rng = SplitMix64::new(seed);
    let mut kept = Vec::new();
    // Depth-first over index ranges of `order`; the right half is pushed first so the left is visited first.
    let mut stack: Vec<(usize, usize)> = vec![(0, order.len())];
    while let Some((start, end)) = stack.pop() {
        let n = end - start;
        if n == 0 {
            continue;
        }
        let range = &mut order[start..end];
        let (lo, hi) = bounding_box(range.iter().map(|&i| &points[i]));
        let axis = (0..3)
            .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])).then(b.cmp(&a)))
            .unwrap_or(0);
        let extent = hi[axis] - lo[axis];
        let leaf = (n <= k && !(extent > max_box_m)) || !(extent > 0.0) || {
            range.sort_by(|&a, &b| points[a][axis].total_cmp(&points[b][axis]).then(a.cmp(&b)));
            let cut = match split {
                ThinningSplit::Median => n - n / 2,
                ThinningSplit::Midpoint => {
                    let mid = lo[axis] + 0.5 * extent;
                    range.partition_point(|&i| points[i][axis] < mid)
                }
            };
            if cut == 0 || cut == n {
                true
            } else {
                stack.push((start + cut, end));
                stack.push((start, start + cut));
                false
            }
        };
        if leaf {
            let pick = rng.below(n as u64) as usize;
            kept.push(order[start + pick]);
        }
    }
    kept.sort_unstable();
    kept
}
