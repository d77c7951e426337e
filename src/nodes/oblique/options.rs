//! `[oblique]`: options of the oblique pipeline that shape the DAG (which recordings form a triplet, which
//! oblique images a recording's façades are registered with), and `[oblique.consensus]`, the parameters of the
//! global `oblique` node (thesis 4.4.7 median consensus). Read by `pipelines::oblique`.

use crate::workflow::{ParamError, StageParams};
use serde::{Deserialize, Serialize};
use skytie_stages::oblique::consensus::ConsensusParams;

/// See the module documentation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ObliqueOptions {
    /// Consecutive recordings further apart than this (recorded positions, horizontal, metres) do not form a
    /// triplet (a gap in the trajectory, or the start of another street).
    pub max_neighbour_distance_m: f64,
    /// Façade planes of a triplet are fitted to its own sparse points and those of up to this many
    /// triplets before and after it along the trajectory (thesis 4.4.2 fits planes along the street; one
    /// triplet's points span a few metres of façade). 0 = the triplet's own points only.
    pub plane_neighbours: usize,
    /// … whose centre recordings lie within this distance of the triplet's centre, metres.
    pub max_plane_distance_m: f64,
    /// Façades are looked for up to this distance left and right of a recording, metres
    /// (`skytie_stages::oblique::candidates`).
    pub max_facade_distance_m: f64,
    /// … and up to this height above the street, metres.
    pub max_facade_height_m: f64,
    /// The median consensus (thesis 4.4.7; Table 4-8 varies `threshold_m` and `tracking`).
    pub consensus: ConsensusParams,
}

impl Default for ObliqueOptions {
    fn default() -> Self {
        Self {
            max_neighbour_distance_m: 12.0,
            plane_neighbours: 2,
            max_plane_distance_m: 15.0,
            max_facade_distance_m: 20.0,
            max_facade_height_m: 15.0,
            consensus: ConsensusParams::default(),
        }
    }
}

impl StageParams for ObliqueOptions {
    fn validate(&self) -> Result<(), Vec<ParamError>> {
        let mut errs = Vec::new();
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(self.max_neighbour_distance_m) {
            errs.push(ParamError::new(
                "max_neighbour_distance_m",
                "must be a distance > 0 m",
            ));
        }
        if self.plane_neighbours > 10 {
            errs.push(ParamError::new(
                "plane_neighbours",
                "must be at most 10 triplets on each side",
            ));
        }
        if !positive(self.max_plane_distance_m) {
            errs.push(ParamError::new(
                "max_plane_distance_m",
                "must be a distance > 0 m",
            ));
        }
        if !positive(self.max_facade_distance_m) || self.max_facade_distance_m > 200.0 {
            errs.push(ParamError::new(
                "max_facade_distance_m",
                "must be in (0, 200] m",
            ));
        }
        if !positive(self.max_facade_height_m) || self.max_facade_height_m > 500.0 {
            errs.push(ParamError::new(
                "max_facade_height_m",
                "must be in (0, 500] m",
            ));
        }
        if let Err(problems) = self.consensus.validate() {
            errs.extend(
                problems
                    .into_iter()
                    .map(|(field, message)| ParamError::new(format!("consensus.{field}"), message)),
            );
        }
        if errs.is_empty() {
            Ok(())
        } else {
            Err(errs)
        }
    }
}
