//! 2-D similarity: exact recovery, inverse/compose, Umeyama equivalence, normalisation invariance.

use crate::geometry::{PointPair, Similarity2};
use nalgebra::{Matrix2, Vector2};

fn truth() -> Similarity2 {
    Similarity2::new(1.37, 0.61, -412.5, 88.25)
}

fn pairs_for(sim: &Similarity2, n: usize, seed: u64, offset: f64, noise: f64) -> Vec<PointPair> {
    let map = |src: &Vector2<f64>| sim.apply(src);
    super::pairs_of(map, n, seed, (offset, (1000.0, 800.0)), Some(noise))
}

fn assert_sim_close(a: &Similarity2, b: &Similarity2, rel: f64) {
    assert!((a.scale - b.scale).abs() <= rel * b.scale, "{a:?} vs {b:?}");
    assert!(
        (a.rotation_rad - b.rotation_rad).abs() <= rel,
        "{a:?} vs {b:?}"
    );
    let t_scale = 1.0 + b.tx.abs().max(b.ty.abs());
    assert!(
        (a.tx - b.tx).abs() <= rel * t_scale && (a.ty - b.ty).abs() <= rel * t_scale,
        "{a:?} vs {b:?}"
    );
}

#[test]
fn apply_by_hand() {
    let sim = Similarity2::new(2.0, std::f64::consts::FRAC_PI_2, 1.0, -1.0);
    let p = sim.apply(&Vector2::new(1.0, 0.0));
    assert!((p - Vector2::new(1.0, 1.0)).norm() < 1e-15);
    let m = sim.to_matrix();
    assert!((m[(0, 1)] + 2.0).abs() < 1e-15 && (m[(1, 0)] - 2.0).abs() < 1e-15 && m[(2, 2)] == 1.0);
}

#[test]
fn exact_recovery_from_two_and_many_pairs() {
    let t = truth();
    let pairs = pairs_for(&t, 30, 1, 0.0, 0.0);
    let two =
        Similarity2::from_two_pairs(&pairs[0].src, &pairs[0].dst, &pairs[1].src, &pairs[1].dst)
            .unwrap();
    assert_sim_close(&two, &t, 1e-10);
    assert_sim_close(&Similarity2::least_squares(&pairs).unwrap(), &t, 1e-10);
    // At world-scale coordinates too.
    let world = pairs_for(&t, 30, 2, 437_000.0, 0.0);
    assert_sim_close(&Similarity2::least_squares(&world).unwrap(), &t, 1e-9);
}

#[test]
fn degenerate_inputs_give_none() {
    let p = Vector2::new(5.0, 5.0);
    assert_eq!(
        Similarity2::from_two_pairs(&p, &Vector2::new(1.0, 1.0), &p, &Vector2::new(2.0, 2.0)),
        None
    );
    let q = Vector2::new(3.0, 1.0);
    assert_eq!(
        Similarity2::from_two_pairs(&p, &q, &Vector2::new(1.0, 0.0), &q),
        None,
        "zero scale"
    );
    assert_eq!(
        Similarity2::least_squares(&[PointPair::new(1.0, 2.0, 3.0, 4.0)]),
        None
    );
}

#[test]
fn inverse_and_compose() {
    let a = truth();
    let b = Similarity2::new(0.8, -2.9, 10.0, 20.0);
    let p = Vector2::new(123.4, -56.7);
    assert!((a.inverse().apply(&a.apply(&p)) - p).norm() < 1e-9);
    assert!((a.compose(&b).apply(&p) - a.apply(&b.apply(&p))).norm() < 1e-9);
    let id = a.compose(&a.inverse());
    assert_sim_close(&id, &Similarity2::identity(), 1e-12);
    assert!((a.compose(&b).to_matrix() - a.to_matrix() * b.to_matrix()).norm() < 1e-9);
}

/// Umeyama (1991) with an SVD, as a reference for the closed form.
fn umeyama_reference(pairs: &[PointPair]) -> Similarity2 {
    let n = pairs.len() as f64;
    let mu_s = pairs.iter().map(|p| p.src).sum::<Vector2<f64>>() / n;
    let mu_d = pairs.iter().map(|p| p.dst).sum::<Vector2<f64>>() / n;
    let var_s = pairs
        .iter()
        .map(|p| (p.src - mu_s).norm_squared())
        .sum::<f64>()
        / n;
    let cov = pairs
        .iter()
        .map(|p| (p.dst - mu_d) * (p.src - mu_s).transpose())
        .sum::<Matrix2<f64>>()
        / n;
    let svd = cov.svd(true, true);
    let (u, v_t) = (svd.u.unwrap(), svd.v_t.unwrap());
    let sign = (u.determinant() * v_t.determinant()).signum();
    let s_mat = Matrix2::new(1.0, 0.0, 0.0, sign);
    let r = u * s_mat * v_t;
    let scale = (Matrix2::from_diagonal(&svd.singular_values) * s_mat).trace() / var_s;
    let t = mu_d - r * mu_s * scale;
    Similarity2 {
        scale,
        rotation_rad: r[(1, 0)].atan2(r[(0, 0)]),
        tx: t.x,
        ty: t.y,
    }
}

#[test]
fn least_squares_equals_umeyama_on_noisy_data() {
    let pairs = pairs_for(&truth(), 50, 3, 0.0, 2.0);
    let ls = Similarity2::least_squares(&pairs).unwrap();
    assert_sim_close(&ls, &umeyama_reference(&pairs), 1e-12);
    // And it is close to the truth given the noise.
    assert_sim_close(&ls, &truth(), 1e-2);
}

#[test]
fn normalisation_invariance() {
    // Move both point sets by (1e5, 1e5) and scale by 10: the fit is the conjugated transform.
    let pairs = pairs_for(&truth(), 40, 4, 0.0, 0.5);
    let fit = Similarity2::least_squares(&pairs).unwrap();
    let g = Similarity2::new(10.0, 0.0, 1e5, 1e5);
    let moved: Vec<PointPair> = pairs
        .iter()
        .map(|p| PointPair {
            src: g.apply(&p.src),
            dst: g.apply(&p.dst),
        })
        .collect();
    let fit_moved = Similarity2::least_squares(&moved).unwrap();
    let back = g.inverse().compose(&fit_moved).compose(&g);
    assert_sim_close(&back, &fit, 1e-9);
}
