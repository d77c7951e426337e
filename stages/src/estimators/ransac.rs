//! Generic, deterministic RANSAC (Fischler & Bolles 1981; Hartley & Zisserman 2004, ch. 4; thesis 3.4.4 and 3.4.5.2):
//! minimal samples from a seeded [`SplitMix64`], degenerate samples rejected by the model's `fit`, adaptive
//! trial count `N = ⌈ln(1 − p) / ln(1 − wˢ)⌉` from the best inlier fraction w so far (capped by
//! `max_iterations`), and a least-squares refit on the inliers repeated while the consensus set grows.
//!
//! Ties in the inlier count are broken by the smaller sum of squared inlier residuals (MSAC-like), so the
//! result depends only on the data, the parameters and the seed.

use crate::params::Params;
use crate::rng::SplitMix64;

/// A model RANSAC can estimate: fitted from `MIN_SAMPLES` data (minimal sample) or more (least squares).
pub trait Model: Sized {
    /// Size of a minimal sample.
    const MIN_SAMPLES: usize;
    /// One observation (e.g. a point correspondence).
    type Datum;
    /// Fits the model to the given data (≥ `MIN_SAMPLES`); `None` if the data are degenerate.
    fn fit(data: &[&Self::Datum]) -> Option<Self>;
    /// Residual of one datum under the model, in the units of [`RansacParams::threshold`] (non-negative;
    /// infinite if undefined).
    fn residual(&self, d: &Self::Datum) -> f64;
}

crate::params! {
    /// RANSAC settings.
    #[derive(Copy)]
    pub struct RansacParams {
        /// A datum is an inlier when its residual is at most this, in the model's units (e.g. destination
        /// pixels); callers set it for their model.
        threshold: f64 = 1.0, above 0.0;
        /// Probability of drawing at least one all-inlier sample.
        confidence: f64 = 0.99, above 0.0, below 1.0;
        /// Upper bound on the number of samples drawn.
        max_iterations: usize = 2000, min 1;
        /// Seed of the sampling RNG.
        seed: u64 = 0;
    }
}

impl RansacParams {
    /// Parameters with OpenCV's `estimateAffinePartial2D` defaults for confidence (0.99) and iterations (2000).
    pub fn new(threshold: f64, seed: u64) -> Self {
        Self {
            threshold,
            seed,
            ..Self::default()
        }
    }
}

/// The outcome of [`ransac`].
#[derive(Clone, Debug, PartialEq)]
pub struct RansacResult<M> {
    /// The model refitted (least squares) on its consensus set.
    pub model: M,
    /// Indices (ascending) of the data within the threshold of `model`.
    pub inliers: Vec<usize>,
    /// Number of minimal samples drawn (degenerate ones included).
    pub iterations: usize,
}

/// Number of trials needed to draw one all-inlier sample of size `sample_size` with probability
/// `confidence` when a fraction `inlier_fraction` of the data are inliers (`usize::MAX` if impossible).
pub fn required_iterations(confidence: f64, inlier_fraction: f64, sample_size: usize) -> usize {
    let p_good = inlier_fraction.clamp(0.0, 1.0).powi(sample_size as i32);
    if p_good >= 1.0 {
        return 0;
    }
    let denominator = (-p_good).ln_1p();
    if !(denominator < 0.0) {
        return usize::MAX;
    }
    let n = ((1.0 - confidence).ln() / denominator).ceil();
    if n.is_finite() && n < usize::MAX as f64 {
        n.max(0.0) as usize
    } else {
        usize::MAX
    }
}

/// Maximum number of least-squares refits on the growing consensus set.
const MAX_REFITS: usize = 10;

/// Robustly fits `M` to `data`; `None` if the parameters are invalid ([`Params::validate`]), there are
/// fewer than `M::MIN_SAMPLES` data, or no non-degenerate sample was found.
pub fn ransac<M: Model>(data: &[M::Datum], p: &RansacParams) -> Option<RansacResult<M>> {
    ransac_filtered(data, p, |_: &M| true)
}

