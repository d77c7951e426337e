//! The `vehicle` phase of the `skytie` pipeline: before the per-recording stages, the recording vehicle is found
//! in a sample of the campaign's validated panoramas (`nodes::nadir::vehicle`), and every ortho image masks the
//! detected box instead of the `[ortho.vehicle]` values — unless `[ortho.vehicle] detect = false` makes those
//! the mask.

use super::validate::add_validated_snapshot;
use super::{stage, wf_err};
use crate::dag::{DagBuilder, PipelineError, RawFile, Session};
use crate::nodes::campaign::ingest::ingest_file;
use crate::nodes::campaign::load::CampaignSnapshot;
use crate::nodes::nadir::vehicle::{DetectVehicle, VehicleDetection, VehicleNodeParams};
use crate::nodes::LoadCampaignParams;
use crate::workflow::Workflow;
use skytie_stages::nadir::vehicle_detect::{spread_indices, VehicleDetectParams};
use skytie_stages::nadir::OrthoParams;
use std::path::Path;

/// The campaign as the pipeline has read it: its folder, the load node's parameters and inputs, the loaded
/// snapshot (which images there are) and the validated one (which recordings are usable).
pub struct LoadedCampaign<'a> {
    pub root: &'a Path,
    pub load_params: &'a LoadCampaignParams,
    pub inputs: &'a [RawFile],
    pub loaded: &'a CampaignSnapshot,
    pub validated: &'a CampaignSnapshot,
}

/// Run the detection when the ortho images are made and asked to use it; `None` otherwise.
pub fn detect(
    wf: &Workflow,
    session: &mut Session<'_>,
    c: &LoadedCampaign<'_>,
) -> Result<Option<VehicleDetection>, PipelineError> {
    let ortho_on = wf.enables(stage::ORTHO);
    let base: OrthoParams = wf.params(stage::ORTHO, "default").map_err(wf_err)?;
    if !ortho_on || !base.vehicle.detect || !base.vehicle.enabled {
        return Ok(None);
    }
    let detect = VehicleDetectParams::default();
    let recs = &c.validated.campaign.recordings;
    let picks = spread_indices(recs.len(), detect.max_recordings);
    let params = VehicleNodeParams {
        detect,
        image_ids: picks.iter().map(|&i| recs[i].image_id.clone()).collect(),
    };
    let mut b = DagBuilder::new();
    let snap = add_validated_snapshot(&mut b, c.root, c.load_params, c.inputs, c.loaded)?;
    let panos = picks
        .iter()
        .map(|&i| {
            let path = c.root.join("mm/panoramas").join(&recs[i].file);
            ingest_file(&mut b, &format!("rec {}", recs[i].image_id), path)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let h = b.add(DetectVehicle, "", params, (snap, panos))?;
    b.request(h);
    b.metrics(h, "vehicle", |d: &VehicleDetection| d.metrics());
    let values = session.execute("vehicle", b.build());
    let detection = values.require(h, "the vehicle detection")?;
    if detection.detected.is_none() {
        session.progress.warn(&detection.message);
    }
    Ok(Some((*detection).clone()))
}

/// The `[ortho]` parameters of `variant` with the detected vehicle (when there is one and detection is on).
pub fn ortho_params(
    wf: &Workflow,
    variant: &str,
    detection: Option<&VehicleDetection>,
) -> Result<OrthoParams, PipelineError> {
    let mut p: OrthoParams = wf.params(stage::ORTHO, variant).map_err(wf_err)?;
    if let Some(d) = detection {
        p.vehicle = d.mask_or(&p.vehicle);
    }
    Ok(p)
}
