//! A whole decoded image in memory as `f32` grey (tools and tests that want the full image; the pipeline
//! reads pyramids instead). The `f32` buffer is reserved from the memory budget.

use super::{GreyInfo, GreyRowSink};
use crate::imaging::budget::Reservation;
use crate::imaging::huge_pages::advise_huge_pages;
use crate::imaging::pyramid::builder::white_for;
use crate::imaging::pyramid::SampleDepth;
use crate::imaging::GrayImage;
use std::path::Path;

/// Collects rows into a [`GrayImage`]: 8-bit samples / 255, 16-bit samples / white (the smallest `2^k − 1`
/// holding the image's largest sample, as in pyramids).
pub struct GreyCollector {
    path: std::path::PathBuf,
    image: GrayImage,
    depth: SampleDepth,
    max16: u16,
    reservation: Option<Reservation<'static>>,
}

impl GreyCollector {
    pub fn new(path: &Path) -> Self {
        Self {
            path: path.to_path_buf(),
            image: GrayImage::filled(0, 0, 0.0),
            depth: SampleDepth::U8,
            max16: 0,
            reservation: None,
        }
    }

    /// The image (16-bit values rescaled to the white level).
    pub fn finish(mut self) -> GrayImage {
        if self.depth == SampleDepth::U16 {
            let white = f32::from(white_for(self.max16));
            for v in &mut self.image.data {
                *v = (*v * 65535.0).round() / white;
            }
        }
        drop(self.reservation);
        self.image
    }
}

impl GreyRowSink for GreyCollector {
    fn begin(&mut self, info: &GreyInfo) -> std::io::Result<()> {
        let n = info.width * info.height;
        let reservation = super::limits::reserve(
            &self.path,
            info.format.name(),
            info.width,
            info.height,
            n * 4,
            "its whole grey image as 32-bit floats",
        )
        .map_err(std::io::Error::other)?;
        self.reservation = Some(reservation);
        self.depth = info.depth;
        self.image = GrayImage {
            width: info.width,
            height: info.height,
            data: Vec::with_capacity(n),
        };
        advise_huge_pages(self.image.data.as_mut_ptr() as usize, n * 4);
        Ok(())
    }

    fn row_u8(&mut self, row: &[u8]) -> std::io::Result<()> {
        self.image
            .data
            .extend(row.iter().map(|&v| f32::from(v) / 255.0));
        Ok(())
    }

    fn row_u16(&mut self, row: &[u16]) -> std::io::Result<()> {
        self.max16 = self.max16.max(row.iter().copied().max().unwrap_or(0));
        self.image
            .data
            .extend(row.iter().map(|&v| f32::from(v) / 65535.0));
        Ok(())
    }
}
