//! Parameters of the patch registration (thesis 4.4.5–4.4.6; defaults of Appendix A of ALGORITHMS.md and
//! Table 4-1: hierarchical NCC 8 × 8 m → Mattes MI 6 × 6 m, real-resolution ratio ≥ 0.6).

use serde::{Deserialize, Serialize};

/// Similarity criterion of one registration level.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Similarity {
    /// Normalised cross-correlation over the overlapping valid pixels, exhaustive at integer shifts with a
    /// quadratic sub-pixel peak fit.
    Ncc,
    /// Mattes mutual information maximised by the (1+1)-ES.
    Mi,
}

/// Everything the patch registration can be told.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PatchParams {
    /// Two levels (coarse, then fine around the coarse shift) instead of one (default true, thesis 4.4.6).
    pub hierarchical: bool,
    /// Similarity of the coarse level (default NCC).
    pub coarse: Similarity,
    /// Similarity of the fine level, and of the single level when not hierarchical (default MI).
    pub fine: Similarity,
    /// Patch extent of the coarse level, metres (default 8 m).
    pub coarse_extent_m: f64,
    /// Patch extent of the fine level, metres (default 6 m).
    pub fine_extent_m: f64,
    /// Patch extent of the single level (non-hierarchical), metres (default 8 m).
    pub single_extent_m: f64,
    /// Largest shift searched by the coarse (or single) level, per axis, metres (default 2 m: expected
    /// MM position error plus façade relief). A best shift on the border of this window is no peak: the
    /// registration fails.
    pub search_radius_m: f64,
    /// The coarse level samples its patches at this multiple of the theoretical resolution (default 2: "larger
    /// patches with a lower resolution").
    pub coarse_spacing_factor: f64,
    /// Oblique patches with a lower real-resolution ratio are rejected (default 0.6, thesis 4.4.5).
    pub min_real_resolution_ratio: f64,
    /// 2-D median consensus after the coarse level: coarse shifts farther than this from the set's median
    /// shift are rejected, metres (default 0.5 m, the thesis' consensus threshold).
    pub coarse_consensus_threshold_m: f64,
    /// The fine level searches within ± this of the coarse shift, per axis, metres (default 0.5 m).
    pub fine_window_m: f64,
    /// Mattes MI histogram bins (default 50).
    pub mi_bins: usize,
    /// Mattes MI fixed samples per patch; `None` = every valid pixel (default, MATLAB's UseAllPixels).
    pub mi_samples: Option<usize>,
    /// Step of the exhaustive integer MI scan that seeds the ES when MI searches the full radius (coarse = MI,
    /// or single level with MI), patch px (default 2). 0 = no scan: the ES alone from zero shift, as in the
    /// thesis, where the MI of the initial transformation used the fine registration's parameters (4.5.3).
    pub mi_scan_step_px: usize,
    /// (1+1)-ES iteration limit (default 200).
    pub es_max_iterations: usize,
    /// (1+1)-ES initial radius, metres on the façade (default 0.1 m).
    pub es_initial_radius_m: f64,
    /// (1+1)-ES stop when the search matrix' Frobenius norm falls below this, metres (default 1e-3 m).
    pub es_epsilon_m: f64,
    /// A patch needs at least this fraction of its pixels with data, in the panorama and in the oblique
    /// image (default 0.5); otherwise it counts as `rejected_outside`.
    pub min_valid_fraction: f64,
    /// Largest patch side, px: a finer theoretical resolution is coarsened to keep patches at most this size
    /// (default 256).
    pub max_patch_px: usize,
    /// Coarsest resolution on the façade the patches are made at, metres: an oblique image finer than this
    /// (at the finest of the node's façade points) is read from the coarsest level of its pyramid whose
    /// resolution does not exceed it, and the theoretical resolution is that level's (default 0.12 m: the
    /// thesis' 5–15 cm obliques are used at full resolution; a 150-megapixel frame at 1.5 cm is read at 12 cm).
    pub registration_resolution_m: f64,
    /// Seed of the MI sampling and the ES; each registration derives its own from it, the point id and the
    /// oblique image id.
    pub seed: u64,
}

