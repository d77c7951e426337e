//! One ortho image made ready for MM-to-MM matching: masked pixels filled with the mean grey value (so the
//! vehicle mask's border creates no artificial edges for KAZE or Förstner), the validity index, and its
//! upright one-octave KAZE features (thesis 3.4.4.2) without the keypoints near masked pixels.

use super::params::MmMatchParams;
use super::template::ValidIndex;
use crate::features::kaze::{detect_and_describe, Features, KazeParams};
use crate::imaging::GrayImage;
use crate::nadir::ortho_mask::fill_masked;
use crate::nadir::OrthoImage;

/// An ortho image with what every pair needs of it, computed once per window.
pub struct PreparedOrtho {
    /// The grey values, masked pixels replaced by the mean of the valid ones.
    pub filled: GrayImage,
    pub valid: ValidIndex,
    /// KAZE keypoints (upright, one octave) at least `kaze_mask_margin_px` away from masked pixels.
    pub features: Features,
}

/// KAZE settings of thesis 3.4.4.2: upright, one octave, 64-value descriptor.
pub fn kaze_params(p: &MmMatchParams) -> KazeParams {
    KazeParams {
        threshold: p.kaze_threshold,
        octaves: 1,
        sublevels: p.kaze_sublevels,
        upright: true,
        extended: false,
        ..KazeParams::default()
    }
}

impl PreparedOrtho {
    /// Fill, index and describe `ortho`.
    pub fn new(ortho: &OrthoImage, p: &MmMatchParams) -> Self {
        let filled = fill_masked(ortho);
        let valid = ValidIndex::new(&ortho.valid, ortho.image.width, ortho.image.height);
        let all = detect_and_describe(&filled, &kaze_params(p));
        let margin = p.kaze_mask_margin_px.ceil() as i64;
        let keep: Vec<usize> = (0..all.len())
            .filter(|&i| {
                let k = &all.keypoints[i];
                let (col, row) = (k.u_px.floor() as i64, k.v_px.floor() as i64);
                valid.square_valid(col, row, margin)
            })
            .collect();
        let len = all.descriptor_len;
        let mut descriptors = Vec::with_capacity(keep.len() * len);
        for &i in &keep {
            descriptors.extend_from_slice(all.descriptor(i));
        }
        let features = Features {
            keypoints: keep.iter().map(|&i| all.keypoints[i]).collect(),
            descriptors,
            descriptor_len: len,
        };
        Self {
            filled,
            valid,
            features,
        }
    }
}
