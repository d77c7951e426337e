//! Known-answer tests of AGAST corners and DAISY descriptors (Mair et al. 2010; Tola, Lepetit & Fua 2010) on synthetic images whose
//! corners and shifts are known exactly: squares on black, and a scene of random rectangles over a smooth
//! sinusoidal texture that is rendered in world coordinates, so an integer-shifted copy is exact.

use skytie_stages::features::agast::{detect_agast, AgastCorner, AgastParams};
use skytie_stages::features::daisy::{
    describe_points, DaisyExtractor, DaisyNormalization, DaisyParams,
};
use skytie_stages::imaging::GrayImage;
use skytie_stages::rng::SplitMix64;

/// Uniform in [lo, hi).
fn range(rng: &mut SplitMix64, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.next_f64()
}

/// Rectangles (integer world pixel bounds, grey level) over a smooth texture; pixel (c, r) of a render with
/// origin (ox, oy) shows world pixel (c + ox, r + oy), so rendering with origin (−sx, −sy) shifts the content by
/// (+sx, +sy).
struct Scene {
    rects: Vec<(i64, i64, i64, i64, f64)>,
    waves: Vec<(f64, f64, f64, f64)>,
}

impl Scene {
    fn new(seed: u64, n_rects: usize, extent: f64) -> Self {
        let mut rng = SplitMix64::new(seed);
        let rects = (0..n_rects)
            .map(|_| {
                let (x, y) = (
                    range(&mut rng, -40.0, extent),
                    range(&mut rng, -40.0, extent),
                );
                let (w, h) = (range(&mut rng, 8.0, 50.0), range(&mut rng, 8.0, 50.0));
                (
                    x as i64,
                    y as i64,
                    (x + w) as i64,
                    (y + h) as i64,
                    range(&mut rng, 0.1, 0.9),
                )
            })
            .collect();
        let waves = (0..6)
            .map(|_| {
                let a = range(&mut rng, 0.0, std::f64::consts::TAU);
                let f = range(&mut rng, 0.05, 0.25);
                (f * a.cos(), f * a.sin(), range(&mut rng, 0.0, 6.3), 0.03)
            })
            .collect();
        Self { rects, waves }
    }

    fn value(&self, x: i64, y: i64) -> f64 {
        let mut v = 0.5;
        for &(fx, fy, ph, amp) in &self.waves {
            v += amp * (fx * x as f64 + fy * y as f64 + ph).sin();
        }
        // Later rectangles are drawn over earlier ones (blend keeps the texture visible).
        for &(x0, y0, x1, y1, g) in &self.rects {
            if (x0..x1).contains(&x) && (y0..y1).contains(&y) {
                v = 0.3 * v + 0.7 * g;
            }
        }
        v.clamp(0.0, 1.0)
    }

    /// 8-bit quantised render (values k/255, as loaded from a PNG).
    fn render(&self, w: usize, h: usize, ox: i64, oy: i64) -> GrayImage {
        let data = (0..w * h)
            .map(|k| {
                let v = self.value((k % w) as i64 + ox, (k / w) as i64 + oy);
                ((v * 255.0).round() / 255.0) as f32
            })
            .collect();
        GrayImage::from_vec(w, h, data).unwrap()
    }
}

fn squares_image(contrast: f32, background: f32) -> (GrayImage, Vec<(f64, f64)>) {
    let (w, h) = (200, 160);
    let mut img = GrayImage::filled(w, h, background / 255.0);
    let mut corners = Vec::new();
    for (x0, y0) in [(20usize, 20usize), (90, 30), (150, 100), (40, 110)] {
        for r in y0..y0 + 20 {
            for c in x0..x0 + 20 {
                img.set(c, r, (background + contrast) / 255.0);
            }
        }
        for (cx, cy) in [(x0, y0), (x0 + 20, y0), (x0, y0 + 20), (x0 + 20, y0 + 20)] {
            corners.push((cx as f64, cy as f64));
        }
    }
    (img, corners)
}

