//! `aerial`: one aerial image's row (nadir or oblique) out of the campaign snapshot — the per-item entry point
//! for stages that work per (recording × aerial image). Like `recording`, its unchanged output cuts off its
//! dependents when other rows of the campaign change.

use crate::dag::{Handle, NodeCtx, Stage, StageError};
use crate::nodes::campaign::load::CampaignSnapshot;
use crate::workflow::{ParamError, StageParams};
use serde::{Deserialize, Serialize};
use skytie_stages::campaign::{AerialImage, AerialKind};
use std::sync::Arc;

crate::serde_artifact!(AerialImage);

/// Parameters of the aerial-row selector (set by the pipeline).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SelectAerialParams {
    pub image_id: String,
    pub kind: AerialKind,
}

impl StageParams for SelectAerialParams {
    fn validate(&self) -> Result<(), Vec<ParamError>> {
        Ok(())
    }
}

impl Default for SelectAerialParams {
    fn default() -> Self {
        Self {
            image_id: String::new(),
            kind: AerialKind::Nadir,
        }
    }
}

/// One aerial image's row of the snapshot.
pub struct SelectAerial;

impl Stage for SelectAerial {
    const NAME: &'static str = "aerial";
    const VERSION: &'static str = "1";
    type Params = SelectAerialParams;
    type Output = AerialImage;
    type Inputs = Handle<CampaignSnapshot>;

    fn run(
        &self,
        p: &SelectAerialParams,
        snap: Arc<CampaignSnapshot>,
        _: &NodeCtx,
    ) -> Result<AerialImage, StageError> {
        let rows = match p.kind {
            AerialKind::Nadir => &snap.campaign.nadir,
            AerialKind::Oblique => &snap.campaign.oblique,
        };
        rows.iter()
            .find(|r| r.image_id == p.image_id)
            .cloned()
            .ok_or_else(|| {
                StageError::new(format!(
                    "aerial image '{}' is not in the campaign any more",
                    p.image_id
                ))
            })
    }
}
