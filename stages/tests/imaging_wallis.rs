//! Known-answer tests of the Wallis filter (Wallis 1976; Baltsavias 1991).

use skytie_stages::imaging::wallis::{local_mean_std, wallis_apply, wallis_filter, WallisParams};
use skytie_stages::imaging::GrayImage;

/// Deterministic textured test image (sum of incommensurate sinusoids), values roughly 0.1..0.9.
fn texture(w: usize, h: usize) -> GrayImage {
    let data = (0..w * h)
        .map(|k| {
            let (x, y) = ((k % w) as f64, (k / w) as f64);
            (0.5 + 0.2 * (0.37 * x + 0.11 * y).sin()
                + 0.15 * (0.23 * y - 0.05 * x).cos()
                + 0.05 * (1.7 * x).sin()) as f32
        })
        .collect();
    GrayImage::from_vec(w, h, data).unwrap()
}

#[test]
fn constant_image_gives_b_mf_plus_one_minus_b_a_exactly() {
    let a = 0.3f32;
    let p = WallisParams {
        target_mean: 0.6,
        target_std: 0.2,
        contrast_c: 0.8,
        brightness_b: 0.7,
        window_px: 9,
    };
    let out = wallis_filter(&GrayImage::filled(30, 20, a), &p).unwrap();
    let want = 0.7 * 0.6 + 0.3 * 0.3;
    for &v in &out.data {
        assert!((v as f64 - want).abs() < 1e-6, "{v} vs {want}");
    }
}

#[test]
fn global_statistics_give_target_mean_and_std() {
    let img = texture(80, 60);
    let (m, s) = img.mean_std();
    let p = WallisParams {
        target_mean: 0.45,
        target_std: 0.12,
        contrast_c: 1.0 - 1e-9,
        brightness_b: 1.0,
        window_px: 21,
    };
    let mi = GrayImage::filled(80, 60, m as f32);
    let si = GrayImage::filled(80, 60, s as f32);
    let out = wallis_apply(&img, &mi, &si, &p).unwrap();
    let (mo, so) = out.mean_std();
    assert!((mo - 0.45).abs() < 1e-3, "mean {mo}");
    assert!((so - 0.12).abs() < 1e-3, "std {so}");
}

#[test]
fn local_filter_equalises_local_contrast() {
    // Left half low contrast, right half high contrast: after Wallis (c → 1, b = 1) the local std is the
    // target on both sides (interior, away from the seam and borders).
    let base = texture(120, 60);
    let mut img = base.clone();
    for row in 0..60 {
        for col in 0..120 {
            let g = base.get(col, row) - 0.5;
            img.set(
                col,
                row,
                if col < 60 {
                    0.2 + 0.1 * g
                } else {
                    0.7 + 1.0 * g
                },
            );
        }
    }
    let p = WallisParams {
        target_mean: 0.5,
        target_std: 0.1,
        contrast_c: 0.999,
        brightness_b: 1.0,
        window_px: 15,
    };
    let out = wallis_filter(&img, &p).unwrap();
    let (m, s) = local_mean_std(&out, 15);
    for &(col, row) in &[(25usize, 30usize), (95, 30), (20, 15), (100, 45)] {
        assert!(
            (m.get(col, row) - 0.5).abs() < 0.02,
            "mean at {col},{row}: {}",
            m.get(col, row)
        );
        assert!(
            (s.get(col, row) - 0.1).abs() < 0.02,
            "std at {col},{row}: {}",
            s.get(col, row)
        );
    }
}

#[test]
fn affine_invariance_for_c_to_one_and_b_one() {
    let img = texture(50, 40);
    let transformed = GrayImage {
        width: 50,
        height: 40,
        data: img.data.iter().map(|&g| 2.5 * g + 0.3).collect(),
    };
    let p = WallisParams {
        contrast_c: 1.0,
        brightness_b: 1.0,
        ..Default::default()
    };
    let a = wallis_filter(&img, &p).unwrap();
    let b = wallis_filter(&transformed, &p).unwrap();
    for (x, y) in a.data.iter().zip(&b.data) {
        assert!((x - y).abs() < 1e-4, "{x} vs {y}");
    }
}

#[test]
fn c_and_max_gain_parameterisations_agree() {
    let img = texture(40, 30);
    let c = 0.94f32;
    let by_c = WallisParams {
        contrast_c: c,
        brightness_b: 0.6,
        ..Default::default()
    };
    let by_a = WallisParams {
        brightness_b: 0.6,
        ..Default::default()
    }
    .with_max_gain(c / (1.0 - c));
    let (m, s) = local_mean_std(&img, by_c.window_px);
    let x = wallis_apply(&img, &m, &s, &by_c).unwrap();
    let y = wallis_apply(&img, &m, &s, &by_a).unwrap();
    // Also against the original closed form g_w = (g − m)·A·s_f/(A·s_g + s_f) + b·m_f + (1 − b)·m.
    let a = (c / (1.0 - c)) as f64;
    let (s_f, m_f, b) = (by_c.target_std as f64, by_c.target_mean as f64, 0.6f64);
    for k in 0..img.data.len() {
        assert!((x.data[k] - y.data[k]).abs() < 1e-5);
        let (g, mg, sg) = (img.data[k] as f64, m.data[k] as f64, s.data[k] as f64);
        let original = (g - mg) * a * s_f / (a * sg + s_f) + b * m_f + (1.0 - b) * mg;
        assert!((x.data[k] as f64 - original).abs() < 1e-5);
    }
}

#[test]
fn flat_region_with_c_one_does_not_produce_nan() {
    let p = WallisParams {
        contrast_c: 1.0,
        ..Default::default()
    };
    let out = wallis_filter(&GrayImage::filled(16, 16, 0.8), &p).unwrap();
    assert!(out.data.iter().all(|v| (v - p.target_mean).abs() < 1e-6));
}
