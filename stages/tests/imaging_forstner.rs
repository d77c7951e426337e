//! Known-answer tests of the Förstner operator with Köthe's 2× structure tensor (Förstner & Gülch 1987; Köthe 2003).
//!
//! Test images are rendered analytically: an ideal corner blurred by a Gaussian (σ_b) is the product of two
//! normal CDFs along the edge normals; each pixel averages 4 × 4 sub-samples (anti-aliasing, pixel area).

use skytie_stages::features::forstner::{
    forstner_corners, refine_point, Corner, ForstnerParams, LineWeighting, PointKind,
    StructureTensor,
};
use skytie_stages::imaging::GrayImage;

fn phi(x: f64) -> f64 {
    // Normal CDF via erf (Abramowitz–Stegun 7.1.26 is too coarse; use a series/continued-fraction-free form).
    0.5 * (1.0 + erf(x / std::f64::consts::SQRT_2))
}

/// erf with |error| < 1.2e-7 (Numerical Recipes erfc Chebyshev approximation).
fn erf(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.26551223
            + t * (1.00002368
                + t * (0.37409196
                    + t * (0.09678418
                        + t * (-0.18628806
                            + t * (0.27886807
                                + t * (-1.13520398
                                    + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277)))))))))
            .exp();
    if x >= 0.0 {
        1.0 - r
    } else {
        r - 1.0
    }
}

/// Render `f(u, v)` with 4 × 4 sub-samples per pixel.
fn render(w: usize, h: usize, f: impl Fn(f64, f64) -> f64) -> GrayImage {
    let data = (0..w * h)
        .map(|k| {
            let (c, r) = ((k % w) as f64, (k / w) as f64);
            let mut acc = 0.0;
            for j in 0..4 {
                for i in 0..4 {
                    acc += f(c + (i as f64 + 0.5) / 4.0, r + (j as f64 + 0.5) / 4.0);
                }
            }
            (acc / 16.0) as f32
        })
        .collect();
    GrayImage::from_vec(w, h, data).unwrap()
}

/// Bright right-angle corner with vertex (u0, v0), edges rotated by `angle_deg`, blurred by σ_b = 1 px.
fn corner_image(w: usize, h: usize, u0: f64, v0: f64, angle_deg: f64) -> GrayImage {
    let (s, c) = angle_deg.to_radians().sin_cos();
    render(w, h, |u, v| {
        let (du, dv) = (u - u0, v - v0);
        let a = c * du + s * dv; // along the first edge normal
        let b = -s * du + c * dv;
        0.2 + 0.6 * phi(a / 1.0) * phi(b / 1.0)
    })
}

