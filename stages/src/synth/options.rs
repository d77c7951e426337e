//! What to generate: preset, seed, error profile and the overrides of a preset's knobs, with the checks that
//! turn bad values into errors naming the option.

use super::orthophoto::OrthophotoOptions;
use super::preset::{Preset, PresetParams};
use super::profile::{Profile, RenderOptions};
use super::sizes::SizeOptions;
use super::SynthError;
use serde::{Deserialize, Serialize};

/// What to generate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SynthOptions {
    pub preset: Preset,
    pub seed: u64,
    /// The error profile (`thesis` by default).
    pub profile: Profile,
    /// Override the nadir flying height above ground, m (the GSD is kept, so the focal length follows).
    pub nadir_altitude_m: Option<f64>,
    /// Override the oblique flying height above ground, m (GSD kept).
    pub oblique_altitude_m: Option<f64>,
    /// Override the panorama width (even; height = width / 2).
    pub panorama_width_px: Option<u32>,
    /// Override the maximum number of panoramas per route.
    pub max_recordings_per_route: Option<usize>,
    /// Sensor sizes and image files.
    #[serde(default)]
    pub sizes: SizeOptions,
    /// Also write an orthophoto and a DTM (`synth::orthophoto`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orthophoto: Option<OrthophotoOptions>,
}

/// Everything that decides the rendered images (and nothing else): the identity of a rendered folder.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenderIdentity {
    pub preset: Preset,
    pub seed: u64,
    pub nadir_altitude_m: Option<f64>,
    pub oblique_altitude_m: Option<f64>,
    pub panorama_width_px: Option<u32>,
    pub max_recordings_per_route: Option<usize>,
    #[serde(default)]
    pub sizes: SizeOptions,
    pub render: RenderOptions,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orthophoto: Option<OrthophotoOptions>,
}

impl SynthOptions {
    /// Preset defaults with the thesis' error profile (3.5.1.2).
    pub fn new(preset: Preset, seed: u64) -> Self {
        Self {
            preset,
            seed,
            profile: Profile::thesis(),
            nadir_altitude_m: None,
            oblique_altitude_m: None,
            panorama_width_px: None,
            max_recordings_per_route: None,
            sizes: SizeOptions::default(),
            orthophoto: None,
        }
    }

    /// Options that render the images of `identity` (the profile holds only the components that change
    /// images, so their render identity is `identity` again).
    pub fn rendering(identity: &RenderIdentity) -> Self {
        Self {
            preset: identity.preset,
            seed: identity.seed,
            profile: Profile::rendering(&identity.render),
            nadir_altitude_m: identity.nadir_altitude_m,
            oblique_altitude_m: identity.oblique_altitude_m,
            panorama_width_px: identity.panorama_width_px,
            max_recordings_per_route: identity.max_recordings_per_route,
            sizes: identity.sizes.clone(),
            orthophoto: identity.orthophoto.clone(),
        }
    }

    /// What decides the rendered images of these options.
    pub fn render_identity(&self) -> RenderIdentity {
        RenderIdentity {
            preset: self.preset,
            seed: self.seed,
            nadir_altitude_m: self.nadir_altitude_m,
            oblique_altitude_m: self.oblique_altitude_m,
            panorama_width_px: self.panorama_width_px,
            max_recordings_per_route: self.max_recordings_per_route,
            sizes: self.sizes.clone(),
            render: self.profile.render_options(),
            orthophoto: self.orthophoto.clone(),
        }
    }

    /// What identifies the images of a generation with these options in a render store (the render
    /// identity as JSON: profiles that change only tables share their images).
    pub fn store_identity(&self) -> Result<String, SynthError> {
        serde_json::to_string(&self.render_identity()).map_err(|e| SynthError::InvalidOption {
            option: "options".into(),
            message: format!("cannot serialise the options ({e})"),
        })
    }

    /// The preset's parameters with this option set's overrides applied and checked.
    pub fn params(&self) -> Result<PresetParams, SynthError> {
        let mut p = self.preset.params();
        let bad = |option: &str, message: String| SynthError::InvalidOption {
            option: option.into(),
            message,
        };
        if let Some(v) = self.profile.problems().into_iter().next() {
            return Err(bad(&format!("profile parameter {}", v.field), v.message));
        }
        if let Some(a) = self.nadir_altitude_m {
            if !(a.is_finite() && a > 10.0) {
                return Err(bad(
                    "nadir_altitude_m",
                    format!("{a} m; give a height above ground > 10 m"),
                ));
            }
            p.nadir.altitude_m = a;
        }
        if let Some(a) = self.oblique_altitude_m {
            if !(a.is_finite() && a > 10.0) {
                return Err(bad(
                    "oblique_altitude_m",
                    format!("{a} m; give a height above ground > 10 m"),
                ));
            }
            p.oblique.altitude_m = a;
        }
        if let Some(w) = self.panorama_width_px {
            if w < 16 || w % 2 != 0 {
                return Err(bad(
                    "panorama_width_px",
                    format!("{w}; give an even width ≥ 16"),
                ));
            }
            p.panorama_width_px = w;
        }
        if let Some(n) = self.max_recordings_per_route {
            if n == 0 {
                return Err(bad("max_recordings_per_route", "0; give at least 1".into()));
            }
            p.max_recordings_per_route = n;
        }
        let render = self.profile.render_options();
        p.nadir.corner_distortion_px = render.nadir_corner_distortion_px;
        p.exposure_log_sigma = render.epoch.map_or(0.0, |e| e.exposure_log_sigma);
        self.sizes.apply(&mut p)?;
        if let Some(o) = &self.orthophoto {
            o.check()?;
        }
        Ok(p)
    }

    /// `synth-<preset>-seed<N>`, followed by `-<profile>` unless the profile is `thesis`.
    pub fn campaign_name(&self) -> String {
        let base = format!("synth-{}-seed{}", self.preset.name(), self.seed);
        match self.profile.name().as_str() {
            "thesis" => base,
            other => format!("{base}-{other}"),
        }
    }
}
