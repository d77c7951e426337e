//! Per-node run records kept in the store: for each node identity (`stage[item]`) and variant, the key and
//! ingredients of its last successful run. `plan` compares a node's current ingredients with its record to
//! say WHY it will run (new node, stage version bump, which param field changed, which input changed);
//! `explain` prints the record as the node's provenance. A second record maps an output key to its content
//! hash so an all-cached run need not read artifacts it does not use. A third one keeps a node's last
//! failure (error message and ingredients) until the node next succeeds, so `plan` can say "failed last
//! time: `<error>`" instead of calling the node new. A run keeps the records of its nodes in one pack
//! ([`crate::dag::record_pack`]), which also maps keys to output hashes.

use crate::hashing::{ContentHash, NodeKey};
use crate::store::Store;
use serde::{Deserialize, Serialize};

/// Record namespace: node identity@variant → [`NodeRecord`] (JSON).
pub const NODES_NS: &str = "nodes";
/// Record namespace: key hex → output content hash (32 raw bytes).
pub const OUTPUT_NS: &str = "outputs";
/// Record namespace: node identity@variant → [`FailureRecord`] of its last failed run (JSON); removed when
/// the node next succeeds.
pub const FAILURES_NS: &str = "failures";

/// One input as recorded: its label, where it came from (upstream identity or file path) and its hash.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RecordedInput {
    pub label: String,
    pub source: String,
    pub hash: String,
}

/// What a node ran with: its identity and variant, the key of the attempt, and the ingredients of that key.
/// Both the record of a success and that of a failure start with it (flattened: the JSON keeps one level).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Ingredients {
    pub identity: String,
    pub variant: String,
    /// Key of the attempt (hex); empty when a node failed before its key was known (e.g. an input file could
    /// not be read).
    pub key: String,
    pub stage_version: String,
    pub params: serde_json::Value,
    pub inputs: Vec<RecordedInput>,
}

/// The ingredients and provenance of a node's last successful run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NodeRecord {
    #[serde(flatten)]
    pub ran_with: Ingredients,
    pub output_hash: String,
    /// Seconds the stage ran when it was computed (0 if it was found in the cache by this run).
    pub seconds: f64,
    /// When the record was written, seconds since the Unix epoch.
    pub recorded_unix_s: u64,
    pub skytie_version: String,
}

/// A node's last failed run: the error and the ingredients it failed with.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FailureRecord {
    #[serde(flatten)]
    pub ran_with: Ingredients,
    /// The stage's error (or panic) message.
    pub error: String,
    /// When the failure was recorded, seconds since the Unix epoch.
    pub recorded_unix_s: u64,
    pub skytie_version: String,
}

/// Record name of a node identity in a variant.
pub fn record_name(identity: &str, variant: &str) -> String {
    format!("{identity}@{variant}")
}

/// The last record of node `identity` in `variant`: from the record packs (where runs keep them, see
/// [`crate::dag::record_pack`]), else a record of its own (as [`save_record`] writes).
pub fn load_record(store: &Store, identity: &str, variant: &str) -> Option<NodeRecord> {
    record_in(
        &crate::dag::record_pack::RecordIndex::load(store),
        identity,
        variant,
    )
    .or_else(|| load_record_file(store, identity, variant))
}

/// The record of node `identity` in `variant` from the loaded record packs, if it is there and names it.
pub fn record_in(
    index: &crate::dag::record_pack::RecordIndex,
    identity: &str,
    variant: &str,
) -> Option<NodeRecord> {
    let rec: NodeRecord = serde_json::from_slice(&index.record_bytes(identity, variant)?).ok()?;
    (rec.ran_with.identity == identity && rec.ran_with.variant == variant).then_some(rec)
}

/// A record of its own of node `identity` in `variant` (as [`save_record`] writes, and earlier versions did
/// for every node), without looking into the packs.
pub fn load_record_file(store: &Store, identity: &str, variant: &str) -> Option<NodeRecord> {
    let bytes = store.get_record(NODES_NS, &record_name(identity, variant))?;
    serde_json::from_slice(&bytes).ok()
}

/// Whether any failure record exists (one listing of their folder).
pub fn any_failure_recorded(store: &Store) -> bool {
    std::fs::read_dir(store.root().join("records").join(FAILURES_NS))
        .map(|mut d| d.next().is_some())
        .unwrap_or(false)
}

