//! Known-answer tests of NCC template matching (OpenCV TM_CCOEFF_NORMED, OpenCV TM_CCOEFF_NORMED semantics).

mod imaging_support;

use imaging_support::{SplitMix64, Texture};
use skytie_stages::imaging::GrayImage;
use skytie_stages::matching::ncc::{match_template, ncc_map};

fn crop(img: &GrayImage, x0: usize, y0: usize, w: usize, h: usize) -> GrayImage {
    let mut data = Vec::with_capacity(w * h);
    for r in y0..y0 + h {
        data.extend_from_slice(&img.row(r)[x0..x0 + w]);
    }
    GrayImage::from_vec(w, h, data).unwrap()
}

/// Brute-force reference: the definition in f64, flat → 0.
fn reference_score(img: &GrayImage, t: &GrayImage, x: usize, y: usize) -> f64 {
    let n = (t.width * t.height) as f64;
    let tm = t.data.iter().map(|&v| v as f64).sum::<f64>() / n;
    let mut im = 0.0;
    for j in 0..t.height {
        for i in 0..t.width {
            im += img.get(x + i, y + j) as f64;
        }
    }
    im /= n;
    let (mut num, mut st, mut si) = (0.0, 0.0, 0.0);
    for j in 0..t.height {
        for i in 0..t.width {
            let a = t.get(i, j) as f64 - tm;
            let b = img.get(x + i, y + j) as f64 - im;
            num += a * b;
            st += a * a;
            si += b * b;
        }
    }
    if st * si == 0.0 {
        0.0
    } else {
        num / (st * si).sqrt()
    }
}

#[test]
fn template_cut_from_the_image_is_found_with_score_one() {
    let tex = Texture::new(128, 32, 21);
    let img = tex.render(100, 100, 0.0, 0.0, 0.0, 0.0);
    let t = crop(&img, 37, 52, 40, 40);
    let map = ncc_map(&img, &t).unwrap();
    assert_eq!((map.width, map.height), (61, 61));
    assert!((map.get(37, 52) - 1.0).abs() < 1e-6);
    let best = map
        .data
        .iter()
        .enumerate()
        .fold(0, |b, (i, &v)| if v > map.data[b] { i } else { b });
    assert_eq!((best % map.width, best / map.width), (37, 52));
    // Template centre (37 + 20, 52 + 20); the sub-pixel fit of the (slightly asymmetric) NCC surface around an
    // exact integer match stays within a few hundredths of a pixel.
    let m = match_template(&img, &t).unwrap();
    assert!(
        (m.u_px - 57.0).abs() < 0.03 && (m.v_px - 72.0).abs() < 0.03,
        "{m:?}"
    );
    assert!((m.score - 1.0).abs() < 1e-6);
}

#[test]
fn map_equals_the_definition_on_random_data() {
    let mut rng = SplitMix64(5);
    let data = (0..30 * 25).map(|_| rng.uniform() as f32).collect();
    let img = GrayImage::from_vec(30, 25, data).unwrap();
    let t = crop(&img, 4, 6, 9, 7);
    let map = ncc_map(&img, &t).unwrap();
    for y in 0..map.height {
        for x in 0..map.width {
            let want = reference_score(&img, &t, x, y);
            assert!(
                (map.get(x, y) as f64 - want).abs() < 1e-5,
                "({x},{y}) {} vs {want}",
                map.get(x, y)
            );
        }
    }
}

#[test]
fn affine_radiometric_change_keeps_or_negates_the_score() {
    let tex = Texture::new(128, 32, 22);
    let img = tex.render(60, 50, 0.0, 0.0, 0.0, 0.0);
    let t = crop(&tex.render(60, 50, 0.0, 0.0, 0.0, 0.0), 10, 12, 16, 16);
    let a = ncc_map(&img, &t).unwrap();
    let scaled = GrayImage {
        data: img.data.iter().map(|&g| 2.0 * g + 0.5).collect(),
        ..img.clone()
    };
    let negated = GrayImage {
        data: img.data.iter().map(|&g| -0.7 * g + 1.0).collect(),
        ..img.clone()
    };
    let b = ncc_map(&scaled, &t).unwrap();
    let c = ncc_map(&negated, &t).unwrap();
    for k in 0..a.data.len() {
        assert!((a.data[k] - b.data[k]).abs() < 1e-4);
        assert!((a.data[k] + c.data[k]).abs() < 1e-4);
    }
}

#[test]
fn flat_template_or_flat_window_gives_zero_not_nan() {
    let tex = Texture::new(64, 16, 23);
    let mut img = tex.render(40, 40, 0.0, 0.0, 0.0, 0.0);
    for r in 0..20 {
        for c in 0..20 {
            img.set(c, r, 0.3); // flat quadrant
        }
    }
    let flat_t = GrayImage::filled(8, 8, 0.5);
    let map = ncc_map(&img, &flat_t).unwrap();
    assert!(map.data.iter().all(|&v| v == 0.0));
    let t = crop(&img, 25, 25, 8, 8);
    let map = ncc_map(&img, &t).unwrap();
    assert!(map.data.iter().all(|v| v.is_finite()));
    assert_eq!(map.get(3, 3), 0.0); // window entirely inside the flat quadrant
    let m = match_template(&img, &flat_t).unwrap();
    assert!(m.u_px.is_finite() && m.score == 0.0);
}

#[test]
fn subpixel_placement_is_recovered() {
    // Template = texture around a sub-pixel position of the image (exact Fourier shift).
    let tex = Texture::new(256, 48, 24);
    let img = tex.render(100, 100, 0.0, 0.0, 0.0, 0.0);
    let mut rng = SplitMix64(77);
    let mut sum_sq = 0.0;
    let trials = 20;
    for _ in 0..trials {
        let (cx, cy) = (rng.range(30.0, 70.0), rng.range(30.0, 70.0));
        let (ox, oy) = (cx - 8.0, cy - 8.0);
        let t = tex.crop_at(16, 16, (ox, oy));
        let m = match_template(&img, &t).unwrap();
        sum_sq += (m.u_px - cx).powi(2) + (m.v_px - cy).powi(2);
        assert!(m.score > 0.9, "{m:?}");
    }
    let rms = (sum_sq / trials as f64).sqrt();
    eprintln!("NCC sub-pixel RMS {rms:.4} px");
    assert!(rms < 0.1, "RMS {rms:.4} px");
}
