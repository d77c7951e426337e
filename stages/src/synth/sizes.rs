//! Overrides of a preset's sensor sizes and image files: real-size cameras (the footprint kept, so the GSD
//! follows the width), the aerial file format, rendering at a fraction of the size and upsampling, and the
//! demo-size twin of a real-size preset.

use super::output::{render_factor, AerialFormat};
use super::preset::PresetParams;
use super::SynthError;
use serde::{Deserialize, Serialize};

/// Overrides of the preset's sensor sizes and image files.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SizeOptions {
    /// Nadir camera width × height, px; the footprint is kept (the GSD scales with the width).
    pub nadir_px: Option<(u32, u32)>,
    /// Oblique camera width × height, px; the footprint and the distortion coefficients are kept.
    pub oblique_px: Option<(u32, u32)>,
    /// File format of the aerial frames.
    pub aerial_format: Option<AerialFormat>,
    /// Render at most this wide and upsample (`Some(0)`: render at the camera's size).
    pub render_max_width_px: Option<u32>,
    /// Write the campaign at the size it is rendered at (cameras divided by the render factors): the
    /// demo-size twin of a real-size preset, with the same scene, trajectory, flight plans and content.
    pub at_render_size: bool,
}

impl SizeOptions {
    /// `p` with these overrides applied.
    pub(super) fn apply(&self, p: &mut PresetParams) -> Result<(), SynthError> {
        let bad = |option: &str, message: String| SynthError::InvalidOption {
            option: option.into(),
            message,
        };
        if let Some((w, h)) = self.nadir_px {
            let f = size_factor("nadir_px", (w, h), p.nadir.width_px)?;
            p.nadir.gsd_m /= f;
            p.nadir.corner_distortion_px *= f;
            (p.nadir.width_px, p.nadir.height_px) = (w, h);
        }
        if let Some((w, h)) = self.oblique_px {
            let f = size_factor("oblique_px", (w, h), p.oblique.width_px)?;
            p.oblique.gsd_center_m /= f;
            p.oblique.corner_distortion_px *= f;
            (p.oblique.width_px, p.oblique.height_px) = (w, h);
        }
        if let Some(format) = self.aerial_format {
            format.check().map_err(|m| bad("aerial_format", m))?;
            p.aerial_format = format;
        }
        if let Some(cap) = self.render_max_width_px {
            p.render_max_width_px = (cap > 0).then_some(cap);
        }
        if self.at_render_size {
            at_render_size(p);
        }
        Ok(())
    }
}

/// The preset at the size its images are rendered at: every camera divided by its render factor, GSDs and
/// pixel-sized noise and distortion scaled to match, nothing upsampled.
fn at_render_size(p: &mut PresetParams) {
    let cap = p.render_max_width_px;
    let k = f64::from(render_factor(p.nadir.width_px, p.nadir.height_px, cap));
    p.nadir.width_px = (f64::from(p.nadir.width_px) / k) as u32;
    p.nadir.height_px = (f64::from(p.nadir.height_px) / k) as u32;
    p.nadir.gsd_m *= k;
    p.nadir.corner_distortion_px /= k;
    let k = f64::from(render_factor(p.oblique.width_px, p.oblique.height_px, cap));
    p.oblique.width_px = (f64::from(p.oblique.width_px) / k) as u32;
    p.oblique.height_px = (f64::from(p.oblique.height_px) / k) as u32;
    p.oblique.gsd_center_m *= k;
    p.oblique.corner_distortion_px /= k;
    let k = render_factor(p.panorama_width_px, p.panorama_height_px(), cap);
    p.panorama_width_px /= k;
    p.observation_sigma_px /= f64::from(k);
    p.render_max_width_px = None;
}

/// The factor by which the option `option`'s requested image size `(w, h)` enlarges a camera `width_px`
/// wide; an error for sides outside [16, 2^20].
fn size_factor(option: &str, (w, h): (u32, u32), width_px: u32) -> Result<f64, SynthError> {
    if !(16..=1 << 20).contains(&w) || !(16..=1 << 20).contains(&h) {
        return Err(SynthError::InvalidOption {
            option: option.into(),
            message: format!("{w} × {h}; give sides in [16, 1048576]"),
        });
    }
    Ok(f64::from(w) / f64::from(width_px))
}
