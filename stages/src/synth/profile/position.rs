//! Profile `thesis` (thesis 3.5.1.2): every recorded panorama position gets one systematic horizontal offset
//! (same for the whole campaign, towards an azimuth drawn from the seed) plus independent normal noise per
//! horizontal axis and recording; heights untouched. The simulated GNSS problem of the thesis' experiments.

use super::Tables;
use crate::synth::rng::{hash_str, Stream};

crate::params! {
    /// Parameters of the `thesis` component (`[synth.thesis]`).
    pub struct ThesisParams {
        /// Length of the systematic horizontal offset (thesis: 0.80).
        offset_m: f64 = 0.80, unit "m", min 0.0;
        /// SD of the random part per horizontal axis and recording (thesis: 0.10).
        sigma_m: f64 = 0.10, unit "m", min 0.0;
        /// Direction of the offset, clockwise from grid north; absent = drawn from the seed (rounded to 0.1°).
        azimuth_deg: Option<f64> = None, unit "deg";
    }
    check(p, v) {
        crate::params::check_finite("azimuth_deg", &p.azimuth_deg, v);
    }
}

impl ThesisParams {
    /// The offset's azimuth for `seed`.
    pub fn azimuth_for(&self, seed: u64) -> f64 {
        self.azimuth_deg.unwrap_or_else(|| {
            let mut s = Stream::new(&[seed, hash_str("deterioration-azimuth")]);
            (s.range(0.0, 360.0) * 10.0).round() / 10.0 % 360.0
        })
    }

    /// Add the offset and noise to the recorded positions; returns the README lines. The noise of a recording
    /// depends only on (seed, its image_id).
    pub fn apply(&self, seed: u64, truth: &Tables, out: &mut Tables) -> Vec<String> {
        let azimuth_deg = self.azimuth_for(seed);
        let (sa, ca) = azimuth_deg.to_radians().sin_cos();
        for (t, r) in truth.recordings.iter().zip(out.recordings.iter_mut()) {
            let mut s = Stream::new(&[seed, hash_str("deterioration"), hash_str(&t.image_id)]);
            let (nx, ny) = (s.normal(), s.normal());
            r.x += self.offset_m * sa + self.sigma_m * nx;
            r.y += self.offset_m * ca + self.sigma_m * ny;
        }
        vec![
            format!(
                "`thesis` (thesis 3.5.1.2): a systematic horizontal offset of {:.3} m towards azimuth {:.1}° \
                 (clockwise from grid north), i.e. dx = {:+.4} m, dy = {:+.4} m for every panorama;",
                self.offset_m,
                azimuth_deg,
                self.offset_m * sa,
                self.offset_m * ca
            ),
            format!(
                "`thesis`: plus random normal noise N(0, {:.3} m) added to x and, independently, to y of every \
                 panorama;",
                self.sigma_m
            ),
        ]
    }
}
