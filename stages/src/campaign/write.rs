//! Writers for every campaign file and run output (campaign-format.md): `campaign.toml`, the CSV tables,
//! `trajectory_adjusted.csv`, `trajectory.geojson` and `tie_points.ply`.
//!
//! All writes are atomic ([`crate::fsutil`]). Floats are written with Rust's shortest round-trip
//! representation (`{}` of f64), so reading a written file gives back bit-identical values. Text fields are
//! quoted when they contain a comma, quote, line break, leading/trailing space, or start with `#` (which the
//! reader would otherwise take for a comment line). Output is deterministic: same rows ⇒ same bytes.

use super::model::{AerialImage, CheckPoint, Observation, Recording};
use super::read_recordings::RECORDING_COLUMNS;
use super::time::format_time_iso;
use crate::crs::CoordinateFrame;
use crate::fsutil::atomic_write_with;
use skytie_util::csv_out::quote;
use std::collections::BTreeMap;
use std::io::{self, Write};
use std::path::Path;

/// One point of a GeoJSON layer: a position in the campaign CRS plus its attributes.
#[derive(Clone, Debug, PartialEq)]
pub struct GeoJsonPoint {
    /// X (east), Y (north), Z (up), world frame, metres.
    pub xyz_world: [f64; 3],
    /// Attributes of the feature (sorted by key in the output).
    pub properties: BTreeMap<String, serde_json::Value>,
}

/// A named set of points (e.g. "recorded", "adjusted"), optionally joined by a LineString.
#[derive(Clone, Debug, PartialEq)]
pub struct GeoJsonLayer {
    /// Written as property `layer` on every feature of the layer.
    pub name: String,
    /// Campaign CRS as in `campaign.toml`, e.g. `EPSG:28992`; all layers of a file must agree (empty = none).
    pub crs: String,
    pub points: Vec<GeoJsonPoint>,
    /// Also write one LineString feature through the points (in the given order); needs ≥ 2 points.
    pub line: bool,
}

/// One vertex of the tie-point cloud.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlyPoint {
    pub xyz_world: [f64; 3],
    pub rgb: [u8; 3],
    /// Where the point comes from (caller-defined code, e.g. 0 = tie point, 1 = check point).
    pub source: i32,
}

/// `campaign.toml` with `name`, `crs` and — when the coordinates are not map coordinates of `crs` — `frame`.
pub fn write_campaign_toml(
    path: &Path,
    name: &str,
    crs: &str,
    frame: CoordinateFrame,
) -> io::Result<()> {
    #[derive(serde::Serialize)]
    struct CampaignToml<'a> {
        name: &'a str,
        crs: &'a str,
        #[serde(skip_serializing_if = "Option::is_none")]
        frame: Option<CoordinateFrame>,
    }
    let frame = (frame != CoordinateFrame::default()).then_some(frame);
    let text = toml::to_string(&CampaignToml { name, crs, frame }).map_err(io::Error::other)?;
    atomic_write_with(path, |w| w.write_all(text.as_bytes()))
}

/// `mm/recordings.csv` (also `truth/recordings.csv`). `time` is written as given; when it is empty it is
/// formatted from `time_s`. Optional columns `sigma_xy`, `sigma_z` appear only if some row has them (empty
/// cell for rows without); `yaw`, `pitch`, `roll` only if some row has a non-zero value.
pub fn write_recordings_csv(path: &Path, rows: &[Recording]) -> io::Result<()> {
    let rows: Vec<(&Recording, Option<[f64; 3]>)> = rows.iter().map(|r| (r, None)).collect();
    write_recording_rows(path, &rows)
}

/// `trajectory_adjusted.csv`: the recordings columns (adjusted positions in `x, y, z`) plus
/// `sigma_x, sigma_y, sigma_z` (posterior standard deviations, metres). The a-priori `sigma_xy`/`sigma_z`
/// of the recordings are not written (they describe the recorded, not the adjusted position, and `sigma_z`
/// would collide): reading this file as a recordings file gives `sigma_xy_m = None` and
/// `sigma_z_m = Some(posterior sigma_z)`, i.e. the adjusted trajectory with its precision as a new input.
pub fn write_trajectory_adjusted_csv(
    path: &Path,
    rows: &[(Recording, [f64; 3])],
) -> io::Result<()> {
    let rows: Vec<(&Recording, Option<[f64; 3]>)> =
        rows.iter().map(|(r, s)| (r, Some(*s))).collect();
    write_recording_rows(path, &rows)
}

