//! `skytie explain WORKFLOW NODE`: one node's key ingredients and provenance. NODE is `stage[item]`
//! (as printed by `plan`), or a unique prefix of it.

use crate::cli::common::{load_workflow, CacheOpt, ThreadsOpt};
use crate::cli::run::plan_stop;
use crate::dag::{Mode, Session};
use crate::hashing::StatCache;
use crate::progress::{Progress, ProgressMode};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug, Clone)]
pub struct ExplainArgs {
    /// Workflow file.
    pub workflow: PathBuf,
    /// Node identity, e.g. `toy_scale[item_003]`.
    pub node: String,
    /// Use this campaign folder instead of the workflow's `campaign`.
    #[arg(long, value_name = "DIR")]
    pub campaign: Option<PathBuf>,
    #[command(flatten)]
    pub cache: CacheOpt,
    #[command(flatten)]
    pub threads: ThreadsOpt,
}

pub fn main(args: &ExplainArgs) -> i32 {
    let r = (|| {
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
        let stopped = plan_stop(result).map_err(|e| (1, e.to_string()))?;
        let mut text = crate::explain::explain(&session, &args.node).map_err(|e| (1, e))?;
        if let Some(s) = stopped {
            text.push_str(&format!("note: {s}\n"));
        }
        Ok::<String, (i32, String)>(text)
    })();
    match r {
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
