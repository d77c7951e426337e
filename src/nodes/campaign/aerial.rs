//! `aerial`: one aerial image's row (nadir or oblique) out of the campaign snapshot — the per-item entry point
//! for stages that work per (recording × aerial image). Like `recording`, its unchanged output cuts off its
//! dependents when other rows of the campaign change.

use crate::dag::{BuildError, DagBuilder, Handle, InputsOf, NodeCtx, RunResult, Stage, StageError};
use crate::nodes::campaign::load::CampaignSnapshot;
use skytie_stages::campaign::{AerialImage, AerialKind};
use skytie_stages::params::StageId;
use std::collections::BTreeMap;

crate::serde_artifact!(AerialImage);

skytie_stages::params! {
    /// Parameters of the aerial-row selector (set by the pipeline).
    pub struct SelectAerialParams {
        /// The aerial image's id.
        image_id: String = String::new();
        /// Nadir or oblique.
        kind: AerialKind = AerialKind::Nadir;
    }
}

/// The stage's identity in cache keys (the computation lives in this node); bump the version whenever its
/// output for the same inputs and parameters changes.
pub const STAGE: StageId = StageId::new("aerial", "1");

/// One aerial image's row of the snapshot.
pub struct SelectAerial;

impl Stage for SelectAerial {
    crate::nodes::stage_types!(STAGE, SelectAerialParams => AerialImage, inputs: Handle<CampaignSnapshot>);

    fn run(&self, p: &SelectAerialParams, snap: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        snap.aerial(p.kind, &p.image_id).cloned().ok_or_else(|| {
            StageError::new(format!(
                "aerial image '{}' is not in the campaign any more",
                p.image_id
            ))
        })
    }
}

/// The `aerial` nodes of one kind that a pipeline has added, by row index in the snapshot: a row's node is added
/// the first time a recording needs it and shared by every later one.
pub struct AerialRowNodes {
    kind: AerialKind,
    snap: Handle<CampaignSnapshot>,
    nodes: BTreeMap<usize, Handle<AerialImage>>,
}

impl AerialRowNodes {
    pub fn new(kind: AerialKind, snap: Handle<CampaignSnapshot>) -> Self {
        Self {
            kind,
            snap,
            nodes: BTreeMap::new(),
        }
    }

    /// The node of row `index` (`row` is that row of the snapshot), added on first use.
    pub fn get_or_add(
        &mut self,
        b: &mut DagBuilder,
        index: usize,
        row: &AerialImage,
    ) -> Result<Handle<AerialImage>, BuildError> {
        if let Some(h) = self.nodes.get(&index) {
            return Ok(*h);
        }
        let kind_name = match self.kind {
            AerialKind::Nadir => "nadir",
            AerialKind::Oblique => "oblique",
        };
        let h = b.add(
            SelectAerial,
            &format!("{kind_name} {}", row.image_id),
            SelectAerialParams {
                image_id: row.image_id.clone(),
                kind: self.kind,
            },
            self.snap,
        )?;
        self.nodes.insert(index, h);
        Ok(h)
    }
}
