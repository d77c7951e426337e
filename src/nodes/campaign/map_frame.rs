//! `map_frame`: the campaign's intersection frame (`skytie_stages::crs::MapFrameSpec`) from its declaration in
//! `campaign.toml` (`crs`, `frame`) — the tangent frame of a projected CRS with its origin at the first
//! recording (rounded to whole kilometres, so it stays put when recordings are added), or the coordinates as
//! they are. Aerial control points are intersected in it. Its output changes only when the declaration does,
//! so editing rows re-runs nothing downstream of it.

use crate::dag::{Handle, InputsOf, NodeCtx, RunResult, Stage};
use crate::nodes::campaign::load::CampaignSnapshot;
use crate::nodes::campaign::summary::SummaryParams;
use skytie_stages::campaign::Campaign;
use skytie_stages::crs::MapFrameSpec;

crate::serde_artifact!(MapFrameSpec);

/// The campaign's frame spec, and why a `projected` declaration fell back to the coordinates themselves.
pub fn campaign_frame_spec(c: &Campaign) -> (MapFrameSpec, Option<String>) {
    let near = c.recordings.first().map(|r| [r.x, r.y, r.z]).or_else(|| {
        c.nadir
            .iter()
            .chain(&c.oblique)
            .next()
            .map(|a| [a.x, a.y, a.z])
    });
    MapFrameSpec::for_campaign(c.frame, &c.crs, near)
}

/// The map-frame node.
pub struct MapFrameStage;

impl Stage for MapFrameStage {
    crate::nodes::stage_types!(named "map_frame" version "1", SummaryParams => MapFrameSpec,
        inputs: Handle<CampaignSnapshot>);

    fn run(&self, _: &SummaryParams, snap: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        Ok(campaign_frame_spec(&snap.campaign).0)
    }
}
