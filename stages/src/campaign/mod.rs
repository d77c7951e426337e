//! The campaign contract (shared/docs/campaign-format.md): model, reading with validation, writers.

pub mod cameras;
pub mod check;
pub mod model;
pub mod problem;
pub mod read;
mod read_aerial;
mod read_control;
mod read_recordings;
mod table;
pub mod time;
mod unique;
pub mod write;

pub use check::{check_campaign, CheckReport};
pub use model::{AerialImage, AerialKind, Campaign, CheckPoint, Observation, Recording};
pub use problem::{Problem, Severity};
pub use read::{read_campaign, CampaignError};
pub use read_aerial::read_aerial_csv;
pub use read_recordings::read_recordings_csv;
pub use time::{format_time_iso, parse_time_s};
pub use write::{
    write_aerial_cameras_csv, write_campaign_toml, write_checkpoints_csv, write_observations_csv,
    write_ply, write_recordings_csv, write_trajectory_adjusted_csv, write_trajectory_geojson,
    GeoJsonLayer, GeoJsonPoint, PlyPoint,
};
