//! `orthophoto`: the orthophoto route of one recording (`skytie_stages::orthophoto`): its north-up ground ortho
//! registered to the orthophoto tile around it, its tie points located there (each template first compared with
//! the window's neighbouring recordings' north-up orthos, the parallax check), and control points with XY from
//! the orthophoto and Z from the DTM (or the MM ground, flagged).

use crate::dag::{Handle, NodeCtx, Stage, StageError};
use crate::nodes::campaign::image_tiles;
use crate::nodes::campaign::ingest::IngestedImage;
use crate::workflow::{ParamError, StageParams};
use serde::{Deserialize, Serialize};
use skytie_stages::campaign::orthophoto::RasterFile;
use skytie_stages::nadir::refine::NeighbourOrtho;
use skytie_stages::nadir::{MmWindowMatch, OrthoImage};
use skytie_stages::orthophoto::{
    orthophoto_control, Dtm, OrthophotoControl, OrthophotoInput, OrthophotoParams,
};
use std::sync::Arc;

crate::serde_artifact!(OrthophotoControl);

/// Parameters of one recording's `orthophoto` node: the route's parameters (the workflow's `[orthophoto]`
/// table) and the campaign's tile and accuracies.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct OrthophotoNodeParams {
    pub route: OrthophotoParams,
    pub tile: RasterFile,
    /// Stated planimetric accuracy of the orthophoto, m.
    pub sigma_m: f64,
    /// Stated height accuracy of the DTM, m.
    pub dtm_sigma_m: f64,
}

impl StageParams for OrthophotoNodeParams {
    fn validate(&self) -> Result<(), Vec<ParamError>> {
        StageParams::validate(&self.route)
    }
}

/// The orthophoto route of one recording.
pub struct OrthophotoStage;

impl Stage for OrthophotoStage {
    crate::nodes::stage_types!(skytie_stages::orthophoto::STAGE, OrthophotoNodeParams => OrthophotoControl,
        inputs: (Handle<MmWindowMatch>, Handle<OrthoImage>, Handle<IngestedImage>, Vec<Handle<Dtm>>,
            Vec<Handle<OrthoImage>>));

    fn run(
        &self,
        p: &OrthophotoNodeParams,
        (window, ortho, photo, dtm, neighbour_orthos): (
            Arc<MmWindowMatch>,
            Arc<OrthoImage>,
            Arc<IngestedImage>,
            Vec<Arc<Dtm>>,
            Vec<Arc<OrthoImage>>,
        ),
        _: &NodeCtx,
    ) -> Result<OrthophotoControl, StageError> {
        let pixels = image_tiles::open(&photo)?;
        let input = OrthophotoInput {
            tile: &p.tile,
            pixels: &pixels,
            sigma_m: p.sigma_m,
            dtm: dtm.first().map(|d| (d.as_ref(), p.dtm_sigma_m)),
        };
        let neighbours = NeighbourOrtho::of_window(&window, &neighbour_orthos);
        orthophoto_control(&ortho, &window, &neighbours, &input, &p.route)
            .map_err(|e| StageError::new(format!("orthophoto {}: {e}", p.tile.file)))
    }
}
