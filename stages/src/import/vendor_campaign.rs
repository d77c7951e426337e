//! A whole campaign → the vendor files a surveyor would hold for it, plus the import configuration that reads
//! them back: the nadir block as Pix4D outputs (first half) and a classical AT list in gon / yaw-pitch-roll
//! (second half), the oblique block as Metashape camera XML (first half) and a Metashape ω-φ-κ export (second
//! half), the trajectory as an SBET in a geographic CRS with ellipsoidal heights and an event file with the
//! panoramas' true-north attitude, and the check points in another CRS with ellipsoidal heights, their
//! measurements with the first pixel's centre at (0, 0). Every importer and every CRS path is exercised by one
//! export → `skytie import` round trip; the images are not copied (the configuration points at the campaign's
//! folders).

use super::config::{
    AerialFormat, AerialKindName, AerialSource, CampaignSection, ControlSource, ImportConfig,
    MmSource, PanoramaOrientation, TrajectoryFormat,
};
use super::context::ImportContext;
use super::export::{
    aerial_poses, export_metashape_xml, export_opk_list, export_pix4d, export_sbet_with_events,
    ExportError, TrajectoryExport,
};
use crate::campaign::{AerialImage, Campaign, Recording};

use crate::formats::camera_model::CameraModel;
use crate::formats::events::{EventFormat, TimeSystem};
use crate::formats::opk_list::OpkListFormat;
use crate::formats::points::{
    write_measurements, write_points, MeasurementRow, PixelOrigin, PointRow,
};
use crate::formats::text_table::Delimiter;
use std::path::{Path, PathBuf};

/// What the vendor files are written in.
#[derive(Debug, Clone, PartialEq)]
pub struct VendorExport {
    /// The `[campaign]` of the import configuration: the campaign's CRS with its vertical part (the
    /// campaign's heights are taken to be in it) and the geoid model that links it to ellipsoidal heights.
    pub campaign: CampaignSection,
    /// Geographic CRS of the SBET, e.g. `EPSG:4937` (ETRS89).
    pub trajectory_crs: String,
    /// IMU → panorama centre in the body frame, m (the SBET holds the IMU position).
    pub lever_arm_m: [f64; 3],
    /// Pix4D's pixel size, mm.
    pub pixel_size_mm: f64,
    /// Projected CRS of the check point list, heights ellipsoidal (e.g. `EPSG:25831`).
    pub control_crs: String,
}

/// Write `campaign` as vendor files into `dir` (which must exist) and `dir/import.toml`; returns the
/// configuration written there.
pub fn export_vendor_campaign(
    campaign: &Campaign,
    spec: &VendorExport,
    dir: &Path,
) -> Result<ImportConfig, ExportError> {
    let ctx = ImportContext::new(&spec.campaign).map_err(|p| ExportError::Setup(p.to_string()))?;
    let horizontal = spec
        .campaign
        .crs
        .split('+')
        .next()
        .unwrap_or_default()
        .to_string();
    let mut aerial = Vec::new();
    let root = &campaign.root;
    let (n1, n2) = halves(&campaign.nadir);
    if !n1.is_empty() {
        export_pix4d(n1, &ctx, &horizontal, spec.pixel_size_mm, dir, "nadir")?;
        aerial.push(AerialSource {
            internals: Some(dir.join("nadir_pix4d_calibrated_internal_camera_parameters.cam")),
            crs: Some(spec.campaign.crs.clone()),
            image_width_px: Some(n1[0].width_px),
            image_height_px: Some(n1[0].height_px),
            ..source(
                AerialKindName::Nadir,
                AerialFormat::Pix4d,
                dir.join("nadir_calibrated_external_camera_parameters.txt"),
                root.join("aerial/nadir"),
                n1,
            )
        });
    }
    if !n2.is_empty() {
        let layout = OpkListFormat::at_list();
        let path = dir.join("nadir_at.txt");
        export_opk_list(n2, &ctx, &horizontal, &layout, &path)?;
        aerial.push(AerialSource {
            layout: Some(layout),
            camera: Some(camera_section(n2)?),
            ..source(
                AerialKindName::Nadir,
                AerialFormat::OpkList,
                path,
                root.join("aerial/nadir"),
                n2,
            )
        });
    }
    let (o1, o2) = halves(&campaign.oblique);
    if !o1.is_empty() {
        let path = dir.join("oblique_cameras.xml");
        export_metashape_xml(o1, &ctx, &horizontal, &path)?;
        aerial.push(source(
            AerialKindName::Oblique,
            AerialFormat::MetashapeXml,
            path,
            root.join("aerial/oblique"),
            o1,
        ));
    }
    if !o2.is_empty() {
        let path = dir.join("oblique_opk.txt");
        export_opk_list(o2, &ctx, &horizontal, &OpkListFormat::metashape(), &path)?;
        aerial.push(AerialSource {
            camera: Some(camera_section(o2)?),
            ..source(
                AerialKindName::Oblique,
                AerialFormat::MetashapeOpk,
                path,
                root.join("aerial/oblique"),
                o2,
            )
        });
    }
    let mm = (!campaign.recordings.is_empty())
        .then(|| export_mm(&campaign.recordings, root, &ctx, spec, dir))
        .transpose()?;
    let control = (!campaign.checkpoints.is_empty())
        .then(|| export_control(campaign, &ctx, spec, dir))
        .transpose()?;
    let config = ImportConfig {
        campaign: spec.campaign.clone(),
        aerial,
        mm,
        panorama_tags: None,
        control,
    };
    let text = toml::to_string(&config)
        .map_err(|e| ExportError::Setup(format!("import configuration: {e}")))?;
    crate::fsutil::atomic_write(&dir.join("import.toml"), text.as_bytes())?;
    Ok(config)
}

