//! The records of an execution: each node that ran (or was found under a key its record did not name) is
//! recorded once per variant in the execution's record pack, which is committed and flushed at the end.

use super::{now_unix_s, Exec};
use crate::dag::inputs::NodeId;
use crate::dag::record::{self, Ingredients, NodeRecord};
use crate::dag::record_pack::{name_hash, PackWriter};
use crate::hashing::{ContentHash, NodeKey};

impl Exec<'_> {
    /// Records node `id`'s run (key, output hash, ingredients) in this execution's pack, once per variant.
    pub(super) fn write_records(&self, id: NodeId, key: NodeKey, hash: ContentHash, seconds: f64) {
        let node = &self.dag.nodes[id];
        let identity = node.identity();
        let inputs = self.recorded_now(id);
        let mut pack = self.pack.lock().unwrap_or_else(|e| e.into_inner());
        if pack.is_none() {
            match PackWriter::open(self.env.store) {
                Ok(w) => *pack = Some(w),
                Err(e) => {
                    drop(pack);
                    self.warn(format!("could not write the run's records: {e}"));
                    return;
                }
            }
        }
        let Some(writer) = pack.as_mut() else { return };
        for variant in &node.variants {
            let rec = NodeRecord {
                ran_with: Ingredients {
                    identity: identity.clone(),
                    variant: variant.clone(),
                    key: key.to_string(),
                    stage_version: node.version.to_string(),
                    params: (*node.params_json).clone(),
                    inputs: inputs.clone(),
                },
                output_hash: hash.to_string(),
                seconds,
                recorded_unix_s: now_unix_s(),
                skytie_version: env!("CARGO_PKG_VERSION").to_string(),
            };
            let name = name_hash(node.stage, &node.item, variant);
            // With a remote cache every node record (and below, the key's output hash) is also a record of its own,
            // uploaded: other hosts and the remote collection (whose roots they are) read the remote's records, not
            // this host's packs.
            let remote = self.env.store.remote_url().is_some();
            let pushed = serde_json::to_vec(&rec)
                .map_err(std::io::Error::other)
                .and_then(|bytes| {
                    writer.push(name, key, hash, &bytes)?;
                    if remote {
                        let own = record::record_name(&identity, variant);
                        self.env
                            .store
                            .put_record(record::NODES_NS, &own, &bytes)
                            .map_err(std::io::Error::other)?;
                    }
                    Ok(())
                });
            if let Err(e) = pushed {
                drop(pack);
                self.warn(format!("could not write the run's records: {e}"));
                return;
            }
        }
        drop(pack);
        if self.env.store.remote_url().is_some() {
            if let Err(e) = record::save_output_hash(self.env.store, &key, &hash) {
                self.warn(format!("could not write the run's records: {e}"));
            }
        }
        if self.failures_recorded {
            for variant in &node.variants {
                let name = record::record_name(&identity, variant);
                if let Err(e) = self.env.store.remove_record(record::FAILURES_NS, &name) {
                    self.warn(format!("could not update a failure record: {e}"));
                }
            }
        }
    }

    /// Commits this execution's record pack and flushes the entries it stored to disk.
    pub(super) fn commit_records(&self) {
        let pack = self.pack.lock().unwrap_or_else(|e| e.into_inner()).take();
        let Some(pack) = pack else { return };
        if let Err(e) = pack.finish() {
            self.warn(format!("could not write the run's records: {e}"));
        }
        if let Err(e) = self.env.store.sync() {
            self.warn(format!("could not flush the cache to disk: {e}"));
        }
    }
}
