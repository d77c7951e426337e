//! `sparse_cloud`: per panorama triplet (recordings i−1, i, i+1 along the trajectory) the façade sparse cloud
//! (thesis 4.4.1, `skytie_stages::oblique::sparse_cloud`): perspective views per side, AGAST + DAISY, trifocal
//! outlier removal, triangulation in the original equirectangular geometry. Inputs: the three recording rows
//! and panorama files (hashed by content).

use crate::dag::{Handle, InputsOf, NodeCtx, RawFile, RunResult, Stage, StageError};
use crate::nodes::campaign::decoded_images;
use skytie_stages::campaign::Recording;
use skytie_stages::oblique::sparse_cloud::{sparse_cloud, SparseCloudParams};
use skytie_stages::oblique::SparseCloud;

crate::serde_artifact!(SparseCloud);

/// The sparse-cloud node; the triplet's members are in trajectory order, the centre second.
pub struct SparseCloudStage;

impl Stage for SparseCloudStage {
    crate::nodes::stage_types!(skytie_stages::oblique::sparse_cloud::STAGE, SparseCloudParams => SparseCloud);
    type Inputs = (Vec<Handle<Recording>>, Vec<RawFile>);

    fn run(&self, p: &SparseCloudParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (recs, panos) = inputs;
        if recs.len() != 3 || panos.len() != 3 {
            return Err(StageError::new(
                "internal: sparse_cloud needs exactly three recordings and panoramas",
            ));
        }
        let images = panos
            .iter()
            .map(decoded_images::gray)
            .collect::<Result<Vec<_>, _>>()?;
        Ok(sparse_cloud(
            [&recs[0], &recs[1], &recs[2]],
            [&images[0], &images[1], &images[2]],
            p,
        ))
    }
}
