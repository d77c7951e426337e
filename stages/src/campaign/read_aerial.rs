//! Reading `aerial/{nadir,oblique}/cameras.csv` row by row with validation (campaign-format.md,
//! "Aerial frame images").

use super::model::AerialImage;
use super::problem::Problem;
use super::ranges;
use super::read_recordings::check_file_exists;
use super::table::read_rows;
use super::unique::Sourced;
use std::path::Path;

const AERIAL_COLUMNS: &[&str] = &[
    "image_id", "file", "x", "y", "z", "omega", "phi", "kappa", "focal_px", "cx", "cy", "width",
    "height",
];

/// Valid rows of `root/rel` in file order; with `check_files`, `file` must exist next to the CSV. Id
/// uniqueness is checked by the caller across nadir and oblique together.
pub(crate) fn read_aerial_rows(
    root: &Path,
    rel: &Path,
    check_files: bool,
    problems: &mut Vec<Problem>,
) -> Vec<Sourced<AerialImage>> {
    let dir = rel.parent().unwrap_or(Path::new(""));
    let rows = read_rows(root, rel, AERIAL_COLUMNS, problems, |f| {
        let image_id = f.text("image_id");
        let file = f.text("file");
        let (x, y, z) = (f.number("x"), f.number("y"), f.number("z"));
        let (omega_deg, phi_deg, kappa_deg) =
            (f.number("omega"), f.number("phi"), f.number("kappa"));
        let focal_px = f.number("focal_px");
        let (cx_px, cy_px) = (f.number("cx"), f.number("cy"));
        let (width_px, height_px) = (f.pixel_count("width"), f.pixel_count("height"));
        let (k1, k2, p1, p2) = (
            f.number_or("k1", 0.0),
            f.number_or("k2", 0.0),
            f.number_or("p1", 0.0),
            f.number_or("p2", 0.0),
        );
        let (k3, k4, b1, b2) = (
            f.number_or("k3", 0.0),
            f.number_or("k4", 0.0),
            f.number_or("b1", 0.0),
            f.number_or("b2", 0.0),
        );
        let sigma_px = f.number_or("sigma_px", 0.5);
        // campaign-format.md: ω and φ tilt the view axis away from the nadir; beyond ±90° it looks up.
        for (column, angle) in [("omega", omega_deg), ("phi", phi_deg)] {
            if angle.abs() > 90.0 {
                f.error(
                    column,
                    format!("{angle}° is beyond ±90° (the camera would look upwards)"),
                    "check the angle convention (ω-φ-κ, degrees; 0,0,0 looks straight down)",
                );
            }
        }
        ranges::coordinates(f, x, y, z);
        ranges::angle(f, "kappa", kappa_deg, -360.0, 360.0);
        ranges::frame_camera(f, focal_px, width_px, height_px);
        for (column, c, size) in [("cx", cx_px, width_px), ("cy", cy_px, height_px)] {
            if size > 0 && !(0.0..=f64::from(size)).contains(&c) {
                f.error(column, format!("principal point {c} px lies outside the image (0..{size} px)"), "give the principal point in continuous pixel coordinates of this image (centre = size/2)");
            }
        }
        ranges::sigma_px(f, sigma_px);
        if check_files && !file.is_empty() {
            check_file_exists(f, root, dir, &file);
        }
        Some(AerialImage {
            image_id,
            file,
            x,
            y,
            z,
            omega_deg,
            phi_deg,
            kappa_deg,
            focal_px,
            cx_px,
            cy_px,
            width_px,
            height_px,
            k1,
            k2,
            p1,
            p2,
            k3,
            k4,
            b1,
            b2,
            sigma_px,
        })
    });
    rows
}

/// Read any file with the columns of `aerial/*/cameras.csv` (e.g. `truth/aerial_nadir.csv`) without checking
/// that the image files exist. Returns the valid rows in file order and the problems (file as given).
pub fn read_aerial_csv(path: &Path) -> (Vec<AerialImage>, Vec<Problem>) {
    let mut problems = Vec::new();
    let (root, rel) = match (path.parent(), path.file_name()) {
        (Some(parent), Some(name)) => (parent, Path::new(name)),
        _ => (Path::new("."), path),
    };
    let rows = read_aerial_rows(root, rel, false, &mut problems);
    for p in &mut problems {
        p.file = path.to_path_buf();
    }
    (rows.into_iter().map(|r| r.item).collect(), problems)
}
