//! Tiled, multi-resolution grey images: how skytie holds images of any size in bounded memory.
//!
//! An image file is decoded once ([`crate::imaging::decode`]) into a pyramid of 8- or 16-bit grey samples:
//! level 0 at full resolution, each further level a 2 × 2 box average of the previous, cut into square tiles
//! each authenticated by its blake3 hash ([`layout`] describes the file). Stages then ask for a *window* —
//! a rectangle of one level — at the resolution they work at ([`nearest_level`]), and only the tiles under
//! it are read. A [`ScaledWindow`] maps its pixels back to full-resolution image pixels.
//!
//! Grey values are `sample / white`: 8-bit images use white = 255, 16-bit images the smallest `2^k − 1`
//! (k = 8…16) that holds their largest sample, so a 12-bit frame in a 16-bit file spans 0..1 like an 8-bit
//! one and keeps its 4096 levels (the stages compute in `f32`).

pub mod builder;
pub mod layout;
pub mod memory;
pub mod reader;
pub mod sample;

pub use builder::{PyramidBuilder, PyramidSummary};
pub use layout::{PixelRect, PyramidLayout, SampleDepth, DEFAULT_TILE_SIDE};
pub use memory::MemoryPyramid;
pub use reader::{read_window, PyramidError, PyramidHeader, TileId, TileSource, TiledPyramid};

use crate::imaging::GrayImage;

/// The level whose resolution is nearest (by ratio) to `target`, for an image whose full resolution is
/// `native` (both in the same unit: metres per pixel, degrees per pixel; larger = coarser). Level `l` has
/// resolution `native · 2^l`; a target at or below `native` gives level 0; at most `levels − 1`.
pub fn nearest_level(native: f64, target: f64, levels: usize) -> usize {
    if !(native > 0.0 && target > native && native.is_finite() && target.is_finite()) {
        return 0;
    }
    let l = ((target / native).log2() + 0.5).floor();
    (l.max(0.0) as usize).min(levels.saturating_sub(1))
}

/// The finest level whose resolution is not finer than `footprint` (a pixel of the product being sampled,
/// in the image's own resolution unit): level `l` with `native · 2^l ≤ footprint < native · 2^(l+1)`, the
/// mip-map rule that avoids aliasing without blurring more than needed.
pub fn footprint_level(native: f64, footprint: f64, levels: usize) -> usize {
    if !(native > 0.0 && footprint > native && native.is_finite() && footprint.is_finite()) {
        return 0;
    }
    let l = ((footprint / native).log2() + 1e-9).floor();
    (l.max(0.0) as usize).min(levels.saturating_sub(1))
}

/// A window of one pyramid level and where it lies in the full-resolution image.
#[derive(Clone, Debug, PartialEq)]
pub struct ScaledWindow {
    pub image: GrayImage,
    pub level: usize,
    /// The window's rectangle in pixels of `level`.
    pub rect: PixelRect,
    /// Size of the whole image at `level`.
    pub level_size: (usize, usize),
    /// Size of the whole image at full resolution.
    pub full_size: (usize, usize),
}

impl ScaledWindow {
    /// Reads the window of `level` covering the continuous full-resolution box [u0, u1) × [v0, v1), clipped
    /// to the image. `Ok(None)` when the box misses the image.
    pub fn read(
        source: &dyn TileSource,
        level: usize,
        box_full_px: [f64; 4],
    ) -> Result<Option<Self>, PyramidError> {
        let layout = source.layout();
        let level = level.min(layout.levels() - 1);
        let s = (1u64 << level) as f64;
        let [u0, v0, u1, v1] = box_full_px;
        let Some(rect) = PixelRect::covering(u0 / s, v0 / s, u1 / s, v1 / s) else {
            return Ok(None);
        };
        let level_size = layout.level_sizes[level];
        let Some(rect) = rect.clipped(level_size.0, level_size.1) else {
            return Ok(None);
        };
        Ok(Some(Self {
            image: read_window(source, level, rect)?,
            level,
            rect,
            level_size,
            full_size: (layout.width, layout.height),
        }))
    }

    /// A window that is a whole in-memory image at full resolution (level 0).
    pub fn whole(image: GrayImage) -> Self {
        let size = (image.width, image.height);
        Self {
            rect: PixelRect::new(0, 0, size.0, size.1),
            image,
            level: 0,
            level_size: size,
            full_size: size,
        }
    }

