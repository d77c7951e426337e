//! Reading `mm/recordings.csv` (or any file with its columns, e.g. `truth/recordings.csv`,
//! `trajectory_adjusted.csv`) row by row with validation (campaign-format.md, "Panoramas").

use super::model::Recording;
use super::problem::{Problem, ProblemKind};
use super::ranges;
use super::table::read_rows;
use super::time::parse_time_s;
use super::unique::{keep_unique, Sourced};
use std::path::Path;

/// The required columns of a recordings table, in the order the writers put them.
pub const RECORDING_COLUMNS: &[&str] = &[
    "image_id",
    "file",
    "time",
    "x",
    "y",
    "z",
    "heading",
    "camera_height",
];

/// Above this a "camera height above the road" is almost certainly a wrong column or unit (warning only).
const SUSPICIOUS_CAMERA_HEIGHT_M: f64 = 10.0;

/// Valid rows of the recordings table `root/rel`, in file order, with their rows. Bad rows are reported and
/// skipped; ids must be unique; equal or decreasing times in file order are warnings. When `images_dir`
/// (relative to `root`) is given, every `file` must exist in it.
pub(crate) fn read_recording_rows(
    root: &Path,
    rel: &Path,
    images_dir: Option<&Path>,
    problems: &mut Vec<Problem>,
) -> Vec<Sourced<Recording>> {
    let rows = read_rows(root, rel, RECORDING_COLUMNS, problems, |f| {
        let image_id = f.text("image_id");
        let file = f.text("file");
        let time = f.text("time");
        let time_s = if time.is_empty() {
            0.0
        } else {
            parse_time_s(&time).unwrap_or_else(|message| {
                f.error(
                    "time",
                    message,
                    "write ISO 8601 with a zone, e.g. 2019-06-14T10:31:07.250Z",
                );
                0.0
            })
        };
        let (x, y, z) = (f.number("x"), f.number("y"), f.number("z"));
        let heading_deg = f.number("heading");
        let camera_height_m = f.number("camera_height");
        let sigma_xy_m = f.optional_number("sigma_xy");
        let sigma_z_m = f.optional_number("sigma_z");
        let yaw_deg = f.number_or("yaw", 0.0);
        let pitch_deg = f.number_or("pitch", 0.0);
        let roll_deg = f.number_or("roll", 0.0);
        if camera_height_m <= 0.0 {
            f.error(
                "camera_height",
                format!("{camera_height_m} m is not above the road"),
                "give the height of the projection centre above the road surface, > 0 m",
            );
        } else if camera_height_m > SUSPICIOUS_CAMERA_HEIGHT_M {
            f.warning(
                "camera_height",
                format!("{camera_height_m} m is unusually high for a vehicle-mounted camera"),
                "check the column and its unit (metres)",
            );
        }
        ranges::coordinates(f, x, y, z);
        ranges::angle(f, "heading", heading_deg, -180.0, 360.0);
        ranges::angle(f, "yaw", yaw_deg, -360.0, 360.0);
        ranges::sigma_m(f, "sigma_xy", sigma_xy_m);
        ranges::sigma_m(f, "sigma_z", sigma_z_m);
        for (column, angle) in [("pitch", pitch_deg), ("roll", roll_deg)] {
            if angle.abs() > 90.0 {
                f.error(column, format!("{angle}° is beyond ±90°"), "the residual tilt of a levelled panorama is a few degrees; check the column and its unit (degrees)");
            }
        }
        if let (Some(dir), false) = (images_dir, file.is_empty()) {
            check_file_exists(f, root, dir, &file);
        }
        Some(Recording {
            image_id,
            file,
            time,
            time_s,
            x,
            y,
            z,
            heading_deg,
            camera_height_m,
            sigma_xy_m,
            sigma_z_m,
            yaw_deg,
            pitch_deg,
            roll_deg,
        })
    });
    let rows = keep_unique(
        rows,
        |r| r.image_id.clone(),
        "image_id",
        "give every panorama its own image_id",
        problems,
    );
    for pair in rows.windows(2) {
        let (a, b) = (&pair[0], &pair[1]);
        if b.item.time_s <= a.item.time_s {
            let relation = if b.item.time_s == a.item.time_s {
                "equals"
            } else {
                "is before"
            };
            problems.push(Problem::warning(
                rel,
                Some(b.row),
                Some("time"),
                format!("{} {relation} the time on row {} ({}): times are not increasing in file order", b.item.time, a.row, a.item.time),
                "list recordings in acquisition order with distinct times; skytie orders them by time",
            ));
        }
    }
    rows
}

/// `file` (relative to `root/dir`) must be an existing file inside the campaign folder: no absolute path, no
/// `..`, no symbolic link that leads out of `root`.
pub(crate) fn check_file_exists(
    f: &mut super::table::Fields<'_>,
    root: &Path,
    dir: &Path,
    file: &str,
) {
    let rel = Path::new(file);
    let shown = dir.display();
    let leaves = rel
        .components()
        .any(|c| matches!(c, std::path::Component::ParentDir));
    if rel.is_absolute() || leaves {
        let what = if leaves {
            "leads out of its folder with '..'"
        } else {
            "is an absolute path"
        };
        f.error_of(
            ProblemKind::Path,
            "file",
            format!("'{file}' {what}; images must lie inside the campaign folder"),
            format!("copy the image into {shown}/ and write its path relative to {shown}/"),
        );
        return;
    }
    let path = root.join(dir).join(rel);
    if !path.is_file() {
        f.error_of(
            ProblemKind::ImageMissing,
            "file",
            format!("{shown}/{file} does not exist"),
            format!("put the image into {shown}/ or correct the file name"),
        );
        return;
    }
    let inside = match (std::fs::canonicalize(root), std::fs::canonicalize(&path)) {
        (Ok(r), Ok(p)) => p.starts_with(r),
        _ => true,
    };
    if !inside {
        f.error_of(
            ProblemKind::Path,
            "file",
            format!("{shown}/{file} is a link to a file outside the campaign folder"),
            "copy the image itself into the campaign folder (a campaign must be complete on its own)",
        );
    }
}

/// Sort recordings by time (stable: file order for equal times).
pub(crate) fn sort_by_time(rows: &mut [Sourced<Recording>]) {
    rows.sort_by(|a, b| a.item.time_s.total_cmp(&b.item.time_s));
}

/// Read any file with the columns of `mm/recordings.csv` (e.g. `truth/recordings.csv`,
/// `trajectory_adjusted.csv`; extra columns such as `sigma_x` are ignored). Image files are not checked.
/// Returns the valid rows sorted by time and the problems (file as given in `path`).
pub fn read_recordings_csv(path: &Path) -> (Vec<Recording>, Vec<Problem>) {
    let mut problems = Vec::new();
    let (root, rel) = match (path.parent(), path.file_name()) {
        (Some(parent), Some(name)) => (parent, Path::new(name)),
        _ => (Path::new("."), path),
    };
    let mut rows = read_recording_rows(root, rel, None, &mut problems);
    for p in &mut problems {
        p.file = path.to_path_buf();
    }
    sort_by_time(&mut rows);
    (rows.into_iter().map(|r| r.item).collect(), problems)
}
