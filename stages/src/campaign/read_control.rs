//! Reading `control/checkpoints.csv` and `control/observations.csv` with validation (campaign-format.md,
//! "Control"): check points are for evaluation only; observations must name a known point and panorama.

use super::model::{CheckPoint, Observation};
use super::problem::{Problem, ProblemKind};
use super::ranges;
use super::table::read_rows;
use super::unique::{keep_unique, Sourced};
use std::collections::HashSet;
use std::path::Path;

/// Valid, uniquely named check points of `root/rel` in file order.
pub(crate) fn read_checkpoint_rows(
    root: &Path,
    rel: &Path,
    problems: &mut Vec<Problem>,
) -> Vec<Sourced<CheckPoint>> {
    let rows = read_rows(root, rel, &["point_id", "x", "y", "z"], problems, |f| {
        let point_id = f.text("point_id");
        let (x, y, z) = (f.number("x"), f.number("y"), f.number("z"));
        let sigma_xy_m = f.optional_number("sigma_xy");
        let sigma_z_m = f.optional_number("sigma_z");
        ranges::coordinates(f, x, y, z);
        ranges::sigma_m(f, "sigma_xy", sigma_xy_m);
        ranges::sigma_m(f, "sigma_z", sigma_z_m);
        Some(CheckPoint {
            point_id,
            x,
            y,
            z,
            sigma_xy_m,
            sigma_z_m,
        })
    });
    keep_unique(
        rows,
        |c| c.point_id.clone(),
        "point_id",
        "give every check point its own point_id",
        problems,
    )
}

/// Valid observations of `root/rel` in file order: `point_id` among `points`, `image_id` among `images`
/// (the usable recordings), u, v ≥ 0, one observation per point and panorama. The upper pixel bounds need
/// the panorama size and are checked by `check_campaign`.
pub(crate) fn read_observation_rows(
    root: &Path,
    rel: &Path,
    points: &HashSet<&str>,
    images: &HashSet<&str>,
    problems: &mut Vec<Problem>,
) -> Vec<Sourced<Observation>> {
    let rows = read_rows(
        root,
        rel,
        &["point_id", "image_id", "u", "v"],
        problems,
        |f| {
            let point_id = f.text("point_id");
            let image_id = f.text("image_id");
            let (u_px, v_px) = (f.number("u"), f.number("v"));
            if !point_id.is_empty() && !points.contains(point_id.as_str()) {
                f.error_of(ProblemKind::Reference, "point_id", format!("'{point_id}' is not a usable point of control/checkpoints.csv"), "add the point to control/checkpoints.csv (or fix its row there), or correct the id");
            }
            if !image_id.is_empty() && !images.contains(image_id.as_str()) {
                f.error_of(
                    ProblemKind::Reference,
                    "image_id",
                    format!("'{image_id}' is not a usable panorama of mm/recordings.csv"),
                    "use the image_id of a panorama in mm/recordings.csv (or fix its row there)",
                );
            }
            for (column, value) in [("u", u_px), ("v", v_px)] {
                if value < 0.0 {
                    f.error(
                        column,
                        format!("{value} px lies outside the panorama"),
                        "pixel coordinates start at 0 at the top-left corner",
                    );
                }
            }
            Some(Observation {
                point_id,
                image_id,
                u_px,
                v_px,
            })
        },
    );
    keep_unique(
        rows,
        |o| format!("{}' in image '{}", o.point_id, o.image_id),
        "point_id",
        "measure each point at most once per panorama: delete the extra row",
        problems,
    )
}
