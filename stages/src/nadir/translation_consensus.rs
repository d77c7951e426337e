//! Robust translation between two point sets whose scale and rotation are already known (thesis 3.4.5.2: the MM
//! ortho image is made at the aerial GSD and in the aerial image's orientation, so the similarity ortho px →
//! aerial px is the recorded-pose one up to a translation of at most the localisation error).
//!
//! Every correspondence proposes one translation (`dst − nominal(src)`); all of them are tried (exhaustive, so
//! the result is deterministic and needs no seed) and the one with the most others within `threshold_px` wins
//! (ties: smaller residual sum, then lower index). The consensus is then refined by averaging its members'
//! translations and re-selecting them until the member set is stable. One free 2-D parameter per sample instead
//! of the similarity's four makes a random consensus far less likely than with 2-point similarity samples: a
//! wrong match agrees with a random translation only by falling into a `threshold_px` disc. [`false_alarms`]
//! says how often chance alone gives a consensus of a given size (the a-contrario test of the initial transform).

use crate::geometry::{PointPair, Similarity2};
use nalgebra::Vector2;

/// A translation consensus: the model and the indices of its members.
#[derive(Clone, Debug, PartialEq)]
pub struct TranslationConsensus {
    /// `nominal` followed by the translation (aerial px).
    pub model: Similarity2,
    /// The translation added to `nominal`, aerial px.
    pub shift_px: Vector2<f64>,
    /// Indices into the input pairs, ascending.
    pub inliers: Vec<usize>,
    /// Size of the best consensus among hypotheses more than `2 × threshold_px` away from the winner (how much
    /// support a competing translation has; 0 when none).
    pub runner_up: usize,
}

/// How many translations supported by `k` or more of `n` matches (within `threshold_px`) random matches would
/// produce: the number of false alarms of the a-contrario test. Under the null hypothesis each match's offset
/// is uniform over the ±`window_px` matching window, so another match agrees with a given one with probability
/// `p = π r² / (2W)²`; every match is a hypothesis, so NFA = n · P[Bin(n − 1, p) ≥ k − 1]. A consensus with
/// NFA ≪ 1 is meaningful; NFA ≳ 1 is what chance gives.
pub fn false_alarms(n: usize, k: usize, threshold_px: f64, window_px: f64) -> f64 {
    if n == 0 || k <= 1 {
        return n as f64;
    }
    let area = (2.0 * window_px).powi(2);
    let p = (std::f64::consts::PI * threshold_px * threshold_px / area).min(1.0);
    if p >= 1.0 {
        return n as f64;
    }
    let (m, j0) = (n - 1, k - 1);
    if j0 > m {
        return 0.0;
    }
    let (lp, lq) = (p.ln(), (1.0 - p).ln());
    let ln_choose: f64 = (1..=j0)
        .map(|i| ((m - j0 + i) as f64 / i as f64).ln())
        .sum();
    let mut term = (ln_choose + j0 as f64 * lp + (m - j0) as f64 * lq).exp();
    let mut tail = 0.0;
    for j in j0..=m {
        tail += term;
        if term < tail * 1e-16 {
            break;
        }
        term *= (m - j) as f64 / (j + 1) as f64 * p / (1.0 - p);
    }
    n as f64 * tail
}

/// Why the consensus `c` of `n_matches` matches is not accepted, if it is not: a competing translation has more
/// than `1 / min_margin` of its support (ambiguous content), or a consensus of its size among matches spread over
/// the ±`window_px` window is what chance gives (more than `max_false_alarms` false alarms, [`false_alarms`]
/// with `threshold_px`).
pub fn consensus_doubt(
    c: &TranslationConsensus,
    n_matches: usize,
    (min_margin, max_false_alarms): (f64, f64),
    threshold_px: f64,
    window_px: f64,
) -> Option<String> {
    let n = c.inliers.len();
    if (n as f64) < min_margin * c.runner_up as f64 {
        return Some(format!(
            "{n_matches} matches: ambiguous translation ({n} inliers, a competing one has {})",
            c.runner_up
        ));
    }
    let nfa = false_alarms(n_matches, n, threshold_px, window_px);
    (nfa > max_false_alarms).then(|| {
        format!(
            "{n_matches} matches: a consensus of {n} is what chance gives (expected {nfa:.2} among \
             random matches > {max_false_alarms})"
        )
    })
}

