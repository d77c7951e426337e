//! The validation phase of the `skytie` pipeline: the loaded campaign's images probed (one cached node per
//! file) and applied to the snapshot (`nodes::validate`), so that the per-item stages are built only for rows
//! whose images are usable — the same validation `skytie check` runs.

use crate::dag::{BuildError, DagBuilder, Handle, RawFile};
use crate::nodes::campaign::load::CampaignSnapshot;
use crate::nodes::campaign::validate::{ProbeImage, ValidateImages};
use crate::nodes::{LoadCampaign, LoadCampaignParams, SummaryParams};
use skytie_stages::campaign::image_jobs;
use std::path::Path;

/// Add load → probe (per image) → validate to `b`; the handle of the validated snapshot. `loaded` is the
/// load node's value (it says which images there are).
pub fn add_validated_snapshot(
    b: &mut DagBuilder,
    root: &Path,
    load_params: &LoadCampaignParams,
    inputs: &[RawFile],
    loaded: &CampaignSnapshot,
) -> Result<Handle<CampaignSnapshot>, BuildError> {
    let snap = b.add(LoadCampaign, "", load_params.clone(), inputs.to_vec())?;
    let probes = image_jobs(&loaded.sourced())
        .iter()
        .map(|job| {
            let label = job.rel_path.to_string_lossy().replace('\\', "/");
            b.add(
                ProbeImage,
                &label,
                SummaryParams::default(),
                RawFile(root.join(&job.rel_path)),
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    b.add(ValidateImages, "", SummaryParams::default(), (snap, probes))
}
