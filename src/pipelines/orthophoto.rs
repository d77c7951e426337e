//! The orthophoto route in the nadir part of the `skytie` pipeline, for campaigns that declare an orthophoto
//! (`campaign.toml` `[orthophoto]`): per tile the orthophoto ingested into its pyramid, the DTM tiles loaded
//! once (cropped to the recordings' area), per recording a north-up ground ortho at the orthophoto's working
//! resolution (never finer than the orthophoto's detail level, `orthophoto_ortho`) and the `orthophoto` node (registration, tie points, control points), whose control points join
//! the frames' (when the campaign has both, the adjustment takes both, each with its own σ).

use super::wf_err;
use crate::dag::{optional_all, DagBuilder, Handle, PipelineError, RawFile};
use crate::nodes::campaign::ingest::{ingest_file, IngestedImage};
use crate::nodes::campaign::load::CampaignSnapshot;
use crate::nodes::campaign::summary::SummaryParams;
use crate::nodes::nadir::dtm::{DtmParams, LoadDtm};
use crate::nodes::nadir::orthophoto::{OrthophotoNodeParams, OrthophotoStage};
use crate::nodes::nadir::orthophoto_ortho::{OrthoForOrthophoto, OrthophotoOrthoParams};
use crate::nodes::nadir::orthophoto_points::OrthophotoPoints;
use crate::nodes::nadir::orthophoto_summary::SummarizeOrthophoto;
use crate::workflow::Workflow;
use skytie_stages::campaign::orthophoto::{OrthophotoSource, DEFAULT_DTM_SIGMA_M};
use skytie_stages::campaign::Recording;
use skytie_stages::nadir::{MmWindowMatch, OrthoParams, RecordingControl};
use skytie_stages::orthophoto::{Dtm, OrthophotoControl, OrthophotoParams, OrthophotoSummary};
use std::collections::BTreeMap;
use std::path::Path;

/// Margin around the recordings kept of the DTM, m.
const DTM_MARGIN_M: f64 = 100.0;

/// The orthophoto route of one variant, built recording by recording.
pub struct OrthophotoRoute<'a> {
    root: &'a Path,
    source: &'a OrthophotoSource,
    params: OrthophotoParams,
    ortho_base: OrthoParams,
    dtm: Option<(Handle<Dtm>, f64)>,
    tiles: BTreeMap<usize, Handle<IngestedImage>>,
    results: Vec<Handle<OrthophotoControl>>,
}

impl<'a> OrthophotoRoute<'a> {
    /// The route for the campaign of `snapshot`; `None` when it declares no orthophoto.
    pub fn new(
        b: &mut DagBuilder,
        wf: &Workflow,
        variant: &str,
        root: &'a Path,
        snapshot: &'a CampaignSnapshot,
        ortho_base: &OrthoParams,
    ) -> Result<Option<Self>, PipelineError> {
        let Some(source) = snapshot.campaign.orthophoto.as_ref() else {
            return Ok(None);
        };
        let params: OrthophotoParams = wf
            .params(skytie_stages::orthophoto::STAGE.name, variant)
            .map_err(wf_err)?;
        let dtm = campaign_dtm(b, root, snapshot)?;
        Ok(Some(Self {
            root,
            source,
            params,
            ortho_base: ortho_base.clone(),
            dtm,
            tiles: BTreeMap::new(),
            results: Vec::new(),
        }))
    }