fn members(offsets: &[Vector2<f64>], t: &Vector2<f64>, threshold_px: f64) -> (Vec<usize>, f64) {
    let t2 = threshold_px * threshold_px;
    let mut idx = Vec::new();
    let mut ssr = 0.0;
    for (j, o) in offsets.iter().enumerate() {
        let d2 = (o - t).norm_squared();
        if d2 <= t2 {
            idx.push(j);
            ssr += d2;
        }
    }
    (idx, ssr)
}

/// The translation consensus of `pairs` under `nominal` (see the module documentation); `None` without pairs or
/// with a non-finite threshold.
pub fn translation_consensus(
    pairs: &[PointPair],
    nominal: &Similarity2,
    threshold_px: f64,
) -> Option<TranslationConsensus> {
    if pairs.is_empty() || !(threshold_px.is_finite() && threshold_px > 0.0) {
        return None;
    }
    let offsets: Vec<Vector2<f64>> = pairs
        .iter()
        .map(|p| p.dst - nominal.apply(&p.src))
        .collect();
    let t2 = threshold_px * threshold_px;
    let mut counts = vec![0usize; offsets.len()];
    let mut best: Option<(usize, usize, f64)> = None; // (index, count, ssr)
    for (i, oi) in offsets.iter().enumerate() {
        if !(oi.x.is_finite() && oi.y.is_finite()) {
            continue;
        }
        let (mut count, mut ssr) = (0usize, 0.0f64);
        for oj in &offsets {
            let d2 = (oj - oi).norm_squared();
            if d2 <= t2 {
                count += 1;
                ssr += d2;
            }
        }
        counts[i] = count;
        let better = match best {
            None => true,
            Some((_, c, s)) => count > c || (count == c && ssr < s),
        };
        if better {
            best = Some((i, count, ssr));
        }
    }
    let (seed, _, _) = best?;
    let mut shift = offsets[seed];
    let (mut inliers, _) = members(&offsets, &shift, threshold_px);
    for _ in 0..10 {
        let mean = inliers
            .iter()
            .fold(Vector2::zeros(), |a, &j| a + offsets[j])
            / inliers.len() as f64;
        let (next, _) = members(&offsets, &mean, threshold_px);
        if next.is_empty() {
            break;
        }
        shift = mean;
        if next == inliers {
            break;
        }
        inliers = next;
    }
    let far2 = 4.0 * t2;
    let runner_up = offsets
        .iter()
        .zip(&counts)
        .filter(|(o, _)| (*o - shift).norm_squared() > far2)
        .map(|(_, &c)| c)
        .max()
        .unwrap_or(0);
    let model = Similarity2 {
        tx: nominal.tx + shift.x,
        ty: nominal.ty + shift.y,
        ..*nominal
    };
    Some(TranslationConsensus {
        model,
        shift_px: shift,
        inliers,
        runner_up,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn false_alarms_follow_the_binomial_tail() {
        // p = π·4/900 = 0.01396: with 3 matches, all 3 agreeing by chance: 3 · p² = 5.85e-4.
        let p = std::f64::consts::PI * 4.0 / 900.0;
        assert!((false_alarms(3, 3, 2.0, 15.0) - 3.0 * p * p).abs() < 1e-12);
        // k = 2 of 2: 2 · p.
        assert!((false_alarms(2, 2, 2.0, 15.0) - 2.0 * p).abs() < 1e-12);
        // A random-looking consensus (7 of 105) is expected 0.4 times by chance, 6 of 60 0.09 times; 20 of 60
        // never.
        let chance = false_alarms(105, 7, 2.0, 15.0);
        assert!(chance > 0.3 && chance < 0.5, "{chance}");
        let weak = false_alarms(60, 6, 2.0, 15.0);
        assert!(weak > 0.05 && weak < 0.1, "{weak}");
        assert!(false_alarms(60, 20, 2.0, 15.0) < 1e-15);
        assert!(false_alarms(8, 6, 2.0, 15.0) < 1e-3);
        assert_eq!(false_alarms(5, 1, 2.0, 15.0), 5.0);
        assert_eq!(false_alarms(4, 9, 2.0, 15.0), 0.0);
    }
}
