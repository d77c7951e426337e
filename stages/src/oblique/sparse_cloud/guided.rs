//! Guided matching between two perspective views of the sparse cloud (thesis 4.4.1 matches views 1–2 and
//! 2–3; here the recorded poses narrow each feature's candidates first, as 3.4.5.2 does for the nadir
//! matching with its search window). A feature at pixel x of view A sees the object points C_A + d·r(x) for
//! depths d in [`min_depth`, `max_depth`]; their images in view B form a segment of the epipolar line of x.
//! Candidates in view B are the features within `tolerance_px` of that segment. Façades repeat windows and
//! panels along the street; without this restriction the ratio test rejects most true matches as ambiguous.

use crate::geometry::perspective::PerspectiveView;

/// Depth samples along a ray (geometric spacing: the image of the ray is dense near the camera).
const DEPTH_SAMPLES: usize = 24;

/// The image in `b` of the ray of pixel `x_a` of `a` for depths in [min_depth_m, max_depth_m], as a
/// polyline of view-B pixels (only the samples in front of B; may be empty).
pub fn epipolar_segment(
    a: &PerspectiveView,
    b: &PerspectiveView,
    x_a: [f64; 2],
    min_depth_m: f64,
    max_depth_m: f64,
) -> Vec<[f64; 2]> {
    let dir = a.pixel_to_ray_world(x_a[0], x_a[1]);
    let ratio = (max_depth_m / min_depth_m).powf(1.0 / (DEPTH_SAMPLES - 1) as f64);
    let mut depth = min_depth_m;
    let mut out = Vec::with_capacity(DEPTH_SAMPLES);
    for _ in 0..DEPTH_SAMPLES {
        if let Some((u, v)) = b.project_world(&(a.center_world + dir * depth)) {
            out.push([u, v]);
        }
        depth *= ratio;
    }
    out
}

/// Distance of `p` from the polyline `line` (a single point: distance to it; empty: infinite), px.
pub fn distance_to_polyline(p: [f64; 2], line: &[[f64; 2]]) -> f64 {
    match line {
        [] => f64::INFINITY,
        [q] => (p[0] - q[0]).hypot(p[1] - q[1]),
        _ => line
            .windows(2)
            .map(|s| distance_to_segment(p, s[0], s[1]))
            .fold(f64::INFINITY, f64::min),
    }
}

fn distance_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

/// For every feature of view `a` (pixels `pts_a`), the ascending indices of the features of view `b`
/// (pixels `pts_b`) within `tolerance_px` of its epipolar segment.
pub fn epipolar_candidates(
    a: &PerspectiveView,
    b: &PerspectiveView,
    pts_a: &[[f64; 2]],
    pts_b: &[[f64; 2]],
    min_depth_m: f64,
    max_depth_m: f64,
    tolerance_px: f64,
) -> Vec<Vec<usize>> {
    use rayon::prelude::*;
    pts_a
        .par_iter()
        .map(|&x| {
            let line = epipolar_segment(a, b, x, min_depth_m, max_depth_m);
            if line.is_empty() {
                return Vec::new();
            }
            // Bounding box of the polyline, grown by the tolerance, for a cheap first test.
            let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for q in &line {
                for k in 0..2 {
                    lo[k] = lo[k].min(q[k] - tolerance_px);
                    hi[k] = hi[k].max(q[k] + tolerance_px);
                }
            }
            pts_b
                .iter()
                .enumerate()
                .filter(|(_, p)| (0..2).all(|k| p[k] >= lo[k] && p[k] <= hi[k]))
                .filter(|(_, p)| distance_to_polyline(**p, &line) <= tolerance_px)
                .map(|(i, _)| i)
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn a_point_lies_on_its_epipolar_segment_and_a_shifted_one_does_not() {
        let a = PerspectiveView::new(512, 90.0, 300.0, 30.0, 0.0, Vector3::new(0.0, 0.0, 2.5));
        let b = PerspectiveView::new(512, 90.0, 270.0, 30.0, 0.0, Vector3::new(0.0, 5.0, 2.5));
        // An object point 9 m west of b, 4 m up.
        let x = Vector3::new(-9.0, 5.0, 6.5);
        let (ua, va) = a.project_world(&x).unwrap();
        let (ub, vb) = b.project_world(&x).unwrap();
        let line = epipolar_segment(&a, &b, [ua, va], 2.0, 30.0);
        assert!(
            distance_to_polyline([ub, vb], &line) < 0.2,
            "on the segment"
        );
        let c = epipolar_candidates(
            &a,
            &b,
            &[[ua, va]],
            &[[ub, vb], [ub, vb + 30.0]],
            2.0,
            30.0,
            3.0,
        );
        assert_eq!(c, vec![vec![0]]);
        // Depth outside [2, 5] m: the segment stops before the true image.
        let short = epipolar_segment(&a, &b, [ua, va], 2.0, 5.0);
        assert!(distance_to_polyline([ub, vb], &short) > 10.0);
    }

    #[test]
    fn polyline_distance_handles_degenerate_lines() {
        assert_eq!(distance_to_polyline([1.0, 1.0], &[]), f64::INFINITY);
        assert!((distance_to_polyline([3.0, 4.0], &[[0.0, 0.0]]) - 5.0).abs() < 1e-12);
        assert!((distance_to_polyline([1.0, 2.0], &[[0.0, 0.0], [4.0, 0.0]]) - 2.0).abs() < 1e-12);
    }
}
