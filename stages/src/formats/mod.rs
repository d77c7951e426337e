//! Readers and writers of the files surveyors get from other software: aerial orientations (Pix4D,
//! Metashape, generic ω-φ-κ lists), GNSS/INS trajectories (Applanix SBET, generic CSV) with image event
//! files, panorama pose tags (EXIF GPS, XMP GPano), check points and image measurements.
//!
//! Readers return the rows they could read plus a [`crate::campaign::Problem`] for every row they skipped
//! (file, line, field, reason); they convert nothing between CRSs (that is [`crate::import`]'s job). Writers
//! exist for the formats skytie also delivers or tests with (SBET, Pix4D, Metashape, ω-φ-κ lists).

pub mod angles;
pub mod camera_model;
pub mod events;
pub mod gps_time;
pub mod image_tags;
pub mod metashape_xml;
pub mod opk_list;
pub mod pix4d;
pub mod points;
pub mod sbet;
pub mod text_table;
pub mod trajectory_csv;

use crate::campaign::Problem;
use std::path::Path;

/// The problem of an import source file that cannot be read at all (missing, no permission, ...).
pub(crate) fn unreadable(path: &Path, e: &std::io::Error) -> Problem {
    Problem::error(
        path,
        None,
        None,
        format!("cannot be read ({e})"),
        "check the path in the import configuration",
    )
}
