//! Multi-view triangulation: exact rays, two-ray closed form, covariance behaviour, Monte Carlo check of the
//! covariance, errors.

use crate::geometry::{triangulate_rays, Ray, TriangulationError};
use crate::rng::SplitMix64;
use nalgebra::{Matrix3, Vector3};

fn rd_point() -> Vector3<f64> {
    Vector3::new(92_031.257, 437_118.642, 4.871)
}

fn rays_to(point: &Vector3<f64>, centres: &[Vector3<f64>]) -> Vec<Ray> {
    centres.iter().map(|c| Ray::new(*c, point - c)).collect()
}

fn street_centres(n: usize, scale: f64) -> Vec<Vector3<f64>> {
    let p = rd_point();
    (0..n)
        .map(|k| {
            let t = k as f64 - (n as f64 - 1.0) / 2.0;
            p + Vector3::new(5.0 * t, -8.0 + 0.3 * t * t, -2.4) * scale
        })
        .collect()
}

#[test]
fn exact_rays_recover_the_point_at_rd_coordinates() {
    let x = rd_point();
    for n in 2..=5 {
        let centres = street_centres(n, 1.0);
        let rays = rays_to(&x, &centres);
        let t = triangulate_rays(&rays, &vec![1e-3; n]).unwrap();
        assert!(
            (t.point_world - x).norm() < 1e-9,
            "n = {n}: error {}",
            (t.point_world - x).norm()
        );
        assert!(t.residuals_m.iter().all(|&r| r < 1e-9));
        assert_eq!(t.residuals_m.len(), n);
    }
    // Aerial-like geometry: one panorama plus two cameras 1 km up.
    let centres = [
        x + Vector3::new(3.0, -9.0, -2.5),
        x + Vector3::new(-300.0, 50.0, 1000.0),
        x + Vector3::new(400.0, -20.0, 1100.0),
    ];
    let t = triangulate_rays(&rays_to(&x, &centres), &[1e-3, 5e-5, 5e-5]).unwrap();
    assert!((t.point_world - x).norm() < 1e-9);
}

#[test]
fn two_skew_rays_match_the_closed_form() {
    // Symmetric configuration (equal ranges ⇒ equal weights): the LS point is the closed-form midpoint.
    let o = Vector3::new(92_000.0, 437_000.0, 0.0);
    let c1 = o + Vector3::new(-10.0, 0.0, 0.0);
    let c2 = o + Vector3::new(10.0, 0.0, 0.0);
    let d1 = Vector3::new(10.0, 10.0, 0.01).normalize();
    let d2 = Vector3::new(-10.0, 10.0, -0.01).normalize();
    let rays = [Ray::new(c1, d1), Ray::new(c2, d2)];
    let t = triangulate_rays(&rays, &[1e-3, 1e-3]).unwrap();
    // Closed form (Hartley & Zisserman 2004, ch. 12).
    let b = d1.dot(&d2);
    let w0 = c1 - c2;
    let (p, q) = (d1.dot(&w0), d2.dot(&w0));
    let s = (b * q - p) / (1.0 - b * b);
    let u = (q - b * p) / (1.0 - b * b);
    let (a1, a2) = (c1 + d1 * s, c2 + d2 * u);
    let midpoint = (a1 + a2) / 2.0;
    let miss = (a1 - a2).norm();
    assert!(
        (t.point_world - midpoint).norm() < 1e-9,
        "{:?} vs {midpoint:?}",
        t.point_world
    );
    for r in &t.residuals_m {
        assert!((r - miss / 2.0).abs() < 1e-9);
    }
    assert!((t.max_angle_deg - 90.0).abs() < 1e-3);
}

#[test]
fn covariance_shrinks_with_more_rays() {
    let x = rd_point();
    let all = street_centres(6, 1.0);
    let mut previous = f64::INFINITY;
    for n in 2..=6 {
        let t = triangulate_rays(&rays_to(&x, &all[..n]), &vec![1e-3; n]).unwrap();
        let trace = t.covariance_m2.trace();
        assert!(
            trace < previous,
            "n = {n}: trace {trace} not below {previous}"
        );
        previous = trace;
        // Symmetric positive definite.
        assert!((t.covariance_m2 - t.covariance_m2.transpose()).norm() < 1e-15 * trace.max(1.0));
        assert!(t.covariance_m2.symmetric_eigen().eigenvalues.min() > 0.0);
    }
}

