//! Relative constraints released where the evidence contradicts the recorded step beyond its uncertainty.
//!
//! A relative constraint keeps the recorded difference of two consecutive recordings with the σ of the
//! trajectory's noise, estimated from its second differences. A smooth drift (a GNSS outage) does not show in
//! second differences: each step of the outage is off by many σ, and the constraints hold the recorded shape
//! against tie points and control even under a robust loss, whose minimum next to the recorded trajectory the
//! solver does not leave.
//!
//! So the evidence is asked first. The block is solved without its relative constraints (tie points, aerial
//! evidence and the recorded positions' weak priors alone); for each constraint, the solution's change of
//! the step, `Δ = (ĉ_to − ĉ_from)` with ĉ = adjusted − recorded position (horizontal), is compared with what
//! the constraint and the solution's own uncertainty allow: under the constraint
//! `Δ ~ N(0, σ²·I + Q)`, with `Q = V_to + V_from − C − Cᵀ` the covariance of the solution's step (its
//! a-posteriori covariance blocks, scaled by σ̂0² when that exceeds 1; the cross block `C` where the two
//! recordings share tie points, else 0, which only makes the test more cautious). A step whose
//! `T = Δᵀ(σ²·I + Q)⁻¹Δ` exceeds the threshold (a χ² quantile with 2 degrees of freedom) is contradicted: its
//! σ becomes `√(σ² + s²)` with the added variance `s²` at which `T` equals its expectation 2 (a variance
//! component of this one step). Every other constraint keeps its σ — a step the solution determines poorly
//! has a large `Q` and is not released. Only steps between two recordings with aerial evidence of their own
//! (each observes at least two tie points that have a control point or aerial image observations, so that a
//! wrong one shows against the other; [`MIN_ANCHORED_POINTS`]) are tested at all: a recording without it (a
//! bridged recording) is placed by tie points alone in that solution, whose
//! chain of small errors and free yaw corrections can bend a stretch of them by decimetres while their
//! covariance says centimetres; its steps take the σ of the tested steps next to its stretch
//! ([`super::relative_bridge`]). The adjustment proper then runs with these σ from the recorded trajectory (started from
//! the solution without relative constraints instead, it ends at the same result on demo seeds 1–3).

use super::problem::{Block, RelativeConstraint};
use super::relative_bridge::widen_bridges;
use super::residuals::State;
use nalgebra::{Matrix2, Matrix4, Vector2};

/// Bisection steps for the added variance (the interval shrinks by 2⁻⁶⁰).
const BISECTION_STEPS: usize = 60;

/// What the release did: the constraints' σ after it and how many were widened.
#[derive(Clone, Debug, PartialEq)]
pub struct Release {
    pub constraints: Vec<RelativeConstraint>,
    /// Constraints whose σ was widened.
    pub released: usize,
}

/// The evidence of the solution without relative constraints, per recording.
pub struct Evidence<'a> {
    /// That solution.
    pub state: &'a State,
    /// The recorded trajectory (the initial state of the block).
    pub recorded: &'a State,
    /// Whether each recording has aerial evidence of its own in that solution (it observes at least two tie
    /// points with a control point or aerial image observations).
    pub aerial: &'a [bool],
    /// A-priori covariance blocks over (x, y, z, ψ) per recording.
    pub covariance: &'a [Matrix4<f64>],
    /// The cross-covariance block of each constraint's (from, to) pair, where known.
    pub cross: &'a [Option<Matrix4<f64>>],
    /// Factor from a-priori to a-posteriori variance (σ̂0² when above 1, else 1).
    pub variance_scale: f64,
}

/// Distinct tie points with aerial evidence that a recording must observe to have aerial evidence of its own:
/// one such point cannot be checked against anything, and a wrong correspondence there (one panorama ray to
/// one aerial ray) moves the recording in the solution without relative constraints while its covariance
/// stays small, so a step next to it would be released on that alone (measured in docs/evaluation.md: a
/// recording at the start of a trajectory placed 0.66 m off with a stated σ of 0.08 m). With two, a wrong one
/// contradicts the other in that solution.
pub const MIN_ANCHORED_POINTS: usize = 2;

/// Per recording (`recordings` of them), whether it observes at least [`MIN_ANCHORED_POINTS`] distinct tie
/// points with aerial evidence; `observed` lists (recording, tie point) for each observation of such a point
/// (repeats count once).
pub fn with_aerial_evidence(
    recordings: usize,
    observed: impl IntoIterator<Item = (usize, usize)>,
) -> Vec<bool> {
    let mut pairs: Vec<(usize, usize)> = observed
        .into_iter()
        .filter(|&(r, _)| r < recordings)
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    let mut count = vec![0_usize; recordings];
    for (recording, _) in pairs {
        count[recording] += 1;
    }
    count.iter().map(|&n| n >= MIN_ANCHORED_POINTS).collect()
}

