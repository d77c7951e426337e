//! What the `skytie` pipeline tells the engine about sharding its per-item phase (`crate::dag::shard`): the
//! seeds are the recordings in time order; these stages work on a recording, a window or triplet of
//! neighbouring recordings, or a recording × aerial image pair, and are split between shards. Every other stage
//! of the phase (summaries, the oblique consensus, adjustment, verification, grading) is campaign-wide and
//! runs in the merge. A per-item stage missing here would still be correct, only computed by the merge.

use super::stage;

/// The per-item stages of the `items` phase.
pub const PER_ITEM_STAGES: [&str; 13] = [
    crate::nodes::campaign::load::RECORDING_STAGE.name,
    stage::ORTHO,
    stage::MM_MATCH,
    stage::ORTHO_AERIAL,
    stage::TRANSFORM,
    skytie_stages::nadir::transform_agreement::STAGE.name,
    stage::REFINE,
    stage::BASELINE,
    skytie_stages::nadir::peak_support::STAGE.name,
    stage::CONTROL,
    stage::SPARSE_CLOUD,
    stage::FACADES,
    stage::PATCHES,
];
