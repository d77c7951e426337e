//! Deterioration of the recorded panorama positions (thesis 3.5.1.2): the true poses are kept in
//! `truth/recordings.csv`, `mm/recordings.csv` gets positions with a systematic horizontal offset plus random
//! noise (simulating GNSS problems), optionally a GNSS-outage drift and a height error.

use super::rng::{hash_str, Stream};
use crate::campaign::Recording;
use serde::{Deserialize, Serialize};

/// A GNSS-outage drift: along a segment of the route the horizontal offset ramps up linearly from 0 to
/// `peak_m` (at the segment's middle) and back to 0, in direction `azimuth_deg` (clockwise from grid north).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DriftProfile {
    /// Start of the segment, metres along the route from its first panorama.
    pub start_m: f64,
    /// Length of the segment, m.
    pub length_m: f64,
    /// Largest drift (segment middle), m.
    pub peak_m: f64,
    pub azimuth_deg: f64,
}

impl DriftProfile {
    /// Drift magnitude (m) at `along_m` metres along the route: a triangle over the segment, 0 outside.
    pub fn magnitude_m(&self, along_m: f64) -> f64 {
        if self.length_m <= 0.0 {
            return 0.0;
        }
        let t = (along_m - self.start_m) / self.length_m;
        if (0.0..=1.0).contains(&t) {
            self.peak_m * (1.0 - (2.0 * t - 1.0).abs())
        } else {
            0.0
        }
    }
}

/// How the recorded positions are deteriorated.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Deterioration {
    /// Recorded = true.
    None,
    /// Thesis 3.5.1.2: 0.80 m systematic horizontal offset (azimuth fixed per seed) plus N(0, 0.10 m) per
    /// horizontal axis and recording; heights untouched.
    Thesis,
    /// Anything else: systematic offset `offset_m` towards `azimuth_deg`, N(0, `sigma_m`) per horizontal axis,
    /// N(0, `z_sigma_m`) in height, and an optional drift.
    Custom {
        offset_m: f64,
        azimuth_deg: f64,
        sigma_m: f64,
        z_sigma_m: f64,
        drift: Option<DriftProfile>,
    },
}

/// A deterioration with every number fixed (the azimuth of [`Deterioration::Thesis`] drawn from the seed).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DeteriorationModel {
    pub offset_m: f64,
    pub azimuth_deg: f64,
    pub sigma_m: f64,
    pub z_sigma_m: f64,
    pub drift: Option<DriftProfile>,
}

impl Deterioration {
    /// Fix all numbers for `seed`.
    pub fn resolve(&self, seed: u64) -> DeteriorationModel {
        match self {
            Deterioration::None => DeteriorationModel {
                offset_m: 0.0,
                azimuth_deg: 0.0,
                sigma_m: 0.0,
                z_sigma_m: 0.0,
                drift: None,
            },
            Deterioration::Thesis => {
                let mut s = Stream::new(&[seed, hash_str("deterioration-azimuth")]);
                // Rounded to 0.1° so the README's number is exactly the one used.
                let azimuth_deg = (s.range(0.0, 360.0) * 10.0).round() / 10.0 % 360.0;
                DeteriorationModel {
                    offset_m: 0.80,
                    azimuth_deg,
                    sigma_m: 0.10,
                    z_sigma_m: 0.0,
                    drift: None,
                }
            }
            Deterioration::Custom {
                offset_m,
                azimuth_deg,
                sigma_m,
                z_sigma_m,
                drift,
            } => DeteriorationModel {
                offset_m: *offset_m,
                azimuth_deg: *azimuth_deg,
                sigma_m: *sigma_m,
                z_sigma_m: *z_sigma_m,
                drift: drift.clone(),
            },
        }
    }
}

impl DeteriorationModel {
    /// Whether recorded positions differ from the truth at all.
    pub fn is_identity(&self) -> bool {
        self.offset_m == 0.0
            && self.sigma_m == 0.0
            && self.z_sigma_m == 0.0
            && self.drift.as_ref().is_none_or(|d| d.peak_m == 0.0)
    }

