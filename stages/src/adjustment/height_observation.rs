//! Height observations of the recordings from a terrain model: a recording's projection centre lies its
//! `camera_height` above the ground under it, so a digital terrain model (DTM) gives its height independently
//! of the GNSS/INS — Z = DTM(x, y) + camera_height, σ = √(σ_DTM² + σ_camera_height²).
//!
//! Why: a control point fixes a panorama's ray, not the position along it. The tie points of a recording often
//! lie on one side of it, and then its height and its horizontal position along the ray trade off against each
//! other; the recorded height's σ (decimetres) leaves that trade free, a terrain model (centimetres) does not.
//!
//! The DTM is sampled at the recorded horizontal position: the recordings are off by decimetres to metres
//! horizontally, and the terrain under a road changes by millimetres over that distance. A recording outside
//! the terrain model, or over one of its holes, gets no observation (counted).

use super::problem::HeightObservation;
use crate::campaign::Recording;
use serde::{Deserialize, Serialize};

/// Where the recordings' height observations came from, as the adjustment reports it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HeightSource {
    /// Not requested (`dtm_height = false`).
    #[default]
    Off,
    /// Requested, but the campaign declares no DTM: no height was observed.
    NoDtm,
    /// The campaign's DTM plus each recording's camera height.
    Dtm,
}

impl HeightSource {
    /// The label written into metrics.
    pub fn label(self) -> &'static str {
        match self {
            HeightSource::Off => "off",
            HeightSource::NoDtm => "no_dtm",
            HeightSource::Dtm => "dtm",
        }
    }
}

/// What the recordings' height observations were.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct HeightObservations {
    pub source: HeightSource,
    /// Recordings with a height observation.
    pub observed: usize,
    /// Recordings the terrain model has no height for (outside it, or at a hole).
    pub without_terrain: usize,
    /// σ of each observation, metres (0 when there are none).
    pub sigma_m: f64,
}

impl HeightObservations {
    /// The summary of `heights` (one per recording) taken from `source`.
    pub fn of(source: HeightSource, heights: &[Option<HeightObservation>]) -> Self {
        let observed = heights.iter().flatten().count();
        Self {
            source,
            observed,
            without_terrain: match source {
                HeightSource::Dtm => heights.len() - observed,
                _ => 0,
            },
            sigma_m: heights
                .iter()
                .flatten()
                .map(|h| h.sigma_m)
                .next()
                .unwrap_or(0.0),
        }
    }

    /// One line for a run's log and report.
    pub fn describe(&self) -> String {
        match self.source {
            HeightSource::Off => "recording heights: the recorded ones only".to_string(),
            HeightSource::NoDtm => "recording heights: no DTM in the campaign, so no height was observed \
                 (declare [dtm] in campaign.toml to observe them)"
                .to_string(),
            HeightSource::Dtm => format!(
                "recording heights: {} observed from the DTM + camera height (σ {:.3} m), {} outside the DTM",
                self.observed, self.sigma_m, self.without_terrain
            ),
        }
    }
}

/// σ of a height taken from a terrain model whose stated σ is `dtm_sigma_m`, with a camera height of σ
/// `camera_height_sigma_m`, metres.
pub fn dtm_height_sigma_m(dtm_sigma_m: f64, camera_height_sigma_m: f64) -> f64 {
    dtm_sigma_m.hypot(camera_height_sigma_m)
}

/// Per recording, its height from the terrain model `terrain_z_m` (height of the ground at world x, y, `None`
/// where it has none) plus its camera height, each with σ `sigma_m`.
pub fn terrain_heights(
    recordings: &[Recording],
    terrain_z_m: impl Fn(f64, f64) -> Option<f64>,
    sigma_m: f64,
) -> Vec<Option<HeightObservation>> {
    recordings
        .iter()
        .map(|r| {
            terrain_z_m(r.x, r.y)
                .filter(|z| z.is_finite())
                .map(|z| HeightObservation {
                    z_world: z + r.camera_height_m,
                    sigma_m,
                })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heights_are_terrain_plus_camera_height_and_holes_are_counted() {
        let rec = |x: f64| Recording::new(&format!("r{x}"), x, [x, 0.0, 50.0], 0.0, 2.5);
        let recs = [rec(0.0), rec(10.0), rec(20.0)];
        let terrain = |x: f64, _y: f64| (x < 15.0).then_some(40.0 + 0.1 * x);
        let sigma = dtm_height_sigma_m(0.05, 0.02);
        assert!((sigma - 0.053_851_648).abs() < 1e-8);
        let h = terrain_heights(&recs, terrain, sigma);
        assert_eq!(h[0].unwrap().z_world, 42.5);
        assert!((h[1].unwrap().z_world - 43.5).abs() < 1e-12);
        assert!(h[2].is_none());
        let s = HeightObservations::of(HeightSource::Dtm, &h);
        assert_eq!((s.observed, s.without_terrain), (2, 1));
        assert!(s.describe().contains("2 observed"));
        let none = HeightObservations::of(HeightSource::NoDtm, &[]);
        assert_eq!((none.observed, none.without_terrain), (0, 0));
        assert!(none.describe().contains("no DTM"));
    }
}
