//! Plain owned image buffers: single-channel `f32` ([`GrayImage`]) and interleaved RGB `f32` ([`RgbImage`]).
//!
//! Row-major, no padding: pixel (col, row) is at `data[row * width + col]` (times 3 for RGB). These are the
//! types stages exchange and the engine stores (as raw bytes plus a small header, see the engine's codec).

use serde::{Deserialize, Serialize};

/// Single-channel `f32` image; values are intensities (0..1 after loading an 8-bit file, but any range is allowed).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GrayImage {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

impl GrayImage {
    /// An image of `width × height` filled with `value`.
    pub fn filled(width: usize, height: usize, value: f32) -> Self {
        Self {
            width,
            height,
            data: vec![value; width * height],
        }
    }

    /// An image from row-major data; `None` if `data.len() != width * height`.
    pub fn from_vec(width: usize, height: usize, data: Vec<f32>) -> Option<Self> {
        (data.len() == width * height).then_some(Self {
            width,
            height,
            data,
        })
    }

    #[inline]
    pub fn get(&self, col: usize, row: usize) -> f32 {
        self.data[row * self.width + col]
    }

    #[inline]
    pub fn set(&mut self, col: usize, row: usize, value: f32) {
        self.data[row * self.width + col] = value;
    }

    /// Row `row` as a slice.
    #[inline]
    pub fn row(&self, row: usize) -> &[f32] {
        &self.data[row * self.width..(row + 1) * self.width]
    }

    /// Mean and (population) standard deviation of the grey values (0, 0 for an empty image).
    pub fn mean_std(&self) -> (f64, f64) {
        let n = self.data.len().max(1) as f64;
        let mean = self.data.iter().map(|&g| g as f64).sum::<f64>() / n;
        let var = self
            .data
            .iter()
            .map(|&g| (g as f64 - mean).powi(2))
            .sum::<f64>()
            / n;
        (mean, var.sqrt())
    }
}

/// Interleaved RGB `f32` image (linear values, nominally 0..1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

impl RgbImage {
    pub fn filled(width: usize, height: usize, rgb: [f32; 3]) -> Self {
        let mut data = Vec::with_capacity(width * height * 3);
        for _ in 0..width * height {
            data.extend_from_slice(&rgb);
        }
        Self {
            width,
            height,
            data,
        }
    }

    #[inline]
    pub fn get(&self, col: usize, row: usize) -> [f32; 3] {
        let i = (row * self.width + col) * 3;
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }

    #[inline]
    pub fn set(&mut self, col: usize, row: usize, rgb: [f32; 3]) {
        let i = (row * self.width + col) * 3;
        self.data[i..i + 3].copy_from_slice(&rgb);
    }

    /// Luminance (Rec. 709 weights) as a [`GrayImage`].
    pub fn to_gray(&self) -> GrayImage {
        let data = self
            .data
            .chunks_exact(3)
            .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
            .collect();
        GrayImage {
            width: self.width,
            height: self.height,
            data,
        }
    }
}
