//! The option "re-use a neighbour's transform" of thesis 3.4.5.2 (last paragraph): a recording takes the
//! initial transform of a neighbouring recording to the same aerial image, carried over through the recorded
//! relative pose, instead of matching features itself.

use super::initial_transform::{centre_offset_world, TransformParams};
use super::ortho::OrthoGeoref;
use super::registration::{InitialTransform, TransformOutcome};
use crate::campaign::{AerialImage, Recording};
use crate::geometry::{FrameCamera, PointPair, Similarity2};

/// The option "re-use a neighbour's transform" (thesis 3.4.5.2, last paragraph): the relative orientation along the
/// trajectory is accurate, so this recording's ortho pixel p shows the same ground as the neighbour's ortho pixel
/// that the *recorded* poses put at the same world point. The transform is therefore
/// `neighbour.ortho_to_aerial ∘ (this ortho px → world → neighbour ortho px)`, checked for plausibility like a
/// computed one. Matches/inliers are the neighbour's; `reused_from` names the neighbour.
pub fn reuse_neighbour(
    neighbour: &InitialTransform,
    neighbour_georef: &OrthoGeoref,
    rec: &Recording,
    georef: &OrthoGeoref,
    aerial_row: &AerialImage,
    p: &TransformParams,
) -> TransformOutcome {
    let reject = |reason: String| TransformOutcome::Rejected {
        recording_id: rec.image_id.clone(),
        aerial_id: aerial_row.image_id.clone(),
        reason,
        matches: neighbour.matches,
        inliers: neighbour.inliers,
    };
    if neighbour.aerial_id != aerial_row.image_id {
        return reject(format!(
            "neighbour {}'s transform is for aerial image {}, not {}",
            neighbour.recording_id, neighbour.aerial_id, aerial_row.image_id
        ));
    }
    let (w, h) = (georef.width_px as f64, georef.height_px as f64);
    let pairs: Vec<PointPair> = [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)]
        .iter()
        .map(|&(x, y)| {
            let (nx, ny) = neighbour_georef.world_to_pixel(&georef.pixel_to_world(x, y));
            PointPair::new(x, y, nx, ny)
        })
        .collect();
    let Some(to_neighbour) = Similarity2::least_squares(&pairs) else {
        return reject("degenerate ortho georeference".into());
    };
    let transform = neighbour.ortho_to_aerial.compose(&to_neighbour);
    let cam = FrameCamera::from_aerial(aerial_row);
    let Some(offset) = centre_offset_world(&transform, georef, &cam) else {
        return reject("the transformed ortho centre does not meet the ground plane".into());
    };
    let centre_offset_m = offset[0].hypot(offset[1]);
    if !(centre_offset_m <= p.max_localisation_error_m) {
        return reject(format!(
            "reused transform of {}: centre offset {centre_offset_m:.2} m > {} m",
            neighbour.recording_id, p.max_localisation_error_m
        ));
    }
    TransformOutcome::Accepted(InitialTransform {
        recording_id: rec.image_id.clone(),
        aerial_id: aerial_row.image_id.clone(),
        ortho_to_aerial: transform,
        matches: neighbour.matches,
        inliers: neighbour.inliers,
        centre_offset_m,
        centre_offset_world_m: offset,
        reused_from: Some(neighbour.recording_id.clone()),
    })
}
