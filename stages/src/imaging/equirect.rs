//! An equirectangular panorama as the resampling stages read it: full-width bands of the rows they need, at
//! the pyramid levels they need, sampled bilinearly with the columns wrapping across the ±180° seam and the
//! rows clamping at the poles. Positions are given in full-resolution panorama pixels (the panorama
//! camera's), whatever level is sampled: level `l` is read at `(u / 2^l, v / 2^l)`.
//!
//! The level of a sample follows the mip-map rule ([`level_for`]): the finest level whose pixel is not
//! smaller than the footprint of the output pixel, so that a product at a coarser resolution than the
//! panorama averages the panorama's pixels instead of picking some of them (aliasing).
//!
//! A level finer than the panorama's detail level ([`crate::imaging::pyramid::PyramidLayout::detail_level`])
//! is never sampled: such levels only repeat the detail level's pixels (a panorama enlarged by pixel
//! repetition), so they are read from the detail level, which samples the panorama at its real angular
//! resolution — exactly as the panorama it was enlarged from.

use super::bilinear_many::sample_bilinear_many;
use super::border::Border;
use super::pyramid::{MemoryPyramid, PixelRect, PyramidError, TileSource};
use super::sample::{floor_fast, sample_bilinear};
use super::GrayImage;

/// Rows `[row0, row0 + image.height)` of one level, all columns.
#[derive(Clone, Debug, PartialEq)]
pub struct PanoramaBand {
    pub level: usize,
    pub row0: usize,
    /// Height of the whole level, pixels (for clamping at the poles).
    pub level_height: usize,
    pub image: GrayImage,
}

impl PanoramaBand {
    fn scale(&self) -> f64 {
        (1u64 << self.level) as f64
    }

    /// Bilinear sample at level coordinates (`u`, `v` relative to the whole level), columns wrapping, rows
    /// clamped to the level (and to the band, which covers every row it is asked for).
    #[cold]
    #[inline(never)]
    fn sample_wrapped(&self, u: f64, v_band: f64) -> f32 {
        let img = &self.image;
        let (w, h) = (img.width, img.height);
        if w == 0 || h == 0 || !u.is_finite() || !v_band.is_finite() {
            return 0.0;
        }
        let x = u - 0.5;
        let x0f = floor_fast(x);
        let x0 = x0f as isize;
        if x0 >= 0 && (x0 as usize) + 1 < w {
            return sample_bilinear(img, u, v_band, Border::Clamp);
        }
        let wrap = |c: isize| c.rem_euclid(w as isize) as usize;
        let (c0, c1) = (wrap(x0), wrap(x0 + 1));
        let y = (v_band - 0.5).clamp(0.0, (h - 1) as f64);
        let y0 = (floor_fast(y) as usize).min(h - 1);
        let y1 = (y0 + 1).min(h - 1);
        let (fx, fy) = ((x - x0f) as f32, (y - y0 as f64) as f32);
        let at = |c: usize, r: usize| img.data[r * w + c];
        let top = at(c0, y0) + (at(c1, y0) - at(c0, y0)) * fx;
        let bottom = at(c0, y1) + (at(c1, y1) - at(c0, y1)) * fx;
        top + (bottom - top) * fy
    }
}

/// Bands of a panorama at some levels; see the module documentation.
#[derive(Clone, Debug, PartialEq)]
pub struct PanoramaLevels {
    /// Full-resolution size, pixels.
    pub width_px: usize,
    pub height_px: usize,
    /// Band of level `l` at index `l` (levels not read are `None`).
    bands: Vec<Option<PanoramaBand>>,
    /// The finest level sampled (the source's detail level): finer levels are read from it.
    detail_level: usize,
}

impl PanoramaLevels {
    /// Reads, at each level of `levels`, the full-width band of the full-resolution rows [v0, v1) (one pixel
    /// of margin; clipped to the panorama). Levels the pyramid does not have are left out.
    pub fn read(
        source: &dyn TileSource,
        (v0, v1): (f64, f64),
        levels: std::ops::RangeInclusive<usize>,
    ) -> Result<Self, PyramidError> {
        let bands: Vec<(usize, (f64, f64))> = levels.map(|l| (l, (v0, v1))).collect();
        Self::read_bands(source, &bands)
    }