/// [`ransac`] where every hypothesis (sampled or refitted) must also pass `accept`, e.g. "the transformed
/// patch centre lies within the expected localisation error" (thesis 3.4.5.2). Rejected samples count as
/// iterations like degenerate ones; a refit that is rejected ends the refinement.
pub fn ransac_filtered<M: Model>(
    data: &[M::Datum],
    p: &RansacParams,
    accept: impl Fn(&M) -> bool,
) -> Option<RansacResult<M>> {
    if p.validate().is_err() || data.len() < M::MIN_SAMPLES || M::MIN_SAMPLES == 0 {
        return None;
    }
    let n = data.len();
    let mut rng = SplitMix64::new(p.seed);
    let mut sample_idx = vec![0usize; M::MIN_SAMPLES];
    let mut sample: Vec<&M::Datum> = Vec::with_capacity(M::MIN_SAMPLES);

    let mut best: Option<(M, Score)> = None;
    let mut required = p.max_iterations;
    let mut iterations = 0usize;
    while iterations < required.min(p.max_iterations) {
        iterations += 1;
        rng.sample_distinct(n, &mut sample_idx);
        sample.clear();
        sample.extend(sample_idx.iter().map(|&i| &data[i]));
        let Some(model) = M::fit(&sample).filter(|m| accept(m)) else {
            continue;
        };
        let score = Score::of(&model, data, p.threshold);
        if best.as_ref().is_none_or(|(_, b)| score.better_than(b)) {
            let fraction = score.inliers as f64 / n as f64;
            required = required_iterations(p.confidence, fraction, M::MIN_SAMPLES);
            best = Some((model, score));
        }
    }
    let (mut model, mut score) = best?;
    let mut inliers = inlier_indices(&model, data, p.threshold);

    // Least-squares refit on the consensus set, repeated while it grows (or stays equal on the first pass,
    // so the returned model is always a refit when one is possible).
    let mut refs: Vec<&M::Datum> = Vec::with_capacity(n);
    for pass in 0..MAX_REFITS {
        refs.clear();
        refs.extend(inliers.iter().map(|&i| &data[i]));
        let Some(refit) = M::fit(&refs).filter(|m| accept(m)) else {
            break;
        };
        let refit_score = Score::of(&refit, data, p.threshold);
        let accept = refit_score.inliers > score.inliers
            || (pass == 0 && refit_score.inliers == score.inliers);
        if !accept {
            break;
        }
        let refit_inliers = inlier_indices(&refit, data, p.threshold);
        let unchanged = refit_inliers == inliers;
        model = refit;
        score = refit_score;
        inliers = refit_inliers;
        if unchanged && pass > 0 {
            break;
        }
    }
    if inliers.len() < M::MIN_SAMPLES {
        return None;
    }
    Some(RansacResult {
        model,
        inliers,
        iterations,
    })
}

/// Consensus of one hypothesis: inlier count, then the sum of squared inlier residuals.
#[derive(Clone, Copy, Debug)]
struct Score {
    inliers: usize,
    sum_sq: f64,
}

impl Score {
    fn of<M: Model>(model: &M, data: &[M::Datum], threshold: f64) -> Self {
        let mut inliers = 0;
        let mut sum_sq = 0.0;
        for d in data {
            let r = model.residual(d);
            if r <= threshold {
                inliers += 1;
                sum_sq += r * r;
            }
        }
        Self { inliers, sum_sq }
    }

    fn better_than(&self, other: &Self) -> bool {
        self.inliers > other.inliers
            || (self.inliers == other.inliers && self.sum_sq < other.sum_sq)
    }
}

fn inlier_indices<M: Model>(model: &M, data: &[M::Datum], threshold: f64) -> Vec<usize> {
    (0..data.len())
        .filter(|&i| model.residual(&data[i]) <= threshold)
        .collect()
}
