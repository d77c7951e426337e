//! The orthophoto route's nodes (`skytie_stages::orthophoto`): `dtm` loads the campaign's DTM tiles cropped
//! to the area of the recordings; `orthophoto`, per recording, registers its north-up ground ortho to the
//! orthophoto tile around it, locates its tie points there and makes control points (XY from the orthophoto,
//! Z from the DTM or the MM ground); `orthophoto_points` hands the control points on to the adjustment like
//! the `control` node's.

use crate::dag::{Handle, NodeCtx, Optional, RawFile, RawFileValue, Stage, StageError};
use crate::nodes::campaign::image_tiles;
use crate::nodes::campaign::ingest::IngestedImage;
use crate::workflow::{ParamError, StageParams};
use serde::{Deserialize, Serialize};
use skytie_stages::campaign::orthophoto::RasterFile;
use skytie_stages::nadir::{MmWindowMatch, OrthoImage, RecordingControl};
use skytie_stages::orthophoto::dtm::load_tile;
use skytie_stages::orthophoto::{
    orthophoto_control, Dtm, OrthophotoControl, OrthophotoInput, OrthophotoParams,
    OrthophotoSummary,
};
use std::sync::Arc;

crate::serde_artifact!(Dtm);
crate::serde_artifact!(OrthophotoControl);

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
    const NAME: &'static str = "dtm";
    const VERSION: &'static str = "1";
    type Params = DtmParams;
    type Output = Dtm;
    type Inputs = Vec<RawFile>;

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
    const NAME: &'static str = skytie_stages::orthophoto::STAGE.name;
    const VERSION: &'static str = skytie_stages::orthophoto::STAGE.version;
    type Params = OrthophotoNodeParams;
    type Output = OrthophotoControl;
    type Inputs = (
        Handle<MmWindowMatch>,
        Handle<OrthoImage>,
        Handle<IngestedImage>,
        Vec<Handle<Dtm>>,
    );

    fn run(
        &self,
        p: &OrthophotoNodeParams,
        (window, ortho, photo, dtm): (
            Arc<MmWindowMatch>,
            Arc<OrthoImage>,
            Arc<IngestedImage>,
            Vec<Arc<Dtm>>,
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
        orthophoto_control(&ortho, &window, &input, &p.route)
            .map_err(|e| StageError::new(format!("orthophoto {}: {e}", p.tile.file)))
    }
}

/// Parameters of `orthophoto_points` (none).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct NoParams {}

impl StageParams for NoParams {
    fn validate(&self) -> Result<(), Vec<ParamError>> {
        Ok(())
    }
}

/// The control points of an `orthophoto` node, as the adjustment takes them.
pub struct OrthophotoPoints;

impl Stage for OrthophotoPoints {
    const NAME: &'static str = "orthophoto_points";
    const VERSION: &'static str = "1";
    type Params = NoParams;
    type Output = RecordingControl;
    type Inputs = Handle<OrthophotoControl>;

    fn run(
        &self,
        _: &NoParams,
        c: Arc<OrthophotoControl>,
        _: &NodeCtx,
    ) -> Result<RecordingControl, StageError> {
        Ok(c.control.clone())
    }
}

crate::serde_artifact!(OrthophotoSummary);

/// The orthophoto route's counts over the campaign.
pub struct SummarizeOrthophoto;

impl Stage for SummarizeOrthophoto {
    const NAME: &'static str = "orthophoto_summary";
    const VERSION: &'static str = "1";
    type Params = NoParams;
    type Output = OrthophotoSummary;
    type Inputs = Vec<Optional<OrthophotoControl>>;

    fn run(
        &self,
        _: &NoParams,
        results: Vec<Option<Arc<OrthophotoControl>>>,
        _: &NodeCtx,
    ) -> Result<OrthophotoSummary, StageError> {
        let refs: Vec<Option<&OrthophotoControl>> = results.iter().map(|r| r.as_deref()).collect();
        Ok(OrthophotoSummary::of(&refs))
    }
}
