//! Run outputs for users (issue 6 "Outputs"; campaign-format.md "Outputs of a run"), one file each, all written
//! atomically ([`crate::fsutil`]) and deterministically:
//! [`trajectory`] `trajectory_adjusted.csv`, [`geojson`] `trajectory.geojson` (QGIS), [`ply`] `tie_points.ply`
//! (CloudCompare), [`checkpoints`] `checkpoints.csv` (per-point errors before/after), [`correspondences`]
//! `correspondences.csv` (every control point's observations), [`colmap`] a COLMAP text
//! model (`cameras.txt`, `images.txt`, `points3D.txt`) with COLMAP's EQUIRECTANGULAR model for the panoramas.
//! The CSV/GeoJSON/PLY encoders are the campaign writers ([`crate::campaign::write`]); this module maps an
//! [`crate::adjustment::AdjustmentRun`] onto them.

pub mod checkpoints;
pub mod colmap;
pub mod correspondences;
pub mod geojson;
pub mod ply;
pub mod trajectory;

pub use checkpoints::{
    checkpoint_rows, write_checkpoint_errors_csv, CheckPointRow, CHECKPOINTS_CSV_HEADER,
};
pub use colmap::{write_colmap_model, ColmapExport};
pub use correspondences::{write_correspondences_csv, CORRESPONDENCES_CSV_HEADER};
pub use geojson::write_run_geojson;
pub use ply::{
    write_tie_points_ply, PLY_SOURCE_CONTROL, PLY_SOURCE_RECORDING, PLY_SOURCE_SINGLE_AERIAL,
    PLY_SOURCE_TIE,
};
pub use trajectory::{adjusted_recordings, write_adjusted_trajectory};
