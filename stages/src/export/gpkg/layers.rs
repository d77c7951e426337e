//! The layers of `skytie.gpkg`, all in the campaign's world frame (x east, y north, z up, metres):
//!
//! | layer | geometry | one feature per |
//! |---|---|---|
//! | `recordings_recorded` | POINT Z | recording, at its recorded position |
//! | `recordings_adjusted` | POINT Z | recording, at its adjusted position |
//! | `corrections` | LINESTRING Z | recording, from the recorded to the adjusted position |
//! | `control_points` | POINT Z | aerial control point, at its aerial triangulation |
//! | `check_points` | POINT Z | surveyed check point |
//! | `verification_segments` | LINESTRING Z | trajectory segment × trajectory (`recorded` / `adjusted`) |
//!
//! Corrections and residuals follow one sign convention: adjusted (or estimated) minus recorded (or
//! reference), i.e. what was added.

use super::writer::{FieldType, Geometry, GeometryType, Layer, Value};
use crate::adjustment::verify::Verification;
use crate::adjustment::AdjustmentRun;
use crate::campaign::{CheckPoint, Recording};
use crate::correction::support::recording_support;
use crate::correspondence::AerialControlPoint;
use crate::export::checkpoints::CheckPointRow;
use crate::export::control_status::ControlStatuses;
use crate::export::corrections::CorrectionSeries;
use crate::positions::positions_by;
use std::collections::HashMap;

/// Everything the layers are made of.
pub struct RunLayers<'a> {
    pub recordings: &'a [Recording],
    pub run: &'a AdjustmentRun,
    pub series: &'a CorrectionSeries,
    pub checkpoints: &'a [CheckPoint],
    pub checkpoint_rows: &'a [CheckPointRow],
    /// (source label, control points).
    pub control: &'a [(&'a str, &'a [AerialControlPoint])],
    /// Verification with the recorded poses, and with the adjusted ones.
    pub verification: Option<&'a Verification>,
    pub verification_adjusted: Option<&'a Verification>,
}

fn fields(spec: &[(&str, FieldType)]) -> Vec<(String, FieldType)> {
    spec.iter().map(|(n, t)| (n.to_string(), *t)).collect()
}

fn text(s: &str) -> Value {
    Value::Text(s.to_string())
}

fn real(v: f64) -> Value {
    Value::Real(Some(v))
}

fn opt(v: Option<f64>) -> Value {
    Value::Real(v)
}

fn int(v: usize) -> Value {
    Value::Int(Some(v as i64))
}

/// Per recording index: (status, mean horizontal offset) of its segment in `v`.
fn segment_status(recordings: &[Recording], v: Option<&Verification>) -> Vec<(Value, Value)> {
    let mut out = vec![(Value::Text(String::new()), Value::Real(None)); recordings.len()];
    let Some(v) = v else {
        return out;
    };
    let index = positions_by(recordings, |r| r.image_id.as_str());
    for s in &v.segments {
        if let (Some(&a), Some(&b)) = (
            index.get(s.first_image_id.as_str()),
            index.get(s.last_image_id.as_str()),
        ) {
            for slot in out.iter_mut().take(b + 1).skip(a) {
                *slot = (text(s.status.label()), real(s.offset_2d_m));
            }
        }
    }
    out
}

/// The layers of the module doc.
pub fn run_layers(x: &RunLayers<'_>) -> Vec<Layer> {
    let mut layers = recording_layers(x);
    layers.push(control_layer(x));
    layers.push(checkpoint_layer(x));
    layers.push(verification_layer(x));
    layers
}

