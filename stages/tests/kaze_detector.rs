//! Known-answer tests of the KAZE detector and descriptor (Alcantarilla, Bartoli & Davison 2012 KAT): Gaussian blob located
//! within 0.2 px, integer translation moves keypoints exactly and keeps upright descriptors identical,
//! ≥ 90 % repeatability on an integer-shifted crop of a texture, 90° rotation stability of non-upright
//! descriptors, determinism.

use skytie_stages::features::kaze::{detect_and_describe, Features, KazeParams, Scheme};
use skytie_stages::imaging::GrayImage;
use skytie_stages::rng::SplitMix64;

/// A continuous texture: 0.5 + Σ signed Gaussian blobs (centre, radius 1.5..5 px, amplitude ±0.25).
struct Texture {
    blobs: Vec<[f64; 4]>,
}

impl Texture {
    /// `count` blobs with centres uniform in [lo, hi)².
    fn new(seed: u64, count: usize, lo: f64, hi: f64) -> Self {
        let mut rng = SplitMix64::new(seed);
        let blobs = (0..count)
            .map(|_| {
                let amp = if rng.next_f64() < 0.5 { -0.25 } else { 0.25 };
                [
                    lo + (hi - lo) * rng.next_f64(),
                    lo + (hi - lo) * rng.next_f64(),
                    1.5 + 3.5 * rng.next_f64(),
                    amp,
                ]
            })
            .collect();
        Self { blobs }
    }

    fn value(&self, x: f64, y: f64) -> f64 {
        0.5 + self
            .blobs
            .iter()
            .map(|b| {
                let d2 = (x - b[0]).powi(2) + (y - b[1]).powi(2);
                b[3] * (-d2 / (2.0 * b[2] * b[2])).exp()
            })
            .sum::<f64>()
    }

    /// Render `w × h`, pixel (col, row) = value at (col + 0.5 + du, row + 0.5 + dv), clamped to [0, 1].
    fn render(&self, w: usize, h: usize, du: f64, dv: f64) -> GrayImage {
        let data = (0..w * h)
            .map(|k| {
                let (x, y) = ((k % w) as f64 + 0.5 + du, (k / w) as f64 + 0.5 + dv);
                self.value(x, y).clamp(0.0, 1.0) as f32
            })
            .collect();
        GrayImage::from_vec(w, h, data).unwrap()
    }
}

fn blob_image(w: usize, h: usize, cu: f64, cv: f64) -> GrayImage {
    let data = (0..w * h)
        .map(|k| {
            let (x, y) = ((k % w) as f64 + 0.5, (k / w) as f64 + 0.5);
            let d2 = (x - cu).powi(2) + (y - cv).powi(2);
            (0.25 + 0.5 * (-d2 / (2.0 * 16.0)).exp()) as f32
        })
        .collect();
    GrayImage::from_vec(w, h, data).unwrap()
}

fn strongest(f: &Features) -> usize {
    (0..f.len())
        .max_by(|&a, &b| f.keypoints[a].response.total_cmp(&f.keypoints[b].response))
        .expect("no keypoints")
}

/// Upright, extended (128-value) descriptors over `octaves` octaves.
fn upright_extended(octaves: usize) -> KazeParams {
    KazeParams {
        upright: true,
        extended: true,
        octaves,
        ..KazeParams::default()
    }
}

#[test]
fn gaussian_blob_is_found_within_a_fifth_of_a_pixel() {
    let (cu, cv) = (64.3, 70.6);
    let img = blob_image(128, 140, cu, cv);
    for scheme in [Scheme::Fed, Scheme::Aos] {
        let p = KazeParams {
            scheme,
            ..KazeParams::default()
        };
        let f = detect_and_describe(&img, &p);
        let k = f.keypoints[strongest(&f)];
        let err = ((k.u_px as f64 - cu).powi(2) + (k.v_px as f64 - cv).powi(2)).sqrt();
        assert!(
            err < 0.2,
            "{scheme:?}: strongest at ({}, {}), error {err} px",
            k.u_px,
            k.v_px
        );
        // The scale is of the order of the blob's σ = 4 px.
        assert!(k.size_px > 4.0 && k.size_px < 20.0, "size {}", k.size_px);
    }
}

#[test]
fn integer_translation_moves_keypoints_exactly_and_keeps_upright_descriptors() {
    // Texture confined to the centre, constant background: the shift is exact everywhere.
    let tex = Texture::new(5, 120, 60.0, 140.0);
    let (du, dv) = (9i32, -6i32);
    let a = tex.render(200, 200, 0.0, 0.0);
    let b = tex.render(200, 200, -du as f64, -dv as f64);
    let p = upright_extended(2);
    let fa = detect_and_describe(&a, &p);
    let fb = detect_and_describe(&b, &p);
    assert!(fa.len() >= 30, "only {} keypoints", fa.len());
    assert_eq!(fa.len(), fb.len());
    for (i, (ka, kb)) in fa.keypoints.iter().zip(&fb.keypoints).enumerate() {
        assert_eq!(ka.level, kb.level);
        assert!(
            (ka.u_px + du as f32 - kb.u_px).abs() < 1e-4,
            "{i}: u {} vs {}",
            ka.u_px,
            kb.u_px
        );
        assert!(
            (ka.v_px + dv as f32 - kb.v_px).abs() < 1e-4,
            "{i}: v {} vs {}",
            ka.v_px,
            kb.v_px
        );
        assert_eq!(ka.size_px, kb.size_px);
        assert_eq!(ka.response, kb.response);
        let dist: f32 = fa
            .descriptor(i)
            .iter()
            .zip(fb.descriptor(i))
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f32::max);
        assert!(dist < 1e-5, "{i}: descriptor max difference {dist}");
    }
}