fn nearest(points: &[AgastCorner], x: f64, y: f64) -> Option<(f64, &AgastCorner)> {
    points
        .iter()
        .map(|c| ((c.x_px - x).hypot(c.y_px - y), c))
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

#[test]
fn agast_finds_every_square_corner_and_nothing_on_edges_or_flat_areas() {
    let (img, truth) = squares_image(255.0, 0.0);
    let found = detect_agast(&img, &AgastParams::default());
    for &(x, y) in &truth {
        let (d, _) = nearest(&found, x, y).expect("corners found");
        assert!(
            d <= 1.0,
            "square corner ({x}, {y}): nearest detection {d:.2} px"
        );
    }
    for c in &found {
        let d = truth
            .iter()
            .map(|&(x, y)| (c.x_px - x).hypot(c.y_px - y))
            .fold(f64::INFINITY, f64::min);
        assert!(
            d <= 1.0,
            "spurious corner at ({}, {}), {d:.2} px from a square corner",
            c.x_px,
            c.y_px
        );
    }
    assert_eq!(found.len(), truth.len());
    // Every corner of a binary square scores the full contrast.
    assert!(found.iter().all(|c| c.score == 255.0));
}

#[test]
fn agast_score_equals_and_grows_with_contrast() {
    let mut last = 0.0;
    for contrast in [20.0f32, 60.0, 120.0, 200.0] {
        let (img, truth) = squares_image(contrast, 30.0);
        let found = detect_agast(&img, &AgastParams::default());
        assert_eq!(found.len(), truth.len(), "contrast {contrast}");
        for c in &found {
            assert_eq!(c.score, contrast);
        }
        assert!(found[0].score > last);
        last = found[0].score;
    }
    // Below the threshold: no corner at all.
    let (img, _) = squares_image(8.0, 30.0);
    assert!(detect_agast(&img, &AgastParams::default()).is_empty());
}

#[test]
fn agast_corners_follow_an_integer_shift_exactly() {
    let scene = Scene::new(7, 120, 300.0);
    let (w, h) = (300, 260);
    let (sx, sy) = (9i64, -5i64);
    let a = scene.render(w, h, 0, 0);
    let b = scene.render(w, h, -sx, -sy);
    let p = AgastParams::default();
    let (ca, cb) = (detect_agast(&a, &p), detect_agast(&b, &p));
    // Corners of A whose shifted position stays ≥ 5 px inside B (away from the untested border).
    let inside: Vec<&AgastCorner> = ca
        .iter()
        .filter(|c| {
            let (x, y) = (c.x_px + sx as f64, c.y_px + sy as f64);
            x > 5.0 && y > 5.0 && x < w as f64 - 5.0 && y < h as f64 - 5.0
        })
        .collect();
    assert!(inside.len() > 200, "only {} corners", inside.len());
    let hits = inside
        .iter()
        .filter(|c| {
            cb.iter().any(|d| {
                d.x_px == c.x_px + sx as f64 && d.y_px == c.y_px + sy as f64 && d.score == c.score
            })
        })
        .count();
    let share = hits as f64 / inside.len() as f64;
    assert!(share >= 0.9, "{hits} of {} corners repeated", inside.len());
}

#[test]
fn agast_max_corners_keeps_the_strongest_in_a_deterministic_order() {
    let img = Scene::new(3, 80, 200.0).render(200, 200, 0, 0);
    let all = detect_agast(&img, &AgastParams::default());
    let top = detect_agast(
        &img,
        &AgastParams {
            max_corners: Some(25),
            ..AgastParams::default()
        },
    );
    assert_eq!(top.len(), 25);
    assert_eq!(&all[..25], &top[..]);
    assert!(all.windows(2).all(|p| p[0].score >= p[1].score));
}

fn textured_pair(seed: u64, shift: (i64, i64)) -> (GrayImage, GrayImage) {
    let scene = Scene::new(seed, 150, 320.0);
    (
        scene.render(320, 280, 0, 0),
        scene.render(320, 280, -shift.0, -shift.1),
    )
}

#[test]
fn daisy_descriptor_is_unchanged_by_an_integer_shift() {
    let (sx, sy) = (11i64, 6i64);
    let (a, b) = textured_pair(11, (sx, sy));
    let p = DaisyParams::default();
    let (ea, eb) = (DaisyExtractor::new(&a, &p), DaisyExtractor::new(&b, &p));
    assert_eq!(ea.descriptor_len(), 200);
    let (mut da, mut db) = (vec![0.0f32; 200], vec![0.0f32; 200]);
    let mut tested = 0;
    let mut worst = 0.0f32;
    // Points (sub-pixel positions too) far enough from both images' borders that the reflective layer borders
    // cannot reach the samples: 15 px pattern + 3σ (≈ 23 px) of the widest layer.
    for k in 0..60 {
        let x = 60.3 + 3.1 * k as f64;
        let y = 60.7 + 2.3 * k as f64 % 140.0;
        assert!(ea.describe(x, y, &mut da));
        assert!(eb.describe(x + sx as f64, y + sy as f64, &mut db));
        for (u, v) in da.iter().zip(&db) {
            worst = worst.max((u - v).abs());
        }
        tested += 1;
    }
    assert_eq!(tested, 60);
    assert!(worst <= 1e-4, "max |difference| {worst}");
}

#[test]
fn daisy_partial_normalisation_cancels_gain_and_offset_none_does_not() {
    let (a, _) = textured_pair(5, (0, 0));
    let data = a.data.iter().map(|&v| 0.6 * v + 0.15).collect();
    let b = GrayImage::from_vec(a.width, a.height, data).unwrap();
    let points: Vec<(f64, f64)> = (0..40)
        .map(|k| (40.5 + 6.0 * k as f64, 40.5 + 4.5 * k as f64))
        .collect();
    let partial = DaisyParams::default();
    let (pa, pb) = (
        describe_points(&a, &points, &partial),
        describe_points(&b, &points, &partial),
    );
    let mut worst = 0.0f32;
    for (u, v) in pa.iter().zip(&pb) {
        let (u, v) = (u.as_ref().unwrap(), v.as_ref().unwrap());
        for (x, y) in u.iter().zip(v) {
            worst = worst.max((x - y).abs());
        }
    }
    assert!(worst <= 1e-4, "Partial: max |difference| {worst}");
    // NONE scales with the gain (0.6), the documented contrast dependence.
    let none = DaisyParams {
        normalization: DaisyNormalization::None,
        ..DaisyParams::default()
    };
    let (na, nb) = (
        describe_points(&a, &points, &none),
        describe_points(&b, &points, &none),
    );
    for (u, v) in na.iter().zip(&nb) {
        for (x, y) in u.as_ref().unwrap().iter().zip(v.as_ref().unwrap()) {
            assert!((0.6 * x - y).abs() <= 1e-5, "{x} {y}");
        }
    }
    // Points too close to the border are refused.
    let near = describe_points(&a, &[(10.0, 100.0), (100.0, 275.0)], &partial);
    assert!(near.iter().all(|d| d.is_none()));
}

#[test]
fn daisy_nearest_neighbour_matching_recovers_the_shift() {
    let (sx, sy) = (-13i64, 8i64);
    let (a, b) = textured_pair(23, (sx, sy));
    // Independent noise on the copy (σ = 1 grey level), re-quantised to 8 bit.
    let mut rng = SplitMix64::new(99);
    let data = b
        .data
        .iter()
        .map(|&v| {
            let n = (rng.next_f64() + rng.next_f64() + rng.next_f64() - 1.5) * 2.0 / 255.0;
            (((v as f64 + n).clamp(0.0, 1.0) * 255.0).round() / 255.0) as f32
        })
        .collect();
    let b = GrayImage::from_vec(b.width, b.height, data).unwrap();
    let p = AgastParams {
        threshold: 20.0,
        ..AgastParams::default()
    };
    let (ca, cb) = (detect_agast(&a, &p), detect_agast(&b, &p));
    let pts = |c: &[AgastCorner]| c.iter().map(|c| (c.x_px, c.y_px)).collect::<Vec<_>>();
    let (pa, pb) = (pts(&ca), pts(&cb));
    let dp = DaisyParams::default();
    let (da, db) = (describe_points(&a, &pa, &dp), describe_points(&b, &pb, &dp));
    let b_desc: Vec<(usize, &Vec<f32>)> = db
        .iter()
        .enumerate()
        .filter_map(|(i, d)| d.as_ref().map(|d| (i, d)))
        .collect();
    let (mut total, mut correct) = (0, 0);
    for (i, d) in da.iter().enumerate() {
        let Some(d) = d else { continue };
        let (x, y) = (pa[i].0 + sx as f64, pa[i].1 + sy as f64);
        // Only A corners whose counterpart was detected in B (within 1 px of the true position) and is
        // describable there count: this measures the descriptor, not the detector's repeatability under noise.
        let has_counterpart = b_desc
            .iter()
            .any(|&(j, _)| (pb[j].0 - x).hypot(pb[j].1 - y) <= 1.0);
        if !has_counterpart {
            continue;
        }
        total += 1;
        let best = b_desc
            .iter()
            .map(|&(j, e)| {
                let d2: f32 = d.iter().zip(e).map(|(u, v)| (u - v) * (u - v)).sum();
                (d2, j)
            })
            .min_by(|u, v| u.0.total_cmp(&v.0))
            .unwrap()
            .1;
        if (pb[best].0 - x).hypot(pb[best].1 - y) <= 1.0 {
            correct += 1;
        }
    }
    assert!(total > 100, "only {total} describable corners");
    let share = correct as f64 / total as f64;
    assert!(
        share >= 0.9,
        "{correct} of {total} nearest neighbours correct"
    );
}
