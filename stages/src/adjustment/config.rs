//! The parameters of one adjustment configuration as the adjust node receives them (thesis 5.4.3, 5.5.1–5.5.3,
//! 5.7): which correspondence sources (a label: the node passes the chosen sets), horizontal-only or full 3-D,
//! residual weighting method 1–4, control weighting (σ = 0.10 m, 5.4.3, or the aerial triangulation
//! covariance), aerial pixel observations directly in the bundle, robust loss and rejection, prior σ
//! overrides, relative constraints and yaw estimation.
//!
//! Declared with [`crate::params!`]: a workflow TOML names only what differs from the defaults, unknown keys
//! are rejected and [`Params::validate`](crate::params::Params::validate) names every bad field at once.

use super::problem::{AdjustOptions, LmOptions, DEFAULT_CONTROL_SIGMA_M};
use super::robust::RobustLoss;
use super::weighting::{ResidualWeighting, WeightingMethod};
use serde::{Deserialize, Serialize};

/// Prior σ of recorded X and Y when neither the config nor `recordings.csv` gives one, metres.
pub const DEFAULT_PRIOR_SIGMA_XY_M: f64 = 2.0;
/// Prior σ of recorded Z when neither the config nor `recordings.csv` gives one, metres.
pub const DEFAULT_PRIOR_SIGMA_Z_M: f64 = 2.0;

/// Where the correspondences of a configuration come from (thesis 5.5.1–5.5.3); a label for metrics, the
/// node decides which correspondence sets to pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Sources {
    Nadir,
    Oblique,
    #[default]
    Combined,
}

impl Sources {
    /// The metrics label (`nadir`, `oblique`, `combined`).
    pub fn label(&self) -> &'static str {
        match self {
            Sources::Nadir => "nadir",
            Sources::Oblique => "oblique",
            Sources::Combined => "combined",
        }
    }
}

/// Which recording coordinates are adjusted (thesis 5.7: horizontal adjustment vs full adjustment).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Dimensions {
    /// X and Y only; Z keeps its recorded value.
    Horizontal,
    /// X, Y and Z.
    #[default]
    Full,
}

/// How aerial control points are weighted (thesis 5.4.3: all with σ = 0.10 m).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum ControlWeighting {
    /// Isotropic σ = `control_sigma_m` (thesis 5.4.3).
    #[default]
    Fixed,
    /// The a-priori covariance of the aerial triangulation (from the aerial images' `sigma_px`).
    Covariance,
}

/// How the recorded trajectory's error is modelled between consecutive recordings ([`super::gauss_markov`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum TrajectoryError {
    /// Every recording has its own position prior, and consecutive recordings differ by a random-walk step
    /// of `relative_sigma_m` (thesis 3.4.2).
    #[default]
    RandomWalk,
    /// A first-order Gauss–Markov error: each step carries the share of the previous recording's correction
    /// that the prior σ and `relative_sigma_m` imply, and stands for the next recording's prior; only the
    /// first recording of each chain has a prior of its own.
    GaussMarkov,
}

/// Loss on the observations (panorama, aerial, control); priors and relative constraints stay quadratic.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum LossKind {
    #[default]
    None,
    Huber,
    Cauchy,
}