impl Default for PatchParams {
    fn default() -> Self {
        Self {
            hierarchical: true,
            coarse: Similarity::Ncc,
            fine: Similarity::Mi,
            coarse_extent_m: 8.0,
            fine_extent_m: 6.0,
            single_extent_m: 8.0,
            search_radius_m: 2.0,
            coarse_spacing_factor: 2.0,
            min_real_resolution_ratio: 0.6,
            coarse_consensus_threshold_m: 0.5,
            fine_window_m: 0.5,
            mi_bins: 50,
            mi_samples: None,
            mi_scan_step_px: 2,
            es_max_iterations: 200,
            es_initial_radius_m: 0.1,
            es_epsilon_m: 1e-3,
            min_valid_fraction: 0.5,
            max_patch_px: 256,
            registration_resolution_m: 0.12,
            seed: 0,
        }
    }
}

impl PatchParams {
    /// Check ranges; each error is (field, message with the allowed range).
    pub fn validate(&self) -> Result<(), Vec<(String, String)>> {
        let mut errs: Vec<(String, String)> = Vec::new();
        let mut check = |ok: bool, field: &str, msg: String| {
            if !ok {
                errs.push((field.to_string(), msg));
            }
        };
        for (field, v) in [
            ("coarse_extent_m", self.coarse_extent_m),
            ("fine_extent_m", self.fine_extent_m),
            ("single_extent_m", self.single_extent_m),
        ] {
            check(
                v.is_finite() && (0.5..=100.0).contains(&v),
                field,
                format!("must be in [0.5, 100] m, got {v}"),
            );
        }
        check(
            self.search_radius_m.is_finite() && (0.0..=20.0).contains(&self.search_radius_m),
            "search_radius_m",
            format!("must be in [0, 20] m, got {}", self.search_radius_m),
        );
        check(
            self.coarse_spacing_factor.is_finite()
                && (1.0..=16.0).contains(&self.coarse_spacing_factor),
            "coarse_spacing_factor",
            format!("must be in [1, 16], got {}", self.coarse_spacing_factor),
        );
        check(
            (0.0..=1.0).contains(&self.min_real_resolution_ratio),
            "min_real_resolution_ratio",
            format!("must be in [0, 1], got {}", self.min_real_resolution_ratio),
        );
        check(
            self.coarse_consensus_threshold_m.is_finite()
                && self.coarse_consensus_threshold_m > 0.0,
            "coarse_consensus_threshold_m",
            format!(
                "must be finite and > 0 m, got {}",
                self.coarse_consensus_threshold_m
            ),
        );
        check(
            self.fine_window_m.is_finite() && (0.0..=10.0).contains(&self.fine_window_m),
            "fine_window_m",
            format!("must be in [0, 10] m, got {}", self.fine_window_m),
        );
        check(
            (5..=1024).contains(&self.mi_bins),
            "mi_bins",
            format!("must be in [5, 1024], got {}", self.mi_bins),
        );
        check(
            self.mi_samples.is_none_or(|n| n >= 16),
            "mi_samples",
            format!(
                "must be ≥ 16 (or absent for all pixels), got {:?}",
                self.mi_samples
            ),
        );
        check(
            self.mi_scan_step_px <= 64,
            "mi_scan_step_px",
            format!(
                "must be in [0, 64] (0 = no scan), got {}",
                self.mi_scan_step_px
            ),
        );
        check(
            (1..=100_000).contains(&self.es_max_iterations),
            "es_max_iterations",
            format!("must be in [1, 100000], got {}", self.es_max_iterations),
        );
        check(
            self.es_epsilon_m.is_finite() && self.es_epsilon_m > 0.0,
            "es_epsilon_m",
            format!("must be finite and > 0 m, got {}", self.es_epsilon_m),
        );
        check(
            self.es_initial_radius_m.is_finite() && self.es_initial_radius_m > self.es_epsilon_m,
            "es_initial_radius_m",
            format!(
                "must be finite and > es_epsilon_m ({}), got {}",
                self.es_epsilon_m, self.es_initial_radius_m
            ),
        );
        check(
            self.min_valid_fraction > 0.0 && self.min_valid_fraction <= 1.0,
            "min_valid_fraction",
            format!("must be in (0, 1], got {}", self.min_valid_fraction),
        );
        check(
            self.registration_resolution_m.is_finite()
                && (0.001..=10.0).contains(&self.registration_resolution_m),
            "registration_resolution_m",
            format!(
                "must be in [0.001, 10] m, got {}",
                self.registration_resolution_m
            ),
        );
        check(
            (8..=4096).contains(&self.max_patch_px),
            "max_patch_px",
            format!("must be in [8, 4096], got {}", self.max_patch_px),
        );
        if errs.is_empty() {
            Ok(())
        } else {
            Err(errs)
        }
    }
}
