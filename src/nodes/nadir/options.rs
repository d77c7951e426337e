//! `[nadir]`: options of the nadir pipeline that shape the DAG rather than one node (which neighbours form an
//! MM matching window, which aerial images a recording is matched with). Read by `pipelines::nadir`.

use serde::{Deserialize, Serialize};

skytie_stages::params! {
    /// See the module documentation.
    pub struct NadirOptions {
        /// Match triples (the next two recordings) instead of pairs (thesis 3.4.4.1).
        triples: bool = true;
        /// A neighbour farther than this from the detecting recording (recorded positions, horizontal) is not in
        /// its window (a gap in the trajectory, or the start of another street).
        max_neighbour_distance_m: f64 = 12.0, unit "m", above 0.0;
        /// Expected maximum localisation error of the recorded positions: an aerial image is matched with a
        /// recording only if the recording's foot point grown by this margin lies inside it (thesis 3.4.5.1).
        overlap_margin_m: f64 = 1.5, unit "m", min 0.0, max 50.0;
        /// How tie points are located in the aerial images: `phase_correlation` (thesis 3.4.5.3, the `refine`
        /// node) or `baseline` (thesis 2.2.3: isolated Förstner keypoints + NCC, the `baseline` node).
        matcher: Matcher = Matcher::PhaseCorrelation;
    }
}

/// See [`NadirOptions::matcher`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Matcher {
    #[default]
    PhaseCorrelation,
    Baseline,
}
