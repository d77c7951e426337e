//! Run outputs for users (campaign-format.md "Outputs of a run"; every file is described in `docs/outputs.md`),
//! one file each, all written atomically ([`crate::fsutil`]) and deterministically:
//! [`trajectory`] `trajectory_adjusted.csv` (the input recordings file with adjusted values),
//! [`corrections_csv`] `corrections.csv` (the correction time series of [`corrections`], each value with what
//! supports it, [`crate::correction::support`]), [`geojson`] `trajectory.geojson` (QGIS), [`ply`] `tie_points.ply`
//! (CloudCompare), [`checkpoints`] `checkpoints.csv` (per-point errors before/after), [`correspondences`]
//! `correspondences.csv` (every control point's observations), [`control_status`] what the adjustment made of
//! each control point, [`gcp`] ground control for OpenSfM /
//! OpenDroneMap, Metashape and as a plain list, [`gpkg`] `skytie.gpkg` (GeoPackage layers for GIS), [`colmap`] a COLMAP text
//! model (`cameras.txt`, `images.txt`, `points3D.txt`) with COLMAP's EQUIRECTANGULAR model for the panoramas;
//! [`second_crs_files`]: the adjusted trajectory, corrections and control points also in a second CRS
//! (`campaign.toml` `[outputs]`, [`crate::crs::second_crs`]).
//! The CSV/GeoJSON/PLY encoders are the campaign writers ([`crate::campaign::write`]); this module maps an
//! [`crate::adjustment::AdjustmentRun`] onto them.

pub mod checkpoints;
pub mod colmap;
pub mod control_status;
pub mod corrections;
pub mod corrections_csv;
pub mod correspondences;
pub mod gcp;
pub mod geojson;
pub mod gpkg;
pub mod ply;
pub mod sbet;
pub mod second_crs_files;
pub mod synthetic_outputs;
pub mod trajectory;

pub use crate::correction::{recording_support, RecordingSupport, Support};
pub use checkpoints::{
    checkpoint_rows, write_checkpoint_errors_csv, CheckPointRow, CHECKPOINTS_CSV_HEADER,
};
pub use colmap::{write_colmap_model, ColmapExport};
pub use control_status::{ControlStatus, ControlStatuses};
pub use corrections::{Correction, CorrectionSeries, SampleKind};
pub use corrections_csv::{write_corrections_csv, CORRECTIONS_CSV_HEADER, CORRECTION_STEP_S};
pub use correspondences::{write_correspondences_csv, CORRESPONDENCES_CSV_HEADER};
pub use gcp::{opensfm_projection, write_ground_control, GcpExport};
pub use geojson::write_run_geojson;
pub use ply::{
    write_tie_points_ply, PLY_SOURCE_CONTROL, PLY_SOURCE_RECORDING, PLY_SOURCE_SINGLE_AERIAL,
    PLY_SOURCE_TIE,
};
pub use sbet::{write_corrected_sbet, SbetOutput, SBET_ADJUSTED, SBET_QUALITY_CSV};
pub use second_crs_files::{write_second_crs_files, SecondCrsRun};
pub use trajectory::{adjusted_recordings, write_adjusted_trajectory, TrajectoryExportCounts};
