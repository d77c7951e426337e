//! Robust translation between two point sets whose scale and rotation are already known (thesis 3.4.5.2: the MM
//! ortho image is made at the aerial GSD and in the aerial image's orientation, so the similarity ortho px →
//! aerial px is the recorded-pose one up to a translation of at most the localisation error).
//!
//! Every correspondence proposes one translation (`dst − nominal(src)`); all of them are tried (exhaustive, so
//! the result is deterministic and needs no seed) and the one with the most others within `threshold_px` wins
//! (ties: smaller residual sum, then lower index). The consensus is then refined by averaging its members'
//! translations and re-selecting them until the member set is stable. One free 2-D parameter per sample instead
//! of the similarity's four makes a random consensus far less likely than with 2-point similarity samples: a
//! wrong match agrees with a random translation only by falling into a `threshold_px` disc.

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
