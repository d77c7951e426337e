//! `skytie plan WORKFLOW [--campaign DIR] [--cache DIR]`: per stage, cached / will run, and why.

use crate::cli::common::{with_plan_session, CacheOpt, ThreadsOpt};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug, Clone)]
pub struct PlanArgs {
    /// Workflow: a built-in name (`skytie workflows` lists them) or a TOML file.
    pub workflow: PathBuf,
    /// Use this campaign folder instead of the workflow's `campaign`.
    #[arg(long, value_name = "DIR")]
    pub campaign: Option<PathBuf>,
    #[command(flatten)]
    pub cache: CacheOpt,
    #[command(flatten)]
    pub threads: ThreadsOpt,
}

pub fn main(args: &PlanArgs) -> i32 {
    match plan(args) {
        Ok(text) => {
            print!("{text}");
            0
        }
        Err((code, msg)) => {
            eprintln!("error: {msg}");
            code
        }
    }
}

/// The plan text, or (exit code, message).
pub fn plan(args: &PlanArgs) -> Result<String, (i32, String)> {
    with_plan_session(
        &args.workflow,
        args.campaign.as_deref(),
        &args.cache,
        &args.threads,
        |session, stopped| Ok(crate::plan::plan_text(session, stopped.as_ref())),
    )
}
