//! Known-answer tests of the chapter-2 baseline (thesis 2.2.3): isolated Förstner keypoints (kd-tree box
//! count) and NCC template matching of MM-ortho templates in aerial windows, on a synthetic marking pattern
//! whose aerial image is a similarity-transformed, radiometrically changed copy.

use nalgebra::Vector2;
use skytie_stages::campaign::AerialImage;
use skytie_stages::geometry::Similarity2;
use skytie_stages::imaging::pyramid::MemoryPyramid;
use skytie_stages::imaging::GrayImage;
use skytie_stages::nadir::aerial_patch::AerialWindow;
use skytie_stages::nadir::baseline::{
    baseline_matches, isolated_aerial_keypoints, BaselineParams, KdTree2,
};
use skytie_stages::nadir::{AerialRefinement, MmWindowMatch, OrthoImage};
use skytie_stages::params::Params;
use support::ortho_pair::{
    initial_transform, ortho_georef, render_aerial, render_ortho, tie_index, true_aerial_px,
    true_similarity, window_at, FOOT_WORLD,
};

mod support;

/// Bright axis-aligned squares (world metres) on a grey road with smooth (blurred) edges.
struct Markings {
    squares: Vec<[f64; 4]>,
}

impl Markings {
    fn new(foot: [f64; 2]) -> Self {
        let mut squares = Vec::new();
        // Three isolated 1 m squares ≥ 10 m apart.
        for (cx, cy) in [(-6.0, -6.0), (6.0, -6.0), (-6.0, 6.0)] {
            squares.push([
                foot[0] + cx - 0.5,
                foot[1] + cy - 0.5,
                foot[0] + cx + 0.5,
                foot[1] + cy + 0.5,
            ]);
        }
        // A repetitive block: 3 × 3 squares of 0.8 m every 1.6 m (every corner has ≥ 15 others within 3 m).
        for j in 0..3 {
            for i in 0..3 {
                let (x, y) = (
                    foot[0] + 3.0 + 1.6 * i as f64,
                    foot[1] + 3.0 + 1.6 * j as f64,
                );
                squares.push([x, y, x + 0.8, y + 0.8]);
            }
        }
        Self { squares }
    }

    fn at(&self, x: f64, y: f64) -> f64 {
        let edge = |t: f64| 0.5 * (1.0 + (t / 0.06).tanh());
        let mut v = 0.3;
        for s in &self.squares {
            v += 0.5 * (edge(x - s[0]) - edge(x - s[2])) * (edge(y - s[1]) - edge(y - s[3]));
        }
        v
    }

    fn corners(&self) -> Vec<[f64; 2]> {
        self.squares
            .iter()
            .flat_map(|s| [[s[0], s[1]], [s[2], s[1]], [s[0], s[3]], [s[2], s[3]]])
            .collect()
    }
}

struct Scene {
    ortho: OrthoImage,
    aerial: GrayImage,
    truth: Similarity2,
    window: MmWindowMatch,
    row: AerialImage,
    isolated_tie_points: usize,
}

fn scene() -> Scene {
    let foot = FOOT_WORLD;
    let m = Markings::new([foot[0], foot[1]]);
    let georef = ortho_georef(foot);
    let (w, h) = (georef.width_px, georef.height_px);
    let ortho = OrthoImage {
        image: render_ortho(&georef, |x_m, y_m| m.at(x_m, y_m)),
        valid: vec![1; w * h],
        georef: georef.clone(),
    };
    let truth = true_similarity();
    let aerial = render_aerial(&georef, &truth, |c, r, x_m, y_m| {
        // Different sensor: gain, offset, gamma, a faint deterministic texture.
        let texture = 0.01 * ((0.7 * c as f64).sin() * (0.9 * r as f64).cos());
        0.1 + 0.7 * m.at(x_m, y_m).powf(0.8) + texture
    });
    let window = window_at(m.corners().iter().map(|c| [c[0], c[1], foot[2]]).collect());
    // A nadir camera whose GSD at the ground is 0.1 m (only the GSD is used by the isolation test).
    let row = AerialImage::ideal(
        "aer",
        [foot[0], foot[1], foot[2] + 4470.0],
        [0.0, 0.0, 0.0],
        44700.0,
        [400, 360],
    );
    Scene {
        ortho,
        aerial,
        truth,
        window,
        row,
        isolated_tie_points: 12,
    }
}

/// `baseline_matches` of the scene's window from the initial similarity `initial`.
fn matches(s: &Scene, initial: Similarity2, p: &BaselineParams) -> AerialRefinement {
    baseline_matches(
        &s.ortho,
        &MemoryPyramid::from_gray(&s.aerial),
        &s.row,
        &initial_transform(initial),
        &s.window,
        p,
    )
    .unwrap()
}