fn recording_layers(x: &RunLayers<'_>) -> Vec<Layer> {
    let support = recording_support(x.run);
    let before = segment_status(x.recordings, x.verification);
    let after = segment_status(x.recordings, x.verification_adjusted);
    let mut recorded = Layer {
        name: "recordings_recorded".into(),
        geometry: GeometryType::Point,
        description: "recorded panorama positions (mm/recordings.csv)".into(),
        fields: fields(&[
            ("image_id", FieldType::Text),
            ("time", FieldType::Text),
            ("correction", FieldType::Text),
            ("verification", FieldType::Text),
            ("verification_offset_2d_m", FieldType::Real),
        ]),
        features: Vec::new(),
    };
    let mut adjusted = Layer {
        name: "recordings_adjusted".into(),
        geometry: GeometryType::Point,
        description: "adjusted panorama positions with posterior sigma".into(),
        fields: fields(&[
            ("image_id", FieldType::Text),
            ("time", FieldType::Text),
            ("correction", FieldType::Text),
            ("control_points", FieldType::Integer),
            ("dx_m", FieldType::Real),
            ("dy_m", FieldType::Real),
            ("dz_m", FieldType::Real),
            ("d2d_m", FieldType::Real),
            ("dyaw_deg", FieldType::Real),
            ("sigma_x_m", FieldType::Real),
            ("sigma_y_m", FieldType::Real),
            ("sigma_z_m", FieldType::Real),
            ("sigma_yaw_deg", FieldType::Real),
            ("sigma_a_posteriori", FieldType::Integer),
            ("verification", FieldType::Text),
            ("verification_offset_2d_m", FieldType::Real),
        ]),
        features: Vec::new(),
    };
    let mut vectors = Layer {
        name: "corrections".into(),
        geometry: GeometryType::LineString,
        description: "correction vectors, recorded to adjusted position".into(),
        fields: fields(&[
            ("image_id", FieldType::Text),
            ("correction", FieldType::Text),
            ("d2d_m", FieldType::Real),
            ("dz_m", FieldType::Real),
        ]),
        features: Vec::new(),
    };
    for (i, (r, a)) in x.recordings.iter().zip(&x.run.recordings).enumerate() {
        let s = support[i].support.label();
        let c = &x.series.recordings[i].correction;
        let [dx, dy, dz] = c.delta_enu_m;
        let d2 = dx.hypot(dy);
        recorded.features.push((
            Geometry::PointZ(a.recorded_world),
            vec![
                text(&r.image_id),
                text(&r.time),
                text(s),
                before[i].0.clone(),
                before[i].1.clone(),
            ],
        ));
        let [sx, sy, sz] = a.sigma_m;
        adjusted.features.push((
            Geometry::PointZ(a.adjusted_world),
            vec![
                text(&r.image_id),
                text(&r.time),
                text(s),
                int(support[i].control_points),
                real(dx),
                real(dy),
                real(dz),
                real(d2),
                real(c.delta_yaw_deg),
                real(sx),
                real(sy),
                real(sz),
                real(a.sigma_yaw_deg),
                int(usize::from(a.sigma_is_a_posteriori)),
                after[i].0.clone(),
                after[i].1.clone(),
            ],
        ));
        vectors.features.push((
            Geometry::LineStringZ(vec![a.recorded_world, a.adjusted_world]),
            vec![text(&r.image_id), text(s), real(d2), real(dz)],
        ));
    }
    vec![recorded, adjusted, vectors]
}

fn control_layer(x: &RunLayers<'_>) -> Layer {
    let adjusted: HashMap<&str, [f64; 3]> = x
        .run
        .points
        .iter()
        .filter(|p| p.determined)
        .map(|p| (p.point.id.as_str(), p.position_world))
        .collect();
    let mut l = Layer {
        name: "control_points".into(),
        geometry: GeometryType::Point,
        description: "aerial control points at their aerial triangulation".into(),
        fields: fields(&[
            ("source", FieldType::Text),
            ("point_id", FieldType::Text),
            ("sigma_x_m", FieldType::Real),
            ("sigma_y_m", FieldType::Real),
            ("sigma_z_m", FieldType::Real),
            ("aerial_observations", FieldType::Integer),
            ("panorama_observations", FieldType::Integer),
            ("residual_x_m", FieldType::Real),
            ("residual_y_m", FieldType::Real),
            ("residual_z_m", FieldType::Real),
            ("status", FieldType::Text),
        ]),
        features: Vec::new(),
    };
    let statuses = ControlStatuses::of(Some(x.run));
    for &(source, points) in x.control {
        for p in points {
            let Some(xyz) = p.point_world else {
                continue;
            };
            let sigma = p
                .covariance_m2
                .map(|c| [0, 1, 2].map(|k| Some(c[k][k].max(0.0).sqrt())))
                .unwrap_or([None; 3]);
            let res = adjusted
                .get(p.tie_point_id.as_str())
                .map(|a| [0, 1, 2].map(|k| Some(a[k] - xyz[k])))
                .unwrap_or([None; 3]);
            let mut values = vec![text(source), text(&p.tie_point_id)];
            values.extend(sigma.map(opt));
            values.extend([int(p.aerial.len()), int(p.mm.len())]);
            values.extend(res.map(opt));
            values.push(text(statuses.get(&p.tie_point_id).as_str()));
            l.features.push((Geometry::PointZ(xyz), values));
        }
    }
    l
}

