//! AGAST corner detector, OAST 9-16 mask (Mair et al. 2010; Mair et al. 2010; Tola, Lepetit & Fua 2010): corners for matching perspective
//! views rendered from the panoramas (façade sparse cloud, thesis 4.4.1).
//!
//! Segment test: pixel p (intensity I_p) is a corner at threshold t when ≥ 9 contiguous pixels of the 16-pixel
//! Bresenham circle of radius 3 are all brighter than I_p + t or all darker than I_p − t (strict comparisons).
//! AGAST evaluates this test with generated decision trees; the *result* is that of the plain segment test, which
//! is what is implemented here: a quick rejection with the circle pixels 1, 9 and 5, 13 (an arc of 9 of 16 holds
//! at least one pixel of every opposite pair), then the exact score of the survivors.
//!
//! Score: the supremum of the thresholds at which p is still a corner, i.e.
//! `max over arcs of 9 (min over the arc of d)` with d = I_circle − I_p for bright arcs and I_p − I_circle for dark
//! ones; p is a corner at t iff score > t. OpenCV's `agast_cornerScore` returns the largest *integer* t still
//! passing, which on 8-bit images is our score − 1 (same ranking).
//!
//! Intensity scale: OpenCV's 0..255 grey levels. [`GrayImage`] holds 0..1 after loading an 8-bit file, so the
//! detector works on 255·value; values within 1e-3 of an integer are snapped to it so that images loaded from
//! 8-bit files reproduce OpenCV's integer decisions exactly despite the f32 rounding of k/255.
//!
//! Non-maximum suppression over the 3×3 neighbourhood on the key (score, strength), compared lexicographically;
//! strength = Σ over the circle of max(0, |d| − t) for the pixels of the winning class (bright or dark), FAST's
//! "sum of absolute differences". Scores tie often (integer on 8-bit images, and a whole cluster of pixels at a
//! sharp corner scores the full contrast); the strength then prefers the pixel with the longest arc, which is the
//! one at the corner. Remaining ties: a corner survives if its key is > the keys of its neighbours earlier in
//! raster order and ≥ those of the later ones (non-corners have key (0, 0)), so exactly one pixel of a tied pair
//! survives (deterministic). OpenCV suppresses on the score alone. The 3-pixel border is never tested.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::imaging::GrayImage;

/// Radius of the Bresenham circle (pixels): also the untested border.
const CIRCLE_RADIUS_PX: usize = 3;
/// Length of the contiguous arc (OAST 9-16).
const ARC_LEN: usize = 9;

/// The 16 circle offsets (dx, dy), clockwise from the top (dy = −3), y down.
const CIRCLE: [(isize, isize); 16] = [
    (0, -3),
    (1, -3),
    (2, -2),
    (3, -1),
    (3, 0),
    (3, 1),
    (2, 2),
    (1, 3),
    (0, 3),
    (-1, 3),
    (-2, 2),
    (-3, 1),
    (-3, 0),
    (-3, -1),
    (-2, -2),
    (-1, -3),
];

crate::params! {
    /// Detector parameters (OpenCV `AgastFeatureDetector::create` defaults).
    pub struct AgastParams {
        /// Segment-test threshold in 0..255 grey levels, compared against 255·value of the 0..1 image
        /// (OpenCV's scale and default).
        threshold: f32 = 10.0, min 0.0, max 255.0;
        /// 3×3 non-maximum suppression on the score.
        nonmax_suppression: bool = true;
        /// Keep only the strongest corners (after suppression); absent keeps all.
        max_corners: Option<usize> = None, min 1;
    }
}

/// One corner; continuous pixel coordinates (pixel (c, r) has its centre at (c + 0.5, r + 0.5)).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AgastCorner {
    pub x_px: f64,
    pub y_px: f64,
    /// Score in 0..255 grey levels (see the module doc): the corner passes every threshold below it.
    pub score: f32,
}

/// Detect AGAST (OAST 9-16) corners. Order: score descending, ties in raster order (row, then column).
/// A negative or non-finite threshold is treated as 0; images smaller than 7×7 have no corners.
pub fn detect_agast(img: &GrayImage, p: &AgastParams) -> Vec<AgastCorner> {
    let (w, h) = (img.width, img.height);
    let b = CIRCLE_RADIUS_PX;
    if w < 2 * b + 1 || h < 2 * b + 1 || img.data.len() != w * h {
        return Vec::new();
    }
    let t = if p.threshold.is_finite() {
        p.threshold.max(0.0)
    } else {
        0.0
    };
    let scaled = to_grey_levels(img);
    let scores = score_map(&scaled, w, h, t);
    let mut corners: Vec<AgastCorner> = (b..h - b)
        .into_par_iter()
        .map(|row| {
            let mut out = Vec::new();
            let s_row = &scores[row * w..(row + 1) * w];
            for col in b..w - b {
                let key = s_row[col];
                if key.0 <= 0.0 {
                    continue;
                }
                if p.nonmax_suppression && !is_local_max(&scores, w, col, row, key) {
                    continue;
                }
                out.push(AgastCorner {
                    x_px: col as f64 + 0.5,
                    y_px: row as f64 + 0.5,
                    score: key.0,
                });
            }
            out
        })
        .flatten()
        .collect();
    // Stable sort: raster order is kept among equal scores.
    corners.sort_by(|a, c| c.score.total_cmp(&a.score));
    if let Some(n) = p.max_corners {
        corners.truncate(n);
    }
    corners
}

