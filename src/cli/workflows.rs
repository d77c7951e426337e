//! `skytie workflows [show NAME]`: the built-in workflows — a list with each one's description, or one
//! workflow's text to copy and adapt (`skytie workflows show nadir > my-nadir.toml`).

use super::builtin_workflows::{names, BUILT_IN};
use crate::workflow::Workflow;
use clap::{Args, Subcommand};

/// Arguments of `skytie workflows`.
#[derive(Args, Debug)]
pub struct WorkflowsArgs {
    #[command(subcommand)]
    pub command: Option<WorkflowsCommand>,
}

/// What to do with the built-in workflows.
#[derive(Subcommand, Debug)]
pub enum WorkflowsCommand {
    /// Print one built-in workflow's TOML text.
    Show {
        /// Its name (as listed by `skytie workflows`).
        name: String,
    },
}

/// Run `skytie workflows`; returns the exit code.
pub fn main(a: &WorkflowsArgs) -> i32 {
    match &a.command {
        None => {
            println!("Built-in workflows (run one with `skytie run NAME [--campaign DIR]`):");
            for name in names() {
                let description = Workflow::built_in(name, BUILT_IN)
                    .ok()
                    .and_then(|w| w.description)
                    .unwrap_or_default();
                println!("  {name:<16} {description}");
            }
            println!("`skytie workflows show NAME` prints one; a workflow file of your own is run the same way.");
            0
        }
        Some(WorkflowsCommand::Show { name }) => {
            let file = format!("{}.toml", name.trim_end_matches(".toml"));
            match BUILT_IN.iter().find(|(n, _)| *n == file) {
                Some((_, text)) => {
                    print!("{text}");
                    0
                }
                None => {
                    eprintln!(
                        "error: no built-in workflow '{name}' (built in: {})",
                        names().join(", ")
                    );
                    2
                }
            }
        }
    }
}
