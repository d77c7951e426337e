//! The recorded trajectory's error as a first-order Gauss–Markov process (`[adjust] trajectory_error =
//! "gauss_markov"`): how much of one recording's correction the next one is expected to share.
//!
//! The default model treats a recording's error in two independent ways at once: every recording has its
//! own position prior (σ_abs, the `sigma_xy` / `sigma_z` of recordings.csv), and consecutive recordings differ
//! by a random-walk step of σ_rel (thesis 3.4.2). Real GNSS/INS errors are correlated over many recordings —
//! a common offset, slow multipath, drift — so N independent priors claim N times the absolute information
//! the trajectory has. Where a stretch of recordings has no aerial evidence of its own, those priors pull it
//! back to the recorded positions and the correction found next to it fades within a few recordings
//! (the characteristic length is σ_abs / σ_rel recordings).
//!
//! A first-order Gauss–Markov error with marginal σ_abs and steps of σ_rel has the correlation
//! `φ = √(1 − σ_rel² / σ_abs²)` between consecutive recordings. Its density factors into the prior of the
//! first recording and one term per step, `c_to − φ·c_from ~ N(0, σ_rel²)` (`c` the correction of a
//! centre): a relative constraint with carry φ that stands for `to`'s own prior. Every recording keeps the
//! marginal σ_abs the trajectory states, the priors count once per chain instead of once per recording, and
//! a correction carries along the chain over σ_abs² / σ_rel² recordings instead of σ_abs / σ_rel.
//! With σ_abs = 1 m and σ_rel = 0.14 m that is 51 recordings (255 m at 5 m spacing) instead of 7.

/// The carry φ between two consecutive recordings whose position priors have σ `sigma_from_m` and `sigma_to_m`
/// on one axis, for relative σ `relative_sigma_m`: `√(1 − σ_rel² / (σ_from·σ_to))`, 0 when the step is as
/// uncertain as the positions themselves (independent errors).
pub fn carry(relative_sigma_m: f64, sigma_from_m: f64, sigma_to_m: f64) -> f64 {
    let ratio = relative_sigma_m * relative_sigma_m / (sigma_from_m * sigma_to_m);
    if ratio.is_finite() {
        (1.0 - ratio).max(0.0).sqrt()
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_carry_keeps_the_marginal_sigma_of_a_stationary_process() {
        // Var(c_to) = φ²·σ_abs² + σ_rel² = σ_abs².
        let (rel, abs) = (0.14, 1.0);
        let phi = carry(rel, abs, abs);
        assert!((phi * phi * abs * abs + rel * rel - abs * abs).abs() < 1e-12);
        assert!((phi - 0.990_15).abs() < 1e-5, "{phi}");
    }

    #[test]
    fn steps_as_large_as_the_positions_mean_independent_errors() {
        assert_eq!(carry(1.0, 1.0, 1.0), 0.0);
        assert_eq!(carry(3.0, 1.0, 2.0), 0.0);
        assert_eq!(carry(0.1, 0.0, 1.0), 0.0);
        assert!(carry(0.01, 2.0, 2.0) > 0.9999);
    }
}
