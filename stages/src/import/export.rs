//! Campaign → vendor files, the inverses of the importers: ω-φ-κ lists (Pix4D, Metashape, generic), Pix4D
//! internals, Metashape camera XML, and a trajectory as an Applanix SBET with an image event file. They let
//! skytie deliver results in the formats surveyors use and let tests export a known campaign and import it
//! back.

use super::context::ImportContext;
use super::convert::{ConvertError, Inverse};
use super::pose::{body_to_ned, panorama_angles, panorama_matrix, LeverArm};
use crate::campaign::{AerialImage, Recording};
use crate::crs::{Crs, Ellipsoid, HeightKind};
use crate::formats::camera_model::CameraModel;
use crate::formats::gps_time::unix_to_gps;
use crate::formats::metashape_xml::{
    write_metashape_xml, ChunkTransform, MetashapeCamera, MetashapeDocument, MetashapeSensor,
};
use crate::formats::opk_list::{write_opk_list, OpkListFormat, PoseRow};
use crate::formats::pix4d::write_pix4d_cam;
use crate::formats::sbet::{write_sbet, SbetRecord};
use crate::geometry::opk_to_matrix;
use nalgebra::{Matrix3, Matrix4, Vector3};
use std::path::Path;

/// An export that cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("{0}")]
    Setup(String),
    #[error("image '{id}': {source}")]
    Point { id: String, source: ConvertError },
    #[error(transparent)]
    Io(#[from] std::io::Error),
}

pub(crate) fn inverse(
    ctx: &ImportContext,
    crs: &str,
    heights: &str,
) -> Result<Inverse, ExportError> {
    let parse = |t: &str| Crs::parse(t).map_err(|e| ExportError::Setup(e.to_string()));
    let source = match crs.strip_prefix("geographic:") {
        Some(rest) => parse(rest)?.own_geographic(),
        None => parse(crs)?,
    };
    let kind = HeightKind::parse(heights).map_err(ExportError::Setup)?;
    let fwd = super::convert::Converter::new(&source, kind, &ctx.campaign_crs, ctx.geoid.clone())
        .map_err(|e| ExportError::Setup(e.to_string()))?;
    fwd.inverse(&ctx.campaign_crs, kind, ctx.geoid.clone())
        .map_err(|e| ExportError::Setup(e.to_string()))
}

/// Poses of campaign rows in `crs` (native pair, height of kind `heights`, camera→world rotation there).
pub fn aerial_poses(
    rows: &[AerialImage],
    ctx: &ImportContext,
    crs: &str,
    heights: &str,
) -> Result<Vec<PoseRow>, ExportError> {
    let inv = inverse(ctx, crs, heights)?;
    rows.iter()
        .map(|a| {
            let fail = |source: ConvertError| ExportError::Point {
                id: a.image_id.clone(),
                source,
            };
            let (pa, pb, h) = inv.position(a.x, a.y, a.z).map_err(fail)?;
            let r = inv
                .rotation(pa, pb, &opk_to_matrix(a.omega_deg, a.phi_deg, a.kappa_deg))
                .map_err(|e| fail(e.into()))?;
            Ok(PoseRow {
                line: 0,
                image: a.file.clone(),
                a: pa,
                b: pb,
                z: h,
                rotation: r,
            })
        })
        .collect()
}

/// An ω-φ-κ list (any layout) of campaign rows in `crs`.
pub fn export_opk_list(
    rows: &[AerialImage],
    ctx: &ImportContext,
    crs: &str,
    format: &OpkListFormat,
    path: &Path,
) -> Result<(), ExportError> {
    write_opk_list(path, format, &aerial_poses(rows, ctx, crs, "campaign")?)?;
    Ok(())
}

/// The one camera all rows share; `Err` if they differ (each vendor file describes one camera).
fn single_camera(rows: &[AerialImage]) -> Result<CameraModel, ExportError> {
    let first = rows
        .first()
        .map(CameraModel::of_aerial)
        .ok_or_else(|| ExportError::Setup("no images to export".into()))?;
    if rows.iter().any(|r| CameraModel::of_aerial(r) != first) {
        return Err(ExportError::Setup(
            "the images have different interior orientations; export them per camera".into(),
        ));
    }
    Ok(first)
}

/// Pix4D: `<stem>_calibrated_external_camera_parameters.txt` and `<stem>_pix4d_calibrated_internal_camera_
/// parameters.cam` in `dir`, with the given pixel size.
pub fn export_pix4d(
    rows: &[AerialImage],
    ctx: &ImportContext,
    crs: &str,
    pixel_size_mm: f64,
    dir: &Path,
    stem: &str,
) -> Result<(), ExportError> {
    let cam = single_camera(rows)?;
    let internals = cam
        .to_pix4d(pixel_size_mm)
        .map_err(|k| ExportError::Setup(format!("Pix4D's perspective model has no {k}")))?;
    write_pix4d_cam(
        &dir.join(format!(
            "{stem}_pix4d_calibrated_internal_camera_parameters.cam"
        )),
        &internals,
    )?;
    export_opk_list(
        rows,
        ctx,
        crs,
        &OpkListFormat::pix4d(),
        &dir.join(format!("{stem}_calibrated_external_camera_parameters.txt")),
    )
}

