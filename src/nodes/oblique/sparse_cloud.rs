//! `sparse_cloud`: per panorama triplet (recordings i−1, i, i+1 along the trajectory) the façade sparse cloud
//! (thesis 4.4.1, `skytie_stages::oblique::sparse_cloud`): perspective views per side, AGAST + DAISY, trifocal
//! outlier removal, triangulation in the original equirectangular geometry. Inputs: the three recording rows
//! and panorama files (hashed by content).

use crate::dag::{Handle, NodeCtx, RawFile, RawFileValue, Stage, StageError};
use crate::nodes::campaign::decoded_images;
use skytie_stages::campaign::Recording;
use skytie_stages::oblique::sparse_cloud::{sparse_cloud, SparseCloudParams};
use skytie_stages::oblique::SparseCloud;
use std::sync::Arc;

crate::serde_artifact!(SparseCloud);

/// The sparse-cloud node; the triplet's members are in trajectory order, the centre second.
pub struct SparseCloudStage;

impl Stage for SparseCloudStage {
    const NAME: &'static str = skytie_stages::oblique::sparse_cloud::STAGE.name;
    const VERSION: &'static str = skytie_stages::oblique::sparse_cloud::STAGE.version;
    type Params = SparseCloudParams;
    type Output = SparseCloud;
    type Inputs = (Vec<Handle<Recording>>, Vec<RawFile>);

    fn run(
        &self,
        p: &SparseCloudParams,
        (recs, panos): (Vec<Arc<Recording>>, Vec<RawFileValue>),
        _: &NodeCtx,
    ) -> Result<SparseCloud, StageError> {
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
