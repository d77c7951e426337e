//! `skytie import`: vendor files → a campaign folder (campaign-format), driven by an import configuration
//! ([`config::ImportConfig`]), with a report of what was read, converted and skipped.

pub mod aerial;
pub mod config;
pub mod context;
pub mod control;
pub mod convert;
pub mod export;
mod metashape;
pub mod mm;
mod panorama_row;
pub mod panorama_tags;
pub mod pose;
pub mod report;
pub mod run;
mod source_pose;
pub mod vendor_campaign;

pub use config::ImportConfig;
pub use report::ImportReport;
pub use run::{run_import, ImportError};
