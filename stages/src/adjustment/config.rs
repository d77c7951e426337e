//! The parameters of one adjustment configuration as the adjust node receives them (issue 6 "Configurations";
//! thesis 5.4.3, 5.5.1–5.5.3, 5.7): which correspondence sources (a label: the node passes the chosen sets),
//! horizontal-only or full 3-D, residual weighting method 1–4, control weighting (σ = 0.10 m, 5.4.3, or the
//! aerial triangulation covariance), aerial pixel observations directly in the bundle (issue 6 (a)), robust
//! loss and rejection (issue 6 (b)), prior σ overrides, relative constraints and yaw estimation.
//!
//! Serde with `deny_unknown_fields` and defaults for every field, so a workflow TOML names only what differs;
//! [`AdjustConfig::validate`] names every bad field at once.

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

/// Loss on the observations (panorama, aerial, control); priors and relative constraints stay quadratic.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum LossKind {
    #[default]
    None,
    Huber,
    Cauchy,
}

/// One adjustment configuration (the adjust node's params).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AdjustConfig {
    /// Label of the correspondence sources (`nadir`, `oblique`, `combined`).
    pub sources: Sources,
    /// `horizontal` or `full` (thesis 5.7).
    pub dimensions: Dimensions,
    /// Residual weighting method of thesis 5.7: 1 unweighted, 2 near-weighted, 3 far-weighted, 4 GSD-weighted.
    pub weighting_method: u8,
    /// Maximum correspondence distance l of methods 2 and 3, metres (thesis: 15 m).
    pub weighting_max_distance_m: f64,
    /// Angular resolution α of method 4, degrees; absent = 360° / panorama width.
    pub weighting_alpha_deg: Option<f64>,
    /// σ of a panorama observation, pixels.
    pub pano_sigma_px: f64,
    /// `fixed` (σ = `control_sigma_m`, thesis 5.4.3) or `covariance` (aerial triangulation covariance).
    pub control_weighting: ControlWeighting,
    /// σ of an aerial control point per axis with `control_weighting = "fixed"`, metres (thesis: 0.10 m).
    pub control_sigma_m: f64,
    /// Issue 6 (a): put the aerial pixel observations into the bundle (aerial orientation fixed) instead of
    /// aerial-triangulated control points, so points seen in a single aerial image count too.
    pub aerial_observations: bool,
    /// `none`, `huber` or `cauchy`.
    pub loss: LossKind,
    /// Huber threshold / Cauchy scale, in σ units.
    pub loss_scale: f64,
    /// Reject observations whose |normalised residual| exceeds this many σ and re-solve (absent = never).
    pub rejection_threshold: Option<f64>,
    /// Largest number of rejection rounds.
    pub max_rejection_rounds: usize,
    /// Prior σ of recorded X and Y for every recording, metres (overrides `sigma_xy` of recordings.csv).
    pub prior_sigma_xy_m: Option<f64>,
    /// Prior σ of recorded Z for every recording, metres (overrides `sigma_z` of recordings.csv).
    pub prior_sigma_z_m: Option<f64>,
    /// Prior σ of X and Y for recordings without a `sigma_xy` value and no override, metres.
    pub default_prior_sigma_xy_m: f64,
    /// Prior σ of Z for recordings without a `sigma_z` value and no override, metres.
    pub default_prior_sigma_z_m: f64,
    /// Keep the recorded differences between consecutive recordings (thesis 3.4.2) with σ `relative_sigma_m`.
    pub relative_constraints: bool,
    /// σ of a relative constraint per axis, metres.
    pub relative_sigma_m: f64,
    /// Consecutive recordings farther apart than this are not linked (a gap in the trajectory), metres.
    pub relative_max_gap_m: f64,
    /// Estimate a yaw correction per recording.
    pub estimate_yaw: bool,
    /// σ of the zero prior on each yaw correction, degrees.
    pub yaw_prior_sigma_deg: f64,
    /// Largest number of LM iterations per solve.
    pub max_iterations: usize,
}

