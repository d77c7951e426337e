//! `skytie explain WORKFLOW NODE`: one node's key ingredients and provenance. NODE is `stage[item]`
//! (as printed by `plan`), or a unique prefix of it.

use crate::cli::common::{with_plan_session, CacheOpt, ThreadsOpt};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug, Clone)]
pub struct ExplainArgs {
    /// Workflow: a built-in name (`skytie workflows` lists them) or a TOML file.
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
    let r = with_plan_session(
        &args.workflow,
        args.campaign.as_deref(),
        &args.cache,
        &args.threads,
        |session, stopped| {
            let mut text = crate::explain::explain(session, &args.node).map_err(|e| (1, e))?;
            if let Some(s) = stopped {
                text.push_str(&format!("note: {s}\n"));
            }
            Ok(text)
        },
    );
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
