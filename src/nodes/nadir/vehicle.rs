//! `vehicle`: the recording vehicle found in the campaign's panoramas (`skytie_stages::nadir::vehicle_detect`):
//! a sample of panoramas spread over the campaign, the part that stays the same relative to the driving
//! direction, fitted with the box model that masks the car in every ortho image. When nothing stable is found
//! (too few panoramas, a vehicle-free camera) the output says why and the `[ortho.vehicle]` values are used.

use crate::dag::{Handle, InputsOf, NodeCtx, RunResult, Stage, StageError};
use crate::nodes::campaign::image_tiles;
use crate::nodes::campaign::ingest::IngestedImage;
use crate::nodes::campaign::load::CampaignSnapshot;
use serde::{Deserialize, Serialize};
use skytie_stages::imaging::pyramid::{ScaledWindow, TileSource};
use skytie_stages::imaging::GrayImage;
use skytie_stages::nadir::vehicle_detect::{
    detect_vehicle, detection_level, DetectedVehicle, VehicleDetectParams,
};
use skytie_stages::nadir::VehicleMask;

/// Parameters of the node: the detection's and which recordings (image ids) were sampled.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VehicleNodeParams {
    pub detect: VehicleDetectParams,
    /// Image ids of the sampled recordings, in the order of the panorama inputs.
    pub image_ids: Vec<String>,
}

/// What the node found.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VehicleDetection {
    /// The detection, or `None` with `message` saying why not.
    pub detected: Option<DetectedVehicle>,
    pub message: String,
}
crate::serde_artifact!(VehicleDetection);

impl VehicleDetection {
    /// The mask for the ortho images: the detected box (keeping `base`'s `enabled`), else `base`.
    pub fn mask_or(&self, base: &VehicleMask) -> VehicleMask {
        match (&self.detected, base.detect) {
            (Some(d), true) => VehicleMask {
                enabled: base.enabled,
                ..d.mask
            },
            _ => *base,
        }
    }

    /// `vehicle` metrics.
    pub fn metrics(&self) -> serde_json::Value {
        match &self.detected {
            Some(d) => serde_json::json!({
                "detected": true,
                "recordings_used": d.recordings_used,
                "front_m": d.mask.front_m,
                "rear_m": d.mask.rear_m,
                "half_width_m": d.mask.half_width_m,
                "roof_drop_m": d.mask.roof_drop_m,
            }),
            None => serde_json::json!({ "detected": false, "message": self.message }),
        }
    }
}

/// The detection node.
pub struct DetectVehicle;

impl Stage for DetectVehicle {
    crate::nodes::stage_types!(skytie_stages::nadir::vehicle_detect::STAGE, VehicleNodeParams => VehicleDetection,
        inputs: (Handle<CampaignSnapshot>, Vec<Handle<IngestedImage>>));

    fn run(&self, p: &VehicleNodeParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (snap, panos) = inputs;
        let mut images = Vec::new();
        let mut skipped = Vec::new();
        for (id, pano) in p.image_ids.iter().zip(&panos) {
            let rec = snap.campaign.recordings.iter().find(|r| &r.image_id == id);
            match (rec, read_for_detection(pano, &p.detect)) {
                (Some(rec), Ok(img)) if img.width == 2 * img.height => images.push((rec, img)),
                (_, Err(e)) => skipped.push(format!("{}: {e}", pano.source)),
                _ => skipped.push(format!("{}: not usable", pano.source)),
            }
        }
        let views: Vec<_> = images.iter().map(|(r, i)| (*r, i)).collect();
        Ok(match detect_vehicle(&views, &p.detect) {
            Ok(d) => VehicleDetection {
                detected: Some(d),
                message: skipped.join("; "),
            },
            Err(e) => VehicleDetection {
                detected: None,
                message: format!(
                    "the recording vehicle was not found in the panoramas ({e}); [ortho.vehicle] is used"
                ),
            },
        })
    }
}

/// The whole panorama at the pyramid level the detection needs (`detection_level`): the grid's samples are a
/// few degrees apart, so a 12k panorama is read at a fraction of its size (and an enlarged copy at the size it
/// was enlarged from).
fn read_for_detection(
    pano: &IngestedImage,
    p: &VehicleDetectParams,
) -> Result<GrayImage, StageError> {
    let pyramid = image_tiles::open(pano)?;
    let layout = pyramid.layout();
    let level = detection_level(layout, p);
    let whole = [0.0, 0.0, layout.width as f64, layout.height as f64];
    match ScaledWindow::read(&pyramid, level, whole) {
        Ok(Some(w)) => Ok(w.image),
        Ok(None) => Err(StageError::new("empty image")),
        Err(e) => Err(StageError::new(e.to_string())),
    }
}