crate::params! {
    /// One adjustment configuration (the adjust node's params).
    pub struct AdjustConfig {
        /// Label of the correspondence sources (`nadir`, `oblique`, `combined`).
        sources: Sources = Sources::Combined;
        /// `horizontal` or `full` (thesis 5.7).
        dimensions: Dimensions = Dimensions::Full;
        /// Residual weighting method of thesis 5.7: 1 unweighted, 2 near-weighted, 3 far-weighted,
        /// 4 GSD-weighted.
        weighting_method: u8 = 1, min 1, max 4;
        /// Maximum correspondence distance l of methods 2 and 3 (thesis: 15 m).
        weighting_max_distance_m: f64 = 15.0, unit "m", above 0.0;
        /// Angular resolution α of method 4 (thesis: 0.075°); absent = 360° / panorama width.
        weighting_alpha_deg: Option<f64> = None, unit "deg", above 0.0;
        /// σ of a panorama observation.
        pano_sigma_px: f64 = 1.0, unit "px", above 0.0;
        /// `fixed` (σ = `control_sigma_m`, thesis 5.4.3) or `covariance` (aerial triangulation covariance).
        control_weighting: ControlWeighting = ControlWeighting::Fixed;
        /// σ of an aerial control point per axis with `control_weighting = "fixed"` (thesis: 0.10 m).
        control_sigma_m: f64 = DEFAULT_CONTROL_SIGMA_M, unit "m", above 0.0;
        /// Put the aerial pixel observations into the bundle (aerial orientation fixed; σ of the pyramid
        /// level each was located at) instead of aerial-triangulated control points, so points seen in a
        /// single aerial image count too; in a projected campaign the bundle then runs in the campaign's
        /// tangent frame. `false` is the thesis' scheme; `default.toml` sets `true`.
        aerial_observations: bool = false;
        /// Robust loss on the observations: `none`, `huber` or `cauchy`.
        loss: LossKind = LossKind::None;
        /// Huber threshold / Cauchy scale, in σ units.
        loss_scale: f64 = 2.0, above 0.0;
        /// Reject observations whose |normalised residual| exceeds this many σ and re-solve; absent = never.
        rejection_threshold: Option<f64> = None, above 0.0;
        /// Largest number of rejection rounds.
        max_rejection_rounds: usize = 10;
        /// Prior σ of recorded X and Y for every recording (overrides `sigma_xy` of recordings.csv).
        prior_sigma_xy_m: Option<f64> = None, unit "m", above 0.0;
        /// Prior σ of recorded Z for every recording (overrides `sigma_z` of recordings.csv).
        prior_sigma_z_m: Option<f64> = None, unit "m", above 0.0;
        /// Prior σ of X and Y for recordings without a `sigma_xy` value and no override.
        default_prior_sigma_xy_m: f64 = DEFAULT_PRIOR_SIGMA_XY_M, unit "m", above 0.0;
        /// Prior σ of Z for recordings without a `sigma_z` value and no override.
        default_prior_sigma_z_m: f64 = DEFAULT_PRIOR_SIGMA_Z_M, unit "m", above 0.0;
        /// Keep the recorded differences between consecutive recordings (thesis 3.4.2) with σ
        /// `relative_sigma_m`.
        relative_constraints: bool = false;
        /// σ of a relative constraint per axis (the recorded trajectory's relative accuracy between
        /// consecutive recordings); absent = estimated from the recorded trajectory itself (cross-track second
        /// differences, `adjustment::relative_noise`).
        relative_sigma_m: Option<f64> = None, unit "m", above 0.0;
        /// The trajectory error model of the relative constraints: `random_walk` (independent priors and
        /// random-walk steps) or `gauss_markov` (correlated errors: a correction carries along the chain and
        /// the priors count once per chain, `adjustment::gauss_markov`).
        trajectory_error: TrajectoryError = TrajectoryError::RandomWalk;
        /// Robust loss on the relative constraints: `none`, `huber` or `cauchy`. A step between consecutive
        /// recordings that differs from the recorded one by more than `relative_loss_scale` σ (a jump when
        /// GNSS is re-acquired, drift during an outage, an error turning with the vehicle) is released so that
        /// the aerial evidence can correct it: linearly (`huber`) or almost entirely (`cauchy`, whose weight
        /// falls as 1 / (1 + (r/scale)²)); `none` is plain least squares.
        relative_loss: LossKind = LossKind::Huber;
        /// Huber threshold / Cauchy scale of `relative_loss`, in σ units.
        relative_loss_scale: f64 = 3.0, above 0.0;
        /// Consecutive recordings farther apart than this are not linked (a gap in the trajectory).
        relative_max_gap_m: f64 = 15.0, unit "m", above 0.0;
        /// Release the relative constraints that the evidence contradicts beyond its uncertainty: the block is
        /// solved without them first, and a constraint whose step that solution changes by a χ² statistic
        /// (2 degrees of freedom, against σ² plus the solution's own variance of the step) above this value
        /// gets the σ at which the statistic equals its expectation (`adjustment::relative_release`). A
        /// smooth drift (a GNSS outage) does not show in the second differences the σ is estimated from.
        /// Only steps between recordings with aerial evidence of their own (at least two tie points with
        /// aerial evidence each) are tested. The steps of a stretch of recordings without it take the
        /// largest σ of the tested steps at its ends, and are then held by least squares
        /// (`adjustment::relative_bridge`). Absent = every constraint keeps its σ; `default.toml` sets 9.21
        /// (the 99 % quantile).
        relative_release_threshold: Option<f64> = None, above 0.0;
        /// Observe each recording's height as the campaign DTM's height under its recorded position plus
        /// its `camera_height`, with σ = √(the DTM's stated σ² + `camera_height_sigma_m`²), beside the
        /// recorded height's prior: it holds a recording's position along the rays of its control points.
        /// Without a `[dtm]` in the campaign no height is observed (`adjust.<sources>.height_observations`
        /// says so).
        dtm_height: bool = false;
        /// σ of a recording's camera height above the DTM's ground (mounting, tyres, the road surface
        /// against the DTM's), for `dtm_height`.
        camera_height_sigma_m: f64 = 0.02, unit "m", above 0.0;
        /// Observe the height of the nadir matching's tie points (points of the road surface) seen from a
        /// recording without control of its own as the campaign DTM's height under them, σ from the DTM's
        /// stated σ and the terrain's change within the recorded poses' σ (`adjustment::tie_point_heights`):
        /// two panoramas seeing the same ground points fix the direction of their baseline, not its length,
        /// so such a recording is otherwise held along the trajectory by the relative constraints alone.
        /// Without a `[dtm]` in the campaign no height is observed.
        dtm_tie_heights: bool = false;
        /// Check weak orthophoto control against the strong control along the trajectory
        /// (`adjustment::weak_control`): a control point whose orthophoto correlation peak is below
        /// `weak_control_below` and whose correction (control XY − its XY from the recorded poses) differs by
        /// more than this from the correction interpolated between the nearest recordings with strong control
        /// is not used as control (counted in `build.weak_control_dropped`); absent = no check.
        weak_control_tolerance_m: Option<f64> = None, unit "m", above 0.0;
        /// Orthophoto control points whose phase-correlation peak is below this are weak, for
        /// `weak_control_tolerance_m` (the orthophoto refinement's `min_peak`).
        weak_control_below: f64 = 0.75, min 0.0, max 1.0;
        /// Check every control point, strong or weak, against the control of the other recordings within
        /// this many recordings before and after it (`adjustment::control_consistency`): a point whose
        /// correction differs from their median correction by more than the 99.9 % bound of its own scatter
        /// about a common correction (2.63 × the relative σ for a point of one recording, wider along the rays
        /// of a point whose triangulation the recordings' errors move farther) is not used as control
        /// (counted in `build.inconsistent_control_dropped`; with `aerial_observations` its aerial pixels
        /// leave the bundle, `adjustment::control_screen`); absent = no check.
        control_consistency_window: Option<usize> = None, min 1;
        /// Measure the σ of weak orthophoto control (peak below `weak_control_below`) against the strong
        /// control of the same recordings and weight the weak points with it
        /// (`adjustment::weak_control_sigma`): each weak point's horizontal σ becomes at least the RMS
        /// difference per axis between weak points' corrections and the strong control's of their recordings,
        /// and the weak points first seen from one recording count as one observation (σ × √their number),
        /// because a recording's weak peaks are displaced alike. Reported in `build.weak_control_sigma`.
        weak_control_sigma_estimated: bool = false;
        /// Tie each recording before the first or after the last recording with control directly to that
        /// recording (`adjustment::extrapolation_anchor`): the recorded difference between the two is kept
        /// with σ = the relative σ × k^`extrapolation_anchor_growth` for a recording k recordings away, so
        /// the stretch keeps the nearest correction instead of drifting with the tie-point chain (counted in
        /// `build.extrapolation_anchors`).
        extrapolation_anchor: bool = false;
        /// How the σ of `extrapolation_anchor` grows with the number of recordings k from the anchor: σ_rel ×
        /// k^this (0.5: like k consecutive relative constraints; 0: the same σ at every distance).
        extrapolation_anchor_growth: f64 = 0.5, min 0.0, max 2.0;
        /// Leave out the aerial evidence that alone anchors the end of a chain of recordings when it has fewer
        /// aerial observations than this (ground control counts as 2; `adjustment::chain_end_evidence`): at a
        /// chain end nothing checks it, and the recordings up to the next evidence would follow it whatever it
        /// says. They follow the chain's other evidence instead (counted in `build.chain_end_evidence_dropped`;
        /// with `relative_constraints`). 1 = no check.
        chain_end_min_aerial_observations: usize = 1, min 1, max 10;
        /// Estimate a yaw correction per recording.
        estimate_yaw: bool = false;
        /// σ of the zero prior on each yaw correction.
        yaw_prior_sigma_deg: f64 = 1.0, unit "deg", above 0.0;
        /// σ of the change of the yaw correction between two recordings linked by a relative constraint
        /// (with `estimate_yaw` and `relative_constraints`; least squares): an inertial unit's heading error
        /// is a bias that wanders slowly, so neighbouring recordings share their yaw evidence instead of
        /// each estimating its own from its few rays; absent = each recording's yaw is independent.
        yaw_relative_sigma_deg: Option<f64> = None, unit "deg", above 0.0;
        /// With `yaw_relative_sigma_deg`: a chain of recordings keeps its yaw tie only when its common yaw
        /// correction is at least this many times its σ (`adjustment::yaw_support`); otherwise each of its
        /// recordings keeps its own yaw prior, as without the tie. 0 = always tied.
        yaw_tie_significance: f64 = 2.0, min 0.0, max 10.0;
        /// Apply corrections only where they are significant at this level (`correction::significance`): the
        /// recorded trajectory is the null hypothesis; each component (horizontal position, height, yaw) of a
        /// recording is tested against the threshold the level gives for the recordings within
        /// `significance_window_m` (Bonferroni), and a component is applied only within half a window of a
        /// significant correction that a neighbouring recording's corroborates. Elsewhere the recording keeps
        /// its recorded value, with σ widened by the correction not applied (`held` in
        /// `trajectory_adjusted.csv`, `adjust.<sources>.significance` in `metrics.json`). Absent = every
        /// correction applied.
        significance_level: Option<f64> = None, above 0.0, max 0.5;
        /// Length along the recorded track of the window `significance_level` tests in and applies over.
        significance_window_m: f64 = 100.0, unit "m", above 0.0;
        /// Largest number of Levenberg–Marquardt iterations per solve.
        max_iterations: usize = 100, min 1;
        /// Registration passes: with 2, the nadir chain searches the recordings that found no aerial control
        /// again around the first adjustment's positions of them, the oblique chain registers every recording
        /// again from its adjusted position (`adjustment::second_pass`), both with the normal search windows,
        /// and the adjustment runs again on all control; recovers errors larger than the windows once the
        /// neighbours are corrected (`registration_passes`, `oblique_pass2` in `metrics.json`).
        passes: usize = 1, min 1, max 2;
    }
}

