//! The orthophoto route of the nadir registration (thesis chapter 3 with an orthophoto in place of oriented
//! aerial frames): a georeferenced orthophoto (GeoTIFF) with its stated planimetric accuracy and an optional
//! DTM take the place of the nadir frames. Each panorama's ground ortho is made north-up at the orthophoto's
//! resolution, registered to the orthophoto window around it ([`register`]), its tie points are located by
//! the same phase-correlation refinement as in frames (`nadir::refine`, thesis 3.4.5.3), and each located tie
//! point becomes a control point whose XY comes from the orthophoto and Z from the DTM ([`control`]).

pub mod control;
pub mod corroborate;
pub mod dtm;
pub mod level;
pub mod precision;
pub mod register;
pub mod summary;

pub use crate::campaign::orthophoto::{DtmSource, OrthophotoSource, RasterFile};
pub use crate::imaging::georef::{GeoTransform, RasterHeader};
pub use control::{orthophoto_control, OrthophotoControl, OrthophotoInput};
pub use dtm::{Dtm, DtmTile};
pub use level::{ortho_params_for_orthophoto, orthophoto_level};
pub use register::{nominal_transform, register_translation};
pub use summary::OrthophotoSummary;

use crate::nadir::initial_transform::TransformParams;
use crate::nadir::refine::RefineParams;
use crate::params::StageId;

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("orthophoto", "9");

crate::params! {
    /// Parameters of the orthophoto route (registration, refinement and control points).
    pub struct OrthophotoParams {
        /// The initial transform of a recording's ground ortho into the orthophoto (thesis 3.4.5.2 in
        /// translation mode, [`register`]): the keys and defaults of `[transform]`. `max_localisation_error_m`
        /// bounds the offset searched; `estimate_shape`, `seed` and `max_offset_disagreement_m` do not apply
        /// (one north-up orthophoto at a known scale: the translation alone).
        transform: TransformParams = TransformParams::default(), section;
        /// Precision of a tie point located with a strong peak (≥ `refine.min_peak`) in the orthophoto at the
        /// working resolution, added to the stated accuracy of the orthophoto for the control point's
        /// planimetric σ; a weak peak's is larger ([`precision`]).
        match_sigma_px: f64 = 0.3, unit "px", min 0.0, max 10.0;
        /// σ of a control point's height taken from the mobile-mapping ground estimate (no DTM, or outside it).
        mm_height_sigma_m: f64 = 0.5, unit "m", min 0.001, max 100.0;
        /// The phase-correlation refinement of the tie points in the orthophoto (thesis 3.4.5.3).
        refine: RefineParams = RefineParams::default(), section;
        /// Smallest correlation peak of a tie point kept because its correction agrees with the recording's other
        /// located tie points ([`corroborate`]): a template partly hidden in the orthophoto (tree crowns) peaks
        /// below `refine.min_peak` at its correct place. Equal to `refine.min_peak` = no relaxation.
        corroborated_min_peak: f64 = 0.5, min 0.0, below 1.0;
        /// Radius around the agreed correction within which a weak peak is corroborated, working pixels.
        corroboration_px: f64 = 1.0, unit "px", min 0.0, max 10.0;
        /// Measure a located tie point's correction from its triangulated position rather than from its corner
        /// on the ortho's ground plane (module `corroborate`): the plane's parallax spreads correct corrections
        /// radially by 1–4 px where the road lies a few centimetres below it.
        corroborate_triangulated: bool = true;
        /// Fewest located tie points (weak or strong) that must agree on the correction for weak ones to be kept.
        min_corroborating: usize = 3, min 2, max 100;
        /// A weak peak's matching σ is `match_sigma_px` · ((1 − peak) / (1 − `refine.min_peak`)) to this power
        /// ([`precision`]); 0 = the strong peaks' σ. Graded on demo seed 2, 0 gave the best check points (1 and
        /// 2 gave less weight to recordings whose correct weak peaks were their only control).
        weak_sigma_exponent: f64 = 0.0, min 0.0, max 10.0;
        /// The weak peaks of one recording taken as one observation (each σ × √count), for orthophotos whose
        /// hidden templates are displaced alike ([`precision`]).
        weak_peaks_correlated: bool = false;
    }
}