    /// Reads the band of full-resolution rows [v0, v1) (one pixel of margin, clipped) at each listed level;
    /// a level finer than the source's detail level is read from the detail level (rows of several such
    /// levels merged).
    pub fn read_bands(
        source: &dyn TileSource,
        wanted: &[(usize, (f64, f64))],
    ) -> Result<Self, PyramidError> {
        let layout = source.layout();
        let detail_level = layout.detail_level.min(layout.levels() - 1);
        let mut merged: Vec<(usize, (f64, f64))> = Vec::with_capacity(wanted.len());
        for &(level, rows) in wanted.iter().filter(|(l, _)| *l < layout.levels()) {
            let level = level.max(detail_level);
            match merged.iter_mut().find(|(l, _)| *l == level) {
                Some((_, r)) => *r = (r.0.min(rows.0), r.1.max(rows.1)),
                None => merged.push((level, rows)),
            }
        }
        let mut bands: Vec<Option<PanoramaBand>> = vec![None; layout.levels()];
        for &(level, (v0, v1)) in &merged {
            let (lw, lh) = layout.level_sizes[level];
            let s = (1u64 << level) as f64;
            let top = ((v0 / s).floor() - 1.0).clamp(0.0, lh as f64 - 1.0) as usize;
            let bottom = ((v1 / s).ceil() + 1.0).clamp(top as f64 + 1.0, lh as f64) as usize;
            let rect = PixelRect::new(0, top as i64, lw, bottom - top);
            bands[level] = Some(PanoramaBand {
                level,
                row0: top,
                level_height: lh,
                image: super::pyramid::read_window(source, level, rect)?,
            });
        }
        Ok(Self {
            width_px: layout.width,
            height_px: layout.height,
            bands,
            detail_level,
        })
    }

    /// A whole in-memory panorama: level 0 as given, coarser levels (up to `max_level`) from its pyramid.
    pub fn from_image(img: &GrayImage, max_level: usize) -> Self {
        let mut bands: Vec<Option<PanoramaBand>> = vec![Some(PanoramaBand {
            level: 0,
            row0: 0,
            level_height: img.height,
            image: img.clone(),
        })];
        let mut detail_level = 0;
        if max_level > 0 && img.width > 1 && img.height > 1 {
            let pyramid = MemoryPyramid::from_gray(img);
            let coarser = Self::read(&pyramid, (0.0, img.height as f64), 1..=max_level)
                .expect("an in-memory pyramid reads without errors");
            bands.extend(coarser.bands.into_iter().skip(1));
            detail_level = coarser.detail_level.min(max_level);
        }
        Self {
            width_px: img.width,
            height_px: img.height,
            bands,
            detail_level,
        }
    }

    /// The finest level sampled: the source's detail level (module documentation).
    pub fn detail_level(&self) -> usize {
        self.detail_level
    }

    /// The coarsest level read.
    pub fn max_level(&self) -> usize {
        self.bands.iter().rposition(Option::is_some).unwrap_or(0)
    }

    /// The band used for `level`: that level (the detail level for a finer one), or the nearest finer one
    /// that was read.
    pub fn band(&self, level: usize) -> &PanoramaBand {
        let level = level.max(self.detail_level);
        self.bands[..=level.min(self.bands.len() - 1)]
            .iter()
            .rev()
            .flatten()
            .next()
            .or_else(|| self.bands.iter().flatten().next())
            .expect("at least one band")
    }

    /// Bilinear sample at full-resolution panorama pixel (u, v), from `level`.
    pub fn sample(&self, level: usize, u_px: f64, v_px: f64) -> f32 {
        let b = self.band(level);
        let s = b.scale();
        b.sample_wrapped(u_px / s, v_px / s - b.row0 as f64)
    }

    /// Bilinear sample (in `f64`) at full-resolution panorama pixel (u, v) from `level`, columns wrapping;
    /// `None` for a non-finite position or a row outside the panorama.
    pub fn sample_checked(&self, level: usize, u_px: f64, v_px: f64) -> Option<f32> {
        if !u_px.is_finite() || !(0.0..self.height_px as f64).contains(&v_px) {
            return None;
        }
        let b = self.band(level);
        let s = b.scale();
        let img = &b.image;
        let (w, h) = (img.width, img.height);
        if w == 0 || h == 0 {
            return None;
        }
        let x = u_px / s - 0.5;
        let y = (v_px / s - b.row0 as f64 - 0.5).clamp(0.0, (h - 1) as f64);
        let x0f = x.floor();
        let fx = x - x0f;
        let y0 = (y.floor() as usize).min(h - 1);
        let fy = y - y0 as f64;
        let y1 = (y0 + 1).min(h - 1);
        let x0 = (x0f as i64).rem_euclid(w as i64) as usize;
        let x1 = (x0 + 1) % w;
        let p = |c: usize, r: usize| f64::from(img.data[r * w + c]);
        let v = (1.0 - fy) * ((1.0 - fx) * p(x0, y0) + fx * p(x1, y0))
            + fy * ((1.0 - fx) * p(x0, y1) + fx * p(x1, y1));
        Some(v as f32)
    }

