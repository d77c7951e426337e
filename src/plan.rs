//! `skytie plan`: for each phase and stage, how many nodes are cached and how many will run, and WHY each
//! node will run (new item, stage version bump, the param field that changed, the input that changed, or
//! "failed last time: `<error>`" with what changed since that attempt).

use crate::dag::record::{self, RecordedInput};
use crate::dag::{NodeReport, NodeStatus, Phase, PipelineError, Session};
use std::collections::BTreeMap;
use std::fmt::Write;

/// At most this many nodes are listed per stage (the rest are counted).
pub const MAX_LISTED_PER_STAGE: usize = 50;

/// Counts of a plan.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PlanCounts {
    pub cached: usize,
    pub will_run: usize,
    pub failed: usize,
}

/// Count the planned statuses of a session run in plan mode.
pub fn plan_counts(session: &Session<'_>) -> PlanCounts {
    let mut c = PlanCounts::default();
    for r in session.reports() {
        match r.status {
            NodeStatus::Cached | NodeStatus::Executed => c.cached += 1,
            NodeStatus::WillRun { .. } => c.will_run += 1,
            NodeStatus::Failed(_) | NodeStatus::Skipped { .. } => c.failed += 1,
        }
    }
    c
}

/// Why `report` (a node of `phase` that will run) will run. The engine compares the node with its last
/// SUCCESSFUL run; when the node failed since (a failure record exists), the plan says so instead:
/// `failed last time: <error>`, then what changed since the failed attempt (nothing: it is retried as it
/// was), and which upstream nodes will run.
pub fn will_run_reasons(session: &Session<'_>, phase: &Phase, report: &NodeReport) -> Vec<String> {
    let NodeStatus::WillRun { reasons } = &report.status else {
        return Vec::new();
    };
    let Some(node) = phase.dag.nodes().get(report.id) else {
        return reasons.clone();
    };
    let variant = node
        .variants
        .first()
        .map(String::as_str)
        .unwrap_or("default");
    let Some(failure) = record::load_failure(session.store, &report.identity, variant) else {
        return reasons.clone();
    };
    let upstream = |w: &String| w.starts_with("upstream will run");
    let inputs: &[RecordedInput] = &phase.inputs(report.id);
    let mut why: Vec<String> =
        record::failure_reasons(&failure, node.version, &node.params_json, inputs)
            .into_iter()
            .filter(|w| !upstream(w))
            .collect();
    why.extend(reasons.iter().filter(|w| upstream(w)).cloned());
    why
}

/// At most this many reasons are listed for one node (a global node fed by hundreds of items has one
/// "upstream will run" reason per input).
pub const MAX_REASONS_LISTED: usize = 3;

/// The reasons of one node on one line: the first [`MAX_REASONS_LISTED`], then "… and N more".
pub fn reasons_line(reasons: &[String]) -> String {
    if reasons.len() <= MAX_REASONS_LISTED + 1 {
        return reasons.join("; ");
    }
    format!(
        "{}; … and {} more",
        reasons[..MAX_REASONS_LISTED].join("; "),
        reasons.len() - MAX_REASONS_LISTED
    )
}

/// The human-readable plan. `stopped` is the reason planning could not continue past the last phase.
pub fn plan_text(session: &Session<'_>, stopped: Option<&PipelineError>) -> String {
    let mut out = String::new();
    for phase in &session.phases {
        let _ = writeln!(out, "phase '{}': {} nodes", phase.name, phase.reports.len());
        let mut by_stage: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
        for (i, r) in phase.reports.iter().enumerate() {
            by_stage.entry(r.stage).or_default().push(i);
        }
        for (stage, ids) in by_stage {
            let reports: Vec<_> = ids.iter().map(|&i| &phase.reports[i]).collect();
            let cached = reports.iter().filter(|r| r.status.is_ok()).count();
            let will_run: Vec<_> = reports
                .iter()
                .filter(|r| matches!(r.status, NodeStatus::WillRun { .. }))
                .collect();
            let bad: Vec<_> = reports
                .iter()
                .filter(|r| matches!(r.status, NodeStatus::Failed(_) | NodeStatus::Skipped { .. }))
                .collect();
            let _ = writeln!(
                out,
                "  {stage:<20} {cached:>6} cached  {:>6} will run{}",
                will_run.len(),
                if bad.is_empty() {
                    String::new()
                } else {
                    format!("  {:>6} cannot run", bad.len())
                }
            );
            for r in will_run.iter().take(MAX_LISTED_PER_STAGE) {
                let reasons = will_run_reasons(session, phase, r);
                let _ = writeln!(out, "    {}: {}", r.identity, reasons_line(&reasons));
            }
            if will_run.len() > MAX_LISTED_PER_STAGE {
                let _ = writeln!(
                    out,
                    "    … and {} more",
                    will_run.len() - MAX_LISTED_PER_STAGE
                );
            }
            for r in bad.iter().take(MAX_LISTED_PER_STAGE) {
                match &r.status {
                    NodeStatus::Failed(m) => {
                        let _ = writeln!(out, "    {}: cannot run: {m}", r.identity);
                    }
                    NodeStatus::Skipped { upstream } => {
                        let _ = writeln!(
                            out,
                            "    {}: cannot run: upstream {upstream} cannot run",
                            r.identity
                        );
                    }
                    _ => {}
                }
            }
        }
    }
    let c = plan_counts(session);
    let _ = writeln!(
        out,
        "total: {} cached, {} will run, {} cannot run",
        c.cached, c.will_run, c.failed
    );
    if let Some(e) = stopped {
        let _ = writeln!(out, "note: {e}");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_reason_lists_are_cut_with_a_count() {
        let few: Vec<String> = (0..4).map(|i| format!("r{i}")).collect();
        assert_eq!(reasons_line(&few), "r0; r1; r2; r3");
        let many: Vec<String> = (0..250).map(|i| format!("r{i}")).collect();
        assert_eq!(reasons_line(&many), "r0; r1; r2; … and 247 more");
    }
}