#[test]
fn covariance_grows_with_range_squared() {
    let x = rd_point();
    let near = triangulate_rays(&rays_to(&x, &street_centres(3, 1.0)), &[1e-3; 3]).unwrap();
    let far = triangulate_rays(&rays_to(&x, &street_centres(3, 2.0)), &[1e-3; 3]).unwrap();
    // Same angles, every range doubled ⇒ every perpendicular σ doubled ⇒ covariance × 4.
    assert!(
        (far.covariance_m2 - near.covariance_m2 * 4.0).norm() < 1e-9 * far.covariance_m2.norm()
    );
    assert!((far.max_angle_deg - near.max_angle_deg).abs() < 1e-9);
    // Covariance scales with σ².
    let sharper = triangulate_rays(&rays_to(&x, &street_centres(3, 1.0)), &[5e-4; 3]).unwrap();
    assert!(
        (sharper.covariance_m2 * 4.0 - near.covariance_m2).norm()
            < 1e-9 * near.covariance_m2.norm()
    );
}

/// Adds angular noise N(0, σ) about two axes perpendicular to the direction.
fn perturb(d: &Vector3<f64>, sigma: f64, rng: &mut SplitMix64) -> Vector3<f64> {
    let helper = if d.z.abs() < 0.9 {
        Vector3::z()
    } else {
        Vector3::x()
    };
    let e1 = d.cross(&helper).normalize();
    let e2 = d.cross(&e1);
    (d + e1 * (sigma * rng.next_gaussian()) + e2 * (sigma * rng.next_gaussian())).normalize()
}

#[test]
fn monte_carlo_covariance_matches_prediction() {
    // Hartley & Zisserman 2004, ch. 12 KAT: 10 000 trials with angular noise; empirical covariance ≈ N⁻¹ (5 %), σ̂0² ≈ 1.
    let x = rd_point();
    let centres = street_centres(4, 1.0);
    let sigma = [2e-3, 1e-3, 1e-3, 3e-3];
    let exact = triangulate_rays(&rays_to(&x, &centres), &sigma).unwrap();
    let predicted = exact.covariance_m2;
    let mut rng = SplitMix64::new(20_201_122);
    let trials = 10_000;
    let mut sum_outer = Matrix3::zeros();
    let mut sum_vf = 0.0;
    for _ in 0..trials {
        let rays: Vec<Ray> = centres
            .iter()
            .zip(&sigma)
            .map(|(c, &s)| Ray {
                origin_world: *c,
                dir_world: perturb(&(x - c).normalize(), s, &mut rng),
            })
            .collect();
        let t = triangulate_rays(&rays, &sigma).unwrap();
        let e = t.point_world - x;
        sum_outer += e * e.transpose();
        sum_vf += t.variance_factor;
    }
    let empirical = sum_outer / trials as f64;
    // Compare in the eigenbasis of the prediction: each principal variance within 5 %.
    let eig = predicted.symmetric_eigen();
    for i in 0..3 {
        let axis = eig.eigenvectors.column(i);
        let emp = (axis.transpose() * empirical * axis)[(0, 0)];
        let ratio = emp / eig.eigenvalues[i];
        assert!(
            (ratio - 1.0).abs() < 0.05,
            "principal axis {i}: empirical/predicted = {ratio}"
        );
    }
    let mean_vf = sum_vf / trials as f64;
    assert!(
        (mean_vf - 1.0).abs() < 0.05,
        "mean variance factor {mean_vf}"
    );
}

#[test]
fn errors_name_the_problem() {
    let x = rd_point();
    let centres = street_centres(3, 1.0);
    let rays = rays_to(&x, &centres);
    assert_eq!(
        triangulate_rays(&rays[..1], &[1e-3]).unwrap_err(),
        TriangulationError::TooFewRays(1)
    );
    assert_eq!(
        triangulate_rays(&rays, &[1e-3; 2]).unwrap_err(),
        TriangulationError::SigmaCountMismatch { rays: 3, sigmas: 2 }
    );
    assert!(matches!(
        triangulate_rays(&rays, &[1e-3, 0.0, 1e-3]).unwrap_err(),
        TriangulationError::InvalidSigma { index: 1, .. }
    ));
    let mut bad = rays.clone();
    bad[2].dir_world *= 2.0;
    assert_eq!(
        triangulate_rays(&bad, &[1e-3; 3]).unwrap_err(),
        TriangulationError::InvalidRay { index: 2 }
    );
    // Parallel rays.
    let d = Vector3::new(0.0, 1.0, 0.0);
    let parallel = [Ray::new(x, d), Ray::new(x + Vector3::new(1.0, 0.0, 0.0), d)];
    assert!(matches!(
        triangulate_rays(&parallel, &[1e-3; 2]).unwrap_err(),
        TriangulationError::IllConditioned { .. }
    ));
    // Rays that meet behind one origin.
    let behind = [
        Ray::new(
            x + Vector3::new(-5.0, -5.0, 0.0),
            Vector3::new(1.0, 1.0, 0.0),
        ),
        Ray::new(
            x + Vector3::new(5.0, -5.0, 0.0),
            Vector3::new(1.0, -1.0, 0.0),
        ),
    ];
    assert!(matches!(
        triangulate_rays(&behind, &[1e-3; 2]).unwrap_err(),
        TriangulationError::BehindRay { index: 1, .. }
    ));
}

