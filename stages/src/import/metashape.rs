//! Metashape camera XML → poses: camera centre and axes from the camera transform and the chunk transform in
//! earth-centred coordinates of the chunk CRS's datum, then latitude/longitude/ellipsoidal height and
//! east-north-up axes there; the converter takes them into the campaign CRS like any geographic source.

use super::config::AerialSource;
use super::context::ImportContext;
use super::report::SourceReport;
use super::source_pose::{missing, SourcePose};
use crate::campaign::Problem;
use crate::crs::{Crs, Ellipsoid};
use crate::formats::camera_model::CameraModel;
use crate::formats::metashape_xml::{read_metashape_xml, wkt_epsg_code, ChunkTransform};
use crate::formats::opk_list::PoseRow;
use nalgebra::{Matrix3, Vector3};

/// Metashape camera axes (x right, y down, z forward) → skytie's (x right, y up, z backwards).
fn flip_yz() -> Matrix3<f64> {
    Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0))
}

/// Read the XML; the returned poses are latitude/longitude (°) with ellipsoidal heights on the chunk CRS's
/// datum and camera→ENU rotations, and the CRS text names that geographic system.
pub(crate) fn read_metashape_poses(
    src: &AerialSource,
    ctx: &ImportContext,
    report: &mut SourceReport,
) -> Option<(Vec<SourcePose>, Option<String>)> {
    let (doc, problems) = match read_metashape_xml(&src.orientations) {
        Ok(d) => d,
        Err(p) => {
            report.problems.extend(p);
            return None;
        }
    };
    report.read = doc.cameras.len() + problems.len();
    report.problems.extend(problems);
    let Some(chunk) = doc.chunk_transform else {
        report.problems.push(Problem::error(
            &src.orientations,
            None,
            Some("transform"),
            "the chunk has no transform: its cameras are in an arbitrary local frame",
            "georeference the chunk in Metashape (markers or camera reference) before exporting",
        ));
        return None;
    };
    let code = match (
        &src.crs,
        doc.reference_wkt.as_deref().and_then(wkt_epsg_code),
    ) {
        (Some(c), _) => c.clone(),
        (None, Some(code)) => format!("EPSG:{code}"),
        (None, None) => {
            report.problems.push(missing(&src.orientations, "crs", "the chunk's <reference> has no EPSG code: give the chunk CRS as crs = \"EPSG:...\""));
            return None;
        }
    };
    let chunk_crs = match Crs::parse(&code) {
        Ok(c) => c,
        Err(e) => {
            report.problems.push(Problem::error(
                &src.orientations,
                None,
                Some("reference"),
                e.to_string(),
                "",
            ));
            return None;
        }
    };
    let geographic = chunk_crs.own_geographic();
    report.notes.push(format!(
        "Metashape chunk CRS {code}; geocentric coordinates on its datum (ellipsoid a = {} m)",
        geographic.ellipsoid.a_m
    ));
    let _ = ctx;
    let mut poses = Vec::with_capacity(doc.cameras.len());
    for cam in &doc.cameras {
        let Some(sensor) = doc.sensors.iter().find(|s| s.id == cam.sensor_id) else {
            report.problems.push(Problem::error(
                &src.orientations,
                Some(cam.line),
                Some("sensor_id"),
                format!(
                    "camera '{}' refers to sensor '{}', which does not exist; skipped",
                    cam.label, cam.sensor_id
                ),
                "export the cameras again",
            ));
            continue;
        };
        let (pose, _) = camera_pose(&chunk, &cam.transform, &geographic.ellipsoid);
        poses.push(SourcePose {
            pose: PoseRow {
                line: cam.line,
                image: cam.label.clone(),
                ..pose
            },
            camera: CameraModel::from_metashape(&sensor.calibration),
        });
    }
    // The converter works from the chunk datum's geographic 3D system with ellipsoidal heights.
    report.notes.push(
        "heights: ellipsoidal on the chunk datum, reduced with the campaign's geoid model".into(),
    );
    Some((poses, Some(format!("geographic:{code}"))))
}

/// Pose of one camera: latitude, longitude (°), ellipsoidal height and camera→ENU rotation (skytie axes);
/// also returns the ECEF centre.
pub(crate) fn camera_pose(
    chunk: &ChunkTransform,
    camera_to_chunk: &nalgebra::Matrix4<f64>,
    ellipsoid: &Ellipsoid,
) -> (PoseRow, Vector3<f64>) {
    let r_cam = camera_to_chunk.fixed_view::<3, 3>(0, 0).into_owned();
    let c_chunk = camera_to_chunk.fixed_view::<3, 1>(0, 3).into_owned();
    let centre = chunk.scale * chunk.rotation * c_chunk + chunk.translation;
    // Directions: the chunk rotation (scale is isotropic); re-orthonormalise the camera block (it carries
    // no scale in Metashape's exports).
    let axes_ecef = chunk.rotation * r_cam * flip_yz();
    let (lat, lon, h) = ellipsoid.from_ecef(&centre);
    let r_enu = Ellipsoid::enu_to_ecef(lat, lon).transpose() * axes_ecef;
    let svd = r_enu.svd(true, true);
    let r_enu = svd.u.expect("u") * svd.v_t.expect("v_t");
    (
        PoseRow {
            line: 0,
            image: String::new(),
            a: lat,
            b: lon,
            z: h,
            rotation: r_enu,
        },
        centre,
    )
}
