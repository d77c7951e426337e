//! `skytie explain WORKFLOW NODE`: one node's key ingredients and provenance. NODE is `stage[item]`
//! (as printed by `plan`), or a unique prefix of it.

use crate::cli::common::{exit_code, with_plan_session, ThreadsOpt, WorkflowTarget};
use clap::Args;

#[derive(Args, Debug, Clone)]
pub struct ExplainArgs {
    #[command(flatten)]
    pub target: WorkflowTarget,
    /// Node identity, e.g. `toy_scale[item_003]`.
    pub node: String,
    #[command(flatten)]
    pub threads: ThreadsOpt,
}

pub fn main(args: &ExplainArgs) -> i32 {
    let r = with_plan_session(&args.target, &args.threads, |session, stopped| {
        let mut text = crate::explain::explain(session, &args.node).map_err(|e| (1, e))?;
        if let Some(s) = stopped {
            text.push_str(&format!("note: {s}\n"));
        }
        Ok(text)
    });
    exit_code(r, |text| {
        print!("{text}");
        0
    })
}
