//! The recordings of the block: their recorded poses with prior σ and observed heights, the σ of their
//! panorama observations, the lookup of a recording by panorama id, and the relative constraints between
//! consecutive recordings (thesis 3.4.2).

use super::adjust_inputs::AdjustInputs;
use super::config::{AdjustConfig, TrajectoryError};
use super::error::AdjustError;
use super::gauss_markov;
use super::height_observation::{HeightObservations, HeightSource};
use super::problem::{BlockRecording, RelativeConstraint};
use crate::campaign::Recording;
use crate::geometry::PanoramaCamera;
use std::collections::HashMap;

/// σ of each recording's panorama observations, full-resolution pixels (pixels of its detail level).
pub(super) fn pano_sigmas_px(
    inputs: &AdjustInputs,
    config: &AdjustConfig,
    recordings: usize,
) -> Vec<f64> {
    (0..recordings)
        .map(|r| {
            let level = inputs
                .pano_detail_level
                .get(r)
                .copied()
                .unwrap_or(0)
                .min(30);
            config.pano_sigma_px * (1u64 << level) as f64
        })
        .collect()
}

/// The recordings' index by image id, the block's recordings and what their height observations were.
pub(super) type BlockRecordings<'a> = (
    HashMap<&'a str, usize>,
    Vec<BlockRecording>,
    HeightObservations,
);

/// The block's recordings (recorded poses as weak priors, thesis 5.4.3, and with `dtm_height` their observed
/// heights) and their index by image id; refuses a size or height list that does not match and duplicate
/// image ids.
pub(super) fn block_recordings<'a>(
    inputs: &AdjustInputs<'a>,
    config: &AdjustConfig,
) -> Result<BlockRecordings<'a>, AdjustError> {
    let n_rec = inputs.recordings.len();
    for (item, len, what) in [
        (
            "panorama sizes",
            Some(inputs.pano_size_px.len()),
            "(width, height)",
        ),
        (
            "recording heights",
            inputs.heights.map(<[_]>::len),
            "height or none",
        ),
    ] {
        if let Some(len) = len.filter(|&l| l != n_rec) {
            return Err(AdjustError::InvalidInput {
                item: item.to_string(),
                problem: format!(
                    "{len} {item} for {n_rec} recordings; pass one {what} per recording"
                ),
            });
        }
    }
    let (source, heights) = match (config.dtm_height, inputs.heights) {
        (false, _) => (HeightSource::Off, &[][..]),
        (true, None) => (HeightSource::NoDtm, &[][..]),
        (true, Some(h)) => (HeightSource::Dtm, h),
    };
    let mut recording_index: HashMap<&str, usize> = HashMap::with_capacity(n_rec);
    let mut recordings = Vec::with_capacity(n_rec);
    for (i, (rec, &(w, h))) in inputs
        .recordings
        .iter()
        .zip(inputs.pano_size_px)
        .enumerate()
    {
        if recording_index.insert(rec.image_id.as_str(), i).is_some() {
            return Err(AdjustError::InvalidInput {
                item: format!("recording '{}'", rec.image_id),
                problem: "image_id occurs twice; image ids must be unique".to_string(),
            });
        }
        let (prior_xy, prior_z) = prior_sigmas_m(rec, config);
        recordings.push(BlockRecording {
            camera: PanoramaCamera::from_recording(rec, w, h),
            prior_sigma_xy_m: Some(prior_xy),
            prior_sigma_z_m: Some(prior_z),
            height_observation: heights.get(i).copied().flatten(),
        });
    }
    let summary = HeightObservations::of(source, heights);
    Ok((recording_index, recordings, summary))
}

/// The σ of a recording's position prior, m: horizontal, vertical (the workflow's override, else the
/// recording's own `sigma_xy` / `sigma_z`, else the configuration's default).
pub fn prior_sigmas_m(rec: &Recording, config: &AdjustConfig) -> (f64, f64) {
    (
        config
            .prior_sigma_xy_m
            .or(rec.sigma_xy_m)
            .unwrap_or(config.default_prior_sigma_xy_m),
        config
            .prior_sigma_z_m
            .or(rec.sigma_z_m)
            .unwrap_or(config.default_prior_sigma_z_m),
    )
}

/// The recording a correspondence of `owner` names, by image id.
pub(super) fn resolve_recording(
    recording_index: &HashMap<&str, usize>,
    owner: &str,
    image_id: &str,
) -> Result<usize, AdjustError> {
    recording_index
        .get(image_id)
        .copied()
        .ok_or_else(|| AdjustError::InvalidInput {
            item: owner.to_string(),
            problem: format!(
                "panorama '{image_id}' is not among the {} recordings of the adjustment; \
                 pass the recordings the correspondences were made with",
                recording_index.len()
            ),
        })
}

/// Consecutive recordings at most `relative_max_gap_m` apart keep their recorded difference (thesis 3.4.2),
/// or, with `trajectory_error = "gauss_markov"`, the Gauss–Markov step between their corrections.
pub(super) fn relative_constraints(
    recordings: &[Recording],
    config: &AdjustConfig,
    sigma_m: f64,
) -> Vec<RelativeConstraint> {
    (1..recordings.len())
        .filter(|&i| {
            let (a, b) = (&recordings[i - 1], &recordings[i]);
            (a.x - b.x).hypot(a.y - b.y) <= config.relative_max_gap_m
        })
        .map(|i| {
            let constraint = RelativeConstraint::new(i - 1, i, sigma_m);
            match config.trajectory_error {
                TrajectoryError::RandomWalk => constraint,
                TrajectoryError::GaussMarkov => {
                    let (from_xy, from_z) = prior_sigmas_m(&recordings[i - 1], config);
                    let (to_xy, to_z) = prior_sigmas_m(&recordings[i], config);
                    RelativeConstraint {
                        carry_xy: gauss_markov::carry(sigma_m, from_xy, to_xy),
                        carry_z: gauss_markov::carry(sigma_m, from_z, to_z),
                        ..constraint
                    }
                }
            }
        })
        .collect()
}