/// 255·value, snapped to the nearest integer when within 1e-3 of it (8-bit inputs become exact integers).
fn to_grey_levels(img: &GrayImage) -> Vec<f32> {
    img.data
        .par_iter()
        .map(|&v| {
            let g = 255.0 * v;
            let r = g.round();
            if (g - r).abs() < 1e-3 {
                r
            } else {
                g
            }
        })
        .collect()
}

/// NMS key (score, strength) of every pixel ((0, 0) where not a corner at `t`, and in the border).
fn score_map(g: &[f32], w: usize, h: usize, t: f32) -> Vec<(f32, f32)> {
    let b = CIRCLE_RADIUS_PX;
    let offsets: [isize; 16] = CIRCLE.map(|(dx, dy)| dy * w as isize + dx);
    let mut keys = vec![(0.0f32, 0.0f32); w * h];
    keys.par_chunks_mut(w)
        .enumerate()
        .skip(b)
        .take(h - 2 * b)
        .for_each(|(row, out)| {
            for col in b..w - b {
                let i = row * w + col;
                if let Some(k) = segment_score(g, i, &offsets, t) {
                    out[col] = k;
                }
            }
        });
    keys
}

/// Segment-test (score, strength) of the pixel at linear index `i` when it is a corner at `t` (score > t), else
/// None. The caller guarantees that the whole circle is inside the image.
#[inline]
fn segment_score(g: &[f32], i: usize, off: &[isize; 16], t: f32) -> Option<(f32, f32)> {
    let at = |k: usize| g[(i as isize + off[k]) as usize];
    let c = g[i];
    let (hi, lo) = (c + t, c - t);
    // Quick rejection: an arc of 9 contains one pixel of each opposite pair (k, k + 8).
    let (c0, c8) = (at(0), at(8));
    let mut bright = c0 > hi || c8 > hi;
    let mut dark = c0 < lo || c8 < lo;
    if !(bright || dark) {
        return None;
    }
    let (c4, c12) = (at(4), at(12));
    bright &= c4 > hi || c12 > hi;
    dark &= c4 < lo || c12 < lo;
    if !(bright || dark) {
        return None;
    }
    let mut d = [0.0f32; 16];
    for (k, dk) in d.iter_mut().enumerate() {
        *dk = at(k) - c;
    }
    let s_bright = if bright { best_arc_min(&d) } else { f32::MIN };
    let s_dark = if dark {
        for dk in d.iter_mut() {
            *dk = -*dk;
        }
        best_arc_min(&d)
    } else {
        f32::MIN
    };
    let s = s_bright.max(s_dark);
    if s <= t {
        return None;
    }
    // `d` holds the dark differences when the dark test ran; the winning class's differences are ±d.
    let sign = if dark == (s_dark >= s_bright) {
        1.0
    } else {
        -1.0
    };
    let strength: f32 = d.iter().map(|&v| (sign * v - t).max(0.0)).sum();
    Some((s, strength))
}

/// max over the 16 circular arcs of length 9 of the minimum of `d` on the arc (min-doubling: 2, 4, 8, 9).
#[inline]
fn best_arc_min(d: &[f32; 16]) -> f32 {
    let mut m2 = [0.0f32; 16];
    let mut m4 = [0.0f32; 16];
    for k in 0..16 {
        m2[k] = d[k].min(d[(k + 1) & 15]);
    }
    for k in 0..16 {
        m4[k] = m2[k].min(m2[(k + 2) & 15]);
    }
    let mut best = f32::MIN;
    for k in 0..16 {
        let m8 = m4[k].min(m4[(k + 4) & 15]);
        let m9 = m8.min(d[(k + ARC_LEN - 1) & 15]);
        best = best.max(m9);
    }
    best
}

