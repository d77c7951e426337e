//! Parameters of the patch registration (thesis 4.4.5–4.4.6; defaults as in thesis Table 4-1: hierarchical NCC
//! 8 × 8 m → Mattes MI 6 × 6 m, real-resolution ratio ≥ 0.6).

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

crate::params! {
    /// Everything the patch registration can be told.
    pub struct PatchParams {
        /// Two levels (coarse, then fine around the coarse shift) instead of one (thesis 4.4.6).
        hierarchical: bool = true;
        /// Similarity of the coarse level.
        coarse: Similarity = Similarity::Ncc;
        /// Similarity of the fine level, and of the single level when not hierarchical.
        fine: Similarity = Similarity::Mi;
        /// Patch extent of the coarse level.
        coarse_extent_m: f64 = 8.0, unit "m", min 0.5, max 100.0;
        /// Patch extent of the fine level.
        fine_extent_m: f64 = 6.0, unit "m", min 0.5, max 100.0;
        /// Patch extent of the single level (non-hierarchical).
        single_extent_m: f64 = 8.0, unit "m", min 0.5, max 100.0;
        /// Largest shift searched by the coarse (or single) level, per axis. A best shift on the border of this
        /// window is no peak: the registration fails.
        search_radius_m: f64 = 2.0, unit "m", min 0.0, max 20.0;
        /// The coarse level samples its patches at this multiple of the theoretical resolution.
        coarse_spacing_factor: f64 = 2.0, min 1.0, max 16.0;
        /// Oblique patches with a lower real-resolution ratio are rejected (thesis 4.4.5).
        min_real_resolution_ratio: f64 = 0.6, min 0.0, max 1.0;
        /// 2-D median consensus after the coarse level: coarse shifts farther than this from the set's median
        /// shift are rejected.
        coarse_consensus_threshold_m: f64 = 0.5, unit "m", above 0.0;
        /// The fine level searches within ± this of the coarse shift, per axis.
        fine_window_m: f64 = 0.5, unit "m", min 0.0, max 10.0;
        /// Mattes MI histogram bins.
        mi_bins: usize = 50, min 5, max 1024;
        /// Mattes MI fixed samples per patch; absent = every valid pixel.
        mi_samples: Option<usize> = None, min 16;
        /// Step of the exhaustive integer MI scan that seeds the ES when MI searches the full radius (coarse =
        /// MI, or a single MI level), in patch pixels; 0 = no scan, the ES alone from zero shift.
        mi_scan_step_px: usize = 2, unit "px", max 64;
        /// (1+1)-ES iteration limit.
        es_max_iterations: usize = 200, min 1, max 100_000;
        /// (1+1)-ES initial radius on the façade; larger than `es_epsilon_m`.
        es_initial_radius_m: f64 = 0.1, unit "m";
        /// (1+1)-ES stops when the search matrix' Frobenius norm falls below this.
        es_epsilon_m: f64 = 1e-3, unit "m", above 0.0;
        /// A patch needs at least this fraction of its pixels with data, in the panorama and in the oblique
        /// image; otherwise it counts as `rejected_outside`.
        min_valid_fraction: f64 = 0.5, above 0.0, max 1.0;
        /// Largest patch side: a finer theoretical resolution is coarsened to keep patches at most this size.
        max_patch_px: usize = 256, unit "px", min 8, max 4096;
        /// Coarsest resolution on the façade the patches are made at: an oblique image more than twice as fine
        /// as this (at the finest of the node's façade points) is read from the coarsest level of its pyramid
        /// whose resolution does not exceed it, and the theoretical resolution is that level's (0.10 m: obliques
        /// coarser than 5 cm on the façade, as in the thesis, are used at full resolution; a 150-megapixel frame
        /// at 1.5 cm is read at 6 cm).
        registration_resolution_m: f64 = 0.10, unit "m", min 0.001, max 10.0;
        /// Seed of the MI sampling and the ES; each registration derives its own from it, the point id and the
        /// oblique image id.
        seed: u64 = 0;
    }
    check(p, v) {
        let bound = ("es_epsilon_m", p.es_epsilon_m);
        crate::params::check_above_field("es_initial_radius_m", p.es_initial_radius_m, bound, "m", v);
    }
}