    /// Recorded poses from true ones. `along_m[i]` is the distance of recording `i` along its route (for the
    /// drift). The random part of recording `i` depends only on (seed, its image_id), not on order or threads.
    pub fn apply(&self, truth: &[Recording], along_m: &[f64], seed: u64) -> Vec<Recording> {
        let (sa, ca) = self.azimuth_deg.to_radians().sin_cos();
        truth
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let mut s = Stream::new(&[seed, hash_str("deterioration"), hash_str(&t.image_id)]);
                let (nx, ny, nz) = (s.normal(), s.normal(), s.normal());
                let mut dx = self.offset_m * sa + self.sigma_m * nx;
                let mut dy = self.offset_m * ca + self.sigma_m * ny;
                if let Some(d) = &self.drift {
                    let m = d.magnitude_m(along_m.get(i).copied().unwrap_or(0.0));
                    let (sd, cd) = d.azimuth_deg.to_radians().sin_cos();
                    dx += m * sd;
                    dy += m * cd;
                }
                let mut r = t.clone();
                r.x += dx;
                r.y += dy;
                r.z += self.z_sigma_m * nz;
                r
            })
            .collect()
    }

    /// The text of `truth/README.md`: exactly how the recorded positions were made from the true ones.
    pub fn readme(&self, campaign_name: &str, seed: u64, recordings: usize) -> String {
        let mut t = format!(
            "# Truth of the synthetic campaign `{campaign_name}` (seed {seed})\n\n\
             `truth/recordings.csv` holds the true poses of the {recordings} panoramas (same columns as \
             `mm/recordings.csv`). The positions in `mm/recordings.csv` were deteriorated from them \
             (thesis 3.5.1.2) as follows, independently per panorama:\n\n"
        );
        if self.is_identity() {
            t.push_str("- not at all: recorded positions equal the true ones.\n");
        } else {
            let (sa, ca) = self.azimuth_deg.to_radians().sin_cos();
            t.push_str(&format!(
                "- a systematic horizontal offset of {:.3} m towards azimuth {:.1}° (clockwise from grid north), \
                 i.e. dx = {:+.4} m, dy = {:+.4} m for every panorama;\n",
                self.offset_m,
                self.azimuth_deg,
                self.offset_m * sa,
                self.offset_m * ca
            ));
            t.push_str(&format!(
                "- plus random normal noise N(0, {:.3} m) added to x and, independently, to y;\n",
                self.sigma_m
            ));
            if self.z_sigma_m > 0.0 {
                t.push_str(&format!(
                    "- plus random normal noise N(0, {:.3} m) added to z;\n",
                    self.z_sigma_m
                ));
            } else {
                t.push_str("- heights (z) untouched;\n");
            }
            if let Some(d) = &self.drift {
                t.push_str(&format!(
                    "- plus a GNSS-outage drift towards azimuth {:.1}°: 0 m at {:.1} m along the route, rising \
                     linearly to {:.3} m at {:.1} m and back to 0 m at {:.1} m;\n",
                    d.azimuth_deg,
                    d.start_m,
                    d.peak_m,
                    d.start_m + d.length_m / 2.0,
                    d.start_m + d.length_m
                ));
            }
        }
        t.push_str(
            "\nHeadings, camera heights, yaw/pitch/roll and all aerial poses are true (not perturbed); no \
             `truth/aerial_*.csv` is therefore written. Check points in `control/checkpoints.csv` are exact; \
             their observations in `control/observations.csv` are the true projections plus N(0, 0.5 px) per \
             axis.\n\n\
             `truth/scene.toml` names the generator, preset and seed and a fingerprint of the scene, so that an \
             evaluator can rebuild the scene and ask what a camera sees (the oblique grading uses it for the true \
             surface point of a panorama observation and for `non_matchable`).\n",
        );
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(i: usize) -> Recording {
        Recording {
            image_id: format!("p{i}"),
            file: format!("p{i}.jpg"),
            time: String::new(),
            time_s: i as f64,
            x: 92_000.0 + i as f64,
            y: 437_000.0,
            z: 2.2,
            heading_deg: 90.0,
            camera_height_m: 2.2,
            sigma_xy_m: None,
            sigma_z_m: None,
            yaw_deg: 0.0,
            pitch_deg: 0.0,
            roll_deg: 0.0,
        }
    }

    #[test]
    fn custom_offset_without_noise_is_exact() {
        let truth: Vec<_> = (0..3).map(rec).collect();
        let m = Deterioration::Custom {
            offset_m: 2.0,
            azimuth_deg: 90.0,
            sigma_m: 0.0,
            z_sigma_m: 0.0,
            drift: None,
        }
        .resolve(1);
        let out = m.apply(&truth, &[0.0, 5.0, 10.0], 1);
        for (t, r) in truth.iter().zip(&out) {
            assert!((r.x - t.x - 2.0).abs() < 1e-9 && (r.y - t.y).abs() < 1e-9 && r.z == t.z);
        }
    }

    #[test]
    fn drift_is_a_triangle_over_its_segment() {
        let d = DriftProfile {
            start_m: 10.0,
            length_m: 20.0,
            peak_m: 3.0,
            azimuth_deg: 0.0,
        };
        assert_eq!(d.magnitude_m(5.0), 0.0);
        assert!((d.magnitude_m(15.0) - 1.5).abs() < 1e-12);
        assert!((d.magnitude_m(20.0) - 3.0).abs() < 1e-12);
        assert!((d.magnitude_m(25.0) - 1.5).abs() < 1e-12);
        assert_eq!(d.magnitude_m(31.0), 0.0);
    }

    #[test]
    fn thesis_azimuth_depends_on_seed_and_is_reproducible() {
        let a = Deterioration::Thesis.resolve(1);
        assert_eq!(a, Deterioration::Thesis.resolve(1));
        assert_ne!(a.azimuth_deg, Deterioration::Thesis.resolve(2).azimuth_deg);
        assert_eq!((a.offset_m, a.sigma_m, a.z_sigma_m), (0.80, 0.10, 0.0));
        let readme = a.readme("x", 1, 3);
        assert!(
            readme.contains("0.800 m")
                && readme.contains("N(0, 0.100 m)")
                && readme.contains("untouched")
        );
    }
}
