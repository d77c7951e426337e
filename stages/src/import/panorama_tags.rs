//! Panoramas that carry their pose in their own files (EXIF GPS + GPano XMP, [`crate::formats::image_tags`])
//! → `mm/recordings.csv` rows in the campaign CRS, without a trajectory or event file: `[panorama_tags]` of
//! the import configuration names the folder, the datum of the GPS tags, what their altitude is, and the
//! camera height. The panorama's attitude comes from GPano (heading to true north, pitch, roll; absent pitch
//! and roll are 0 as GPano defines them) or, without GPano, from `GPSImgDirection` to true north with the
//! panorama levelled; true north is turned into grid north by the meridian convergence. The driving
//! direction (`heading`) is the grid azimuth between the neighbouring panoramas in time (the panorama's own
//! yaw where it has no distinct neighbour).

use super::config::PanoramaTagSource;
use super::context::ImportContext;
use super::panorama_row::{panorama_row, PanoramaPlacement};
use super::pose::{panorama_angles, panorama_matrix};
use super::report::SourceReport;
use crate::campaign::{Problem, Recording};
use crate::formats::image_tags::{read_image_tags, ImageTags};
use nalgebra::Matrix3;
use std::path::Path;

/// Import every JPEG of the folder.
pub fn import_panorama_tags(
    src: &PanoramaTagSource,
    ctx: &ImportContext,
) -> (Vec<Recording>, SourceReport) {
    let mut report = SourceReport::new("panorama tags", &src.panoramas);
    let converter =
        match ctx.converter(Some(&format!("geographic:{}", src.crs)), Some(&src.heights)) {
            Ok(c) => c,
            Err(p) => {
                report.problems.push(p);
                return (Vec::new(), report);
            }
        };
    let files = match jpeg_files(&src.panoramas) {
        Ok(f) => f,
        Err(p) => {
            report.problems.push(p);
            return (Vec::new(), report);
        }
    };
    report.read = files.len();
    report.notes.push(format!(
        "GPS tags {} (altitude: {}) → {}",
        src.crs, src.heights, ctx.campaign_crs.text
    ));
    let mut rows = Vec::with_capacity(files.len());
    for file in files {
        let path = src.panoramas.join(&file);
        let result = read_image_tags(&path).and_then(|t| {
            recording(src, &file, &t, |lat, lon, alt, r| {
                let (x, y, z) = converter.position(lat, lon, alt).map_err(|e| e.to_string())?;
                let r = converter.rotation(lat, lon, r).map_err(|e| e.to_string())?;
                Ok(((x, y, z), r))
            })
            .map_err(|(tag, m)| {
                Problem::error(&path, None, Some(tag), m, "write the tag into the image (e.g. with exiftool) or import a trajectory instead")
            })
        });
        match result {
            Ok(r) => rows.push(r),
            Err(p) => report.problems.push(p),
        }
    }
    rows.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    set_driving_direction(&mut rows);
    report.converted = rows.len();
    (rows, report)
}

/// The JPEG files of `dir`, sorted by name.
fn jpeg_files(dir: &Path) -> Result<Vec<String>, Problem> {
    let entries = std::fs::read_dir(dir).map_err(|e| {
        Problem::error(
            dir,
            None,
            None,
            format!("cannot be listed ({e})"),
            "give the folder of the panoramas",
        )
    })?;
    let mut files: Vec<String> = entries
        .filter_map(|e| e.ok())
        .filter(|e| e.path().is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| {
            let l = n.to_ascii_lowercase();
            l.ends_with(".jpg") || l.ends_with(".jpeg")
        })
        .collect();
    files.sort();
    Ok(files)
}

/// Campaign position and camera→campaign rotation of a geographic position and camera→ENU rotation.
type Placed = Result<((f64, f64, f64), Matrix3<f64>), String>;

/// One recording from one image's tags; `Err((tag, message))`.
fn recording(
    src: &PanoramaTagSource,
    file: &str,
    t: &ImageTags,
    place: impl Fn(f64, f64, f64, &Matrix3<f64>) -> Placed,
) -> Result<Recording, (&'static str, String)> {
    let need =
        |v: Option<f64>, tag: &'static str| v.ok_or((tag, format!("has no {tag} tag; skipped")));
    let lat = need(t.lat_deg, "GPSLatitude")?;
    let lon = need(t.lon_deg, "GPSLongitude")?;
    let alt = need(t.altitude_m, "GPSAltitude")?;
    let time_s = need(t.time_unix_s, "GPSTimeStamp")?;
    let (heading, pitch, roll) =
        match (t.gpano_heading_deg, t.gps_direction_true_deg) {
            (Some(h), _) => (
                h,
                t.gpano_pitch_deg.unwrap_or(0.0),
                t.gpano_roll_deg.unwrap_or(0.0),
            ),
            (None, Some(h)) => (h, 0.0, 0.0),
            (None, None) => return Err((
                "GPano:PoseHeadingDegrees",
                "has neither GPano:PoseHeadingDegrees nor GPSImgDirection to true north; skipped"
                    .into(),
            )),
        };
    let ((x, y, z), r) = place(lat, lon, alt, &panorama_matrix(heading, pitch, roll))
        .map_err(|m| ("GPSLatitude", m))?;
    let (yaw, pitch, roll) = panorama_angles(&r);
    let placement = PanoramaPlacement {
        xyz: (x, y, z),
        ypr_deg: (yaw, pitch, roll),
        heading_deg: yaw,
    };
    Ok(Recording {
        camera_height_m: src.camera_height_m,
        sigma_xy_m: src.sigma_xy_m,
        sigma_z_m: src.sigma_z_m,
        ..panorama_row(file, time_s, placement).map_err(|m| ("GPSTimeStamp", m))?
    })
}

/// The grid azimuth from the previous to the next recording (time order); kept where they coincide.
fn set_driving_direction(rows: &mut [Recording]) {
    let n = rows.len();
    let pos: Vec<(f64, f64)> = rows.iter().map(|r| (r.x, r.y)).collect();
    for (i, r) in rows.iter_mut().enumerate() {
        let (a, b) = (pos[i.saturating_sub(1)], pos[(i + 1).min(n - 1)]);
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        if dx.hypot(dy) > 1e-3 {
            r.heading_deg = dx.atan2(dy).to_degrees().rem_euclid(360.0);
        }
    }
}
