//! Robust losses for the bundle (beyond the thesis, the open question of 4.6 — let the bundle, not
//! only pre-filtering, remove outliers): Huber and Cauchy losses applied per observation to the squared norm
//! `s = ‖r‖²` of its whitened residual vector, minimised by iteratively re-weighted least squares inside LM
//! (residual and Jacobian scaled by √ρ'(s), the Triggs/ceres first-order correction).

use super::error::AdjustError;

/// The loss ρ(s) of one observation, s = squared norm of its whitened residual (units of σ²).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum RobustLoss {
    /// Plain least squares: ρ(s) = s.
    #[default]
    Squared,
    /// Huber: ρ(s) = s for √s ≤ k, else 2k√s − k² (k in σ units).
    Huber { threshold: f64 },
    /// Cauchy: ρ(s) = c²·ln(1 + s/c²) (c in σ units).
    Cauchy { scale: f64 },
}

impl RobustLoss {
    /// Checks the parameter.
    pub fn validate(&self) -> Result<(), AdjustError> {
        let (field, value) = match *self {
            RobustLoss::Squared => return Ok(()),
            RobustLoss::Huber { threshold } => ("loss.huber.threshold", threshold),
            RobustLoss::Cauchy { scale } => ("loss.cauchy.scale", scale),
        };
        if value.is_finite() && value > 0.0 {
            Ok(())
        } else {
            Err(AdjustError::InvalidOption {
                field,
                value,
                hint: "must be finite and > 0 (in sigma units, e.g. 2)",
            })
        }
    }

    /// ρ(s).
    pub fn rho(&self, s: f64) -> f64 {
        match *self {
            RobustLoss::Squared => s,
            RobustLoss::Huber { threshold: k } => {
                if s <= k * k {
                    s
                } else {
                    2.0 * k * s.sqrt() - k * k
                }
            }
            RobustLoss::Cauchy { scale: c } => c * c * (s / (c * c)).ln_1p(),
        }
    }

    /// ρ'(s) = dρ/ds, the IRLS weight (1 for small residuals).
    pub fn weight(&self, s: f64) -> f64 {
        match *self {
            RobustLoss::Squared => 1.0,
            RobustLoss::Huber { threshold: k } => {
                if s <= k * k {
                    1.0
                } else {
                    k / s.sqrt()
                }
            }
            RobustLoss::Cauchy { scale: c } => 1.0 / (1.0 + s / (c * c)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weight_is_the_derivative_of_rho() {
        for loss in [
            RobustLoss::Squared,
            RobustLoss::Huber { threshold: 2.0 },
            RobustLoss::Cauchy { scale: 2.0 },
        ] {
            for s in [0.01, 1.0, 3.9, 4.1, 25.0, 400.0] {
                let h = 1e-6 * s;
                let numeric = (loss.rho(s + h) - loss.rho(s - h)) / (2.0 * h);
                assert!((numeric - loss.weight(s)).abs() < 1e-6, "{loss:?} at {s}");
            }
        }
        assert_eq!(RobustLoss::Huber { threshold: 2.0 }.rho(3.0), 3.0);
        assert_eq!(RobustLoss::Huber { threshold: 2.0 }.rho(16.0), 12.0);
    }
}
