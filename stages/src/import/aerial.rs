//! Aerial orientation sources → `aerial/{nadir,oblique}/cameras.csv` rows in the campaign CRS.

use super::config::{AerialFormat, AerialKindName, AerialSource};
use super::context::ImportContext;
use super::convert::Converter;
use super::report::SourceReport;
use super::source_pose::{missing, SourcePose};
use crate::campaign::{AerialImage, Problem};
use crate::formats::camera_model::CameraModel;
use crate::formats::opk_list::{read_opk_list, OpkListFormat, PoseRow};
use crate::formats::pix4d::read_pix4d_cam;
use crate::geometry::matrix_to_opk;
use std::path::Path;

/// Import one source; returns the campaign rows (with `file` = the image's file name) and the report.
pub fn import_aerial(src: &AerialSource, ctx: &ImportContext) -> (Vec<AerialImage>, SourceReport) {
    let name = format!(
        "aerial {} ({})",
        match src.kind {
            AerialKindName::Nadir => "nadir",
            AerialKindName::Oblique => "oblique",
        },
        format_name(src.format)
    );
    let mut report = SourceReport::new(name, &src.orientations);
    let read = match src.format {
        AerialFormat::Pix4d => read_pix4d(src, &mut report),
        AerialFormat::MetashapeOpk => read_list(src, &OpkListFormat::metashape(), &mut report),
        AerialFormat::OpkList => match &src.layout {
            Some(layout) => read_list(src, layout, &mut report),
            None => {
                report.problems.push(missing(&src.orientations, "layout", "describe the columns in [aerial.layout] (delimiter, header, angle_unit, attitude, columns)"));
                None
            }
        },
        AerialFormat::MetashapeXml => super::metashape::read_metashape_poses(src, ctx, &mut report),
    };
    let Some((poses, source_crs_text)) = read else {
        return (Vec::new(), report);
    };
    let heights = match src.format {
        AerialFormat::MetashapeXml => Some("ellipsoidal"),
        _ => src.heights.as_deref(),
    };
    let converter = match ctx.converter(source_crs_text.as_deref(), heights) {
        Ok(c) => c,
        Err(p) => {
            report.problems.push(p);
            return (Vec::new(), report);
        }
    };
    report.notes.push(format!(
        "positions {} → {}; heights {}",
        source_crs_text.as_deref().unwrap_or(&ctx.campaign_crs.text),
        ctx.campaign_crs.text,
        heights.unwrap_or("campaign")
    ));
    let rows = convert_poses(src, &poses, &converter, &mut report);
    (rows, report)
}

fn format_name(f: AerialFormat) -> &'static str {
    match f {
        AerialFormat::Pix4d => "pix4d",
        AerialFormat::MetashapeXml => "metashape-xml",
        AerialFormat::MetashapeOpk => "metashape-opk",
        AerialFormat::OpkList => "opk-list",
    }
}

/// The rows of `src`'s orientation list in `layout`, counted as read with the rows that have problems.
fn read_rows(
    src: &AerialSource,
    layout: &OpkListFormat,
    report: &mut SourceReport,
) -> Vec<PoseRow> {
    let (rows, problems) = read_opk_list(&src.orientations, layout);
    report.read = rows.len() + problems.iter().filter(|p| p.row.is_some()).count();
    report.problems.extend(problems);
    rows
}

/// The poses of `rows`, every image taken with `camera`, and the CRS `src` declares for them.
fn with_camera(
    src: &AerialSource,
    rows: Vec<PoseRow>,
    camera: CameraModel,
) -> (Vec<SourcePose>, Option<String>) {
    let poses = rows
        .into_iter()
        .map(|pose| SourcePose { pose, camera })
        .collect();
    (poses, src.crs.clone())
}

fn read_list(
    src: &AerialSource,
    layout: &OpkListFormat,
    report: &mut SourceReport,
) -> Option<(Vec<SourcePose>, Option<String>)> {
    let Some(camera) = src.camera else {
        report.problems.push(missing(&src.orientations, "camera", "give the interior orientation in [aerial.camera] (focal_px, cx_px, cy_px, width_px, height_px, distortion)"));
        return None;
    };
    let rows = read_rows(src, layout, report);
    Some(with_camera(src, rows, camera))
}