/// The robust loss of `kind` with its Huber threshold / Cauchy scale `scale` (σ units).
fn robust_loss(kind: LossKind, scale: f64) -> RobustLoss {
    match kind {
        LossKind::None => RobustLoss::Squared,
        LossKind::Huber => RobustLoss::Huber { threshold: scale },
        LossKind::Cauchy => RobustLoss::Cauchy { scale },
    }
}

impl AdjustConfig {
    /// The residual weighting method.
    pub fn weighting(&self) -> ResidualWeighting {
        ResidualWeighting {
            method: match self.weighting_method {
                2 => WeightingMethod::NearWeighted,
                3 => WeightingMethod::FarWeighted,
                4 => WeightingMethod::GsdWeighted,
                _ => WeightingMethod::Unweighted,
            },
            max_distance_m: self.weighting_max_distance_m,
            angular_resolution_deg: self.weighting_alpha_deg,
        }
    }

    /// The solver options of this configuration.
    pub fn options(&self) -> AdjustOptions {
        AdjustOptions {
            horizontal_only: self.dimensions == Dimensions::Horizontal,
            estimate_yaw: self.estimate_yaw,
            yaw_prior_sigma_deg: self.estimate_yaw.then_some(self.yaw_prior_sigma_deg),
            yaw_relative_sigma_deg: self.yaw_relative_sigma_deg.filter(|_| self.estimate_yaw),
            yaw_tie_significance: self.yaw_tie_significance,
            weighting: self.weighting(),
            loss: robust_loss(self.loss, self.loss_scale),
            relative_loss: robust_loss(self.relative_loss, self.relative_loss_scale),
            relative_release_threshold: self.relative_release_threshold,
            rejection_threshold: self.rejection_threshold,
            max_rejection_rounds: self.max_rejection_rounds,
            lm: LmOptions {
                max_iterations: self.max_iterations,
                ..LmOptions::default()
            },
        }
    }

