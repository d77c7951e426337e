//! The synthetic campaign presets (`tiny`, `demo`, `paper`, `realsize`, `street`) and every knob they fix: scene
//! areas, panorama size and supersampling, aerial flight plans, check-point density, image sizes and files.
//!
//! Aerial geometry follows the thesis data: nadir at ≈ 4470 m above ground with ≈ 10 cm GSD and 60 % / 40 %
//! overlap (thesis 3.5.1.1, 5.5), pentacam obliques tilted 45° at ≈ 450 m (thesis 4.5).

use super::output::AerialFormat;
use super::scene::{RouteSpec, SceneSpec};
use super::SynthError;
use crate::imaging::tiff_write::TiffCompression;
use serde::{Deserialize, Serialize};

/// A named preset of the synthetic campaign.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Preset {
    /// CI smoke test: ~6 panoramas, small images, a few seconds.
    Tiny,
    /// README default: one street with a junction, ~40 panoramas.
    Demo,
    /// The thesis-sized campaign: four areas of ~100 panoramas each at full resolution (slow).
    Paper,
    /// Real sensor sizes on a short street of the demo scene: a 26460 × 17004 nadir camera (UltraCam Eagle
    /// Mark 3 class, tiled TIFF), 14192 × 10640 obliques, 8192 × 4096 panoramas; rendered at ≤ 2400 px wide
    /// and upsampled to those sizes ([`super::output`]).
    Realsize,
    /// A long street at `tiny`'s image sizes: 320 panoramas along 1.6 km, for sharded and cluster runs.
    Street,
}

/// Number of panoramas of the `street` preset (at 5 m: a 1595 m route).
pub const STREET_RECORDINGS: usize = 320;

/// Distance between the origins of the four `paper` areas along world X, m.
pub const PAPER_AREA_SPACING_M: f64 = 2000.0;

/// Length of each (straight) `paper` route, m: 100 panoramas at 5 m.
pub const PAPER_ROUTE_LENGTH_M: f64 = 495.0;

/// Valid preset names, in the order shown in messages.
pub const PRESET_NAMES: [&str; 5] = ["tiny", "demo", "paper", "realsize", "street"];

impl Preset {
    /// Parse a preset name (`tiny`, `demo`, `paper`, `street`, case-insensitive).
    pub fn from_name(name: &str) -> Result<Preset, SynthError> {
        match name.trim().to_ascii_lowercase().as_str() {
            "tiny" => Ok(Preset::Tiny),
            "demo" => Ok(Preset::Demo),
            "paper" => Ok(Preset::Paper),
            "realsize" => Ok(Preset::Realsize),
            "street" => Ok(Preset::Street),
            _ => Err(SynthError::UnknownPreset {
                name: name.to_string(),
                valid: PRESET_NAMES.join(", "),
            }),
        }
    }