fn write_recording_rows(path: &Path, rows: &[(&Recording, Option<[f64; 3]>)]) -> io::Result<()> {
    let has_posterior = rows.iter().any(|(_, s)| s.is_some());
    let has_sigma_xy = !has_posterior && rows.iter().any(|(r, _)| r.sigma_xy_m.is_some());
    let has_sigma_z = !has_posterior && rows.iter().any(|(r, _)| r.sigma_z_m.is_some());
    let has_rotation = rows
        .iter()
        .any(|(r, _)| r.yaw_deg != 0.0 || r.pitch_deg != 0.0 || r.roll_deg != 0.0);
    let mut header = RECORDING_COLUMNS.to_vec();
    if has_sigma_xy {
        header.push("sigma_xy");
    }
    if has_sigma_z {
        header.push("sigma_z");
    }
    if has_rotation {
        header.extend(["yaw", "pitch", "roll"]);
    }
    if has_posterior {
        header.extend(["sigma_x", "sigma_y", "sigma_z"]);
    }
    // Validate before opening the file so nothing is half-written.
    let mut times = Vec::with_capacity(rows.len());
    for (r, _) in rows {
        let time = if r.time.is_empty() {
            format_time_iso(r.time_s).ok_or_else(|| {
                io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!(
                        "recording '{}': empty time and time_s {} cannot be formatted",
                        r.image_id, r.time_s
                    ),
                )
            })?
        } else {
            r.time.clone()
        };
        times.push(time);
    }
    atomic_write_with(path, |w| {
        write_line(w, header.iter().map(|h| h.to_string()))?;
        let mut cells: Vec<String> = Vec::with_capacity(header.len());
        for ((r, sigma), time) in rows.iter().zip(&times) {
            cells.clear();
            cells.extend([quote(&r.image_id), quote(&r.file), quote(time)]);
            cells.extend([r.x, r.y, r.z, r.heading_deg, r.camera_height_m].map(num));
            if has_sigma_xy {
                cells.push(opt(r.sigma_xy_m));
            }
            if has_sigma_z {
                cells.push(opt(r.sigma_z_m));
            }
            if has_rotation {
                cells.extend([r.yaw_deg, r.pitch_deg, r.roll_deg].map(num));
            }
            if has_posterior {
                match sigma {
                    Some(s) => cells.extend(s.map(num)),
                    None => cells.extend(["", "", ""].map(String::from)),
                }
            }
            write_line(w, cells.drain(..))?;
        }
        Ok(())
    })
}

/// `aerial/{nadir,oblique}/cameras.csv`. Distortion columns appear only if some coefficient is non-zero (the
/// extended ones `k3, k4, b1, b2` only if one of them is), `sigma_px` only if some row differs from the default
/// 0.5.
pub fn write_aerial_cameras_csv(path: &Path, rows: &[AerialImage]) -> io::Result<()> {
    let has_distortion = rows.iter().any(|a| {
        [a.k1, a.k2, a.p1, a.p2, a.k3, a.k4, a.b1, a.b2]
            .iter()
            .any(|&c| c != 0.0)
    });
    let has_extended = rows
        .iter()
        .any(|a| a.k3 != 0.0 || a.k4 != 0.0 || a.b1 != 0.0 || a.b2 != 0.0);
    let has_sigma = rows.iter().any(|a| a.sigma_px != 0.5);
    let mut header = vec![
        "image_id", "file", "x", "y", "z", "omega", "phi", "kappa", "focal_px", "cx", "cy",
        "width", "height",
    ];
    if has_distortion {
        header.extend(["k1", "k2", "p1", "p2"]);
    }
    if has_extended {
        header.extend(["k3", "k4", "b1", "b2"]);
    }
    if has_sigma {
        header.push("sigma_px");
    }
    atomic_write_with(path, |w| {
        write_line(w, header.iter().map(|h| h.to_string()))?;
        let mut cells: Vec<String> = Vec::with_capacity(header.len());
        for a in rows {
            cells.clear();
            cells.extend([quote(&a.image_id), quote(&a.file)]);
            cells.extend(
                [
                    a.x,
                    a.y,
                    a.z,
                    a.omega_deg,
                    a.phi_deg,
                    a.kappa_deg,
                    a.focal_px,
                    a.cx_px,
                    a.cy_px,
                ]
                .map(num),
            );
            cells.extend([a.width_px.to_string(), a.height_px.to_string()]);
            if has_distortion {
                cells.extend([a.k1, a.k2, a.p1, a.p2].map(num));
            }
            if has_extended {
                cells.extend([a.k3, a.k4, a.b1, a.b2].map(num));
            }
            if has_sigma {
                cells.push(num(a.sigma_px));
            }
            write_line(w, cells.drain(..))?;
        }
        Ok(())
    })
}

