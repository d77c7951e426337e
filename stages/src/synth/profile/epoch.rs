//! Profile `epoch`: what changes in a street between the aerial flight and the mobile-mapping run, beyond the
//! sun and the parked cars that every synthetic campaign already has. More parked cars moved; some road
//! markings repainted or removed (present in one epoch only); roadworks (a patch of fresh asphalt and traffic
//! cones, in one epoch only); tree crowns grown over the road by the time of the flight; a low sun with long
//! shadows in the mobile-mapping run; and exposure differing from image to image. Changes the rendered images,
//! so campaigns with and without it are rendered separately.

crate::params! {
    /// Parameters of the `epoch` component (`[synth.epoch]`).
    pub struct EpochParams {
        /// Fraction of the parked cars present in one epoch only (half in each), instead of the preset's.
        moved_car_fraction: f64 = 0.6, min 0.0, max 1.0;
        /// Fraction of the painted markings (lines, arrows, stop lines, zebras) present in one epoch only.
        changed_marking_fraction: f64 = 0.15, min 0.0, max 1.0;
        /// Roadworks per street: a patch of fresh asphalt with cones, in one epoch only.
        roadworks_per_street: usize = 1;
        /// Tree crowns in the aerial epoch are larger by this radius.
        crown_growth_m: f64 = 1.0, unit "m", min 0.0;
        /// Sun elevation of the mobile-mapping run (long shadows).
        mm_sun_elevation_deg: f64 = 22.0, unit "deg", above 0.0, below 90.0;
        /// SD of the natural logarithm of each image's exposure gain (per panorama and per aerial frame).
        exposure_log_sigma: f64 = 0.15, min 0.0;
    }
}

impl EpochParams {
    /// README line.
    pub fn note(&self) -> Vec<String> {
        vec![format!(
            "`epoch` (in the images, not the tables): {:.0} % of the parked cars are present in one epoch only, \
             {:.0} % of the painted markings too (repainted or removed), {} roadworks per street (fresh asphalt \
             and cones) in one epoch only, tree crowns {:.1} m larger in radius in the aerial epoch, the \
             mobile-mapping sun {:.0}° above the horizon, and each image's exposure gain multiplied by \
             exp(N(0, {:.2}));",
            100.0 * self.moved_car_fraction,
            100.0 * self.changed_marking_fraction,
            self.roadworks_per_street,
            self.crown_growth_m,
            self.mm_sun_elevation_deg,
            self.exposure_log_sigma
        )]
    }
}