/// Saves the record of a successful run as a record of its own (runs write theirs into a pack); a failure
/// recorded for the node is removed (it succeeded since).
pub fn save_record(store: &Store, record: &NodeRecord) -> Result<(), String> {
    let bytes = serde_json::to_vec(record).map_err(|e| e.to_string())?;
    let name = record_name(&record.ran_with.identity, &record.ran_with.variant);
    store
        .put_record(NODES_NS, &name, &bytes)
        .map_err(|e| e.to_string())?;
    store
        .remove_record(FAILURES_NS, &name)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

pub fn load_failure(store: &Store, identity: &str, variant: &str) -> Option<FailureRecord> {
    let bytes = store.get_record(FAILURES_NS, &record_name(identity, variant))?;
    serde_json::from_slice(&bytes).ok()
}

pub fn save_failure(store: &Store, failure: &FailureRecord) -> Result<(), String> {
    let bytes = serde_json::to_vec(failure).map_err(|e| e.to_string())?;
    store
        .put_record(
            FAILURES_NS,
            &record_name(&failure.ran_with.identity, &failure.ran_with.variant),
            &bytes,
        )
        .map_err(|e| e.to_string())
}

/// Why a node that FAILED last time will run: `failed last time: <error>`, then what changed since that
/// attempt (nothing, when it is retried with the same ingredients). The error is cut to its first line.
pub fn failure_reasons(
    failure: &FailureRecord,
    stage_version: &str,
    params: &serde_json::Value,
    inputs: &[RecordedInput],
) -> Vec<String> {
    let first_line = failure.error.lines().next().unwrap_or_default();
    let mut why = vec![format!("failed last time: {first_line}")];
    why.extend(
        reasons(Some(&failure.ran_with), stage_version, params, inputs)
            .into_iter()
            .filter(|w| !w.starts_with("same ingredients")),
    );
    why
}

pub fn load_output_hash(store: &Store, key: &NodeKey) -> Option<ContentHash> {
    let bytes = store.get_record(OUTPUT_NS, &key.to_string())?;
    let arr: [u8; 32] = bytes.as_slice().try_into().ok()?;
    Some(ContentHash(arr))
}

pub fn save_output_hash(store: &Store, key: &NodeKey, hash: &ContentHash) -> Result<(), String> {
    store
        .put_record(OUTPUT_NS, &key.to_string(), &hash.0)
        .map_err(|e| e.to_string())
}

/// Why a node whose key is not in the cache will run, compared with its last record. `upstream_changed`
/// lists the identities of upstream nodes that will run or whose output changed.
pub fn reasons(
    previous: Option<&Ingredients>,
    stage_version: &str,
    params: &serde_json::Value,
    inputs: &[RecordedInput],
) -> Vec<String> {
    let Some(prev) = previous else {
        return vec![
            "new node (no earlier run of this item: new input item or first run)".to_string(),
        ];
    };
    let mut why = Vec::new();
    if prev.stage_version != stage_version {
        why.push(format!(
            "stage version changed: {} -> {}",
            prev.stage_version, stage_version
        ));
    }
    let mut changes = Vec::new();
    crate::dag::json_diff::diff_json("", &prev.params, params, &mut changes);
    for c in changes {
        why.push(format!("param changed: {c}"));
    }
    for input in inputs {
        match prev.inputs.iter().find(|p| p.label == input.label) {
            None => why.push(format!("new input {} ({})", input.label, input.source)),
            Some(p) if p.hash != input.hash => {
                if input.hash.is_empty() {
                    why.push(format!("upstream will run: {}", input.source));
                } else if input.source.starts_with("file ") {
                    why.push(format!("input changed: {}", input.source));
                } else {
                    why.push(format!("upstream changed: {}", input.source));
                }
            }
            Some(_) => {}
        }
    }
    for p in &prev.inputs {
        if !inputs.iter().any(|i| i.label == p.label) {
            why.push(format!("input removed: {} ({})", p.label, p.source));
        }
    }
    if why.is_empty() {
        why.push(
            "same ingredients as its last run, but the artifact is no longer in the cache"
                .to_string(),
        );
    }
    why
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn diff_names_nested_changed_fields() {
        let mut out = Vec::new();
        crate::dag::json_diff::diff_json(
            "",
            &json!({"a": 1, "b": {"c": 2, "d": 3}}),
            &json!({"a": 1, "b": {"c": 5, "d": 3}, "e": true}),
            &mut out,
        );
        assert_eq!(
            out,
            vec!["b.c: 2 -> 5".to_string(), "e: (absent) -> true".to_string()]
        );
    }

    #[test]
    fn reasons_name_version_param_and_input() {
        let prev = Ingredients {
            identity: "s[i]".into(),
            variant: "default".into(),
            key: "k".into(),
            stage_version: "1".into(),
            params: json!({"gain": 2}),
            inputs: vec![RecordedInput {
                label: "0".into(),
                source: "file a.txt".into(),
                hash: "h1".into(),
            }],
        };
        let inputs = vec![RecordedInput {
            label: "0".into(),
            source: "file a.txt".into(),
            hash: "h2".into(),
        }];
        let why = reasons(Some(&prev), "2", &json!({"gain": 3}), &inputs);
        assert_eq!(
            why,
            vec![
                "stage version changed: 1 -> 2".to_string(),
                "param changed: gain: 2 -> 3".to_string(),
                "input changed: file a.txt".to_string()
            ]
        );
        assert!(reasons(None, "1", &json!({}), &[])[0].starts_with("new node"));
    }
}