/// `control/checkpoints.csv`; `sigma_xy`, `sigma_z` only if some row has them.
pub fn write_checkpoints_csv(path: &Path, rows: &[CheckPoint]) -> io::Result<()> {
    let has_sigma_xy = rows.iter().any(|c| c.sigma_xy_m.is_some());
    let has_sigma_z = rows.iter().any(|c| c.sigma_z_m.is_some());
    let mut header = vec!["point_id", "x", "y", "z"];
    if has_sigma_xy {
        header.push("sigma_xy");
    }
    if has_sigma_z {
        header.push("sigma_z");
    }
    atomic_write_with(path, |w| {
        write_line(w, header.iter().map(|h| h.to_string()))?;
        for c in rows {
            let mut cells = vec![quote(&c.point_id), num(c.x), num(c.y), num(c.z)];
            if has_sigma_xy {
                cells.push(opt(c.sigma_xy_m));
            }
            if has_sigma_z {
                cells.push(opt(c.sigma_z_m));
            }
            write_line(w, cells.into_iter())?;
        }
        Ok(())
    })
}

/// `control/observations.csv`.
pub fn write_observations_csv(path: &Path, rows: &[Observation]) -> io::Result<()> {
    atomic_write_with(path, |w| {
        write_line(
            w,
            ["point_id", "image_id", "u", "v"]
                .into_iter()
                .map(String::from),
        )?;
        for o in rows {
            write_line(
                w,
                [
                    quote(&o.point_id),
                    quote(&o.image_id),
                    num(o.u_px),
                    num(o.v_px),
                ]
                .into_iter(),
            )?;
        }
        Ok(())
    })
}

