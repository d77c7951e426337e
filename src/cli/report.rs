//! `skytie report OUT [--campaign DIR] [--views N]`: (re)build `OUT/report/index.html` from a run's output
//! folder without running anything (see [`crate::report`]). Exit code 0 when the report was written, 2 when
//! OUT is not a run's output folder or the report cannot be written.

use crate::report::{build_report, ReportOptions};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug, Clone)]
pub struct ReportArgs {
    /// Output folder of `skytie run` (its --out).
    pub out: PathBuf,
    /// Campaign folder (images, truth/); default: the one recorded in OUT/provenance.json.
    #[arg(long, value_name = "DIR")]
    pub campaign: Option<PathBuf>,
    /// Number of recordings per correspondence source that get registration views.
    #[arg(long, value_name = "N", default_value_t = 3)]
    pub views: usize,
}

pub fn main(args: &ReportArgs) -> i32 {
    let options = ReportOptions {
        campaign: args.campaign.clone(),
        registration_views: args.views,
    };
    match build_report(&args.out, &options) {
        Ok(s) => {
            for n in &s.notes {
                eprintln!("note: {n}");
            }
            println!(
                "report: {} ({} tables, {} figures)",
                s.index.display(),
                s.tables.len(),
                s.figures.len()
            );
            0
        }
        Err(e) => {
            eprintln!("error: {e}");
            2
        }
    }
}