/// The first and the second half of a block (in campaign order, so the import keeps it).
fn halves(rows: &[AerialImage]) -> (&[AerialImage], &[AerialImage]) {
    rows.split_at(rows.len().div_ceil(2))
}

fn source(
    kind: AerialKindName,
    format: AerialFormat,
    orientations: PathBuf,
    images: PathBuf,
    rows: &[AerialImage],
) -> AerialSource {
    AerialSource {
        kind,
        format,
        orientations,
        internals: None,
        images,
        crs: None,
        heights: None,
        image_width_px: None,
        image_height_px: None,
        layout: None,
        camera: None,
        sigma_px: rows.first().map(|r| r.sigma_px),
    }
}

/// The one interior orientation (and σ) of a block exported as a list; `Err` when the rows differ.
fn camera_section(rows: &[AerialImage]) -> Result<CameraModel, ExportError> {
    let of = CameraModel::of_aerial;
    let first = of(&rows[0]);
    if rows
        .iter()
        .any(|r| of(r) != first || r.sigma_px != rows[0].sigma_px)
    {
        return Err(ExportError::Setup(
            "the images have different interior orientations or σ; a list holds one camera".into(),
        ));
    }
    Ok(first)
}

/// The value every recording shares; `Err` naming `what` when they differ.
fn shared<T: PartialEq + Copy>(
    recs: &[Recording],
    what: &str,
    f: impl Fn(&Recording) -> T,
) -> Result<T, ExportError> {
    let v = f(&recs[0]);
    if recs.iter().any(|r| f(r) != v) {
        return Err(ExportError::Setup(format!(
            "the recordings have different {what}; the import configuration holds one value"
        )));
    }
    Ok(v)
}

fn export_mm(
    recs: &[Recording],
    root: &Path,
    ctx: &ImportContext,
    spec: &VendorExport,
    dir: &Path,
) -> Result<MmSource, ExportError> {
    let traj = TrajectoryExport {
        crs: spec.trajectory_crs.clone(),
        lever_arm_m: spec.lever_arm_m,
        leap_seconds: None,
    };
    let (sbet, events) = (dir.join("sbet.out"), dir.join("events.csv"));
    let week = export_sbet_with_events(recs, ctx, &traj, &sbet, &events)?;
    Ok(MmSource {
        trajectory: sbet,
        format: TrajectoryFormat::Sbet,
        crs: spec.trajectory_crs.clone(),
        heights: "ellipsoidal".into(),
        gps_week: Some(week),
        leap_seconds: None,
        layout: None,
        heading_north: None,
        events,
        event_layout: EventFormat {
            delimiter: Delimiter::Comma,
            header: true,
            time_column: "time".into(),
            image_column: "image".into(),
            time: TimeSystem::GpsSecondsOfWeek {
                gps_week: week,
                leap_seconds: None,
            },
        },
        orientation: PanoramaOrientation::EventColumns,
        pano_columns: Some([
            "pano_heading".into(),
            "pano_pitch".into(),
            "pano_roll".into(),
        ]),
        panoramas: root.join("mm/panoramas"),
        camera_height_m: shared(recs, "camera heights", |r| r.camera_height_m)?,
        boresight_deg: [0.0; 3],
        lever_arm_m: spec.lever_arm_m,
        max_gap_s: 1.0,
        sigma_xy_m: shared(recs, "sigma_xy", |r| r.sigma_xy_m)?,
        sigma_z_m: shared(recs, "sigma_z", |r| r.sigma_z_m)?,
    })
}

fn export_control(
    campaign: &Campaign,
    ctx: &ImportContext,
    spec: &VendorExport,
    dir: &Path,
) -> Result<ControlSource, ExportError> {
    // The points go through the aerial pose conversion (identity attitude) into the list's CRS.
    let as_images: Vec<AerialImage> = campaign
        .checkpoints
        .iter()
        .map(|p| AerialImage {
            image_id: p.point_id.clone(),
            file: p.point_id.clone(),
            x: p.x,
            y: p.y,
            z: p.z,
            ..AerialImage::default()
        })
        .collect();
    let poses = aerial_poses(&as_images, ctx, &spec.control_crs, "ellipsoidal")?;
    let rows: Vec<PointRow> = campaign
        .checkpoints
        .iter()
        .zip(&poses)
        .map(|(p, q)| PointRow {
            line: 0,
            id: p.point_id.clone(),
            a: q.a,
            b: q.b,
            z: q.z,
            sigma_xy_m: p.sigma_xy_m,
            sigma_z_m: p.sigma_z_m,
        })
        .collect();
    let points = dir.join("checkpoints.csv");
    let layout = write_points(&points, &rows)?;
    let file_of = |id: &str| {
        campaign
            .recordings
            .iter()
            .find(|r| r.image_id == id)
            .map_or_else(|| id.to_string(), |r| r.file.clone())
    };
    let measurements: Vec<MeasurementRow> = campaign
        .observations
        .iter()
        .map(|o| MeasurementRow {
            line: 0,
            point: o.point_id.clone(),
            image: file_of(&o.image_id),
            u_px: o.u_px,
            v_px: o.v_px,
        })
        .collect();
    let (measurement_path, measurement_layout) = if measurements.is_empty() {
        (None, None)
    } else {
        let path = dir.join("measurements.csv");
        let layout = write_measurements(&path, &measurements, PixelOrigin::FirstPixelCentre)?;
        (Some(path), Some(layout))
    };
    Ok(ControlSource {
        points,
        layout,
        crs: Some(spec.control_crs.clone()),
        heights: Some("ellipsoidal".into()),
        measurements: measurement_path,
        measurement_layout,
    })
}