impl Default for AdjustConfig {
    fn default() -> Self {
        Self {
            sources: Sources::Combined,
            dimensions: Dimensions::Full,
            weighting_method: 1,
            weighting_max_distance_m: 15.0,
            weighting_alpha_deg: None,
            pano_sigma_px: 1.0,
            control_weighting: ControlWeighting::Fixed,
            control_sigma_m: DEFAULT_CONTROL_SIGMA_M,
            aerial_observations: false,
            loss: LossKind::None,
            loss_scale: 2.0,
            rejection_threshold: None,
            max_rejection_rounds: 10,
            prior_sigma_xy_m: None,
            prior_sigma_z_m: None,
            default_prior_sigma_xy_m: DEFAULT_PRIOR_SIGMA_XY_M,
            default_prior_sigma_z_m: DEFAULT_PRIOR_SIGMA_Z_M,
            relative_constraints: false,
            relative_sigma_m: 0.02,
            relative_max_gap_m: 15.0,
            estimate_yaw: false,
            yaw_prior_sigma_deg: 1.0,
            max_iterations: 100,
        }
    }
}

fn positive_finite(x: f64) -> bool {
    x.is_finite() && x > 0.0
}

impl AdjustConfig {
    /// Every invalid field as (field name, what is wrong and what to use); empty = valid.
    pub fn validate(&self) -> Result<(), Vec<(String, String)>> {
        let mut problems = Vec::new();
        let mut positive = |field: &str, value: f64, hint: &str| {
            if !positive_finite(value) {
                problems.push((
                    field.to_string(),
                    format!("{value} must be finite and > 0 ({hint})"),
                ));
            }
        };
        positive(
            "weighting_max_distance_m",
            self.weighting_max_distance_m,
            "thesis: 15",
        );
        if let Some(a) = self.weighting_alpha_deg {
            positive("weighting_alpha_deg", a, "thesis: 0.075, or leave it out");
        }
        positive("pano_sigma_px", self.pano_sigma_px, "e.g. 1");
        positive("control_sigma_m", self.control_sigma_m, "thesis: 0.10");
        positive("loss_scale", self.loss_scale, "in sigma units, e.g. 2");
        if let Some(k) = self.rejection_threshold {
            positive("rejection_threshold", k, "in sigma units, e.g. 3");
        }
        if let Some(s) = self.prior_sigma_xy_m {
            positive("prior_sigma_xy_m", s, "metres, or leave it out");
        }
        if let Some(s) = self.prior_sigma_z_m {
            positive("prior_sigma_z_m", s, "metres, or leave it out");
        }
        positive(
            "default_prior_sigma_xy_m",
            self.default_prior_sigma_xy_m,
            "metres",
        );
        positive(
            "default_prior_sigma_z_m",
            self.default_prior_sigma_z_m,
            "metres",
        );
        positive(
            "relative_sigma_m",
            self.relative_sigma_m,
            "metres, e.g. 0.02",
        );
        positive(
            "relative_max_gap_m",
            self.relative_max_gap_m,
            "metres, e.g. 15",
        );
        positive(
            "yaw_prior_sigma_deg",
            self.yaw_prior_sigma_deg,
            "degrees, e.g. 1",
        );
        if !(1..=4).contains(&self.weighting_method) {
            problems.push((
                "weighting_method".to_string(),
                format!(
                    "{} is not a thesis 5.7 method; use 1 (unweighted), 2 (near), 3 (far) or 4 (GSD)",
                    self.weighting_method
                ),
            ));
        }
        if self.max_iterations == 0 {
            problems.push((
                "max_iterations".to_string(),
                "0 would not iterate; use e.g. 100".to_string(),
            ));
        }
        if problems.is_empty() {
            Ok(())
        } else {
            Err(problems)
        }
    }

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
            weighting: self.weighting(),
            loss: match self.loss {
                LossKind::None => RobustLoss::Squared,
                LossKind::Huber => RobustLoss::Huber {
                    threshold: self.loss_scale,
                },
                LossKind::Cauchy => RobustLoss::Cauchy {
                    scale: self.loss_scale,
                },
            },
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
            .map(|p| p.0)
            .collect();
        assert_eq!(
            fields,
            ["control_sigma_m", "rejection_threshold", "weighting_method"]
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
