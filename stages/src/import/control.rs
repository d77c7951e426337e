//! Check points and their panorama measurements → `control/checkpoints.csv` and `control/observations.csv`.

use super::config::ControlSource;
use super::context::ImportContext;
use super::report::SourceReport;
use crate::campaign::{CheckPoint, Observation, Problem};
use crate::formats::points::{read_measurements, read_points};
use std::collections::HashSet;

/// Import the points (in the campaign CRS) and the measurements of known points in known panoramas.
pub fn import_control(
    src: &ControlSource,
    ctx: &ImportContext,
    panorama_ids: &HashSet<String>,
) -> (Vec<CheckPoint>, Vec<Observation>, Vec<SourceReport>) {
    let mut report = SourceReport::new("check points", &src.points);
    let mut points = Vec::new();
    match ctx.converter(src.crs.as_deref(), src.heights.as_deref()) {
        Err(p) => report.problems.push(p),
        Ok(conv) => {
            let (rows, problems) = read_points(&src.points, &src.layout);
            report.read = rows.len() + problems.iter().filter(|p| p.row.is_some()).count();
            report.problems.extend(problems);
            for r in rows {
                match conv.position(r.a, r.b, r.z) {
                    Ok((x, y, z)) => points.push(CheckPoint {
                        point_id: r.id,
                        x,
                        y,
                        z,
                        sigma_xy_m: r.sigma_xy_m,
                        sigma_z_m: r.sigma_z_m,
                    }),
                    Err(e) => report.problems.push(Problem::error(
                        &src.points,
                        Some(r.line),
                        Some(&src.layout.x),
                        e.to_string(),
                        "check the point's CRS",
                    )),
                }
            }
        }
    }
    report.converted = points.len();
    let mut reports = vec![report];
    let mut observations = Vec::new();
    if let Some(path) = &src.measurements {
        let mut m_report = SourceReport::new("image measurements", path);
        match &src.measurement_layout {
            None => m_report.problems.push(Problem::error(
                "import configuration",
                None,
                Some("control.measurement_layout"),
                "is required with control.measurements",
                "describe the columns of the measurement file",
            )),
            Some(layout) => {
                let known: HashSet<&str> = points.iter().map(|p| p.point_id.as_str()).collect();
                let (rows, problems) = read_measurements(path, layout);
                m_report.read = rows.len() + problems.iter().filter(|p| p.row.is_some()).count();
                m_report.problems.extend(problems);
                for r in rows {
                    let stem = std::path::Path::new(&r.image)
                        .file_stem()
                        .map(|s| s.to_string_lossy().into_owned())
                        .unwrap_or_else(|| r.image.clone());
                    // (field, message, hint) of a measurement that is skipped.
                    let skipped = if !known.contains(r.point.as_str()) {
                        Some((
                            &layout.point,
                            format!("point '{}' is not in the point list; skipped", r.point),
                            "measure only listed points",
                        ))
                    } else if !panorama_ids.contains(&stem) {
                        Some((
                            &layout.image,
                            format!("panorama '{}' was not imported; skipped", r.image),
                            "measure in imported panoramas",
                        ))
                    } else {
                        None
                    };
                    match skipped {
                        Some((field, message, hint)) => m_report.problems.push(Problem::error(
                            path,
                            Some(r.line),
                            Some(field),
                            message,
                            hint,
                        )),
                        None => observations.push(Observation {
                            point_id: r.point,
                            image_id: stem,
                            u_px: r.u_px,
                            v_px: r.v_px,
                        }),
                    }
                }
            }
        }
        m_report.converted = observations.len();
        reports.push(m_report);
    }
    (points, observations, reports)
}
