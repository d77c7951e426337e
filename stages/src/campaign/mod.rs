//! The campaign contract (docs/campaign-format.md): model, reading with validation, writers.

pub mod accounting;
pub mod cameras;
pub mod check;
pub mod images;
pub mod model;
pub mod orthophoto;
mod plausibility;
pub mod problem;
mod ranges;
pub mod read;
mod read_aerial;
mod read_control;
mod read_recordings;
pub mod source;
mod table;
pub mod time;
mod unique;
pub mod write;

pub use accounting::InputAccount;
pub use check::{check_campaign, check_campaign_with, decode_fully, CheckReport};
pub use images::{
    apply_image_checks, image_jobs, image_problems, ImageJob, ImageRole, ProbeOutcome,
};
pub use model::{AerialImage, AerialKind, Campaign, CheckPoint, Observation, Recording};
pub use problem::{Problem, ProblemKind, Severity};
pub use read::{
    read_campaign, read_sourced, sort_problems, CampaignError, SourceRows, SourcedCampaign,
};
pub use read_aerial::read_aerial_csv;
pub use read_recordings::{read_recordings_csv, RECORDING_COLUMNS};
pub use time::{format_time_iso, parse_time_s};
pub use write::{
    write_aerial_cameras_csv, write_campaign_toml, write_checkpoints_csv, write_observations_csv,
    write_ply, write_recordings_csv, write_trajectory_adjusted_csv, write_trajectory_geojson,
    GeoJsonLayer, GeoJsonPoint, PlyPoint,
};
