//! Profile `epoch`: what changes in a street between the aerial flight and the mobile-mapping run, beyond the
//! sun and the parked cars that every synthetic campaign already has. More parked cars moved; some road
//! markings repainted or removed (present in one epoch only); roadworks (a patch of fresh asphalt and traffic
//! cones, in one epoch only); tree crowns grown over the road by the time of the flight; a low sun with long
//! shadows in the mobile-mapping run; and exposure differing from image to image. Changes the rendered images,
//! so campaigns with and without it are rendered separately.

use super::check_non_negative;
use serde::{Deserialize, Serialize};

/// Parameters of the `epoch` component (`[synth.epoch]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EpochParams {
    /// Fraction of the parked cars present in one epoch only (half in each), instead of the preset's.
    pub moved_car_fraction: f64,
    /// Fraction of the painted markings (lines, arrows, stop lines, zebras) present in one epoch only.
    pub changed_marking_fraction: f64,
    /// Roadworks per street: a patch of fresh asphalt with cones, in one epoch only.
    pub roadworks_per_street: usize,
    /// Tree crowns in the aerial epoch are larger by this radius, m.
    pub crown_growth_m: f64,
    /// Sun elevation of the mobile-mapping run, degrees (long shadows).
    pub mm_sun_elevation_deg: f64,
    /// SD of the natural logarithm of each image's exposure gain (per panorama and per aerial frame).
    pub exposure_log_sigma: f64,
}

impl Default for EpochParams {
    fn default() -> Self {
        Self {
            moved_car_fraction: 0.6,
            changed_marking_fraction: 0.15,
            roadworks_per_street: 1,
            crown_growth_m: 1.0,
            mm_sun_elevation_deg: 22.0,
            exposure_log_sigma: 0.15,
        }
    }
}

impl EpochParams {
    /// Every invalid field as (field, problem).
    pub fn problems(&self) -> Vec<(String, String)> {
        let mut p = Vec::new();
        for (field, v) in [
            ("epoch.moved_car_fraction", self.moved_car_fraction),
            (
                "epoch.changed_marking_fraction",
                self.changed_marking_fraction,
            ),
        ] {
            if !(0.0..=1.0).contains(&v) {
                p.push((field.into(), format!("{v} must be a fraction in [0, 1]")));
            }
        }
        check_non_negative(&mut p, "epoch.crown_growth_m", self.crown_growth_m);
        check_non_negative(&mut p, "epoch.exposure_log_sigma", self.exposure_log_sigma);
        if !(self.mm_sun_elevation_deg > 0.0 && self.mm_sun_elevation_deg < 90.0) {
            p.push((
                "epoch.mm_sun_elevation_deg".into(),
                format!("{} must be in (0, 90) degrees", self.mm_sun_elevation_deg),
            ));
        }
        p
    }

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