fn nearest(corners: &[Corner], u: f64, v: f64) -> (Corner, f64) {
    corners
        .iter()
        .map(|c| (*c, (c.u_px - u).hypot(c.v_px - v)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .expect("no corners detected")
}

#[test]
fn blurred_l_corner_is_located_to_sub_pixel_accuracy() {
    let img = corner_image(40, 36, 20.3, 17.6, 0.0);
    let corners = forstner_corners(&img, &ForstnerParams::default());
    let (c, d) = nearest(&corners, 20.3, 17.6);
    eprintln!("L-corner: {c:?} error {d:.4} px, {} corners", corners.len());
    assert!(d <= 0.05, "error {d} px: {c:?}");
    // Roundness: at the detection pixel (the maximum of w, slightly inside the corner) with the defaults; at
    // the vertex itself (fine pixel containing (2·20.3, 2·17.6)) the blurred vertex zone weighs more against
    // the two edge arms, so q > 0.9 there needs σ_i ≳ 4 px (σ_i = 2: 0.79, σ_i = 3: 0.898).
    assert!(c.roundness > 0.85, "{c:?}");
    let t = StructureTensor::new(&img, 0.7, 4.0, true);
    let (_, q_vertex) = t.weight_roundness(35 * t.jxx.width + 40);
    eprintln!("q at the vertex (σ_i = 4): {q_vertex}");
    assert!(q_vertex > 0.9, "q at vertex {q_vertex}");
    // Only one detection near the vertex (non-maximum suppression).
    assert_eq!(
        corners
            .iter()
            .filter(|k| (k.u_px - 20.3).hypot(k.v_px - 17.6) < 4.0)
            .count(),
        1
    );
}

#[test]
fn rotated_corner_rotates_the_estimate_and_keeps_q_and_w() {
    let p = ForstnerParams::default();
    let a = corner_image(48, 48, 24.2, 23.7, 0.0);
    let b = corner_image(48, 48, 24.2, 23.7, 30.0);
    let (ca, da) = nearest(&forstner_corners(&a, &p), 24.2, 23.7);
    let (cb, db) = nearest(&forstner_corners(&b, &p), 24.2, 23.7);
    eprintln!("0°: {ca:?} ({da:.4}), 30°: {cb:?} ({db:.4})");
    assert!(da < 0.1 && db < 0.1, "{da} {db}");
    assert!(
        (ca.roundness - cb.roundness).abs() / ca.roundness < 0.05,
        "{ca:?} {cb:?}"
    );
    assert!(
        (ca.weight - cb.weight).abs() / ca.weight < 0.05,
        "{ca:?} {cb:?}"
    );
}

#[test]
fn straight_edge_has_low_roundness_and_is_rejected() {
    let img = render(40, 40, |u, v| {
        0.2 + 0.6 * phi((0.8 * (u - 20.3) + 0.6 * (v - 19.0)) / 1.0)
    });
    let corners = forstner_corners(&img, &ForstnerParams::default());
    assert!(corners.is_empty(), "{corners:?}");
    let t = StructureTensor::new(&img, 1.0, 2.0, true);
    // On the edge, well inside the image.
    let (col, row) = (2 * 20, 2 * 19);
    let (_, q) = t.weight_roundness(row * t.jxx.width + col);
    assert!(q < 0.05, "q = {q}");
}

#[test]
fn disc_centre_by_circular_point_model() {
    let (uc, vc, radius) = (31.25, 40.8, 5.0);
    let img = render(64, 80, |u, v| {
        let d = (u - uc).hypot(v - vc) - radius;
        0.2 + 0.6 * (1.0 - phi(d / 0.7))
    });
    let t = StructureTensor::new(&img, 1.0, 2.0, true);
    // Start 1.5 px off; sigma of the estimation window covers the rim (r = 5 px): 3 px (6 fine px).
    let start = (2.0 * (uc + 1.0), 2.0 * (vc - 1.1));
    let (u, v) = refine_point(
        &t.gx,
        &t.gy,
        start,
        6.0,
        PointKind::Circular,
        LineWeighting::GradientMagnitude,
    )
    .expect("no estimate");
    let (u, v) = (u / 2.0, v / 2.0);
    let d = (u - uc).hypot(v - vc);
    eprintln!("disc centre ({u:.4}, {v:.4}) error {d:.4}");
    assert!(d < 0.02, "error {d}");
}

#[test]
fn two_times_tensor_is_less_aliased_on_a_fine_grating() {
    // Grating with period 3 px: g² has frequency 2/3 cycles/px, above Nyquist at 1× sampling, so the 1×
    // tensor trace ripples over the image (aliasing) while the 2× trace is smooth. Worst ripple
    // (max/min of the trace over the interior) over several orientations.
    let ripple = |upsample: bool| {
        let mut worst = 1.0f64;
        for k in 0..6 {
            let ang = (k as f64 * 15.0).to_radians();
            let (s, c) = ang.sin_cos();
            let img = render(48, 48, |u, v| {
                0.5 + 0.3 * (2.0 * std::f64::consts::PI * (c * u + s * v) / 3.0).sin()
            });
            let t = StructureTensor::new(&img, 0.7, 1.4, upsample);
            let sc = t.scale;
            let (mut lo_v, mut hi_v) = (f64::MAX, f64::MIN);
            for r in 12 * sc..36 * sc {
                for col in 12 * sc..36 * sc {
                    let i = r * t.jxx.width + col;
                    let tr = (t.jxx.data[i] + t.jyy.data[i]) as f64;
                    lo_v = lo_v.min(tr);
                    hi_v = hi_v.max(tr);
                }
            }
            worst = worst.max(hi_v / lo_v);
        }
        worst
    };
    let (r1, r2) = (ripple(false), ripple(true));
    eprintln!("trace ripple max/min: 1× {r1:.4}, 2× {r2:.4}");
    assert!(r2 - 1.0 < 0.5 * (r1 - 1.0), "1× {r1}, 2× {r2}");
}

#[test]
fn several_corners_deterministic_order_and_max_corners() {
    // Two bright squares: 8 corners.
    let img = render(80, 60, |u, v| {
        let sq = |u0: f64, v0: f64, s: f64| {
            (phi(u - u0) - phi(u - u0 - s)) * (phi(v - v0) - phi(v - v0 - s))
        };
        0.1 + 0.7 * sq(10.4, 12.2, 20.0) + 0.5 * sq(45.7, 20.1, 22.0)
    });
    let p = ForstnerParams::default();
    let a = forstner_corners(&img, &p);
    let b = forstner_corners(&img, &p);
    assert_eq!(a, b);
    let truth = [
        (10.4, 12.2),
        (30.4, 12.2),
        (10.4, 32.2),
        (30.4, 32.2),
        (45.7, 20.1),
        (67.7, 20.1),
        (45.7, 42.1),
        (67.7, 42.1),
    ];
    for &(u, v) in &truth {
        let (c, d) = nearest(&a, u, v);
        assert!(d < 0.1, "corner ({u}, {v}): {c:?} error {d}");
    }
    assert!(a.windows(2).all(|w| w[0].weight >= w[1].weight));
    let top = forstner_corners(
        &img,
        &ForstnerParams {
            max_corners: Some(3),
            ..p
        },
    );
    assert_eq!(top.len(), 3);
    assert_eq!(&top[..], &a[..3]);
}
