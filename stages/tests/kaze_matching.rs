//! Descriptor matching tests: planted correspondences among random descriptors (ratio test, mutual check,
//! windowed one-to-many), input errors, and KAZE + matching on a synthetic textured image pair related by a
//! known similarity transform (thesis 3.4.5.2 setting: windowed matching around predicted positions).

use skytie_stages::features::kaze::{detect_and_describe, KazeParams};
use skytie_stages::imaging::GrayImage;
use skytie_stages::matching::descriptor_match::{match_ratio, match_windowed, MatchError};
use skytie_stages::rng::SplitMix64;

#[test]
fn ratio_and_mutual_matching_recover_a_planted_permutation() {
    let (len, n, distractors) = (64usize, 200usize, 300usize);
    let mut rng = SplitMix64::new(1);
    let query: Vec<f32> = (0..n * len).map(|_| rng.next_f64() as f32).collect();
    // Train: the queries in a scrambled order (train index of query q is (q·37 + 11) mod n) plus noise,
    // followed by unrelated distractors.
    let perm = |q: usize| (q * 37 + 11) % n;
    let mut train = vec![0.0f32; (n + distractors) * len];
    for q in 0..n {
        for k in 0..len {
            train[perm(q) * len + k] = query[q * len + k] + 0.01 * (rng.next_f64() as f32 - 0.5);
        }
    }
    for v in &mut train[n * len..] {
        *v = rng.next_f64() as f32;
    }
    for mutual in [false, true] {
        let m = match_ratio(&query, &train, len, 0.8, mutual).unwrap();
        assert_eq!(m.len(), n, "mutual {mutual}");
        for (q, mm) in m.iter().enumerate() {
            assert_eq!(mm.query, q);
            assert_eq!(mm.train, perm(q));
            assert!(mm.distance < 0.1 && mm.second_distance > 1.0);
        }
    }
    // A query that is equidistant from two train descriptors fails the ratio test, and the mutual check
    // removes a query whose train partner prefers another query.
    let q2 = vec![0.0f32, 0.0, 1.0, 1.0]; // two queries of length 2: (0,0) and (1,1)
    let t2 = vec![1.0f32, 0.0, -1.0, 0.0]; // both at distance 1 from query 0
    let m = match_ratio(&q2, &t2, 2, 0.8, false).unwrap();
    assert!(m.iter().all(|mm| mm.query != 0), "{m:?}");
    // With ratio 2 (no ratio filtering): query 0 ties between both train features → lower index 0; query 1
    // (1,1) → train 0 (1,0). Train 0's nearest query is a tie (distance 1 to both) → lower index 0, so only
    // query 0 survives the mutual check.
    let m = match_ratio(&q2, &t2, 2, 2.0, true).unwrap();
    assert_eq!(m.len(), 1);
    assert_eq!((m[0].query, m[0].train), (0, 0));
}

#[test]
fn windowed_matching_only_considers_train_features_in_the_window() {
    let len = 8usize;
    let mut rng = SplitMix64::new(2);
    let n = 50;
    let query: Vec<f32> = (0..n * len).map(|_| rng.next_f64() as f32).collect();
    let predicted: Vec<[f64; 2]> = (0..n)
        .map(|i| [20.0 * (i % 10) as f64, 20.0 * (i / 10) as f64])
        .collect();
    // Train: for each query a true partner 3 px away (descriptor with noise) and, 12 px away, an exact copy
    // of the query's descriptor (a decoy outside a 5 px window).
    let mut train = Vec::new();
    let mut train_px = Vec::new();
    for i in 0..n {
        train.extend(query[i * len..(i + 1) * len].iter().map(|&v| v + 0.05));
        train_px.push([predicted[i][0] + 3.0, predicted[i][1] - 2.0]);
        train.extend_from_slice(&query[i * len..(i + 1) * len]);
        train_px.push([predicted[i][0] - 12.0, predicted[i][1]]);
    }
    let m = match_windowed(&query, &predicted, &train, &train_px, len, 5.0, 0.8).unwrap();
    for (i, mm) in m.iter().enumerate() {
        let mm = mm.expect("a match per query");
        assert_eq!((mm.query, mm.train), (i, 2 * i));
    }
    // With a 13 px window the exact decoy wins.
    let m = match_windowed(&query, &predicted, &train, &train_px, len, 13.0, 1.0).unwrap();
    assert!(m
        .iter()
        .enumerate()
        .all(|(i, mm)| mm.unwrap().train == 2 * i + 1));
    // No candidate → None.
    let far = vec![[1e6, 1e6]; n];
    assert!(
        match_windowed(&query, &far, &train, &train_px, len, 5.0, 0.8)
            .unwrap()
            .iter()
            .all(Option::is_none)
    );
}

#[test]
fn inconsistent_inputs_are_errors() {
    assert_eq!(
        match_ratio(&[0.0; 5], &[0.0; 4], 2, 0.8, false).unwrap_err(),
        MatchError::Ragged {
            which: "query",
            values: 5,
            len: 2
        }
    );
    assert_eq!(
        match_ratio(&[0.0; 4], &[0.0; 4], 0, 0.8, false).unwrap_err(),
        MatchError::ZeroLength
    );
    let e = match_windowed(
        &[0.0; 4],
        &[[0.0, 0.0]],
        &[0.0; 4],
        &[[0.0, 0.0]; 2],
        2,
        1.0,
        0.8,
    )
    .unwrap_err();
    assert_eq!(
        e,
        MatchError::PositionCount {
            which: "query",
            positions: 1,
            descriptors: 2
        }
    );
    assert!(e.to_string().contains("one position per descriptor"));
}

