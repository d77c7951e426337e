//! Descriptor matching by L2 distance (thesis 3.4.4.2 and 3.4.5.2): brute-force nearest neighbour with
//! Lowe's ratio test and an optional mutual (cross) check, and the windowed one-to-many variant of thesis
//! 3.4.5.2 where each query is compared only with the train features inside a window around its predicted
//! position.
//!
//! Descriptors are row-major `f32` slices with `len` values each (e.g. [`crate::features::kaze::Features`]).
//! Queries are processed in parallel with ordered collects, and distances are summed in a fixed order, so
//! results do not depend on the thread count. Ties are broken by the lower train index.

use rayon::prelude::*;

/// One correspondence: query feature `query` ↔ train feature `train`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DescriptorMatch {
    pub query: usize,
    pub train: usize,
    /// L2 distance to the best train descriptor.
    pub distance: f32,
    /// L2 distance to the second-best candidate (`f32::INFINITY` if there was only one candidate).
    pub second_distance: f32,
}

/// Errors of the matchers (inconsistent inputs).
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MatchError {
    #[error("descriptor length is 0; pass the length of one descriptor (e.g. 64 or 128)")]
    ZeroLength,
    #[error(
        "{which} descriptors: {values} values is not a multiple of the descriptor length {len}"
    )]
    Ragged {
        which: &'static str,
        values: usize,
        len: usize,
    },
    #[error("{which}: {positions} positions for {descriptors} descriptors; give one position per descriptor")]
    PositionCount {
        which: &'static str,
        positions: usize,
        descriptors: usize,
    },
}

/// Squared L2 distance (sequential sum, deterministic).
#[inline]
pub fn squared_distance(a: &[f32], b: &[f32]) -> f32 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

fn count(which: &'static str, values: &[f32], len: usize) -> Result<usize, MatchError> {
    if len == 0 {
        return Err(MatchError::ZeroLength);
    }
    if !values.len().is_multiple_of(len) {
        return Err(MatchError::Ragged {
            which,
            values: values.len(),
            len,
        });
    }
    Ok(values.len() / len)
}

/// Best and second-best (squared distance, index) among `candidates` of `train` for descriptor `q`.
fn two_nearest(
    q: &[f32],
    train: &[f32],
    len: usize,
    candidates: impl Iterator<Item = usize>,
) -> Option<((f32, usize), f32)> {
    let mut best: Option<(f32, usize)> = None;
    let mut second = f32::INFINITY;
    for t in candidates {
        let d = squared_distance(q, &train[t * len..(t + 1) * len]);
        match best {
            Some((bd, bt)) if d < bd || (d == bd && t < bt) => {
                second = bd;
                best = Some((d, t));
            }
            Some(_) => second = second.min(d),
            None => best = Some((d, t)),
        }
    }
    best.map(|b| (b, second))
}

fn passes_ratio(best_sq: f32, second_sq: f32, ratio: f32) -> bool {
    // d1 < ratio·d2 ⇔ d1² < ratio²·d2² (non-negative distances).
    second_sq.is_infinite() || best_sq < ratio * ratio * second_sq
}

/// Nearest neighbour of every query among all train descriptors, kept if d1 < `ratio`·d2 (ratio > 1 keeps
/// all) and, if `mutual`, only if the query is also the train feature's nearest query. Sorted by query.
pub fn match_ratio(
    query: &[f32],
    train: &[f32],
    len: usize,
    ratio: f32,
    mutual: bool,
) -> Result<Vec<DescriptorMatch>, MatchError> {
    let nt = count("train", train, len)?;
    match_restricted(query, train, len, ratio, mutual, |_| 0..nt)
}