fn checkpoint_layer(x: &RunLayers<'_>) -> Layer {
    let rows: HashMap<&str, &CheckPointRow> = x
        .checkpoint_rows
        .iter()
        .map(|r| (r.point_id.as_str(), r))
        .collect();
    let mut l = Layer {
        name: "check_points".into(),
        geometry: GeometryType::Point,
        description:
            "surveyed check points with their errors (estimated - surveyed) before and after".into(),
        fields: fields(&[
            ("point_id", FieldType::Text),
            ("views_before", FieldType::Integer),
            ("error_x_before_m", FieldType::Real),
            ("error_y_before_m", FieldType::Real),
            ("error_z_before_m", FieldType::Real),
            ("error_2d_before_m", FieldType::Real),
            ("views_after", FieldType::Integer),
            ("error_x_after_m", FieldType::Real),
            ("error_y_after_m", FieldType::Real),
            ("error_z_after_m", FieldType::Real),
            ("error_2d_after_m", FieldType::Real),
            ("note", FieldType::Text),
        ]),
        features: Vec::new(),
    };
    for cp in x.checkpoints {
        let row = rows.get(cp.point_id.as_str());
        let mut values = vec![text(&cp.point_id)];
        for e in [row.and_then(|r| r.before), row.and_then(|r| r.after)] {
            values.push(Value::Int(e.map(|e| e.views as i64)));
            values.extend([0, 1, 2].map(|k| opt(e.map(|e| e.error_m[k]))));
            values.push(opt(e.map(|e| e.d2())));
        }
        values.push(text(row.map_or("not evaluated", |r| r.note.as_str())));
        l.features
            .push((Geometry::PointZ([cp.x, cp.y, cp.z]), values));
    }
    l
}

fn verification_layer(x: &RunLayers<'_>) -> Layer {
    let mut l = Layer {
        name: "verification_segments".into(),
        geometry: GeometryType::LineString,
        description:
            "per trajectory segment: MM minus aerial control-point offsets (thesis Table 5-13)"
                .into(),
        fields: fields(&[
            ("trajectory", FieldType::Text),
            ("segment", FieldType::Integer),
            ("first_image_id", FieldType::Text),
            ("last_image_id", FieldType::Text),
            ("recordings", FieldType::Integer),
            ("points", FieldType::Integer),
            ("mean_x_m", FieldType::Real),
            ("mean_y_m", FieldType::Real),
            ("mean_z_m", FieldType::Real),
            ("offset_2d_m", FieldType::Real),
            ("status", FieldType::Text),
        ]),
        features: Vec::new(),
    };
    let index = positions_by(x.recordings, |r| r.image_id.as_str());
    for (name, v) in [
        ("recorded", x.verification),
        ("adjusted", x.verification_adjusted),
    ] {
        let Some(v) = v else {
            continue;
        };
        for s in &v.segments {
            let (Some(&a), Some(&b)) = (
                index.get(s.first_image_id.as_str()),
                index.get(s.last_image_id.as_str()),
            ) else {
                continue;
            };
            let line: Vec<[f64; 3]> = x.run.recordings[a..=b]
                .iter()
                .map(|r| {
                    if name == "recorded" {
                        r.recorded_world
                    } else {
                        r.adjusted_world
                    }
                })
                .collect();
            // A one-recording segment is drawn as a degenerate line, so every segment has a feature.
            let line = if line.len() == 1 {
                vec![line[0]; 2]
            } else {
                line
            };
            let mut values = vec![
                text(name),
                int(s.index),
                text(&s.first_image_id),
                text(&s.last_image_id),
                int(s.recordings),
                int(s.points),
            ];
            values.extend(s.mean_m.map(real));
            values.extend([real(s.offset_2d_m), text(s.status.label())]);
            l.features.push((Geometry::LineStringZ(line), values));
        }
    }
    l
}