    /// `out[i]` = the bilinear sample at full-resolution (`us[i]`, `vs[i]`) from `level`, `nan_value` where
    /// `us[i]` is NaN. `scratch` holds the scaled positions.
    pub fn sample_many(
        &self,
        level: usize,
        us: &[f64],
        vs: &[f64],
        out: &mut [f32],
        nan_value: f32,
        scratch: &mut (Vec<f64>, Vec<f64>),
    ) {
        let b = self.band(level);
        let (su, sv) = scratch;
        if b.level == 0 && b.row0 == 0 {
            return sample_bilinear_many(&b.image, us, vs, out, nan_value, |_, u, v| {
                b.sample_wrapped(u, v)
            });
        }
        let s = b.scale();
        let row0 = b.row0 as f64;
        su.clear();
        su.extend(us.iter().map(|u| u / s));
        sv.clear();
        sv.extend(vs.iter().map(|v| v / s - row0));
        sample_bilinear_many(&b.image, su, sv, out, nan_value, |_, u, v| {
            b.sample_wrapped(u, v)
        });
    }
}

/// The mip level for an output pixel of size `footprint` (any unit) over a panorama pixel of size `native`
/// (same unit) at that place: the finest level whose pixel is not smaller than the footprint, at most
/// `max_level`.
pub fn level_for(native: f64, footprint: f64, max_level: usize) -> usize {
    super::pyramid::footprint_level(native, footprint, max_level + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_sample_like_the_whole_panorama_and_wrap_across_the_seam() {
        let (w, h) = (512, 256);
        let img = GrayImage::from_vec(
            w,
            h,
            (0..w * h)
                .map(|i| {
                    (((i % w) as f32 * 0.05).sin() + ((i / w) as f32 * 0.07).cos() + 2.0) / 4.0
                })
                .collect(),
        )
        .unwrap();
        let whole = PanoramaLevels::from_image(&img, 0);
        let pyramid = MemoryPyramid::from_gray(&img);
        let band = PanoramaLevels::read(&pyramid, (100.0, 200.0), 0..=2).unwrap();
        for (u, v) in [(10.3, 120.7), (511.9, 150.2), (0.1, 199.0), (256.0, 100.5)] {
            let a = whole.sample(0, u, v);
            let b = band.sample(0, u, v);
            assert!((a - b).abs() < 1e-4, "({u}, {v}): {a} vs {b}");
        }
        // Across the seam: u = 0 lies between the last and the first column.
        let seam = whole.sample(0, 0.0, 130.5);
        let expected = 0.5 * (img.get(0, 130) + img.get(w - 1, 130));
        assert!((seam - expected).abs() < 1e-5);
        // Level 1 at full-resolution coordinates: the average of the 2 × 2 block under it.
        let l1 = band.sample(1, 100.0, 150.0);
        let avg = (img.get(98, 148) + img.get(99, 148) + img.get(98, 149) + img.get(99, 149)) / 4.0;
        let avg2 =
            (img.get(100, 148) + img.get(101, 148) + img.get(100, 149) + img.get(101, 149)) / 4.0;
        let avg3 =
            (img.get(98, 150) + img.get(99, 150) + img.get(98, 151) + img.get(99, 151)) / 4.0;
        let avg4 =
            (img.get(100, 150) + img.get(101, 150) + img.get(100, 151) + img.get(101, 151)) / 4.0;
        assert!((l1 - (avg + avg2 + avg3 + avg4) / 4.0).abs() < 1e-4);
        // Many at once equals one by one.
        let us = [5.5, 300.25, f64::NAN, 511.7];
        let vs = [120.0, 180.5, 0.0, 160.0];
        let mut out = [0.0f32; 4];
        let mut scratch = (Vec::new(), Vec::new());
        band.sample_many(1, &us, &vs, &mut out, -1.0, &mut scratch);
        assert_eq!(out[2], -1.0);
        for i in [0, 1, 3] {
            assert!((out[i] - band.sample(1, us[i], vs[i])).abs() < 1e-6);
        }
    }

    #[test]
    fn mip_levels() {
        let cases = [
            ((0.01, 0.03, 5), 1),
            ((0.01, 0.0401, 5), 2),
            ((0.01, 0.005, 5), 0),
            ((0.001, 1.0, 3), 3),
        ];
        for ((a, b, levels), level) in cases {
            assert_eq!(
                level_for(a, b, levels),
                level,
                "level_for({a}, {b}, {levels})"
            );
        }
    }
}