/// [`match_ratio`] with the candidates of each query restricted: query `qi` is compared only with the train
/// features `candidates(qi)` (ascending indices, e.g. those near its epipolar line — guided matching), the
/// ratio test uses the second-nearest of those, and the mutual check asks whether the query is the nearest
/// among the queries that have the train feature as a candidate. Sorted by query.
pub fn match_restricted<C, I>(
    query: &[f32],
    train: &[f32],
    len: usize,
    ratio: f32,
    mutual: bool,
    candidates: C,
) -> Result<Vec<DescriptorMatch>, MatchError>
where
    C: Fn(usize) -> I + Sync,
    I: Iterator<Item = usize>,
{
    let nq = count("query", query, len)?;
    let nt = count("train", train, len)?;
    let lists: Vec<Vec<usize>> = (0..nq)
        .into_par_iter()
        .map(|qi| candidates(qi).filter(|&t| t < nt).collect())
        .collect();
    let forward: Vec<Option<DescriptorMatch>> = (0..nq)
        .into_par_iter()
        .map(|qi| {
            let q = &query[qi * len..(qi + 1) * len];
            let ((d1, t), d2) = two_nearest(q, train, len, lists[qi].iter().copied())?;
            passes_ratio(d1, d2, ratio).then(|| DescriptorMatch {
                query: qi,
                train: t,
                distance: d1.sqrt(),
                second_distance: d2.sqrt(),
            })
        })
        .collect();
    if !mutual {
        return Ok(forward.into_iter().flatten().collect());
    }
    // Inverse candidate lists (ascending query indices), only for train features some query matched.
    let mut inverse: Vec<Vec<usize>> = vec![Vec::new(); nt];
    let matched: Vec<bool> = {
        let mut m = vec![false; nt];
        for f in forward.iter().flatten() {
            m[f.train] = true;
        }
        m
    };
    for (qi, list) in lists.iter().enumerate() {
        for &t in list {
            if matched[t] {
                inverse[t].push(qi);
            }
        }
    }
    let backward: Vec<Option<usize>> = inverse
        .par_iter()
        .enumerate()
        .map(|(ti, qs)| {
            let t = &train[ti * len..(ti + 1) * len];
            two_nearest(t, query, len, qs.iter().copied()).map(|((_, q), _)| q)
        })
        .collect();
    Ok(forward
        .into_iter()
        .flatten()
        .filter(|m| backward[m.train] == Some(m.query))
        .collect())
}

/// Windowed one-to-many matching (thesis 3.4.5.2): for query i with predicted train-image position
/// `predicted_px[i]` = (u, v), the candidates are the train features whose `train_px` lies within
/// ±`window_px` in both u and v; the nearest candidate is returned if it passes the ratio test against
/// the second-nearest candidate in the same window (a single candidate always passes). Result per query
/// (`None`: no candidate or ratio failed).
pub fn match_windowed(
    query: &[f32],
    predicted_px: &[[f64; 2]],
    train: &[f32],
    train_px: &[[f64; 2]],
    len: usize,
    window_px: f64,
    ratio: f32,
) -> Result<Vec<Option<DescriptorMatch>>, MatchError> {
    let nq = count("query", query, len)?;
    let nt = count("train", train, len)?;
    if predicted_px.len() != nq {
        return Err(MatchError::PositionCount {
            which: "query",
            positions: predicted_px.len(),
            descriptors: nq,
        });
    }
    if train_px.len() != nt {
        return Err(MatchError::PositionCount {
            which: "train",
            positions: train_px.len(),
            descriptors: nt,
        });
    }
    // Train features sorted by u for a binary-searched strip per query.
    let mut by_u: Vec<usize> = (0..nt)
        .filter(|&t| train_px[t].iter().all(|c| c.is_finite()))
        .collect();
    by_u.sort_by(|&a, &b| train_px[a][0].total_cmp(&train_px[b][0]).then(a.cmp(&b)));
    Ok((0..nq)
        .into_par_iter()
        .map(|qi| {
            let [pu, pv] = predicted_px[qi];
            if !(pu.is_finite() && pv.is_finite()) {
                return None;
            }
            let lo = by_u.partition_point(|&t| train_px[t][0] < pu - window_px);
            let hi = by_u.partition_point(|&t| train_px[t][0] <= pu + window_px);
            let q = &query[qi * len..(qi + 1) * len];
            let candidates = by_u[lo..hi]
                .iter()
                .copied()
                .filter(|&t| (train_px[t][1] - pv).abs() <= window_px);
            let ((d1, t), d2) = two_nearest(q, train, len, candidates)?;
            passes_ratio(d1, d2, ratio).then(|| DescriptorMatch {
                query: qi,
                train: t,
                distance: d1.sqrt(),
                second_distance: d2.sqrt(),
            })
        })
        .collect())
}