#[test]
fn thin_intersection_angle_is_still_exact_but_uncertain_along_the_ray() {
    // Two panoramas 5 m apart seeing a point 60 m away (≈ 4.8°): exact rays still give the point to 1e-9 m;
    // the covariance is elongated along the viewing direction.
    let x = rd_point();
    let centres = [
        x + Vector3::new(-2.5, -60.0, -2.0),
        x + Vector3::new(2.5, -60.0, -2.0),
    ];
    let t = triangulate_rays(&rays_to(&x, &centres), &[1e-3, 1e-3]).unwrap();
    assert!((t.point_world - x).norm() < 1e-9);
    assert!(
        t.max_angle_deg > 4.0 && t.max_angle_deg < 5.0,
        "{}",
        t.max_angle_deg
    );
    let along = Vector3::new(0.0, 1.0, 0.0);
    let across = Vector3::new(1.0, 0.0, 0.0);
    let var_along = (along.transpose() * t.covariance_m2 * along)[(0, 0)];
    let var_across = (across.transpose() * t.covariance_m2 * across)[(0, 0)];
    assert!(
        var_along > 100.0 * var_across,
        "along {var_along} across {var_across}"
    );
}

#[test]
fn panorama_and_aerial_pixels_triangulate_a_ground_point() {
    // End to end through the cameras: a road point seen by two panoramas and two nadir images.
    use crate::geometry::{BrownDistortion, FrameCamera, PanoramaCamera};
    let x = Vector3::new(92_031.25, 437_118.5, 0.42);
    let panos = [
        PanoramaCamera::new(
            4800,
            2400,
            x + Vector3::new(-3.0, -6.0, 2.5),
            2.0,
            0.5,
            -0.3,
        ),
        PanoramaCamera::new(
            4800,
            2400,
            x + Vector3::new(-2.0, -1.0, 2.4),
            -1.0,
            0.0,
            0.4,
        ),
    ];
    let distortion = BrownDistortion {
        k1: -0.05,
        k2: 0.01,
        p1: 1e-4,
        p2: -2e-4,
        ..BrownDistortion::NONE
    };
    let aerial = [
        FrameCamera::from_opk(
            x + Vector3::new(-120.0, 80.0, 1000.0),
            0.5,
            -0.3,
            2.0,
            10_000.0,
            6_000.0,
            4_000.0,
            12_000,
            8_000,
            distortion,
        ),
        FrameCamera::from_opk(
            x + Vector3::new(150.0, -60.0, 1010.0),
            -0.4,
            0.2,
            -1.0,
            10_000.0,
            6_010.0,
            3_990.0,
            12_000,
            8_000,
            distortion,
        ),
    ];
    let mut rays = Vec::new();
    let mut sigmas = Vec::new();
    for cam in &panos {
        let (u, v) = cam.project_world(&x).unwrap();
        rays.push(cam.pixel_ray(u, v));
        sigmas.push(cam.angular_sigma_rad(0.5));
    }
    for cam in &aerial {
        let (u, v) = cam.project_world(&x).unwrap();
        assert!(cam.contains(u, v));
        rays.push(cam.pixel_ray(u, v));
        sigmas.push(cam.angular_sigma_rad(0.5));
    }
    assert!((sigmas[0] - 0.5 * 0.075f64.to_radians()).abs() < 1e-15);
    assert!((sigmas[2] - 0.5 / 10_000.0).abs() < 1e-18);
    let t = triangulate_rays(&rays, &sigmas).unwrap();
    assert!(
        (t.point_world - x).norm() < 1e-8,
        "error {}",
        (t.point_world - x).norm()
    );
    // The aerial rays are ≈ 1 km long, the panorama rays a few metres: the panoramas dominate the height,
    // and every standard deviation is millimetric.
    assert!(t
        .covariance_m2
        .diagonal()
        .iter()
        .all(|&v| v > 0.0 && v.sqrt() < 0.01));
}