    /// A short label of the configuration for metrics keys, e.g. `combined.full.w1`.
    pub fn label(&self) -> String {
        let dims = match self.dimensions {
            Dimensions::Horizontal => "horizontal",
            Dimensions::Full => "full",
        };
        format!("{}.{dims}.w{}", self.sources.label(), self.weighting_method)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;

    #[test]
    fn toml_with_defaults_and_errors_naming_fields() {
        let c: AdjustConfig =
            toml::from_str("dimensions = \"horizontal\"\nweighting_method = 4\n").unwrap();
        assert_eq!(c.dimensions, Dimensions::Horizontal);
        assert_eq!(c.weighting().method, WeightingMethod::GsdWeighted);
        assert_eq!(c.control_sigma_m, 0.10);
        assert!(c.options().horizontal_only);
        assert!(toml::from_str::<AdjustConfig>("weighting = 2\n").is_err());
        let bad = AdjustConfig {
            weighting_method: 5,
            control_sigma_m: -1.0,
            rejection_threshold: Some(f64::NAN),
            ..AdjustConfig::default()
        };
        let fields: Vec<String> = bad
            .validate()
            .unwrap_err()
            .into_iter()
            .map(|p| p.field)
            .collect();
        assert_eq!(
            fields,
            ["weighting_method", "control_sigma_m", "rejection_threshold"]
        );
        assert!(AdjustConfig::default().validate().is_ok());
        let robust = AdjustConfig {
            loss: LossKind::Cauchy,
            loss_scale: 3.0,
            ..AdjustConfig::default()
        };
        assert_eq!(robust.options().loss, RobustLoss::Cauchy { scale: 3.0 });
    }
}
