//! `[nadir]`: options of the nadir pipeline that shape the DAG rather than one node (which neighbours form an
//! MM matching window, which aerial images a recording is matched with). Read by `pipelines::nadir`.

use crate::workflow::{ParamError, StageParams};
use serde::{Deserialize, Serialize};

/// See the module documentation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NadirOptions {
    /// Match triples (the next two recordings) instead of pairs (thesis 3.4.4.1).
    pub triples: bool,
    /// A neighbour further than this from the detecting recording (recorded positions, horizontal, metres) is
    /// not in its window (a gap in the trajectory, or the start of another street).
    pub max_neighbour_distance_m: f64,
    /// Expected maximum localisation error of the recorded positions, metres: an aerial image is matched with a
    /// recording only if the recording's foot point grown by this margin lies inside it (thesis 3.4.5.1).
    pub overlap_margin_m: f64,
    /// How tie points are located in the aerial images: `phase_correlation` (thesis 3.4.5.3, the `refine` node)
    /// or `baseline` (thesis 2.2.3: isolated Förstner keypoints + NCC, the `baseline` node; Table 2-10).
    pub matcher: Matcher,
}

/// See [`NadirOptions::matcher`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Matcher {
    #[default]
    PhaseCorrelation,
    Baseline,
}

impl Default for NadirOptions {
    fn default() -> Self {
        Self {
            triples: true,
            max_neighbour_distance_m: 12.0,
            overlap_margin_m: 1.5,
            matcher: Matcher::PhaseCorrelation,
        }
    }
}

impl StageParams for NadirOptions {
    fn validate(&self) -> Result<(), Vec<ParamError>> {
        let mut errs = Vec::new();
        if !(self.max_neighbour_distance_m.is_finite() && self.max_neighbour_distance_m > 0.0) {
            errs.push(ParamError::new(
                "max_neighbour_distance_m",
                "must be a distance > 0 m",
            ));
        }
        if !(self.overlap_margin_m.is_finite() && (0.0..=50.0).contains(&self.overlap_margin_m)) {
            errs.push(ParamError::new("overlap_margin_m", "must be in [0, 50] m"));
        }
        if errs.is_empty() {
            Ok(())
        } else {
            Err(errs)
        }
    }
}
