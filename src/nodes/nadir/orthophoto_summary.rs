//! `orthophoto_summary`: the orthophoto route's counts over the campaign
//! (`skytie_stages::orthophoto::OrthophotoSummary`).

use crate::dag::{NodeCtx, Optional, Stage, StageError};
use crate::nodes::campaign::summary::SummaryParams;
use skytie_stages::orthophoto::{OrthophotoControl, OrthophotoSummary};
use std::sync::Arc;

crate::serde_artifact!(OrthophotoSummary);

/// The orthophoto route's counts over the campaign.
pub struct SummarizeOrthophoto;

impl Stage for SummarizeOrthophoto {
    crate::nodes::stage_types!(named "orthophoto_summary" version "2", SummaryParams => OrthophotoSummary,
        inputs: Vec<Optional<OrthophotoControl>>);

    fn run(
        &self,
        _: &SummaryParams,
        results: Vec<Option<Arc<OrthophotoControl>>>,
        _: &NodeCtx,
    ) -> Result<OrthophotoSummary, StageError> {
        let refs: Vec<Option<&OrthophotoControl>> = results.iter().map(|r| r.as_deref()).collect();
        Ok(OrthophotoSummary::of(&refs))
    }
}
