//! The `vehicle` phase of the `skytie` pipeline: before the per-recording stages, the recording vehicle is found
//! in a sample of the campaign's panoramas (`nodes::vehicle`), and every ortho image masks the detected box
//! instead of the `[ortho.vehicle]` values — unless `[ortho.vehicle] detect = false` makes those the mask.

use super::wf_err;
use crate::dag::{DagBuilder, PipelineError, RawFile, Session};
use crate::nodes::campaign::CampaignSnapshot;
use crate::nodes::vehicle::{DetectVehicle, VehicleDetection, VehicleNodeParams};
use crate::nodes::{LoadCampaign, LoadCampaignParams};
use crate::workflow::Workflow;
use skytie_stages::nadir::vehicle_detect::{spread_indices, VehicleDetectParams};
use skytie_stages::nadir::OrthoParams;
use std::path::Path;

/// Run the detection when the ortho images are made and asked to use it; `None` otherwise.
pub fn detect(
    wf: &Workflow,
    session: &mut Session<'_>,
    root: &Path,
    snapshot: &CampaignSnapshot,
    load: (&LoadCampaignParams, &[RawFile]),
) -> Result<Option<VehicleDetection>, PipelineError> {
    let ortho_on = wf.stages.iter().any(|s| s == "ortho");
    let base: OrthoParams = wf.params("ortho", "default").map_err(wf_err)?;
    if !ortho_on || !base.vehicle.detect || !base.vehicle.enabled {
        return Ok(None);
    }
    let detect = VehicleDetectParams::default();
    let recs = &snapshot.campaign.recordings;
    let picks = spread_indices(recs.len(), detect.max_recordings);
    let params = VehicleNodeParams {
        detect,
        image_ids: picks.iter().map(|&i| recs[i].image_id.clone()).collect(),
    };
    let panos: Vec<RawFile> = picks
        .iter()
        .map(|&i| RawFile(root.join("mm/panoramas").join(&recs[i].file)))
        .collect();
    let mut b = DagBuilder::new();
    let snap = b.add(LoadCampaign, "", load.0.clone(), load.1.to_vec())?;
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
    let mut p: OrthoParams = wf.params("ortho", variant).map_err(wf_err)?;
    if let Some(d) = detection {
        p.vehicle = d.mask_or(&p.vehicle);
    }
    Ok(p)
}