    /// The preset's name as accepted by [`Preset::from_name`].
    pub fn name(self) -> &'static str {
        match self {
            Preset::Tiny => "tiny",
            Preset::Demo => "demo",
            Preset::Paper => "paper",
            Preset::Realsize => "realsize",
            Preset::Street => "street",
        }
    }

    /// The scene areas of this preset (one per route; `paper` has four).
    pub fn scene_specs(self) -> Vec<SceneSpec> {
        match self {
            Preset::Tiny => vec![SceneSpec::tiny()],
            Preset::Demo | Preset::Realsize => vec![SceneSpec::demo()],
            Preset::Street => vec![SceneSpec::long_street(
                STREET_RECORDINGS as f64 * PresetParams::common().recording_spacing_m,
            )],
            // The areas share one origin in their specs; they are placed side by side, far enough apart that
            // no aerial footprint of one area reaches another, and lengthened to ~100 panoramas each.
            Preset::Paper => (0..4)
                .map(|i| {
                    let spec = SceneSpec::paper_area(i);
                    let origin = [
                        spec.origin_world[0] + PAPER_AREA_SPACING_M * i as f64,
                        spec.origin_world[1],
                    ];
                    let route = RouteSpec {
                        end_x_m: spec.route.start_x_m + PAPER_ROUTE_LENGTH_M,
                        ..spec.route
                    };
                    SceneSpec {
                        origin_world: origin,
                        street_length_m: route.end_x_m + 10.0,
                        route,
                        ..spec
                    }
                })
                .collect(),
        }
    }

    /// All numeric parameters of this preset.
    pub fn params(self) -> PresetParams {
        let nadir = |width_px, height_px| NadirPlan {
            altitude_m: 4470.0,
            gsd_m: 0.10,
            width_px,
            height_px,
            forward_overlap: 0.60,
            side_overlap: 0.40,
            attitude_sigma_deg: 0.15,
            corner_distortion_px: 0.0,
        };
        let oblique = |width_px, height_px| ObliquePlan {
            altitude_m: 450.0,
            tilt_deg: 45.0,
            gsd_center_m: 0.10,
            width_px,
            height_px,
            overlap_along_route: 0.5,
            corner_distortion_px: 2.0,
        };
        // The sizes that set the presets apart; everything else is `PresetParams::common()`.
        let sized = |panorama_width_px, max_recordings_per_route, nadir, oblique| PresetParams {
            panorama_width_px,
            max_recordings_per_route,
            nadir,
            oblique,
            ..PresetParams::common()
        };
        match self {
            Preset::Tiny => PresetParams {
                // Three check points along the 25 m route instead of one.
                checkpoint_spacing_m: 8.0,
                ..sized(1024, 6, nadir(512, 384), oblique(320, 240))
            },
            Preset::Street => PresetParams {
                max_recordings_per_route: STREET_RECORDINGS,
                ..Preset::Tiny.params()
            },
            // 1600 × 800 panoramas (0.225°/px) instead of 2048 × 1024: measured 2.3 M primary rays/s per core of
            // CPU time, this keeps the whole demo at ≈ 155 CPU-s, i.e. ≲ 90 s on 2 cores; the aerial sizes too
            // are sized for generation in ≲ 90 s on 2 cores (measured with the render bench).
            Preset::Demo => sized(1600, 40, nadir(1600, 1200), oblique(800, 600)),
            Preset::Paper => sized(4800, 100, nadir(4000, 3000), oblique(2000, 1500)),
            // Rendered at 2205 × 1417 (nadir, ÷ 12), 1774 × 1330 (obliques, ÷ 8) and 2048 × 1024 (panoramas, ÷ 4),
            // the aerial images at ≈ 10 cm on the ground like the demo; the footprints are the rendered images', so
            // the GSD of the real-size files is 10 cm / 12 and / 8. Twelve recordings: a 55 m street.
            Preset::Realsize => PresetParams {
                render_max_width_px: Some(2400),
                aerial_format: AerialFormat::TiledTiff {
                    compression: TiffCompression::Jpeg(92),
                    bits: 8,
                },
                ..sized(
                    8192,
                    12,
                    NadirPlan {
                        gsd_m: 0.10 / 12.0,
                        ..nadir(26460, 17004)
                    },
                    ObliquePlan {
                        gsd_center_m: 0.10 / 8.0,
                        corner_distortion_px: 2.0 * 8.0,
                        ..oblique(14192, 10640)
                    },
                )
            },
        }
    }
}

/// Parameters of the nadir flight plan (thesis 3.5.1.1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NadirPlan {
    /// Flying height above the ground, m.
    pub altitude_m: f64,
    /// Ground sampling distance at the image centre, m (focal_px = altitude / GSD).
    pub gsd_m: f64,
    pub width_px: u32,
    pub height_px: u32,
    /// Forward (along-strip) overlap, fraction of the footprint.
    pub forward_overlap: f64,
    /// Side (across-strip) overlap, fraction of the footprint.
    pub side_overlap: f64,
    /// SD of the small random ω and φ (clamped to < 1°), degrees.
    pub attitude_sigma_deg: f64,
    /// Radial lens distortion at the image corners, pixels (0 = none; the `lens` profiles set it).
    pub corner_distortion_px: f64,
}

/// Parameters of the oblique (pentacam-style) flight plan (thesis 4.5).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObliquePlan {
    /// Flying height above the ground, m.
    pub altitude_m: f64,
    /// Tilt of the optical axis from the nadir, degrees.
    pub tilt_deg: f64,
    /// GSD at the image centre (perpendicular to the viewing direction), m.
    pub gsd_center_m: f64,
    pub width_px: u32,
    pub height_px: u32,
    /// Overlap of consecutive oblique footprints along the route (0.5 ⇒ each route point seen ≥ 2 times per
    /// viewing direction).
    pub overlap_along_route: f64,
    /// Radial distortion at the image corners, pixels (sets k1; k2, p1, p2 are smaller fractions of it).
    pub corner_distortion_px: f64,
}

