//! KAZE features (Alcantarilla, Bartoli, Davison, ECCV 2012): nonlinear-scale-space detector and M-SURF
//! descriptor, as used by skytie's nadir pipeline (thesis 3.4.4.2: MM↔MM ortho homography, upright, one
//! octave; thesis 3.4.5.2: MM↔aerial after Wallis, extended 128, upright, one octave).
//! Specification: Alcantarilla, Bartoli & Davison 2012.
//!
//! Pixel convention (campaign-format.md): keypoint (u, v) are continuous pixel coordinates with the centre
//! of the first pixel at (0.5, 0.5). A maximum found at array index (col, row) is at (col + 0.5, row + 0.5)
//! plus its sub-pixel offset; subtract 0.5 to compare with OpenCV's `KeyPoint.pt`.

pub mod contrast;
pub mod descriptor;
pub mod detector;
pub mod diffusion;
pub mod filters;
pub mod orientation;
pub mod params;
pub mod scale_space;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

pub use params::{Diffusivity, KazeParams, Scheme};

use crate::imaging::GrayImage;

/// A KAZE keypoint.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Keypoint {
    /// Position (campaign pixel convention, px).
    pub u_px: f32,
    pub v_px: f32,
    /// Diameter 2σ (px) of the refined scale σ (OpenCV `KeyPoint.size` semantics).
    pub size_px: f32,
    /// Orientation (rad, [0, 2π), image frame: from +u towards +v); 0 when upright.
    pub angle_rad: f32,
    /// Scale-normalised det(Hessian) at the detected maximum.
    pub response: f32,
    /// Evolution level index the keypoint was detected on.
    pub level: u16,
}

/// Keypoints and their descriptors (row-major, `descriptor_len` values per keypoint, unit L2 norm).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Features {
    pub keypoints: Vec<Keypoint>,
    pub descriptors: Vec<f32>,
    pub descriptor_len: usize,
}

impl Features {
    /// Descriptor of keypoint `i`.
    pub fn descriptor(&self, i: usize) -> &[f32] {
        &self.descriptors[i * self.descriptor_len..(i + 1) * self.descriptor_len]
    }

    pub fn len(&self) -> usize {
        self.keypoints.len()
    }

    pub fn is_empty(&self) -> bool {
        self.keypoints.is_empty()
    }
}

/// Detect KAZE keypoints in `img` (grey, 0..1) and describe them. The order is deterministic (by level,
/// then raster order of detection) and independent of the thread count. Images smaller than 3×3 or
/// parameters with fewer than 3 levels give no features.
pub fn detect_and_describe(img: &GrayImage, p: &KazeParams) -> Features {
    let descriptor_len = p.descriptor_len();
    let space = scale_space::build_scale_space(img, p);
    let detections = detector::detect(&space.levels, p);
    let keypoints: Vec<Keypoint> = detections
        .par_iter()
        .map(|d| {
            let angle_rad = if p.upright {
                0.0
            } else {
                orientation::dominant_orientation(
                    &space.levels[d.level],
                    d.u_px,
                    d.v_px,
                    d.sigma_px,
                )
            };
            Keypoint {
                u_px: d.u_px,
                v_px: d.v_px,
                size_px: 2.0 * d.sigma_px,
                angle_rad,
                response: d.response,
                level: d.level as u16,
            }
        })
        .collect();
    let mut descriptors = vec![0.0f32; keypoints.len() * descriptor_len];
    descriptors
        .par_chunks_mut(descriptor_len)
        .zip(keypoints.par_iter())
        .for_each(|(out, k)| {
            descriptor::describe(
                &space.levels[k.level as usize],
                k.u_px,
                k.v_px,
                0.5 * k.size_px,
                k.angle_rad,
                p.extended,
                out,
            )
        });
    Features {
        keypoints,
        descriptors,
        descriptor_len,
    }
}
