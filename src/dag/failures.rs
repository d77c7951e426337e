//! Failed nodes kept as records in the store, so `skytie plan` can say why a node that failed last time runs
//! again and what changed since.

use crate::dag::builder::Dag;
use crate::dag::executor::{recorded_inputs, NodeReport};
use crate::dag::record::{save_failure, FailureRecord, Ingredients};
use crate::dag::status::NodeStatus;
use crate::store::Store;

/// Records every FAILED node of an executed (run-mode) phase under its first variant, as node records are
/// (nodes skipped because an upstream failed are not failures of their own). Returns the number recorded, or
/// the first error.
pub fn save_failures(store: &Store, dag: &Dag, reports: &[NodeReport]) -> Result<usize, String> {
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let mut recorded = 0;
    for report in reports {
        let NodeStatus::Failed(error) = &report.status else {
            continue;
        };
        let Some(node) = dag.nodes().get(report.id) else {
            continue;
        };
        let failure = FailureRecord {
            ran_with: Ingredients {
                identity: report.identity.clone(),
                variant: node
                    .variants
                    .first()
                    .cloned()
                    .unwrap_or_else(|| "default".to_string()),
                key: report.key.map(|k| k.to_string()).unwrap_or_default(),
                stage_version: node.version.to_string(),
                params: (*node.params_json).clone(),
                inputs: recorded_inputs(dag, reports, report.id),
            },
            error: error.clone(),
            recorded_unix_s: now,
            skytie_version: env!("CARGO_PKG_VERSION").to_string(),
        };
        save_failure(store, &failure)?;
        recorded += 1;
    }
    Ok(recorded)
}