    /// The route for the detecting recording of the MM matching window `window`, whose members (the
    /// recording, then its neighbours in the window's order) are given as (row, its handle, its panorama);
    /// its control points, or `None` when no orthophoto tile covers the recording. The neighbours' orthos for
    /// the same tile feed the parallax check of the refinement (the same nodes as their own routes').
    pub fn add_recording(
        &mut self,
        b: &mut DagBuilder,
        members: &[(&Recording, Handle<Recording>, Handle<IngestedImage>)],
        window: Handle<MmWindowMatch>,
    ) -> Result<Option<Handle<RecordingControl>>, PipelineError> {
        let Some(&(r, _, _)) = members.first() else {
            return Ok(None);
        };
        let Some(k) = self
            .source
            .tile_at(r.x, r.y, self.params.transform.max_localisation_error_m)
        else {
            return Ok(None);
        };
        let tile = &self.source.tiles[k];
        let image = match self.tiles.get(&k) {
            Some(h) => *h,
            None => {
                let h = ingest_file(
                    b,
                    &format!("orthophoto {}", tile.file),
                    tile.path(self.root),
                )?;
                self.tiles.insert(k, h);
                h
            }
        };
        let ortho_params = OrthophotoOrthoParams {
            base: self.ortho_base.clone(),
            pixel_m: tile.header.transform.pixel_m,
        };
        let mut orthos = Vec::with_capacity(members.len());
        for &(m, row, pano) in members {
            let label = format!("rec {} × {}", m.image_id, tile.file);
            let inputs = (row, pano, image);
            orthos.push(b.add(OrthoForOrthophoto, &label, ortho_params.clone(), inputs)?);
        }
        let label = format!("rec {} × {}", r.image_id, tile.file);
        let params = OrthophotoNodeParams {
            route: self.params.clone(),
            tile: tile.clone(),
            sigma_m: self.source.sigma_m,
            dtm_sigma_m: self.dtm.map_or(DEFAULT_DTM_SIGMA_M, |d| d.1),
        };
        let dtm: Vec<Handle<Dtm>> = self.dtm.iter().map(|d| d.0).collect();
        let inputs = (window, orthos[0], image, dtm, orthos[1..].to_vec());
        let result = b.add(OrthophotoStage, &label, params, inputs)?;
        self.results.push(result);
        Ok(Some(b.add(
            OrthophotoPoints,
            &label,
            SummaryParams::default(),
            result,
        )?))
    }

    /// The route's summary node, with its metrics under `orthophoto`.
    pub fn finish(self, b: &mut DagBuilder) -> Result<(), PipelineError> {
        let summary = b.add(
            SummarizeOrthophoto,
            "",
            SummaryParams::default(),
            optional_all(&self.results),
        )?;
        b.metrics(summary, "orthophoto", |s: &OrthophotoSummary| s.metrics());
        Ok(())
    }
}

/// The campaign's DTM tiles loaded once, cropped to the recordings' area grown by 100 m (one node,
/// shared by every caller), with its stated σ in metres; `None` when the campaign declares no DTM or has no
/// recordings.
pub fn campaign_dtm(
    b: &mut DagBuilder,
    root: &Path,
    snapshot: &CampaignSnapshot,
) -> Result<Option<(Handle<Dtm>, f64)>, PipelineError> {
    let recs = &snapshot.campaign.recordings;
    let (Some(d), false) = (&snapshot.campaign.dtm, recs.is_empty()) else {
        return Ok(None);
    };
    let fold = |f: fn(f64, f64) -> f64, pick: fn(&Recording) -> f64, init| {
        recs.iter().map(pick).fold(init, f)
    };
    let area_m = [
        fold(f64::min, |r| r.x, f64::INFINITY) - DTM_MARGIN_M,
        fold(f64::min, |r| r.y, f64::INFINITY) - DTM_MARGIN_M,
        fold(f64::max, |r| r.x, f64::NEG_INFINITY) + DTM_MARGIN_M,
        fold(f64::max, |r| r.y, f64::NEG_INFINITY) + DTM_MARGIN_M,
    ];
    let files: Vec<RawFile> = d.tiles.iter().map(|t| RawFile(t.path(root))).collect();
    let p = DtmParams {
        tiles: d.tiles.iter().map(|t| t.file.clone()).collect(),
        area_m,
    };
    Ok(Some((b.add(LoadDtm, "", p, files)?, d.sigma_m)))
}
