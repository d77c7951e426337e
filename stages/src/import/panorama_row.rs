//! The campaign row (`mm/recordings.csv`) of one imported panorama: its id from the file name, its time in the
//! campaign's ISO 8601 form, its position and grid-frame angles, whatever source it was read from.

use crate::campaign::{format_time_iso, parse_time_s, Recording};
use std::path::Path;

/// Where a panorama is in the campaign frame: its centre (x, y, z), the panorama frame's yaw, pitch and roll
/// to grid north, degrees, and the driving direction, degrees clockwise from grid north (any turn; written
/// within 0..360).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PanoramaPlacement {
    pub xyz: (f64, f64, f64),
    pub ypr_deg: (f64, f64, f64),
    pub heading_deg: f64,
}

/// The row of the panorama `file` taken at `time_unix_s` where `placement` puts it; the mounting fields
/// (camera height, a-priori σ) are the caller's to fill. `Err` when the time cannot be written.
pub(crate) fn panorama_row(
    file: &str,
    time_unix_s: f64,
    placement: PanoramaPlacement,
) -> Result<Recording, String> {
    let time = format_time_iso(time_unix_s).ok_or("time out of range")?;
    let image_id = Path::new(file)
        .file_stem()
        .map_or_else(|| file.to_string(), |s| s.to_string_lossy().into_owned());
    let (x, y, z) = placement.xyz;
    let (yaw_deg, pitch_deg, roll_deg) = placement.ypr_deg;
    Ok(Recording {
        image_id,
        file: file.to_string(),
        time_s: parse_time_s(&time)?,
        time,
        x,
        y,
        z,
        heading_deg: placement.heading_deg.rem_euclid(360.0),
        camera_height_m: 0.0,
        sigma_xy_m: None,
        sigma_z_m: None,
        yaw_deg,
        pitch_deg,
        roll_deg,
    })
}
