//! The `skytie` command line (clap). Each subcommand lives in its own file; the names and flags are a
//! contract used by scripts.
//!
//! Exit codes (all subcommands): 0 = success; 1 = `run` produced nothing useful (see [`run`]) or `cache
//! verify` found bad entries; 2 = usage or setup error (workflow does not load, unknown pipeline, cache or
//! output folder not usable).

pub mod builtin_workflows;
pub mod cache;
pub mod check;
pub mod common;
pub mod eval;
pub mod explain;
pub mod import;
pub mod init;
pub mod params;
pub mod plan;
pub mod report;
pub mod run;
pub mod shard;
pub mod slurm;
pub mod synth;
pub mod tool;
pub mod workflows;

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
    /// Run a workflow on a Slurm cluster: prepare job, shard job array, merge job (docs/cluster.md).
    Slurm(slurm::SlurmArgs),
    /// (Re)build the HTML report OUT/report/index.html of a run's output folder.
    Report(report::ReportArgs),
    /// Say which nodes are cached and which will run, and why.
    Plan(plan::PlanArgs),
    /// Show one node's key ingredients and provenance.
    Explain(explain::ExplainArgs),
    /// Inspect and maintain the cache.
    Cache(cache::CacheArgs),
    /// Generate a synthetic campaign (campaign format plus truth/).
    Synth(synth::SynthArgs),
    /// Validate a campaign folder and list every problem.
    Check(check::CheckArgs),
    /// Held-out evaluation: presets × error profiles × seeds, one table, compared with a baseline.
    Eval(eval::EvalArgs),
    /// Every workflow parameter with default, unit, range and meaning (`skytie params refine`).
    Params(params::ParamsArgs),
    /// List the built-in workflows, or print one (`show NAME`).
    Workflows(workflows::WorkflowsArgs),
    /// Turn vendor files (Pix4D, Metashape, SBET, ...) into a campaign folder (docs/import.md).
    Import(import::ImportArgs),
    /// Write an empty campaign skeleton with commented table headers.
    Init(init::InitArgs),
    /// Building blocks on plain files (ortho, kaze, forstner, wallis, phasecorr, ncc), CSV/plain output.
    #[command(subcommand)]
    Tool(tool::ToolCommand),
}

/// Parse the process arguments and run; returns the exit code.
pub fn main() -> i32 {
    let cli = Cli::parse();
    match &cli.command {
        Command::Run(a) => run::main(a),
        Command::Slurm(a) => slurm::main(a),
        Command::Report(a) => report::main(a),
        Command::Plan(a) => plan::main(a),
        Command::Explain(a) => explain::main(a),
        Command::Cache(a) => cache::main(a),
        Command::Synth(a) => synth::main(a),
        Command::Check(a) => check::main(a),
        Command::Eval(a) => eval::main(a),
        Command::Import(a) => import::main(a),
        Command::Init(a) => init::main(a),
        Command::Tool(t) => tool::main(t),
        Command::Workflows(a) => workflows::main(a),
        Command::Params(a) => params::main(a),
    }
}