/// The relative constraints of `block` with the contradicted ones widened (module documentation);
/// `threshold` is the χ² (2 degrees of freedom) value above which a step is contradicted.
pub fn release(block: &Block, evidence: &Evidence, threshold: f64) -> Release {
    let mut released = 0;
    let mut constraints: Vec<RelativeConstraint> = block
        .relative_constraints
        .iter()
        .zip(evidence.cross)
        .map(|(rc, cross)| {
            if !(evidence.aerial[rc.from] && evidence.aerial[rc.to]) {
                return *rc;
            }
            let (delta, q) = step_change(rc, cross.as_ref(), evidence);
            match added_variance(delta, q, rc.sigma_m * rc.sigma_m, threshold) {
                Some(s2) => {
                    released += 1;
                    RelativeConstraint {
                        sigma_m: (rc.sigma_m * rc.sigma_m + s2).sqrt(),
                        ..*rc
                    }
                }
                None => *rc,
            }
        })
        .collect();
    released += widen_bridges(&mut constraints, evidence.aerial);
    Release {
        constraints,
        released,
    }
}

/// The solution's horizontal change of the constraint's step (`c_to − carry·c_from`, with `c` the correction of
/// a centre) and its covariance, m and m².
fn step_change(
    rc: &RelativeConstraint,
    cross: Option<&Matrix4<f64>>,
    evidence: &Evidence,
) -> (Vector2<f64>, Matrix2<f64>) {
    let correction =
        |c: usize| evidence.state.centers_local[c] - evidence.recorded.centers_local[c];
    let phi = rc.carry_xy;
    let horizontal = |m: &Matrix4<f64>| m.fixed_view::<2, 2>(0, 0).into_owned();
    let (d, mut q) = if phi == 1.0 {
        (
            correction(rc.to) - correction(rc.from),
            horizontal(&evidence.covariance[rc.to]) + horizontal(&evidence.covariance[rc.from]),
        )
    } else {
        (
            correction(rc.to) - correction(rc.from) * phi,
            horizontal(&evidence.covariance[rc.to])
                + horizontal(&evidence.covariance[rc.from]) * (phi * phi),
        )
    };
    if let Some(c) = cross {
        let c = horizontal(c) * phi;
        q -= c + c.transpose();
    }
    (Vector2::new(d.x, d.y), q * evidence.variance_scale)
}

/// The variance `s²` to add to a step of σ² = `sigma2` so that its statistic equals 2, when the statistic
/// without it exceeds `threshold`; `None` when the step is not contradicted (or its numbers are not finite).
pub fn added_variance(
    delta: Vector2<f64>,
    q: Matrix2<f64>,
    sigma2: f64,
    threshold: f64,
) -> Option<f64> {
    let q = (q + q.transpose()) * 0.5;
    let eig = q.symmetric_eigen();
    let along = eig.eigenvectors.transpose() * delta;
    let var = eig.eigenvalues.map(|v| v.max(0.0));
    let statistic = |s2: f64| {
        (0..2)
            .map(|i| along[i] * along[i] / (sigma2 + s2 + var[i]))
            .sum::<f64>()
    };
    let t0 = statistic(0.0);
    if !t0.is_finite() || t0 <= threshold {
        return None;
    }
    // statistic(|Δ|²) ≤ 1 < 2, and the statistic falls monotonically in s².
    let (mut low, mut high) = (0.0, delta.norm_squared());
    for _ in 0..BISECTION_STEPS {
        let mid = 0.5 * (low + high);
        if statistic(mid) > 2.0 {
            low = mid;
        } else {
            high = mid;
        }
    }
    Some(high)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_recording_needs_two_distinct_anchored_points_for_aerial_evidence() {
        // Recording 0: points 4 and 7; recording 1: point 4 twice; recording 2: nothing.
        let observed = [(0, 4), (1, 4), (0, 7), (1, 4)];
        assert_eq!(with_aerial_evidence(3, observed), vec![true, false, false]);
        // An observation of a recording outside the block is ignored.
        assert_eq!(with_aerial_evidence(1, [(5, 1), (5, 2)]), vec![false]);
    }

    #[test]
    fn a_step_within_its_uncertainty_is_kept() {
        let sigma2 = 0.03_f64.powi(2);
        // 5 cm change, 4 cm σ of the solution's step: T ≈ 1.0.
        let q = Matrix2::identity() * 0.04_f64.powi(2);
        assert_eq!(
            added_variance(Vector2::new(0.05, 0.0), q, sigma2, 9.21),
            None
        );
        // A 1 m change of a step the solution does not determine (prior of 2 m on both ends).
        let q = Matrix2::identity() * 8.0;
        assert_eq!(
            added_variance(Vector2::new(0.7, 0.7), q, sigma2, 9.21),
            None
        );
    }

    #[test]
    fn a_contradicted_step_gets_the_variance_that_makes_its_statistic_two() {
        let sigma2 = 0.03_f64.powi(2);
        let q = Matrix2::new(0.02_f64.powi(2), 0.0, 0.0, 0.05_f64.powi(2));
        let delta = Vector2::new(0.3, -0.2);
        let s2 = added_variance(delta, q, sigma2, 9.21).expect("contradicted");
        let t = delta.x * delta.x / (sigma2 + s2 + q[(0, 0)])
            + delta.y * delta.y / (sigma2 + s2 + q[(1, 1)]);
        assert!((t - 2.0).abs() < 1e-9, "{t}");
        assert!(s2 > 0.0);
    }
}