fn read_pix4d(
    src: &AerialSource,
    report: &mut SourceReport,
) -> Option<(Vec<SourcePose>, Option<String>)> {
    let Some(cam_path) = &src.internals else {
        report.problems.push(missing(
            &src.orientations,
            "internals",
            "give the *_pix4d_calibrated_internal_camera_parameters.cam file",
        ));
        return None;
    };
    let cam = match read_pix4d_cam(cam_path) {
        Ok(c) => c,
        Err(p) => {
            report.problems.extend(p);
            return None;
        }
    };
    let rows = read_rows(src, &OpkListFormat::pix4d(), report);
    let size = match (src.image_width_px, src.image_height_px) {
        (Some(w), Some(h)) => Some((w, h)),
        _ => rows
            .iter()
            .find_map(|r| image::image_dimensions(src.images.join(&r.image)).ok()),
    };
    let Some((w, h)) = size else {
        report.problems.push(missing(
            &src.orientations,
            "image_width_px",
            "give image_width_px and image_height_px (no image file could be read for its size)",
        ));
        return None;
    };
    let internals = match cam.internals(cam_path, w, h) {
        Ok(i) => i,
        Err(p) => {
            report.problems.push(p);
            return None;
        }
    };
    let camera = CameraModel::from_pix4d(&internals);
    report.notes.push(format!(
        "Pix4D internals: pixel size {:.6} mm ({} px wide), f = {:.3} px, principal point ({:.3}, {:.3}) px from the top-left corner",
        internals.pixel_size_mm, w, camera.focal_px, camera.cx_px, camera.cy_px
    ));
    Some(with_camera(src, rows, camera))
}

fn convert_poses(
    src: &AerialSource,
    poses: &[SourcePose],
    converter: &Converter,
    report: &mut SourceReport,
) -> Vec<AerialImage> {
    let mut out = Vec::with_capacity(poses.len());
    for SourcePose { pose, camera } in poses {
        let file = &src.orientations;
        let fail = |field: &str, message: String| {
            Problem::error(
                file,
                Some(pose.line),
                Some(field),
                message,
                "check the file's CRS and values",
            )
        };
        if !src.images.join(&pose.image).is_file() {
            report.problems.push(Problem::error(
                file,
                Some(pose.line),
                Some("image"),
                format!(
                    "image file {} does not exist; row skipped",
                    src.images.join(&pose.image).display()
                ),
                "put the image into the images folder or fix its name",
            ));
            continue;
        }
        let position = converter.position(pose.a, pose.b, pose.z);
        let rotation = converter.rotation(pose.a, pose.b, &pose.rotation);
        let ((x, y, z), r) = match (position, rotation) {
            (Ok(p), Ok(r)) => (p, r),
            (Err(e), _) => {
                report.problems.push(fail("x", e.to_string()));
                continue;
            }
            (_, Err(e)) => {
                report.problems.push(fail("omega", e.to_string()));
                continue;
            }
        };
        let (omega_deg, phi_deg, kappa_deg) = matrix_to_opk(&r);
        if omega_deg.abs() > 90.0 || phi_deg.abs() > 90.0 {
            report.problems.push(fail(
                "omega",
                format!("the camera looks upwards (ω = {omega_deg:.3}°, φ = {phi_deg:.3}°)"),
            ));
            continue;
        }
        let stem = Path::new(&pose.image)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| pose.image.clone());
        let mut row = AerialImage {
            image_id: stem,
            file: pose.image.clone(),
            x,
            y,
            z,
            omega_deg,
            phi_deg,
            kappa_deg,
            sigma_px: src.sigma_px.unwrap_or(0.5),
            ..AerialImage::default()
        };
        camera.apply_to(&mut row);
        out.push(row);
    }
    report.converted = out.len();
    out
}