/// Metashape camera XML with the chunk in `chunk_crs` (e.g. `EPSG:28992`): cameras in a local frame whose
/// chunk transform is the east-north-up frame at the block centre (a rotation and translation, scale 1).
pub fn export_metashape_xml(
    rows: &[AerialImage],
    ctx: &ImportContext,
    chunk_crs: &str,
    path: &Path,
) -> Result<(), ExportError> {
    let cam = single_camera(rows)?;
    let crs = Crs::parse(chunk_crs).map_err(|e| ExportError::Setup(e.to_string()))?;
    let poses = aerial_poses(rows, ctx, &format!("geographic:{chunk_crs}"), "ellipsoidal")?;
    let ell = crs.ellipsoid;
    let centres: Vec<Vector3<f64>> = poses.iter().map(|p| ell.to_ecef(p.a, p.b, p.z)).collect();
    let mean = centres.iter().sum::<Vector3<f64>>() / centres.len().max(1) as f64;
    let (lat0, lon0, _) = ell.from_ecef(&mean);
    let chunk = ChunkTransform {
        rotation: Ellipsoid::enu_to_ecef(lat0, lon0),
        translation: mean,
        scale: 1.0,
    };
    let flip = Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0));
    let cameras = poses
        .iter()
        .zip(&centres)
        .zip(rows)
        .map(|((p, c), row)| {
            let axes_ms = Ellipsoid::enu_to_ecef(p.a, p.b) * p.rotation * flip;
            let mut t = Matrix4::identity();
            t.fixed_view_mut::<3, 3>(0, 0)
                .copy_from(&(chunk.rotation.transpose() * axes_ms));
            t.fixed_view_mut::<3, 1>(0, 3)
                .copy_from(&(chunk.rotation.transpose() * (c - mean)));
            MetashapeCamera {
                line: 0,
                sensor_id: "0".into(),
                label: row.file.clone(),
                transform: t,
            }
        })
        .collect();
    let wkt = u16::try_from(crs.horizontal_code)
        .ok()
        .and_then(crs_definitions::from_code)
        .map(|d| d.wkt.to_string());
    let doc = MetashapeDocument {
        sensors: vec![MetashapeSensor {
            id: "0".into(),
            label: "camera".into(),
            calibration: cam.to_metashape(),
        }],
        cameras,
        chunk_transform: Some(chunk),
        reference_wkt: wkt,
    };
    write_metashape_xml(path, &doc)?;
    Ok(())
}

/// How a trajectory is exported.
#[derive(Debug, Clone, PartialEq)]
pub struct TrajectoryExport {
    /// Geographic CRS of the SBET, e.g. `EPSG:4937`.
    pub crs: String,
    /// IMU → panorama centre, body frame, m.
    pub lever_arm_m: [f64; 3],
    /// GPS − UTC override, s.
    pub leap_seconds: Option<f64>,
}

/// The recordings as an SBET (one record per recording: the IMU position behind the lever arm, ellipsoidal
/// height, the vehicle attitude with the driving direction as true heading and zero pitch and roll) and an
/// event file (`time` in GPS seconds of week, `image`, and the panorama's `pano_heading` (true north),
/// `pano_pitch`, `pano_roll` in degrees). Returns the GPS week.
pub fn export_sbet_with_events(
    recordings: &[Recording],
    ctx: &ImportContext,
    spec: &TrajectoryExport,
    sbet: &Path,
    events: &Path,
) -> Result<u32, ExportError> {
    let crs = Crs::parse(&spec.crs).map_err(|e| ExportError::Setup(e.to_string()))?;
    if crs.is_projected() {
        return Err(ExportError::Setup(format!(
            "{} is projected; an SBET holds latitude/longitude",
            spec.crs
        )));
    }
    let inv = inverse(ctx, &format!("geographic:{}", spec.crs), "ellipsoidal")?;
    let mut sorted: Vec<&Recording> = recordings.iter().collect();
    sorted.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    let mut week = None;
    let mut records = Vec::with_capacity(sorted.len());
    let mut lines = vec!["time,image,pano_heading,pano_pitch,pano_roll".to_string()];
    for r in sorted {
        let fail = |source: ConvertError| ExportError::Point {
            id: r.image_id.clone(),
            source,
        };
        let (lat, lon, h) = inv.position(r.x, r.y, r.z).map_err(fail)?;
        // True-north quantities: turn the grid back by the convergence at the panorama.
        let r_true = inv
            .rotation(
                lat,
                lon,
                &panorama_matrix(r.yaw_deg, r.pitch_deg, r.roll_deg),
            )
            .map_err(|e| fail(e.into()))?;
        let heading_true = panorama_angles(
            &inv.rotation(lat, lon, &panorama_matrix(r.heading_deg, 0.0, 0.0))
                .map_err(|e| fail(e.into()))?,
        )
        .0;
        let r_bn = body_to_ned(0.0, 0.0, heading_true);
        let lever = LeverArm {
            ellipsoid: &crs.ellipsoid,
            body_to_ned: &r_bn,
            lever_body_m: spec.lever_arm_m,
        };
        let (ilat, ilon, ih) = lever.remove((lat, lon, h));
        let (w, sow) = unix_to_gps(r.time_s, spec.leap_seconds);
        if *week.get_or_insert(w) != w {
            return Err(ExportError::Setup(
                "the recordings span more than one GPS week; export one SBET per week".into(),
            ));
        }
        records.push(SbetRecord {
            time_sow_s: sow,
            lat_rad: ilat.to_radians(),
            lon_rad: ilon.to_radians(),
            height_m: ih,
            heading_rad: heading_true.rem_euclid(360.0).to_radians(),
            ..SbetRecord::default()
        });
        let (ph, pp, pr) = panorama_angles(&r_true);
        lines.push(format!("{sow},{},{ph},{pp},{pr}", r.file));
    }
    write_sbet(sbet, &records)?;
    crate::fsutil::atomic_write(events, (lines.join("\n") + "\n").as_bytes())?;
    Ok(week.unwrap_or(0))
}
