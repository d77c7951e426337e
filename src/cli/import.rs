//! `skytie import CONFIG.toml --out DIR`: turn vendor files (Pix4D, Metashape, ω-φ-κ lists, SBET + events,
//! trajectory tables, check points) into a new campaign folder, as the import configuration describes
//! (docs/import.md). Prints what was read, converted and skipped; the same report is written to
//! `DIR/import_report.txt`. Exit code 0 = imported without skipped items, 1 = imported with skipped items,
//! 2 = nothing imported (configuration or output folder unusable).

use crate::cli::common::exit_code;
use clap::Args;
use skytie_stages::import::{run_import, ImportConfig, ImportReport};
use std::path::PathBuf;

/// Arguments of `skytie import`.
#[derive(Args, Debug)]
pub struct ImportArgs {
    /// The import configuration (TOML; paths inside are relative to it).
    pub config: PathBuf,
    /// The campaign folder to create (must not exist or be empty).
    #[arg(long)]
    pub out: PathBuf,
}

/// Run `skytie import`; returns the exit code.
pub fn main(a: &ImportArgs) -> i32 {
    exit_code(import(a), |report| {
        print!("{report}");
        let skipped = report.skipped();
        println!(
            "campaign written to {} ({} skipped item{}; see import_report.txt)",
            a.out.display(),
            skipped,
            if skipped == 1 { "" } else { "s" }
        );
        i32::from(skipped > 0)
    })
}

/// Reads the configuration and imports; an unusable configuration or output folder is exit code 2.
fn import(a: &ImportArgs) -> Result<ImportReport, (i32, String)> {
    let config = ImportConfig::read(&a.config).map_err(|e| (2, e.to_string()))?;
    run_import(&config, &a.out).map_err(|e| (2, e.to_string()))
}