/// Similarity x_b = s·R(θ)·(x_a − c) + c + t in continuous pixel coordinates.
#[derive(Clone, Copy)]
struct Similarity {
    scale: f64,
    angle: f64,
    centre: [f64; 2],
    shift: [f64; 2],
}

impl Similarity {
    fn apply(&self, p: [f64; 2]) -> [f64; 2] {
        let (c, s) = (self.angle.cos(), self.angle.sin());
        let (x, y) = (p[0] - self.centre[0], p[1] - self.centre[1]);
        [
            self.scale * (c * x - s * y) + self.centre[0] + self.shift[0],
            self.scale * (s * x + c * y) + self.centre[1] + self.shift[1],
        ]
    }
    fn invert(&self, q: [f64; 2]) -> [f64; 2] {
        let (c, s) = (self.angle.cos(), self.angle.sin());
        let (x, y) = (
            (q[0] - self.centre[0] - self.shift[0]) / self.scale,
            (q[1] - self.centre[1] - self.shift[1]) / self.scale,
        );
        [
            c * x + s * y + self.centre[0],
            -s * x + c * y + self.centre[1],
        ]
    }
}

fn texture(seed: u64, count: usize, size: f64) -> Vec<[f64; 4]> {
    let mut rng = SplitMix64::new(seed);
    (0..count)
        .map(|_| {
            let amp = if rng.next_f64() < 0.5 { -0.25 } else { 0.25 };
            [
                size * rng.next_f64(),
                size * rng.next_f64(),
                1.5 + 3.5 * rng.next_f64(),
                amp,
            ]
        })
        .collect()
}

fn render(
    blobs: &[[f64; 4]],
    w: usize,
    h: usize,
    to_texture: impl Fn([f64; 2]) -> [f64; 2],
) -> GrayImage {
    let data = (0..w * h)
        .map(|k| {
            let p = to_texture([(k % w) as f64 + 0.5, (k / w) as f64 + 0.5]);
            let v: f64 = blobs
                .iter()
                .map(|b| {
                    b[3] * (-((p[0] - b[0]).powi(2) + (p[1] - b[1]).powi(2)) / (2.0 * b[2] * b[2]))
                        .exp()
                })
                .sum();
            (0.5 + v).clamp(0.0, 1.0) as f32
        })
        .collect();
    GrayImage::from_vec(w, h, data).unwrap()
}

#[test]
fn kaze_matching_recovers_a_known_similarity() {
    let size = 240usize;
    let blobs = texture(4, 1400, size as f64);
    let t = Similarity {
        scale: 1.08,
        angle: 0.35,
        centre: [120.0, 120.0],
        shift: [6.0, -4.0],
    };
    let a = render(&blobs, size, size, |p| p);
    let b = render(&blobs, size, size, |q| t.invert(q));
    let p = KazeParams {
        octaves: 2,
        ..KazeParams::default()
    };
    let fa = detect_and_describe(&a, &p);
    let fb = detect_and_describe(&b, &p);
    let correct = |qa: usize, tb: usize| {
        let ka = fa.keypoints[qa];
        let kb = fb.keypoints[tb];
        let pred = t.apply([ka.u_px as f64, ka.v_px as f64]);
        (pred[0] - kb.u_px as f64).hypot(pred[1] - kb.v_px as f64) < 1.5
    };
    let m = match_ratio(
        &fa.descriptors,
        &fb.descriptors,
        fa.descriptor_len,
        0.8,
        true,
    )
    .unwrap();
    let good = m.iter().filter(|mm| correct(mm.query, mm.train)).count();
    assert!(
        good >= 40,
        "{good} correct of {} ratio matches ({} / {} keypoints)",
        m.len(),
        fa.len(),
        fb.len()
    );
    assert!(
        good as f64 >= 0.9 * m.len() as f64,
        "{good} correct of {}",
        m.len()
    );

    // Windowed (thesis 3.4.5.2): predictions off by (2.5, −1.5) px, window ±6 px, no ratio test.
    let predicted: Vec<[f64; 2]> = fa
        .keypoints
        .iter()
        .map(|k| {
            let q = t.apply([k.u_px as f64, k.v_px as f64]);
            [q[0] + 2.5, q[1] - 1.5]
        })
        .collect();
    let train_px: Vec<[f64; 2]> = fb
        .keypoints
        .iter()
        .map(|k| [k.u_px as f64, k.v_px as f64])
        .collect();
    let w = match_windowed(
        &fa.descriptors,
        &predicted,
        &fb.descriptors,
        &train_px,
        fa.descriptor_len,
        6.0,
        0.9,
    )
    .unwrap();
    let found: Vec<_> = w.iter().flatten().collect();
    let good_w = found
        .iter()
        .filter(|mm| correct(mm.query, mm.train))
        .count();
    assert!(
        good_w >= 60,
        "{good_w} correct of {} windowed matches",
        found.len()
    );
    assert!(
        good_w as f64 >= 0.9 * found.len() as f64,
        "{good_w} correct of {}",
        found.len()
    );
    assert!(
        good_w > good,
        "windowing should find more correct matches ({good_w}) than global ratio ({good})"
    );
}
