//! `sparse_cloud`: per panorama triplet (recordings i−1, i, i+1 along the trajectory) the façade sparse cloud
//! (thesis 4.4.1, `skytie_stages::oblique::sparse_cloud`): perspective views per side, AGAST + DAISY, trifocal
//! outlier removal, triangulation in the original equirectangular geometry. Inputs: the three recording rows
//! and panorama files (hashed by content).

use crate::dag::{Handle, InputsOf, NodeCtx, RunResult, Stage, StageError};
use crate::nodes::campaign::image_tiles;
use crate::nodes::campaign::ingest::IngestedImage;
use skytie_stages::campaign::Recording;
use skytie_stages::imaging::equirect::PanoramaLevels;
use skytie_stages::imaging::pyramid::TileSource;
use skytie_stages::oblique::sparse_cloud::{panorama_bands, sparse_cloud, SparseCloudParams};
use skytie_stages::oblique::SparseCloud;

crate::serde_artifact!(SparseCloud);

/// The sparse-cloud node; the triplet's members are in trajectory order, the centre second.
pub struct SparseCloudStage;

impl Stage for SparseCloudStage {
    crate::nodes::stage_types!(skytie_stages::oblique::sparse_cloud::STAGE, SparseCloudParams => SparseCloud,
        inputs: (Vec<Handle<Recording>>, Vec<Handle<IngestedImage>>));

    fn run(&self, p: &SparseCloudParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (recs, panos) = inputs;
        if recs.len() != 3 || panos.len() != 3 {
            return Err(StageError::new(
                "internal: sparse_cloud needs exactly three recordings and panoramas",
            ));
        }
        let images = recs
            .iter()
            .zip(&panos)
            .map(|(rec, pano)| {
                let pyramid = image_tiles::open(pano)?;
                let size = (pano.width as usize, pano.height as usize);
                let bands = panorama_bands(rec, p, size, pyramid.layout().levels() - 1);
                PanoramaLevels::read_bands(&pyramid, &bands)
                    .map_err(|e| StageError::new(e.to_string()))
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(sparse_cloud(
            [&recs[0], &recs[1], &recs[2]],
            [&images[0], &images[1], &images[2]],
            p,
        ))
    }
}
