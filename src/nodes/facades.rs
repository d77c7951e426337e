//! `facades`: per panorama triplet the façade planes of its sparse cloud with the visibility hypothesis for
//! the candidate oblique images and box-grid thinning (thesis 4.4.2–4.4.4,
//! `skytie_stages::oblique::facades`). Inputs: the triplet's sparse cloud, its three recording rows, and the
//! rows of the oblique images that may see the centre recording's street
//! (`skytie_stages::oblique::candidates`).

use crate::dag::{Handle, NodeCtx, Stage, StageError};
use skytie_stages::campaign::{AerialImage, Recording};
use skytie_stages::oblique::facades::{find_facades, FacadeParams};
use skytie_stages::oblique::{SparseCloud, TripletFacades};
use std::sync::Arc;

crate::serde_artifact!(TripletFacades);

/// The façade node.
pub struct FacadesStage;

impl Stage for FacadesStage {
    const NAME: &'static str = "facades";
    const VERSION: &'static str = "1";
    type Params = FacadeParams;
    type Output = TripletFacades;
    type Inputs = (
        Handle<SparseCloud>,
        Vec<Handle<Recording>>,
        Vec<Handle<AerialImage>>,
    );

    fn run(
        &self,
        p: &FacadeParams,
        (cloud, recs, oblique): (Arc<SparseCloud>, Vec<Arc<Recording>>, Vec<Arc<AerialImage>>),
        _: &NodeCtx,
    ) -> Result<TripletFacades, StageError> {
        if recs.len() != 3 {
            return Err(StageError::new(
                "internal: facades needs the triplet's three recordings",
            ));
        }
        let oblique: Vec<AerialImage> = oblique.iter().map(|a| (**a).clone()).collect();
        Ok(find_facades(
            &cloud,
            [&recs[0], &recs[1], &recs[2]],
            &oblique,
            p,
        ))
    }
}
