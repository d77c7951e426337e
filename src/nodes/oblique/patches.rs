//! `patches`: per (triplet centre recording × candidate oblique image) the image-to-plane patches and their
//! hierarchical registration (thesis 4.4.5–4.4.6, `skytie_stages::oblique::patch_registration`). An oblique
//! image that the visibility hypothesis did not accept for any plane gives an empty set. The sparse clouds
//! are the same list as the `facades` node's (the triplet's own first, then its neighbours).

use crate::dag::{Handle, InputsOf, NodeCtx, RunResult, Stage, StageError};
use crate::nodes::campaign::image_tiles;
use crate::nodes::campaign::ingest::IngestedImage;
use crate::nodes::oblique::facades::neighbourhood_cloud;
use skytie_stages::campaign::{AerialImage, Recording};
use skytie_stages::oblique::patch_registration::{register_patches, PatchParams};
use skytie_stages::oblique::{PatchRegistrationSet, PatchStats, SparseCloud, TripletFacades};

crate::serde_artifact!(PatchRegistrationSet);

/// The patch-registration node.
pub struct PatchesStage;

impl Stage for PatchesStage {
    crate::nodes::stage_types!(skytie_stages::oblique::patch_registration::STAGE, PatchParams => PatchRegistrationSet,
        inputs: (Handle<Recording>, Handle<IngestedImage>, Handle<AerialImage>, Handle<IngestedImage>, Vec<Handle<SparseCloud>>, Handle<TripletFacades>));

    fn run(&self, p: &PatchParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (rec, pano, oblique, oblique_file, clouds, facades) = inputs;
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
        if (oblique_file.width, oblique_file.height)
            != (u64::from(oblique.width_px), u64::from(oblique.height_px))
        {
            return Err(StageError::new(format!(
                "{}: oblique image is {}×{} px but aerial/oblique/cameras.csv says {}×{}; fix the width/height columns",
                oblique_file.source, oblique_file.width, oblique_file.height, oblique.width_px, oblique.height_px
            )));
        }
        let pano_img = image_tiles::open(&pano)?;
        let oblique_img = image_tiles::open(&oblique_file)?;
        register_patches(&rec, &pano_img, &oblique, &oblique_img, &cloud, &facades, p)
            .map_err(|e| StageError::new(e.to_string()))
    }
}