fn true_aerial_px_of(s: &Scene, i: usize) -> Vector2<f64> {
    true_aerial_px(&s.ortho.georef, &s.truth, s.window.ground_world[i])
}

#[test]
fn kd_tree_isolation_keeps_corners_of_isolated_markings_only() {
    let s = scene();
    let p = BaselineParams::default();
    // The window `baseline_matches` reads: the footprint grown by half the isolation box.
    let tf = s.truth;
    let size = (s.ortho.image.width, s.ortho.image.height);
    let margin = p.isolation_box_m / 2.0 / 0.1 / tf.scale;
    let pyramid = MemoryPyramid::from_gray(&s.aerial);
    let window = AerialWindow::read(&pyramid, size, &tf, margin)
        .unwrap()
        .unwrap();
    let kps = isolated_aerial_keypoints(&window, 0.1, &p);
    // Every kept keypoint is near a corner of an isolated square, and every such corner has a keypoint.
    let near = |k: &[f64; 2], i: usize| {
        let t = true_aerial_px_of(&s, i);
        (k[0] - t.x).hypot(k[1] - t.y) < 1.0
    };
    for k in &kps {
        assert!(
            (0..s.isolated_tie_points).any(|i| near(k, i)),
            "keypoint {k:?} is not at an isolated corner"
        );
    }
    for i in 0..s.isolated_tie_points {
        assert!(kps.iter().any(|k| near(k, i)), "corner {i} not detected");
    }
    // The repetitive block's corners are crowded: none is kept.
    for i in s.isolated_tie_points..s.window.tie_points.len() {
        assert!(!kps.iter().any(|k| near(k, i)));
    }
}

#[test]
fn kd_tree_box_count_rule_at_the_boundary() {
    // 8 points in a 6 × 6 box: each has exactly 7 neighbours (isolated at the ≤ 7 rule); a 9th makes 8.
    let mut pts: Vec<[f64; 2]> = (0..8).map(|i| [i as f64 * 0.7, (i % 3) as f64]).collect();
    // Far points never count.
    pts.push([20.0, 0.0]);
    pts.push([2.1, -3.01]);
    let tree = KdTree2::build(&pts);
    // Point 3 (2.1, 0): the box [−0.9, 5.1] × [−3, 3] holds all 8 near points, itself included.
    assert_eq!(tree.count_in_box(pts[3], [3.0, 3.0]) - 1, 7);
    pts.push([2.5, 1.5]);
    let tree = KdTree2::build(&pts);
    assert_eq!(tree.count_in_box(pts[3], [3.0, 3.0]) - 1, 8);
}

#[test]
fn baseline_locates_isolated_corners_by_ncc_and_snaps_to_the_keypoints() {
    let s = scene();
    let p = BaselineParams::default();
    p.validate().unwrap();
    // The initial transform is off by a few pixels (well inside the ±12 px of a 16-in-40 search).
    let off = Similarity2::new(1.0, 0.004, 3.2, -2.1);
    let r = matches(&s, off.compose(&s.truth), &p);
    println!("tried {} matched {}", r.tried, r.matches.len());
    assert_eq!(r.tried, s.window.tie_points.len());
    let mut located = vec![false; s.window.tie_points.len()];
    let mut max_err = 0.0f64;
    for m in &r.matches {
        let i = tie_index(&m.tie_point_id);
        located[i] = true;
        let t = true_aerial_px_of(&s, i);
        let e = (m.observation.u_px - t.x).hypot(m.observation.v_px - t.y);
        max_err = max_err.max(e);
        assert!(m.observation.score >= p.min_ncc);
        let pred = (m.predicted_u_px - t.x).hypot(m.predicted_v_px - t.y);
        assert!(pred > 2.0, "prediction was off by {pred}");
    }
    println!("max error {max_err:.3} px");
    assert!(max_err < 0.5, "{max_err}");
    // All isolated corners found, none of the repetitive block.
    assert!(
        located[..s.isolated_tie_points].iter().all(|&l| l),
        "{located:?}"
    );
    assert!(
        located[s.isolated_tie_points..].iter().all(|&l| !l),
        "{located:?}"
    );
    // Deterministic.
    let again = matches(&s, off.compose(&s.truth), &p);
    assert_eq!(r, again);
}

#[test]
fn baseline_params_validate_and_reject_unknown_keys() {
    assert!(BaselineParams::default().validate().is_ok());
    let bad = BaselineParams {
        search_px: 10,
        ..BaselineParams::default()
    };
    assert_eq!(bad.validate().unwrap_err()[0].field, "search_px");
    assert!(toml::from_str::<BaselineParams>("template = 16").is_err());
    let p: BaselineParams = toml::from_str("min_ncc = 0.8").unwrap();
    assert_eq!(p.min_ncc, 0.8);
}
