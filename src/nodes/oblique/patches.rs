//! `patches`: per (triplet centre recording × candidate oblique image) the image-to-plane patches and their
//! hierarchical registration (thesis 4.4.5–4.4.6, `skytie_stages::oblique::patch_registration`). An oblique
//! image that the visibility hypothesis did not accept for any plane gives an empty set. The sparse clouds
//! are the same list as the `facades` node's (the triplet's own first, then its neighbours).

use crate::dag::{Handle, NodeCtx, RawFile, RawFileValue, Stage, StageError};
use crate::nodes::campaign::decoded_images;
use crate::nodes::oblique::facades::neighbourhood_cloud;
use skytie_stages::campaign::{AerialImage, Recording};
use skytie_stages::oblique::patch_registration::{register_patches, PatchParams};
use skytie_stages::oblique::{PatchRegistrationSet, PatchStats, SparseCloud, TripletFacades};
use std::sync::Arc;

crate::serde_artifact!(PatchRegistrationSet);

/// The patch-registration node.
pub struct PatchesStage;

impl Stage for PatchesStage {
    const NAME: &'static str = skytie_stages::oblique::patch_registration::STAGE.name;
    const VERSION: &'static str = skytie_stages::oblique::patch_registration::STAGE.version;
    type Params = PatchParams;
    type Output = PatchRegistrationSet;
    type Inputs = (
        Handle<Recording>,
        RawFile,
        Handle<AerialImage>,
        RawFile,
        Vec<Handle<SparseCloud>>,
        Handle<TripletFacades>,
    );

    fn run(
        &self,
        p: &PatchParams,
        (rec, pano, oblique, oblique_file, clouds, facades): (
            Arc<Recording>,
            RawFileValue,
            Arc<AerialImage>,
            RawFileValue,
            Vec<Arc<SparseCloud>>,
            Arc<TripletFacades>,
        ),
        _: &NodeCtx,
    ) -> Result<PatchRegistrationSet, StageError> {
        let sees = facades
            .planes
            .iter()
            .any(|pl| pl.views.iter().any(|v| v.image_id == oblique.image_id));
        if !sees {
            return Ok(PatchRegistrationSet {
                recording: rec.image_id.clone(),
                oblique_image_id: oblique.image_id.clone(),
                matches: Vec::new(),
                stats: PatchStats::default(),
            });
        }
        let cloud = neighbourhood_cloud(&clouds)?;
        let pano_img = decoded_images::gray(&pano)?;
        let oblique_img = decoded_images::gray(&oblique_file)?;
        Ok(register_patches(
            &rec,
            &pano_img,
            &oblique,
            &oblique_img,
            &cloud,
            &facades,
            p,
        ))
    }
}
