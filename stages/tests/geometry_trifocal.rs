//! Known-answer tests of the trifocal tensor and point transfer (Hartley & Zisserman 2004, ch. 15–16): random cameras K·R·[I | −C]
//! with random points in front of all three; the thesis' perspective-view configuration (three panoramas 5 m
//! apart, views at yaw deviations 300°/270°/240°, pitch 30°).

use nalgebra::{Matrix3, Matrix3x4, Matrix4, Vector3};
use skytie_stages::estimators::SplitMix64;
use skytie_stages::geometry::perspective::PerspectiveView;
use skytie_stages::geometry::rotation::opk_to_matrix;
use skytie_stages::geometry::trifocal::TrifocalTensor;
use skytie_stages::geometry::LocalOrigin;

fn range(rng: &mut SplitMix64, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.next_f64()
}

/// A random camera K·R·[I | −C] looking roughly at the origin from about 10 m.
fn random_camera(rng: &mut SplitMix64) -> Matrix3x4<f64> {
    let f = range(rng, 400.0, 1200.0);
    let k = Matrix3::new(
        f,
        0.0,
        range(rng, 300.0, 700.0),
        0.0,
        f * range(rng, 0.95, 1.05),
        range(rng, 300.0, 700.0),
        0.0,
        0.0,
        1.0,
    );
    let c = Vector3::new(
        range(rng, -3.0, 3.0),
        range(rng, -3.0, 3.0),
        range(rng, -12.0, -8.0),
    );
    // Camera looks along +z_cam; small random rotation about identity keeps the origin in front.
    let r = opk_to_matrix(
        range(rng, -10.0, 10.0),
        range(rng, -10.0, 10.0),
        range(rng, -180.0, 180.0),
    );
    let kr = k * r;
    let mut p = Matrix3x4::zeros();
    p.fixed_view_mut::<3, 3>(0, 0).copy_from(&kr);
    p.set_column(3, &(-(kr * c)));
    p
}

/// Three random cameras (see [`random_camera`]).
fn random_cameras(rng: &mut SplitMix64) -> [Matrix3x4<f64>; 3] {
    [random_camera(rng), random_camera(rng), random_camera(rng)]
}

/// A random point in the cube of ±2 m around the origin.
fn random_point(rng: &mut SplitMix64) -> Vector3<f64> {
    Vector3::new(
        range(rng, -2.0, 2.0),
        range(rng, -2.0, 2.0),
        range(rng, -2.0, 2.0),
    )
}

/// `x` in each of the three views.
fn project_three(ps: &[Matrix3x4<f64>; 3], x: &Vector3<f64>) -> ([f64; 2], [f64; 2], [f64; 2]) {
    (project(&ps[0], x), project(&ps[1], x), project(&ps[2], x))
}

fn project(p: &Matrix3x4<f64>, x: &Vector3<f64>) -> [f64; 2] {
    let h = p * x.push(1.0);
    [h.x / h.z, h.y / h.z]
}

fn flat(t: &TrifocalTensor) -> Vec<f64> {
    t.t.iter().flatten().flatten().copied().collect()
}