#[test]
fn integer_shifted_crop_repeats_at_least_90_percent_of_keypoints() {
    // Two crops of one texture, offset by (11, 7) px: the same scene point must be detected in both
    // (keypoints more than 30 px from either crop border; borders change the contrast factor slightly).
    let tex = Texture::new(21, 2500, -20.0, 300.0);
    let (du, dv) = (11.0, 7.0);
    let a = tex.render(256, 256, 0.0, 0.0);
    let b = tex.render(256, 256, du, dv);
    let p = upright_extended(1);
    let fa = detect_and_describe(&a, &p);
    let fb = detect_and_describe(&b, &p);
    let inside = |u: f32, v: f32| u > 30.0 && v > 30.0 && u < 256.0 - 30.0 && v < 256.0 - 30.0;
    let mut total = 0;
    let mut repeated = 0;
    for ka in &fa.keypoints {
        let (ub, vb) = (ka.u_px - du as f32, ka.v_px - dv as f32);
        if !(inside(ka.u_px, ka.v_px) && inside(ub, vb)) {
            continue;
        }
        total += 1;
        if fb.keypoints.iter().any(|kb| {
            kb.level == ka.level && (kb.u_px - ub).abs() < 0.1 && (kb.v_px - vb).abs() < 0.1
        }) {
            repeated += 1;
        }
    }
    assert!(total >= 50, "only {total} keypoints in the common interior");
    assert!(
        repeated as f64 >= 0.9 * total as f64,
        "repeated {repeated} of {total}"
    );
}

/// Rotate 90°: B(col', row') = A(col = W − 1 − row', row = col'); (u, v) in A ↦ (v, W − u) in B.
fn rotate90(a: &GrayImage) -> GrayImage {
    let (w, h) = (a.width, a.height);
    let mut b = GrayImage::filled(h, w, 0.0);
    for row_b in 0..w {
        for col_b in 0..h {
            b.set(col_b, row_b, a.get(w - 1 - row_b, col_b));
        }
    }
    b
}

#[test]
fn ninety_degree_rotation_keeps_oriented_descriptors() {
    let tex = Texture::new(33, 160, 50.0, 170.0);
    let a = tex.render(220, 200, 0.0, 0.0);
    let b = rotate90(&a);
    let p = KazeParams {
        octaves: 2,
        ..KazeParams::default()
    };
    let fa = detect_and_describe(&a, &p);
    let fb = detect_and_describe(&b, &p);
    let w = a.width as f32;
    let mut total = 0;
    let mut close = 0;
    let mut nn_correct = 0;
    for (i, ka) in fa.keypoints.iter().enumerate() {
        total += 1;
        let (ub, vb) = (ka.v_px, w - ka.u_px);
        let Some(j) = (0..fb.len()).find(|&j| {
            let kb = &fb.keypoints[j];
            kb.level == ka.level && (kb.u_px - ub).abs() < 0.05 && (kb.v_px - vb).abs() < 0.05
        }) else {
            continue;
        };
        let d = |x: &[f32], y: &[f32]| {
            x.iter()
                .zip(y)
                .map(|(p, q)| (p - q) * (p - q))
                .sum::<f32>()
                .sqrt()
        };
        let dist = d(fa.descriptor(i), fb.descriptor(j));
        if dist < 0.1 {
            close += 1;
        }
        let nearest = (0..fb.len())
            .min_by(|&x, &y| {
                d(fa.descriptor(i), fb.descriptor(x))
                    .total_cmp(&d(fa.descriptor(i), fb.descriptor(y)))
            })
            .unwrap();
        if nearest == j {
            nn_correct += 1;
        }
    }
    assert!(total >= 30, "only {total} keypoints");
    assert!(
        close as f64 >= 0.9 * total as f64,
        "descriptor L2 < 0.1 for {close} of {total}"
    );
    assert!(
        nn_correct as f64 >= 0.9 * total as f64,
        "nearest neighbour correct for {nn_correct} of {total}"
    );
}

#[test]
fn output_is_deterministic_across_thread_counts() {
    let tex = Texture::new(8, 400, 0.0, 128.0);
    let img = tex.render(128, 128, 0.0, 0.0);
    let p = KazeParams {
        octaves: 2,
        ..KazeParams::default()
    };
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| detect_and_describe(&img, &p));
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
        .install(|| detect_and_describe(&img, &p));
    assert!(!one.is_empty());
    assert_eq!(one, two);
    assert_eq!(one.descriptor_len, 64);
    for i in 0..one.len() {
        let norm: f32 = one.descriptor(i).iter().map(|v| v * v).sum();
        assert!((norm - 1.0).abs() < 1e-4);
    }
}