    /// Full-resolution pixels per window pixel (`2^level`).
    pub fn scale(&self) -> f64 {
        (1u64 << self.level) as f64
    }

    /// Full-resolution image coordinates of continuous window coordinates (u, v).
    pub fn to_full(&self, u_px: f64, v_px: f64) -> (f64, f64) {
        let s = self.scale();
        (
            (u_px + self.rect.x0 as f64) * s,
            (v_px + self.rect.y0 as f64) * s,
        )
    }

    /// Continuous window coordinates of full-resolution image coordinates (u, v).
    pub fn from_full(&self, u_px: f64, v_px: f64) -> (f64, f64) {
        let s = self.scale();
        (
            u_px / s - self.rect.x0 as f64,
            v_px / s - self.rect.y0 as f64,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn sample_value(c: usize, r: usize) -> u16 {
        ((c * 37 + r * 101 + (c * r) % 13) % 4000) as u16
    }

    fn build(dir: &Path, w: usize, h: usize, depth: SampleDepth, ts: usize) -> PyramidSummary {
        let mut b = PyramidBuilder::create(&dir.join("p.pyr"), w, h, depth, ts).unwrap();
        for r in 0..h {
            let row: Vec<u16> = (0..w).map(|c| sample_value(c, r)).collect();
            match depth {
                SampleDepth::U16 => b.push_row_u16(&row).unwrap(),
                SampleDepth::U8 => {
                    let row8: Vec<u8> = row.iter().map(|&v| (v % 256) as u8).collect();
                    b.push_row_u8(&row8).unwrap()
                }
            }
        }
        b.finish().unwrap()
    }

    #[test]
    fn levels_are_box_averages_and_windows_read_across_tiles() {
        let dir = tempfile::tempdir().unwrap();
        let (w, h) = (101, 67);
        let summary = build(dir.path(), w, h, SampleDepth::U16, 16);
        assert_eq!(summary.white, 4095);
        let p = TiledPyramid::open(&dir.path().join("p.pyr"), &summary.index_hash).unwrap();
        let full = read_window(&p, 0, PixelRect::new(0, 0, w, h)).unwrap();
        for (r, c) in [(0, 0), (15, 16), (66, 100), (33, 47)] {
            assert_eq!(full.get(c, r), f32::from(sample_value(c, r)) / 4095.0);
        }
        // Level 1 pixel (c, r) averages level-0 pixels 2c..2c+1 × 2r..2r+1 (the odd edge pairs with itself).
        let l1 = read_window(&p, 1, PixelRect::new(0, 0, 51, 34)).unwrap();
        for (r, c) in [(0, 0), (10, 20), (33, 50)] {
            let at = |cc: usize, rr: usize| u32::from(sample_value(cc.min(w - 1), rr.min(h - 1)));
            let sum = at(2 * c, 2 * r)
                + at(2 * c + 1, 2 * r)
                + at(2 * c, 2 * r + 1)
                + at(2 * c + 1, 2 * r + 1);
            assert_eq!(l1.get(c, r), ((sum + 2) >> 2) as f32 / 4095.0, "({c}, {r})");
        }
        // Outside the level: the nearest edge pixel.
        let edge = read_window(&p, 0, PixelRect::new(-3, 60, 5, 10)).unwrap();
        assert_eq!(edge.get(0, 0), full.get(0, 60));
        assert_eq!(edge.get(4, 9), full.get(1, 66));
        // A window inside equals the same part of the full read.
        let win = read_window(&p, 0, PixelRect::new(14, 30, 40, 20)).unwrap();
        for r in 0..20 {
            assert_eq!(win.row(r), &full.row(30 + r)[14..54]);
        }
    }

    #[test]
    fn a_damaged_tile_or_index_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let summary = build(dir.path(), 40, 40, SampleDepth::U8, 16);
        let path = dir.path().join("p.pyr");
        let mut bytes = std::fs::read(&path).unwrap();
        bytes[summary.layout.tile_offset(4) as usize + 7] ^= 1;
        std::fs::write(&path, &bytes).unwrap();
        let p = TiledPyramid::open(&path, &summary.index_hash).unwrap();
        assert!(read_window(&p, 0, PixelRect::new(0, 0, 10, 10)).is_ok());
        let e = read_window(&p, 0, PixelRect::new(0, 0, 40, 40)).unwrap_err();
        assert!(
            e.to_string().contains("tile 4") && e.to_string().contains("damaged"),
            "{e}"
        );
        let mut other = summary.index_hash;
        other[0] ^= 1;
        let e = TiledPyramid::open(&path, &other).err().unwrap();
        assert!(e.to_string().contains("does not match"), "{e}");
        std::fs::write(&path, &bytes[..bytes.len() - 1]).unwrap();
        let e = TiledPyramid::open(&path, &summary.index_hash)
            .err()
            .unwrap();
        assert!(e.to_string().contains("truncated"), "{e}");
    }

    #[test]
    fn memory_pyramid_equals_the_file_pyramid() {
        let (w, h) = (300, 280);
        let img = GrayImage::from_vec(
            w,
            h,
            (0..w * h)
                .map(|i| f32::from(sample_value(i % w, i / w)) / 65535.0)
                .collect(),
        )
        .unwrap();
        let mem = MemoryPyramid::from_gray(&img);
        let dir = tempfile::tempdir().unwrap();
        let mut b =
            PyramidBuilder::create(&dir.path().join("p.pyr"), w, h, SampleDepth::U16, 256).unwrap();
        for r in 0..h {
            let row: Vec<u16> = (0..w).map(|c| sample_value(c, r)).collect();
            b.push_row_u16(&row).unwrap();
        }
        let s = b.finish().unwrap();
        let file = TiledPyramid::open(&dir.path().join("p.pyr"), &s.index_hash).unwrap();
        for level in 0..mem.layout().levels() {
            let (lw, lh) = mem.layout().level_sizes[level];
            let rect = PixelRect::new(0, 0, lw, lh);
            let a = read_window(&mem, level, rect).unwrap();
            let b = read_window(&file, level, rect).unwrap();
            // The file's white is 4095, the memory pyramid's 65535: compare samples.
            for (x, y) in a.data.iter().zip(&b.data) {
                assert_eq!((x * 65535.0).round(), (y * 4095.0).round());
            }
        }
    }

    #[test]
    fn scaled_windows_map_back_to_full_pixels() {
        let img = GrayImage::from_vec(
            640,
            480,
            (0..640 * 480).map(|i| (i % 640) as f32 / 640.0).collect(),
        )
        .unwrap();
        let mem = MemoryPyramid::from_gray(&img);
        let win = ScaledWindow::read(&mem, 2, [10.0, 9.0, 50.5, 40.0])
            .unwrap()
            .unwrap();
        assert_eq!(win.rect, PixelRect::new(2, 2, 11, 8));
        assert_eq!(win.scale(), 4.0);
        let (u, v) = win.to_full(0.5, 0.5);
        assert_eq!((u, v), (10.0, 10.0));
        assert_eq!(win.from_full(u, v), (0.5, 0.5));
        assert!(ScaledWindow::read(&mem, 0, [700.0, 0.0, 720.0, 5.0])
            .unwrap()
            .is_none());
    }

    #[test]
    fn level_rules() {
        type Rule = fn(f64, f64, usize) -> usize;
        let cases: [(Rule, &str, f64, f64, usize, usize); 10] = [
            (nearest_level, "nearest_level", 0.025, 0.10, 8, 2),
            (nearest_level, "nearest_level", 0.10, 0.10, 8, 0),
            (nearest_level, "nearest_level", 0.0605, 0.10, 8, 1),
            (nearest_level, "nearest_level", 0.00605, 0.10, 8, 4),
            (nearest_level, "nearest_level", 0.2, 0.10, 8, 0),
            (nearest_level, "nearest_level", 0.001, 10.0, 3, 2),
            (footprint_level, "footprint_level", 1.0, 3.9, 8, 1),
            (footprint_level, "footprint_level", 1.0, 4.0, 8, 2),
            (footprint_level, "footprint_level", 1.0, 0.5, 8, 0),
            (footprint_level, "footprint_level", 1.0, f64::NAN, 8, 0),
        ];
        for (rule, name, a, b, levels, level) in cases {
            assert_eq!(rule(a, b, levels), level, "{name}({a}, {b}, {levels})");
        }
    }
}