/// Largest difference after aligning the sign (both are unit-norm).
fn tensor_distance(a: &TrifocalTensor, b: &TrifocalTensor) -> f64 {
    let (fa, fb) = (flat(a), flat(b));
    let dot: f64 = fa.iter().zip(&fb).map(|(x, y)| x * y).sum();
    let s = dot.signum();
    fa.iter()
        .zip(&fb)
        .map(|(x, y)| (x - s * y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn transfer_of_exact_triples_is_exact() {
    let mut rng = SplitMix64::new(11);
    let mut worst: f64 = 0.0;
    for _ in 0..50 {
        let ps = random_cameras(&mut rng);
        let t = TrifocalTensor::from_cameras(&ps[0], &ps[1], &ps[2]);
        for _ in 0..20 {
            let x = random_point(&mut rng);
            let (x1, x2, x3) = project_three(&ps, &x);
            let got = t.transfer(x1, x2).unwrap();
            worst = worst.max((got[0] - x3[0]).hypot(got[1] - x3[1]));
            // Relative to the scale of the homogeneous pixel vectors (‖x'‖·‖x''‖ ≈ 10⁶).
            let scale = x2[0].hypot(x2[1]).hypot(1.0) * x3[0].hypot(x3[1]).hypot(1.0);
            assert!(
                t.incidence_residual(x1, x2, x3) < 1e-10 * scale,
                "incidence"
            );
        }
    }
    assert!(worst < 1e-8, "worst transfer error {worst} px");
}

#[test]
fn incidence_residual_vanishes_for_exact_triples_relative_to_scale() {
    // Normalised pixel coordinates (f ≈ 1) so that the residual's absolute scale is meaningful: < 1e-10.
    let mut rng = SplitMix64::new(5);
    for _ in 0..20 {
        let mut ps = random_cameras(&mut rng);
        let s = Matrix3::new(1e-3, 0.0, 0.0, 0.0, 1e-3, 0.0, 0.0, 0.0, 1.0);
        for p in &mut ps {
            *p = s * *p;
        }
        let t = TrifocalTensor::from_cameras(&ps[0], &ps[1], &ps[2]);
        let x = random_point(&mut rng);
        let (x1, x2, x3) = project_three(&ps, &x);
        assert!(t.incidence_residual(x1, x2, x3) < 1e-10);
        // A wrong view-3 point breaks incidence.
        assert!(t.incidence_residual(x1, x2, [x3[0] + 0.01, x3[1]]) > 1e-6);
    }
}

#[test]
fn canonical_and_determinant_forms_agree() {
    let mut rng = SplitMix64::new(3);
    for _ in 0..20 {
        let p1 = random_camera(&mut rng);
        let (p2, p3) = (random_camera(&mut rng), random_camera(&mut rng));
        // H with P1·H = [I | 0]: H = [[M⁻¹, −M⁻¹·p4], [0, 1]] for P1 = [M | p4].
        let m = p1.fixed_view::<3, 3>(0, 0).into_owned();
        let mi = m.try_inverse().unwrap();
        let mut h = Matrix4::identity();
        h.fixed_view_mut::<3, 3>(0, 0).copy_from(&mi);
        h.fixed_view_mut::<3, 1>(0, 3)
            .copy_from(&(-(mi * p1.column(3))));
        let p1c = p1 * h;
        assert!((p1c.fixed_view::<3, 3>(0, 0) - Matrix3::identity()).norm() < 1e-9);
        assert!(p1c.column(3).norm() < 1e-9);
        let canonical = TrifocalTensor::from_canonical(&(p2 * h), &(p3 * h));
        let general = TrifocalTensor::from_cameras(&p1, &p2, &p3);
        assert!(
            tensor_distance(&canonical, &general) < 1e-10,
            "{}",
            tensor_distance(&canonical, &general)
        );
        // Transfer with the canonical tensor (canonical frame has the same images).
        let x = Vector3::new(0.3, -0.2, 0.5);
        let got = canonical
            .transfer(project(&p1, &x), project(&p2, &x))
            .unwrap();
        let want = project(&p3, &x);
        assert!((got[0] - want[0]).hypot(got[1] - want[1]) < 1e-8);
    }
}

#[test]
fn tensor_is_invariant_to_a_projective_change_of_world_frame() {
    let mut rng = SplitMix64::new(17);
    for _ in 0..20 {
        let ps = random_cameras(&mut rng);
        let g =
            Matrix4::from_fn(|r, c| if r == c { 1.0 } else { 0.0 } + range(&mut rng, -0.3, 0.3));
        assert!(g.determinant().abs() > 1e-3);
        let a = TrifocalTensor::from_cameras(&ps[0], &ps[1], &ps[2]);
        let b = TrifocalTensor::from_cameras(&(ps[0] * g), &(ps[1] * g), &(ps[2] * g));
        assert!(
            tensor_distance(&a, &b) < 1e-10,
            "{}",
            tensor_distance(&a, &b)
        );
    }
}

/// The thesis configuration: three panoramas 5 m apart along a street heading 30°, left-side views at yaw
/// deviations 300°, 270°, 240° and pitch 30°, points on a façade 8 m to the left.
fn thesis_triplet(
    origin: &LocalOrigin,
) -> ([PerspectiveView; 3], [Matrix3x4<f64>; 3], Vec<Vector3<f64>>) {
    let heading: f64 = 30.0;
    let dir = Vector3::new(heading.to_radians().sin(), heading.to_radians().cos(), 0.0);
    let left = Vector3::new(-dir.y, dir.x, 0.0);
    let base = Vector3::new(512_000.0, 5_400_000.0, 102.5);
    let views: [PerspectiveView; 3] = std::array::from_fn(|i| {
        let c = base + dir * (5.0 * i as f64);
        let dev = [300.0, 270.0, 240.0][i];
        PerspectiveView::new(1024, 90.0, heading + dev, 30.0, 0.0, c)
    });
    let ms = std::array::from_fn(|i| views[i].projection_matrix(origin));
    let mut points = Vec::new();
    for a in 0..8 {
        for h in 0..5 {
            points.push(
                base + dir * (1.0 + a as f64 * 0.5)
                    + left * 8.0
                    + Vector3::new(0.0, 0.0, 2.0 + h as f64 * 1.5),
            );
        }
    }
    (views, ms, points)
}

#[test]
fn thesis_views_transfer_exactly_and_detect_a_5_px_error() {
    let origin = LocalOrigin::new(Vector3::new(512_000.0, 5_400_000.0, 100.0));
    let (views, ms, points) = thesis_triplet(&origin);
    let t = TrifocalTensor::from_cameras(&ms[0], &ms[1], &ms[2]);
    let mut rng = SplitMix64::new(1);
    let mut used = 0;
    for p in &points {
        let px: Vec<(f64, f64)> = views.iter().filter_map(|v| v.project_world(p)).collect();
        if px.len() < 3 || !px.iter().zip(&views).all(|(q, v)| v.contains(q.0, q.1)) {
            continue;
        }
        used += 1;
        let x = |k: usize| [px[k].0, px[k].1];
        assert!(t.transfer_error(x(0), x(1), x(2)) < 1e-8);
        // Perturb x'' by 5 px in a random direction: the transfer error is that perturbation.
        let a = range(&mut rng, 0.0, std::f64::consts::TAU);
        let moved = [px[2].0 + 5.0 * a.cos(), px[2].1 + 5.0 * a.sin()];
        let e = t.transfer_error(x(0), x(1), moved);
        assert!((e - 5.0).abs() < 1e-6, "error {e}");
        // Perturbing x' along the epipolar line moves the transferred point (a wrong match is caught).
        let wrong = [px[1].0 + 5.0, px[1].1];
        assert!(t.transfer_error(x(0), wrong, x(2)) > 0.5);
    }
    assert!(
        used >= 20,
        "only {used} façade points seen by all three views"
    );
}

#[test]
fn transfer_at_the_epipole_is_an_error_not_a_panic() {
    let origin = LocalOrigin::new(Vector3::new(0.0, 0.0, 0.0));
    let v1 = PerspectiveView::new(512, 90.0, 0.0, 0.0, 0.0, Vector3::new(0.0, 0.0, 0.0));
    let v2 = PerspectiveView::new(512, 90.0, 0.0, 0.0, 0.0, Vector3::new(0.0, 5.0, 0.0));
    let v3 = PerspectiveView::new(512, 90.0, 10.0, 0.0, 0.0, Vector3::new(1.0, 10.0, 0.0));
    let t = TrifocalTensor::from_cameras(
        &v1.projection_matrix(&origin),
        &v2.projection_matrix(&origin),
        &v3.projection_matrix(&origin),
    );
    // v2 lies straight ahead of v1: the epipole is at the principal point (256, 256).
    assert!(t.transfer([256.0, 256.0], [256.0, 256.0]).is_err());
    assert!(t
        .transfer_error([256.0, 256.0], [256.0, 256.0], [0.0, 0.0])
        .is_infinite());
}
