//! `[oblique]`: options of the oblique pipeline that shape the DAG (which recordings form a triplet, which
//! oblique images a recording's façades are registered with), and `[oblique.consensus]`, the parameters of the
//! global `oblique` node (thesis 4.4.7 median consensus). Read by `pipelines::oblique`.

use skytie_stages::oblique::consensus::ConsensusParams;

skytie_stages::params! {
    /// See the module documentation.
    pub struct ObliqueOptions {
        /// Consecutive recordings farther apart than this (recorded positions, horizontal) do not form a
        /// triplet (a gap in the trajectory, or the start of another street).
        max_neighbour_distance_m: f64 = 12.0, unit "m", above 0.0;
        /// Façade planes of a triplet are fitted to its own sparse points and those of up to this many
        /// triplets before and after it along the trajectory (thesis 4.4.2 fits planes along the street);
        /// 0 = the triplet's own points only.
        plane_neighbours: usize = 2, max 10;
        /// … whose centre recordings lie within this distance of the triplet's centre.
        max_plane_distance_m: f64 = 15.0, unit "m", above 0.0;
        /// Façades are looked for up to this distance left and right of a recording
        /// (`skytie_stages::oblique::candidates`).
        max_facade_distance_m: f64 = 20.0, unit "m", above 0.0, max 200.0;
        /// … and up to this height above the street.
        max_facade_height_m: f64 = 15.0, unit "m", above 0.0, max 500.0;
        /// The median consensus (thesis 4.4.7; Table 4-8 varies `threshold_m` and `tracking`).
        consensus: ConsensusParams = ConsensusParams::default(), section;
    }
}
