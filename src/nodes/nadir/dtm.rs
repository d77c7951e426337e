//! `dtm`: the orthophoto route's DTM tiles (`skytie_stages::orthophoto::dtm`), cropped to the area of the
//! recordings, loaded once per run for every recording's `orthophoto` node.

use crate::dag::{NodeCtx, RawFile, RawFileValue, Stage, StageError};
use crate::workflow::{ParamError, StageParams};
use serde::{Deserialize, Serialize};
use skytie_stages::orthophoto::dtm::load_tile;
use skytie_stages::orthophoto::Dtm;

crate::serde_artifact!(Dtm);

/// What the `dtm` node loads (set by the pipeline from the campaign).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DtmParams {
    /// The tiles as declared in `campaign.toml` (their files are the node's inputs, in this order).
    pub tiles: Vec<String>,
    /// World area kept (min x, min y, max x, max y), m.
    pub area_m: [f64; 4],
}

impl StageParams for DtmParams {
    fn validate(&self) -> Result<(), Vec<ParamError>> {
        let [x0, y0, x1, y1] = self.area_m;
        if x0 <= x1 && y0 <= y1 {
            Ok(())
        } else {
            Err(vec![ParamError::new("area_m", "an empty area")])
        }
    }
}

/// Loads the DTM tiles.
pub struct LoadDtm;

impl Stage for LoadDtm {
    crate::nodes::stage_types!(named "dtm" version "1", DtmParams => Dtm, inputs: Vec<RawFile>);

    fn run(&self, p: &DtmParams, files: Vec<RawFileValue>, _: &NodeCtx) -> Result<Dtm, StageError> {
        let mut dtm = Dtm::default();
        for (name, f) in p.tiles.iter().zip(&files) {
            let tile = load_tile(&f.path, name, p.area_m)
                .map_err(|e| StageError::new(format!("DTM {name}: {e}")))?;
            dtm.tiles.extend(tile);
        }
        Ok(dtm)
    }
}
