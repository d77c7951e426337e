//! `facades`: per panorama triplet the façade planes of its sparse cloud with the visibility hypothesis for
//! the candidate oblique images and box-grid thinning (thesis 4.4.2–4.4.4,
//! `skytie_stages::oblique::facades`). Inputs: the triplet's sparse cloud followed by its neighbours' along
//! the street (merged by [`neighbourhood_cloud`]: planes are fitted to the points of the whole stretch), its
//! three recording rows, and the rows of the oblique images that may see the centre recording's street
//! (`skytie_stages::oblique::candidates`).

use crate::dag::{Handle, InputsOf, NodeCtx, RunResult, Stage, StageError};
use skytie_stages::campaign::{AerialImage, Recording};
use skytie_stages::oblique::facades::{find_facades, FacadeParams};
use skytie_stages::oblique::{SparseCloud, TripletFacades};
use std::sync::Arc;

crate::serde_artifact!(TripletFacades);

/// The façade node.
pub struct FacadesStage;

impl Stage for FacadesStage {
    crate::nodes::stage_types!(skytie_stages::oblique::facades::STAGE, FacadeParams => TripletFacades,
        inputs: (Vec<Handle<SparseCloud>>, Vec<Handle<Recording>>, Vec<Handle<AerialImage>>));

    fn run(&self, p: &FacadeParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (clouds, recs, oblique) = inputs;
        if recs.len() != 3 {
            return Err(StageError::new(
                "internal: facades needs the triplet's three recordings",
            ));
        }
        let cloud = neighbourhood_cloud(&clouds)?;
        let oblique: Vec<AerialImage> = oblique.iter().map(|a| (**a).clone()).collect();
        Ok(find_facades(
            &cloud,
            [&recs[0], &recs[1], &recs[2]],
            &oblique,
            p,
        ))
    }
}

/// The triplet's own cloud (first) merged with its neighbours' (`SparseCloud::with_neighbours`); the
/// `facades` and `patches` nodes merge the same list, so plane inlier indices refer to the same points.
pub fn neighbourhood_cloud(clouds: &[Arc<SparseCloud>]) -> Result<SparseCloud, StageError> {
    let Some((own, neighbours)) = clouds.split_first() else {
        return Err(StageError::new(
            "internal: facades/patches need the triplet's sparse cloud",
        ));
    };
    Ok(own.with_neighbours(neighbours.iter().map(|c| c.as_ref())))
}
