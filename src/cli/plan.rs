//! `skytie plan WORKFLOW [--campaign DIR] [--cache DIR]`: per stage, cached / will run, and why.

use crate::cli::common::{exit_code, with_plan_session, ThreadsOpt, WorkflowTarget};
use clap::Args;

#[derive(Args, Debug, Clone)]
pub struct PlanArgs {
    #[command(flatten)]
    pub target: WorkflowTarget,
    #[command(flatten)]
    pub threads: ThreadsOpt,
}

pub fn main(args: &PlanArgs) -> i32 {
    exit_code(plan(args), |text| {
        print!("{text}");
        0
    })
}

/// The plan text, or (exit code, message).
pub fn plan(args: &PlanArgs) -> Result<String, (i32, String)> {
    with_plan_session(&args.target, &args.threads, |session, stopped| {
        Ok(crate::plan::plan_text(session, stopped.as_ref()))
    })
}
