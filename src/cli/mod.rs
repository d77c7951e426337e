//! The `skytie` command line (clap). Each subcommand lives in its own file; the names and flags are a
//! contract used by scripts.
//!
//! Exit codes (all subcommands): 0 = success; 1 = `run` produced nothing useful (see [`run`]) or `cache
//! verify` found bad entries; 2 = usage or setup error (workflow does not load, unknown pipeline, cache or
//! output folder not usable).

pub mod cache;
pub mod common;
pub mod explain;
pub mod plan;
pub mod run;

use clap::{Parser, Subcommand};

/// Command-line interface.
#[derive(Parser, Debug)]
#[command(
    name = "skytie",
    version,
    about = "Correct mobile-mapping panorama positions with aerial images"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// Subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Run a workflow (only nodes whose inputs changed are recomputed).
    Run(run::RunArgs),
    /// Say which nodes are cached and which will run, and why.
    Plan(plan::PlanArgs),
    /// Show one node's key ingredients and provenance.
    Explain(explain::ExplainArgs),
    /// Inspect and maintain the cache.
    Cache(cache::CacheArgs),
}

/// Parse the process arguments and run; returns the exit code.
pub fn main() -> i32 {
    let cli = Cli::parse();
    match &cli.command {
        Command::Run(a) => run::main(a),
        Command::Plan(a) => plan::main(a),
        Command::Explain(a) => explain::main(a),
        Command::Cache(a) => cache::main(a),
    }
}
