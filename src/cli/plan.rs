//! `skytie plan WORKFLOW [--campaign DIR] [--cache DIR]`: per stage, cached / will run, and why.

use crate::cli::common::{load_workflow, CacheOpt, ThreadsOpt};
use crate::cli::run::plan_stop;
use crate::dag::{Mode, Session};
use crate::hashing::StatCache;
use crate::progress::{Progress, ProgressMode};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug, Clone)]
pub struct PlanArgs {
    /// Workflow file.
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
    let (wf, pipeline) =
        load_workflow(&args.workflow, args.campaign.as_deref()).map_err(|e| (2, e))?;
    let store = args.cache.open().map_err(|e| (2, e))?;
    let stat_cache = StatCache::open(store.root());
    let progress = Progress::new(ProgressMode::Quiet);
    let mut session = Session::new(&store, &stat_cache, &progress, Mode::Plan);
    let result = args
        .threads
        .install(|| pipeline.run(&wf, &mut session))
        .map_err(|e| (2, e))?;
    let _ = stat_cache.save();
    let stopped = plan_stop(result).map_err(|e| (1, e.to_string()))?;
    Ok(crate::plan::plan_text(&session, stopped.as_ref()))
}