/// Every knob of a preset.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PresetParams {
    /// Panorama width (height = width / 2).
    pub panorama_width_px: u32,
    /// Stratified supersampling per axis for panoramas (n ⇒ n × n rays per pixel).
    pub panorama_spp_axis: u32,
    /// Spacing of panoramas along the route, m.
    pub recording_spacing_m: f64,
    /// At most this many panoramas per route.
    pub max_recordings_per_route: usize,
    /// True height of the panorama centre above the road, m.
    pub camera_height_m: f64,
    /// Vehicle speed (sets the acquisition times), m/s.
    pub speed_m_s: f64,
    /// Every `attitude_every`-th panorama gets a small nonzero residual yaw/pitch/roll (0 = never).
    pub attitude_every: usize,
    /// SD of that residual yaw/pitch/roll, degrees.
    pub attitude_sigma_deg: f64,
    pub nadir: NadirPlan,
    pub oblique: ObliquePlan,
    /// Stratified supersampling per axis for aerial frames.
    pub aerial_spp_axis: u32,
    /// One check point per this many metres of route.
    pub checkpoint_spacing_m: f64,
    /// Check points farther than this from the route are not used, m.
    pub checkpoint_max_route_distance_m: f64,
    /// A check point is observed in panoramas whose true centre is within this distance, m (thesis 3.5.3).
    pub observation_max_distance_m: f64,
    /// SD of the simulated manual measurement of a check point in a panorama, pixels per axis.
    pub observation_sigma_px: f64,
    /// A-priori SDs written to `mm/recordings.csv`, m.
    pub sigma_xy_m: f64,
    pub sigma_z_m: f64,
    /// JPEG quality of all images.
    pub jpeg_quality: u8,
    /// Images are rendered at most this wide (at an exact integer fraction of the camera's size) and upsampled
    /// to the camera's size; `None` renders at the camera's size ([`super::output::render_factor`]).
    pub render_max_width_px: Option<u32>,
    /// File format of the aerial frames (panoramas are always JPEG).
    pub aerial_format: AerialFormat,
    /// SD of the natural logarithm of each image's exposure gain (0 = every image exposed alike; the `epoch`
    /// profile sets it).
    pub exposure_log_sigma: f64,
}

impl PresetParams {
    /// Values shared by all presets (the size-dependent ones are overwritten per preset).
    fn common() -> Self {
        PresetParams {
            panorama_width_px: 1024,
            panorama_spp_axis: 2,
            recording_spacing_m: 5.0,
            max_recordings_per_route: 6,
            camera_height_m: 2.2,
            speed_m_s: 8.0,
            attitude_every: 3,
            attitude_sigma_deg: 0.4,
            nadir: NadirPlan {
                altitude_m: 4470.0,
                gsd_m: 0.1,
                width_px: 640,
                height_px: 480,
                forward_overlap: 0.6,
                side_overlap: 0.4,
                attitude_sigma_deg: 0.15,
                corner_distortion_px: 0.0,
            },
            oblique: ObliquePlan {
                altitude_m: 450.0,
                tilt_deg: 45.0,
                gsd_center_m: 0.1,
                width_px: 480,
                height_px: 360,
                overlap_along_route: 0.5,
                corner_distortion_px: 2.0,
            },
            aerial_spp_axis: 2,
            checkpoint_spacing_m: 17.5,
            checkpoint_max_route_distance_m: 12.0,
            observation_max_distance_m: 15.0,
            observation_sigma_px: 0.5,
            sigma_xy_m: 1.0,
            sigma_z_m: 0.3,
            jpeg_quality: 92,
            render_max_width_px: None,
            aerial_format: AerialFormat::Jpeg,
            exposure_log_sigma: 0.0,
        }
    }

    /// Panorama height (width / 2).
    pub fn panorama_height_px(&self) -> u32 {
        self.panorama_width_px / 2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_unknown_names_list_the_valid_ones() {
        for p in [
            Preset::Tiny,
            Preset::Demo,
            Preset::Paper,
            Preset::Realsize,
            Preset::Street,
        ] {
            assert_eq!(Preset::from_name(p.name()).unwrap(), p);
        }
        assert_eq!(Preset::from_name(" Demo ").unwrap(), Preset::Demo);
        let e = Preset::from_name("huge").unwrap_err().to_string();
        assert!(
            e.contains("huge") && e.contains("tiny, demo, paper, realsize, street"),
            "{e}"
        );
    }

    #[test]
    fn nadir_geometry_matches_the_thesis() {
        for p in [Preset::Demo, Preset::Paper] {
            let n = p.params().nadir;
            assert_eq!(n.altitude_m, 4470.0);
            assert!(
                (n.altitude_m / n.gsd_m - 44_700.0).abs() < 1e-6,
                "focal ≈ 44 700 px"
            );
            assert_eq!((n.forward_overlap, n.side_overlap), (0.6, 0.4));
        }
        let pp = Preset::Paper.params();
        assert_eq!(
            (pp.panorama_width_px, pp.panorama_height_px()),
            (4800, 2400)
        );
    }
}
