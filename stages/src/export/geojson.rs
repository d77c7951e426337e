//! `trajectory.geojson` (QGIS; campaign CRS through the legacy `crs` member, see
//! [`crate::campaign::write_trajectory_geojson`]): layer `recorded` (recorded positions, with the
//! verification status of their segment when given), layer `adjusted` (adjusted positions with correction,
//! posterior σ and flag `large_correction` when the horizontal correction exceeds 3 × its prior σ), each
//! joined by a line, and layer `checkpoints` (surveyed positions with 2-D errors before/after and flag
//! `improved`).

use super::checkpoints::CheckPointRow;
use crate::adjustment::verify::Verification;
use crate::adjustment::AdjustmentRun;
use crate::campaign::{
    write_trajectory_geojson, CheckPoint, GeoJsonLayer, GeoJsonPoint, Recording,
};
use serde_json::{json, Value};
use std::collections::{BTreeMap, HashMap};
use std::io;
use std::path::Path;

/// Prior σ of X/Y assumed for the `large_correction` flag when the recording has no `sigma_xy`, metres.
const FLAG_DEFAULT_SIGMA_XY_M: f64 = 1.0;

fn props(pairs: impl IntoIterator<Item = (&'static str, Value)>) -> BTreeMap<String, Value> {
    pairs.into_iter().map(|(k, v)| (k.to_string(), v)).collect()
}

/// Verification status per recording index (from the segments' first/last image ids).
fn status_per_recording(recordings: &[Recording], v: &Verification) -> Vec<Option<&'static str>> {
    let mut out = vec![None; recordings.len()];
    // First row of each id (as a linear search would find it).
    let mut index: HashMap<&str, usize> = HashMap::with_capacity(recordings.len());
    for (i, r) in recordings.iter().enumerate() {
        index.entry(r.image_id.as_str()).or_insert(i);
    }
    for s in &v.segments {
        let first = index.get(s.first_image_id.as_str());
        let last = index.get(s.last_image_id.as_str());
        if let (Some(&a), Some(&b)) = (first, last) {
            for slot in out.iter_mut().take(b + 1).skip(a) {
                *slot = Some(s.status.label());
            }
        }
    }
    out
}

/// Writes `trajectory.geojson` (atomically). `checkpoints`/`rows` and `verification` are optional layers and
/// properties.
pub fn write_run_geojson(
    path: &Path,
    crs: &str,
    recordings: &[Recording],
    run: &AdjustmentRun,
    checkpoints: &[CheckPoint],
    rows: &[CheckPointRow],
    verification: Option<&Verification>,
) -> io::Result<()> {
    let adjusted = super::trajectory::adjusted_recordings(recordings, run)?;
    let status = verification.map(|v| status_per_recording(recordings, v));
    let recorded_layer = GeoJsonLayer {
        name: "recorded".to_string(),
        crs: crs.to_string(),
        points: recordings
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let mut p = props([("image_id", json!(r.image_id)), ("time", json!(r.time))]);
                if let Some(s) = status.as_ref().and_then(|s| s[i]) {
                    p.insert("verification".to_string(), json!(s));
                }
                GeoJsonPoint {
                    xyz_world: [r.x, r.y, r.z],
                    properties: p,
                }
            })
            .collect(),
        line: true,
    };
    let adjusted_layer = GeoJsonLayer {
        name: "adjusted".to_string(),
        crs: crs.to_string(),
        points: recordings
            .iter()
            .zip(&adjusted)
            .zip(&run.recordings)
            .map(|((r, (a, sigma)), rr)| {
                let shift = [a.x - r.x, a.y - r.y, a.z - r.z];
                let shift_2d = shift[0].hypot(shift[1]);
                let prior = r.sigma_xy_m.unwrap_or(FLAG_DEFAULT_SIGMA_XY_M);
                GeoJsonPoint {
                    xyz_world: [a.x, a.y, a.z],
                    properties: props([
                        ("image_id", json!(r.image_id)),
                        ("dx", json!(shift[0])),
                        ("dy", json!(shift[1])),
                        ("dz", json!(shift[2])),
                        ("correction_2d", json!(shift_2d)),
                        ("yaw_correction_deg", json!(rr.yaw_correction_deg)),
                        ("sigma_x", json!(sigma[0])),
                        ("sigma_y", json!(sigma[1])),
                        ("sigma_z", json!(sigma[2])),
                        ("large_correction", json!(shift_2d > 3.0 * prior)),
                    ]),
                }
            })
            .collect(),
        line: true,
    };
    let mut layers = vec![recorded_layer, adjusted_layer];
    let mut row_of: HashMap<&str, &CheckPointRow> = HashMap::with_capacity(rows.len());
    for r in rows {
        row_of.entry(r.point_id.as_str()).or_insert(r);
    }
    if !checkpoints.is_empty() {
        layers.push(GeoJsonLayer {
            name: "checkpoints".to_string(),
            crs: crs.to_string(),
            points: checkpoints
                .iter()
                .map(|c| {
                    let row = row_of.get(c.point_id.as_str());
                    let before = row.and_then(|r| r.before).map(|e| e.d2());
                    let after = row.and_then(|r| r.after).map(|e| e.d2());
                    let improved = match (before, after) {
                        (Some(b), Some(a)) => json!(a < b),
                        _ => Value::Null,
                    };
                    GeoJsonPoint {
                        xyz_world: [c.x, c.y, c.z],
                        properties: props([
                            ("point_id", json!(c.point_id)),
                            ("error_2d_before", json!(before)),
                            ("error_2d_after", json!(after)),
                            ("improved", improved),
                        ]),
                    }
                })
                .collect(),
            line: false,
        });
    }
    write_trajectory_geojson(path, &layers)
}
