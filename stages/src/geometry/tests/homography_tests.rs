//! Homography: normalised DLT recovery, degeneracy, inverse, normalisation invariance.

use crate::geometry::{Homography, PointPair};
use crate::rng::SplitMix64;
use nalgebra::{Matrix3, Vector2};

pub(crate) fn truth() -> Homography {
    Homography(Matrix3::new(
        1.1, 0.05, -30.0, -0.08, 0.95, 12.0, 2e-4, -1e-4, 1.0,
    ))
    .normalized()
}

fn pairs_for(h: &Homography, n: usize, seed: u64, offset: f64) -> Vec<PointPair> {
    let map = |src: &Vector2<f64>| h.apply(src).unwrap();
    super::pairs_of(map, n, seed, (offset, (1000.0, 1000.0)), None)
}

fn assert_h_close(a: &Homography, b: &Homography, tol: f64) {
    let (a, b) = (a.normalized(), b.normalized());
    assert!((a.0 - b.0).norm() <= tol, "{:?} vs {:?}", a.0, b.0);
}

#[test]
fn exact_recovery_from_four_and_many_pairs() {
    let t = truth();
    let four = pairs_for(&t, 4, 11, 0.0);
    assert_h_close(&Homography::from_pairs(&four).unwrap(), &t, 1e-9);
    let many = pairs_for(&t, 50, 12, 0.0);
    let fit = Homography::from_pairs(&many).unwrap();
    assert_h_close(&fit, &t, 1e-10);
    for p in &many {
        assert!(fit.transfer_error(p) < 1e-8);
    }
}

#[test]
fn apply_by_hand() {
    let h = Homography(Matrix3::new(2.0, 0.0, 1.0, 0.0, 2.0, -1.0, 0.0, 0.0, 2.0));
    assert_eq!(
        h.apply(&Vector2::new(1.0, 1.0)),
        Some(Vector2::new(1.5, 0.5))
    );
    // A point on the line at infinity maps nowhere.
    let p = Homography(Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, -1.0));
    assert_eq!(p.apply(&Vector2::new(1.0, 5.0)), None);
}

#[test]
fn degenerate_samples_give_none() {
    let t = truth();
    // Three of four source points collinear.
    let src = [
        Vector2::new(0.0, 0.0),
        Vector2::new(1.0, 1.0),
        Vector2::new(2.0, 2.0),
        Vector2::new(0.0, 5.0),
    ];
    let pairs: Vec<PointPair> = src
        .iter()
        .map(|s| PointPair {
            src: *s,
            dst: t.apply(s).unwrap(),
        })
        .collect();
    assert_eq!(Homography::from_pairs(&pairs), None);
    // Many points all on one line (a road marking): rank test.
    let line: Vec<PointPair> = (0..20)
        .map(|i| {
            let s = Vector2::new(f64::from(i) * 10.0, 3.0 + f64::from(i) * 5.0);
            PointPair {
                src: s,
                dst: t.apply(&s).unwrap(),
            }
        })
        .collect();
    assert_eq!(Homography::from_pairs(&line), None);
    assert_eq!(Homography::from_pairs(&pairs[..3]), None);
}

#[test]
fn inverse_and_compose() {
    let t = truth();
    let inv = t.inverse().unwrap();
    for p in pairs_for(&t, 10, 13, 0.0) {
        assert!((inv.apply(&p.dst).unwrap() - p.src).norm() < 1e-9);
    }
    assert_h_close(&t.compose(&inv), &Homography::identity(), 1e-12);
    assert_eq!(Homography(Matrix3::zeros()).inverse(), None);
}

#[test]
fn normalisation_invariance() {
    // Translating all inputs by (1e5, 1e5) and scaling by 10 gives the conjugated transform.
    let t = truth();
    let pairs = pairs_for(&t, 30, 14, 0.0);
    let g = Homography(Matrix3::new(10.0, 0.0, 1e5, 0.0, 10.0, 1e5, 0.0, 0.0, 1.0));
    let moved: Vec<PointPair> = pairs
        .iter()
        .map(|p| PointPair {
            src: g.apply(&p.src).unwrap(),
            dst: g.apply(&p.dst).unwrap(),
        })
        .collect();
    let fit_moved = Homography::from_pairs(&moved).unwrap();
    let back = g.inverse().unwrap().compose(&fit_moved).compose(&g);
    assert_h_close(&back, &t, 1e-9);
}

#[test]
fn similarity_converts_to_an_equal_homography() {
    let sim = crate::geometry::Similarity2::new(1.2, 0.4, 3.0, -9.0);
    let h = Homography::from(sim);
    let p = Vector2::new(17.0, -4.0);
    assert!((h.apply(&p).unwrap() - sim.apply(&p)).norm() < 1e-12);
}

fn transfer_cost(h: &Homography, pairs: &[PointPair]) -> f64 {
    pairs.iter().map(|p| h.transfer_error(p).powi(2)).sum()
}

#[test]
fn lm_refinement_lowers_transfer_error_to_a_local_minimum() {
    let t = truth();
    let mut rng = SplitMix64::new(15);
    // World-scale source coordinates, 0.7 px noise in the destination.
    let pairs: Vec<PointPair> = (0..80)
        .map(|_| {
            let src = Vector2::new(1000.0 * rng.next_f64(), 1000.0 * rng.next_f64());
            let dst = t.apply(&src).unwrap()
                + Vector2::new(rng.next_gaussian(), rng.next_gaussian()) * 0.7;
            PointPair { src, dst }
        })
        .collect();
    let dlt = Homography::from_pairs(&pairs).unwrap();
    let refined = dlt.refine_transfer_error(pairs.iter(), 50);
    let (c_dlt, c_ref) = (transfer_cost(&dlt, &pairs), transfer_cost(&refined, &pairs));
    assert!(c_ref <= c_dlt, "refined {c_ref} > dlt {c_dlt}");
    // Local minimum: perturbing any entry (relative 1e-6) does not lower the cost.
    for i in 0..3 {
        for j in 0..3 {
            for sign in [-1.0, 1.0] {
                let mut m = refined.0;
                m[(i, j)] += sign * 1e-6 * m.norm();
                let c = transfer_cost(&Homography(m), &pairs);
                assert!(
                    c >= c_ref * (1.0 - 1e-9),
                    "entry ({i},{j}) {sign}: {c} < {c_ref}"
                );
            }
        }
    }
    // Expected cost at the optimum ≈ (2n − 8)·σ²: a loose sanity check of the noise model.
    let expected = (2.0 * 80.0 - 8.0) * 0.49;
    assert!(
        c_ref > 0.7 * expected && c_ref < 1.3 * expected,
        "cost {c_ref}, expected ≈ {expected}"
    );
}

#[test]
fn lm_refinement_keeps_exact_solutions() {
    let t = truth();
    let pairs = pairs_for(&t, 20, 16, 0.0);
    let refined = Homography::from_pairs(&pairs)
        .unwrap()
        .refine_transfer_error(pairs.iter(), 10);
    assert_h_close(&refined, &t, 1e-10);
    // Fewer than 5 pairs: returned unchanged.
    let four = Homography::from_pairs(&pairs[..4]).unwrap();
    assert_eq!(four.refine_transfer_error(pairs[..4].iter(), 10), four);
}
