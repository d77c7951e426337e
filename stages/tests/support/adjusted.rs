//! A synthetic campaign adjusted end to end, for the tests of what is written from an adjustment run (output
//! files, GeoPackage): the campaign, its run, and its check points compared before and after.

use skytie_stages::adjustment::campaign_checkpoints::{compare_checkpoints, CheckPointComparison};
use skytie_stages::adjustment::synthetic_campaign::{SyntheticCampaign, SyntheticCampaignSpec};
use skytie_stages::adjustment::{
    run, AdjustConfig, AdjustmentRun, SyntheticBlockSpec, ViewSelection,
};

/// The synthetic campaign of `block` (default campaign settings otherwise), adjusted with `config`.
pub fn adjusted_campaign(
    block: SyntheticBlockSpec,
    config: &AdjustConfig,
) -> (SyntheticCampaign, AdjustmentRun) {
    let c = SyntheticCampaignSpec {
        block,
        ..SyntheticCampaignSpec::default()
    }
    .generate();
    let r = run(&c.adjust_inputs(), config).unwrap();
    (c, r)
}

/// The campaign's check points measured in the views `selection` picks (1 px σ), before and after `r`.
pub fn checkpoint_comparison(
    c: &SyntheticCampaign,
    r: &AdjustmentRun,
    selection: ViewSelection,
) -> CheckPointComparison {
    compare_checkpoints(
        &c.recordings,
        &c.pano_size_px,
        r,
        &c.checkpoints,
        &c.observations,
        selection,
        1.0,
    )
    .unwrap()
}
