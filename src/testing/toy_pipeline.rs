//! The `toy` pipeline (`pipeline = "toy"` in a workflow): a campaign folder of `items/*.txt` numbers, or
//! `campaign = "synth:<preset>"` which first runs [`ToyGen`] as phase 1 (staged planning) and then builds
//! phase 2 from the generated folder. Phase 2, per variant: `toy_parse` per item → `toy_scale` per item
//! (if enabled) → one `toy_sum` over all items, whose summary is contributed to metrics under `toy`.

use crate::dag::{DagBuilder, Pipeline, PipelineError, RawFile, Session};
use crate::testing::toy::{
    item_label, list_items, ToyGen, ToyGenParams, ToyParse, ToyParseParams, ToyScale,
    ToyScaleParams, ToySum, ToySumParams, ToySummary,
};
use crate::workflow::{CampaignSource, Workflow};
use std::path::PathBuf;

/// See the module documentation.
pub struct ToyPipeline;

/// Phase 1 (the campaign) is common to all variants: it takes the params of the first variant.
fn first_variant(wf: &Workflow) -> String {
    wf.variants()
        .into_iter()
        .next()
        .unwrap_or_else(|| "default".to_string())
}

fn wf_err(e: impl std::fmt::Display) -> PipelineError {
    PipelineError::Workflow(e.to_string())
}

impl Pipeline for ToyPipeline {
    fn name(&self) -> &'static str {
        "toy"
    }

    fn stage_names(&self) -> Vec<&'static str> {
        vec!["toy_gen", "toy_parse", "toy_scale", "toy_sum"]
    }

    fn validate(&self, wf: &Workflow) -> Result<(), String> {
        let _: ToyGenParams = wf
            .params("toy_gen", &first_variant(wf))
            .map_err(|e| e.to_string())?;
        for v in wf.variants() {
            let _: ToyParseParams = wf.params("toy_parse", &v).map_err(|e| e.to_string())?;
            let _: ToyScaleParams = wf.params("toy_scale", &v).map_err(|e| e.to_string())?;
            let _: ToySumParams = wf.params("toy_sum", &v).map_err(|e| e.to_string())?;
        }
        Ok(())
    }

    fn run(&self, wf: &Workflow, session: &mut Session<'_>) -> Result<(), PipelineError> {
        let campaign_dir: PathBuf = match &wf.campaign {
            // Already resolved against the workflow's folder (or as given by --campaign).
            CampaignSource::Path(p) => p.clone(),
            CampaignSource::Synth { preset, seed } => {
                let mut b = DagBuilder::new();
                let mut params: ToyGenParams =
                    wf.params("toy_gen", &first_variant(wf)).map_err(wf_err)?;
                params.seed = *seed;
                let h = b.add(ToyGen, preset, params, ())?;
                b.request(h);
                let values = session.execute("campaign", b.build());
                PathBuf::from(&values.require(h, "the generated toy campaign")?.path)
            }
        };
        let items = list_items(&campaign_dir).map_err(|e| {
            PipelineError::Input(format!(
                "toy campaign: cannot list items: {e} (expected a folder items/ of *.txt)"
            ))
        })?;
        let scale_enabled = wf.enables("toy_scale");
        let mut b = DagBuilder::new();
        for variant in wf.variants() {
            b.set_variant(&variant);
            let parse: ToyParseParams = wf.params("toy_parse", &variant).map_err(wf_err)?;
            let scale: ToyScaleParams = wf.params("toy_scale", &variant).map_err(wf_err)?;
            let sum: ToySumParams = wf.params("toy_sum", &variant).map_err(wf_err)?;
            let mut values = Vec::with_capacity(items.len());
            for file in &items {
                let label = item_label(file);
                let mut h = b.add(ToyParse, &label, parse.clone(), RawFile(file.clone()))?;
                if scale_enabled {
                    h = b.add(ToyScale, &label, scale.clone(), h)?;
                }
                values.push(h);
            }
            let total = b.add(ToySum, "", sum, values)?;
            b.metrics(
                total,
                "toy",
                |s: &ToySummary| serde_json::json!({ "sum": s.sum, "count": s.count }),
            );
        }
        session.execute("items", b.build());
        Ok(())
    }
}