/// 3×3 suppression on (score, strength) with the raster-order tie rule of the module doc. (col, row) is ≥ 1 px
/// inside the image.
#[inline]
fn is_local_max(keys: &[(f32, f32)], w: usize, col: usize, row: usize, k: (f32, f32)) -> bool {
    let up = (row - 1) * w + col;
    let here = row * w + col;
    let down = (row + 1) * w + col;
    let gt = |j: usize| k.0 > keys[j].0 || (k.0 == keys[j].0 && k.1 > keys[j].1);
    let ge = |j: usize| k.0 > keys[j].0 || (k.0 == keys[j].0 && k.1 >= keys[j].1);
    gt(up - 1)
        && gt(up)
        && gt(up + 1)
        && gt(here - 1)
        && ge(here + 1)
        && ge(down - 1)
        && ge(down)
        && ge(down + 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;

    /// Brute-force FAST-9 test at threshold t on 0..255 values (no rejection, no score).
    fn brute_force_corner(g: &[f32], w: usize, col: usize, row: usize, t: f32) -> bool {
        let c = g[row * w + col];
        let v: Vec<f32> = CIRCLE
            .iter()
            .map(|&(dx, dy)| g[(row as isize + dy) as usize * w + (col as isize + dx) as usize])
            .collect();
        for start in 0..16 {
            if (0..ARC_LEN).all(|k| v[(start + k) % 16] > c + t)
                || (0..ARC_LEN).all(|k| v[(start + k) % 16] < c - t)
            {
                return true;
            }
        }
        false
    }

    fn random_image(w: usize, h: usize, seed: u64, levels: u64) -> GrayImage {
        let data = crate::rng::mmix_states(seed)
            .take(w * h)
            .map(|s| ((s >> 33) % levels) as f32 / 255.0)
            .collect();
        GrayImage::from_vec(w, h, data).unwrap()
    }

    #[test]
    fn eight_bit_levels_scale_back_to_exact_integers() {
        let img =
            GrayImage::from_vec(256, 1, (0..256).map(|k| k as f32 / 255.0).collect()).unwrap();
        let g = to_grey_levels(&img);
        for (k, &v) in g.iter().enumerate() {
            assert_eq!(v, k as f32);
        }
    }

    #[test]
    fn without_nms_equals_brute_force_segment_test_on_random_images() {
        for (seed, levels, t) in [
            (1u64, 256u64, 10.0f32),
            (2, 256, 30.0),
            (3, 40, 5.0),
            (4, 256, 0.0),
        ] {
            let img = random_image(64, 48, seed, levels);
            let g = to_grey_levels(&img);
            let p = AgastParams {
                threshold: t,
                nonmax_suppression: false,
                max_corners: None,
            };
            let mut got: Vec<(usize, usize)> = detect_agast(&img, &p)
                .iter()
                .map(|c| (c.y_px as usize, c.x_px as usize))
                .collect();
            got.sort();
            let mut want = Vec::new();
            for row in 3..45 {
                for col in 3..61 {
                    if brute_force_corner(&g, 64, col, row, t) {
                        want.push((row, col));
                    }
                }
            }
            assert!(!want.is_empty());
            assert_eq!(got, want, "seed {seed} t {t}");
        }
    }

    #[test]
    fn score_is_the_supremum_of_passing_thresholds() {
        let img = random_image(40, 40, 9, 256);
        let g = to_grey_levels(&img);
        let p = AgastParams {
            threshold: 5.0,
            nonmax_suppression: false,
            max_corners: None,
        };
        let corners = detect_agast(&img, &p);
        assert!(corners.len() > 5);
        for c in corners {
            let (col, row) = (c.x_px as usize, c.y_px as usize);
            // Integer image: passes at score − 1 (and everything below), fails at the score itself.
            assert!(brute_force_corner(&g, 40, col, row, c.score - 1.0));
            assert!(!brute_force_corner(&g, 40, col, row, c.score));
        }
    }

    #[test]
    fn raising_the_threshold_never_adds_points_and_constant_image_has_none() {
        let img = random_image(50, 50, 5, 256);
        let set = |t: f32| {
            let p = AgastParams {
                threshold: t,
                nonmax_suppression: false,
                max_corners: None,
            };
            detect_agast(&img, &p)
                .iter()
                .map(|c| (c.x_px as usize, c.y_px as usize))
                .collect::<std::collections::BTreeSet<_>>()
        };
        let (a, b) = (set(10.0), set(25.0));
        assert!(b.len() < a.len());
        assert!(b.is_subset(&a));
        let flat = GrayImage::filled(30, 30, 0.4);
        assert!(detect_agast(&flat, &AgastParams::default()).is_empty());
    }

    #[test]
    fn validate_names_bad_fields() {
        assert!(AgastParams::default().validate().is_ok());
        let bad = AgastParams {
            threshold: -1.0,
            nonmax_suppression: true,
            max_corners: Some(0),
        };
        let e = bad.validate().unwrap_err();
        assert_eq!(e.len(), 2);
        assert_eq!(e[0].field, "threshold");
        assert_eq!(e[1].field, "max_corners");
    }
}