/// `trajectory.geojson`: one FeatureCollection with a Point feature per layer point (property `layer` plus the
/// point's properties) and, for layers with `line`, one LineString feature. Coordinates are in the campaign
/// CRS, named by the legacy `crs` member (`urn:ogc:def:crs:EPSG::28992`), which is what QGIS reads for
/// non-WGS84 GeoJSON. One feature per line.
pub fn write_trajectory_geojson(path: &Path, layers: &[GeoJsonLayer]) -> io::Result<()> {
    use serde_json::{json, Value};
    let crs = layers
        .iter()
        .map(|l| l.crs.as_str())
        .find(|c| !c.is_empty())
        .unwrap_or("");
    if let Some(other) = layers.iter().find(|l| !l.crs.is_empty() && l.crs != crs) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "GeoJSON layers disagree on the CRS: '{crs}' and '{}' (layer '{}')",
                other.crs, other.name
            ),
        ));
    }
    let coords = |p: &[f64; 3]| -> io::Result<Value> {
        if p.iter().all(|v| v.is_finite()) {
            Ok(json!([p[0], p[1], p[2]]))
        } else {
            Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("non-finite GeoJSON coordinate {p:?}"),
            ))
        }
    };
    let mut features: Vec<String> = Vec::new();
    for layer in layers {
        for p in &layer.points {
            let mut props: serde_json::Map<String, Value> = p
                .properties
                .iter()
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect();
            props.insert("layer".into(), Value::String(layer.name.clone()));
            let f = json!({"type": "Feature", "properties": props,
                           "geometry": {"type": "Point", "coordinates": coords(&p.xyz_world)?}});
            features.push(serde_json::to_string(&f).map_err(io::Error::other)?);
        }
        if layer.line && layer.points.len() >= 2 {
            let line: Vec<Value> = layer
                .points
                .iter()
                .map(|p| coords(&p.xyz_world))
                .collect::<io::Result<_>>()?;
            let f = json!({"type": "Feature", "properties": {"layer": layer.name},
                           "geometry": {"type": "LineString", "coordinates": line}});
            features.push(serde_json::to_string(&f).map_err(io::Error::other)?);
        }
    }
    let mut head = serde_json::Map::new();
    head.insert("type".into(), json!("FeatureCollection"));
    if !crs.is_empty() {
        head.insert(
            "crs".into(),
            json!({"type": "name", "properties": {"name": crs_urn(crs)}}),
        );
    }
    let head = serde_json::to_string(&Value::Object(head)).map_err(io::Error::other)?;
    atomic_write_with(path, |w| {
        // `{"type":..,"crs":..}` opened up to append the features member.
        w.write_all(&head.as_bytes()[..head.len() - 1])?;
        w.write_all(b",\"features\":[\n")?;
        for (i, f) in features.iter().enumerate() {
            w.write_all(f.as_bytes())?;
            w.write_all(if i + 1 < features.len() {
                b",\n"
            } else {
                b"\n"
            })?;
        }
        w.write_all(b"]}\n")
    })
}

/// `EPSG:28992` → `urn:ogc:def:crs:EPSG::28992`; anything else is passed through unchanged.
fn crs_urn(crs: &str) -> String {
    match crs.split_once(':') {
        Some((auth, code))
            if auth.eq_ignore_ascii_case("EPSG") && code.chars().all(|c| c.is_ascii_digit()) =>
        {
            format!("urn:ogc:def:crs:EPSG::{code}")
        }
        _ => crs.to_string(),
    }
}

/// `tie_points.ply`: binary_little_endian 1.0; per vertex x, y, z (double), red, green, blue (uchar),
/// source (int) — 31 bytes per vertex after the ASCII header.
pub fn write_ply(path: &Path, points: &[PlyPoint]) -> io::Result<()> {
    atomic_write_with(path, |w| {
        write!(
            w,
            "ply\nformat binary_little_endian 1.0\ncomment skytie tie points, world frame, metres\n\
             element vertex {}\nproperty double x\nproperty double y\nproperty double z\n\
             property uchar red\nproperty uchar green\nproperty uchar blue\nproperty int source\nend_header\n",
            points.len()
        )?;
        let mut record = [0u8; 31];
        for p in points {
            for (k, v) in p.xyz_world.iter().enumerate() {
                record[8 * k..8 * k + 8].copy_from_slice(&v.to_le_bytes());
            }
            record[24..27].copy_from_slice(&p.rgb);
            record[27..31].copy_from_slice(&p.source.to_le_bytes());
            w.write_all(&record)?;
        }
        Ok(())
    })
}

/// Shortest representation that parses back to the same f64.
fn num(v: f64) -> String {
    format!("{v}")
}

fn opt(v: Option<f64>) -> String {
    v.map(num).unwrap_or_default()
}

fn write_line<W: Write>(w: &mut W, cells: impl Iterator<Item = String>) -> io::Result<()> {
    for (i, c) in cells.enumerate() {
        if i > 0 {
            w.write_all(b",")?;
        }
        w.write_all(c.as_bytes())?;
    }
    w.write_all(b"\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_round_trip_exactly() {
        for v in [
            155_000.123_456_789_f64,
            0.1 + 0.2,
            -1e-300,
            463_512.000_000_1,
        ] {
            assert_eq!(num(v).parse::<f64>().unwrap(), v);
        }
    }

    #[test]
    fn crs_names_become_ogc_urns() {
        assert_eq!(crs_urn("EPSG:28992"), "urn:ogc:def:crs:EPSG::28992");
        assert_eq!(crs_urn("local"), "local");
    }
}
