//! `skytie check CAMPAIGN [--deep]`: validate a campaign folder and list every problem at once (file, row,
//! field, what to do) — the same validation `skytie run` applies before it builds the per-item stages. Exit code 0 when there are no errors (warnings allowed), 1 when there are errors, 2 when the folder
//! is not a campaign at all.

use clap::Args;
use skytie_stages::campaign::check_campaign_with;
use std::path::PathBuf;

/// Arguments of `skytie check`.
#[derive(Args, Debug)]
pub struct CheckArgs {
    /// The campaign folder (see docs/campaign-format.md).
    pub campaign: PathBuf,
    /// Print the report as JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Also decode every image in full (slow at real sizes; without it each image's header and structure are
    /// checked, which finds truncated and damaged files without decoding).
    #[arg(long)]
    pub deep: bool,
}

/// Run `skytie check`; returns the exit code.
pub fn main(a: &CheckArgs) -> i32 {
    if !a.campaign.is_dir() {
        eprintln!(
            "error: {}: not a folder; give the campaign folder (the one holding campaign.toml)",
            a.campaign.display()
        );
        return 2;
    }
    let report = check_campaign_with(&a.campaign, a.deep);
    if a.json {
        match serde_json::to_string_pretty(&report) {
            Ok(s) => println!("{s}"),
            Err(e) => {
                eprintln!("error: cannot encode the report: {e}");
                return 2;
            }
        }
    } else {
        print!("{}", report.render());
    }
    if report.error_count() > 0 {
        1
    } else {
        0
    }
}
