//! A digital terrain model from GeoTIFF tiles: heights (single band, any integer or float sample type) in the
//! campaign's vertical datum, cropped on load to the area the campaign needs, and sampled bilinearly between
//! pixel centres. A GDAL no-data value and non-finite samples are holes; a point whose four surrounding
//! samples are not all present has no height (the caller falls back and says so).

use crate::imaging::decode::GeoTiffTags;
use crate::imaging::georef::{geotransform, GeoTransform};
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::BufReader;
use std::path::Path;
use tiff::decoder::{Decoder, DecodingResult, Limits};

/// Largest DTM tile read, samples (a 16 384² tile of f32 is 1 GiB while it is being cropped).
pub const MAX_DTM_SAMPLES: u64 = 1 << 28;

/// One cropped DTM tile: heights row-major, `NaN` for holes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DtmTile {
    /// The file it came from (relative to the campaign root), for messages.
    pub file: String,
    pub transform: GeoTransform,
    pub width_px: usize,
    pub height_px: usize,
    pub heights_m: Vec<f32>,
}

impl DtmTile {
    /// Bilinear height at world (x, y) between the four surrounding pixel centres; `None` outside the tile
    /// or next to a hole.
    pub fn height_at(&self, x_m: f64, y_m: f64) -> Option<f64> {
        let (u, v) = self.transform.world_to_pixel(x_m, y_m);
        // Pixel centres are at +0.5.
        let (fx, fy) = (u - 0.5, v - 0.5);
        if !(fx >= 0.0 && fy >= 0.0) {
            return None;
        }
        let (c0, r0) = (fx.floor() as usize, fy.floor() as usize);
        if c0 + 1 >= self.width_px || r0 + 1 >= self.height_px {
            // On the last row or column exactly: sample it without its missing neighbour.
            let on_edge = (c0 + 1 == self.width_px && fx == c0 as f64)
                || (r0 + 1 == self.height_px && fy == r0 as f64);
            if !on_edge || c0 >= self.width_px || r0 >= self.height_px {
                return None;
            }
        }
        let at = |c: usize, r: usize| {
            let c = c.min(self.width_px - 1);
            let r = r.min(self.height_px - 1);
            f64::from(self.heights_m[r * self.width_px + c])
        };
        let (ax, ay) = (fx - c0 as f64, fy - r0 as f64);
        let h = (1.0 - ay) * ((1.0 - ax) * at(c0, r0) + ax * at(c0 + 1, r0))
            + ay * ((1.0 - ax) * at(c0, r0 + 1) + ax * at(c0 + 1, r0 + 1));
        h.is_finite().then_some(h)
    }
}

/// The DTM tiles of a campaign.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Dtm {
    pub tiles: Vec<DtmTile>,
}

impl Dtm {
    /// Height at world (x, y) from the first tile that has one.
    pub fn height_at(&self, x_m: f64, y_m: f64) -> Option<f64> {
        self.tiles.iter().find_map(|t| t.height_at(x_m, y_m))
    }
}

fn samples_f32(result: DecodingResult) -> Result<Vec<f32>, String> {
    Ok(match result {
        DecodingResult::F32(v) => v,
        DecodingResult::F64(v) => v.into_iter().map(|x| x as f32).collect(),
        DecodingResult::U8(v) => v.into_iter().map(f32::from).collect(),
        DecodingResult::U16(v) => v.into_iter().map(f32::from).collect(),
        DecodingResult::I8(v) => v.into_iter().map(f32::from).collect(),
        DecodingResult::I16(v) => v.into_iter().map(f32::from).collect(),
        DecodingResult::U32(v) => v.into_iter().map(|x| x as f32).collect(),
        DecodingResult::I32(v) => v.into_iter().map(|x| x as f32).collect(),
        _ => return Err("has a sample type a DTM cannot have; write heights as Float32".into()),
    })
}

/// Load the DTM GeoTIFF at `path` (shown as `file` in messages), keeping only the pixels whose centres lie in
/// `area_m` = (min x, min y, max x, max y) grown by one pixel; `Ok(None)` when the tile does not overlap it.
pub fn load_tile(path: &Path, file: &str, area_m: [f64; 4]) -> Result<Option<DtmTile>, String> {
    let f = File::open(path).map_err(|e| format!("cannot be opened ({e})"))?;
    let mut dec = Decoder::new(BufReader::new(f))
        .map_err(|e| format!("is not a readable TIFF ({e})"))?
        .with_limits(Limits::unlimited());
    let (w, h) = dec
        .dimensions()
        .map_err(|e| format!("has no readable size ({e})"))?;
    if u64::from(w) * u64::from(h) > MAX_DTM_SAMPLES {
        return Err(format!(
            "is {w} × {h} samples, more than {MAX_DTM_SAMPLES} per tile; split it into tiles (e.g. gdal_retile.py)"
        ));
    }
    let tags = GeoTiffTags::read(&mut dec).ok_or("has no GeoTIFF tags; write it as a GeoTIFF")?;
    let t = geotransform(&tags)?;
    let nodata: Option<f32> = tags
        .gdal_nodata
        .as_deref()
        .and_then(|s| s.trim_matches(char::from(0)).trim().parse().ok());
    let (u0, v0) = t.world_to_pixel(area_m[0], area_m[3]);
    let (u1, v1) = t.world_to_pixel(area_m[2], area_m[1]);
    let c0 = (u0.floor() - 1.0).max(0.0) as usize;
    let r0 = (v0.floor() - 1.0).max(0.0) as usize;
    let c1 = (u1.ceil() + 1.0).min(f64::from(w)).max(0.0) as usize;
    let r1 = (v1.ceil() + 1.0).min(f64::from(h)).max(0.0) as usize;
    if c1 <= c0 + 1 || r1 <= r0 + 1 {
        return Ok(None);
    }
    let all = samples_f32(
        dec.read_image()
            .map_err(|e| format!("cannot be decoded ({e})"))?,
    )?;
    let w = w as usize;
    let channels = all.len() / (w * h as usize).max(1);
    if channels != 1 {
        return Err(format!(
            "has {channels} bands; a DTM has one band of heights"
        ));
    }
    let mut heights_m = Vec::with_capacity((c1 - c0) * (r1 - r0));
    for r in r0..r1 {
        heights_m.extend(all[r * w + c0..r * w + c1].iter().map(|&z| {
            if !z.is_finite() || nodata == Some(z) {
                f32::NAN
            } else {
                z
            }
        }));
    }
    Ok(Some(DtmTile {
        file: file.to_string(),
        transform: GeoTransform {
            origin_x_m: t.origin_x_m + c0 as f64 * t.pixel_m,
            origin_y_m: t.origin_y_m - r0 as f64 * t.pixel_m,
            pixel_m: t.pixel_m,
        },
        width_px: c1 - c0,
        height_px: r1 - r0,
        heights_m,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_reproduces_a_plane_and_refuses_holes() {
        // z = 10 + 0.1 x − 0.2 y on a 1 m grid whose corner is at (100, 200).
        let t = GeoTransform {
            origin_x_m: 100.0,
            origin_y_m: 200.0,
            pixel_m: 1.0,
        };
        let (w, h) = (6, 5);
        let mut heights = Vec::new();
        for r in 0..h {
            for c in 0..w {
                let [x, y] = t.pixel_to_world(c as f64 + 0.5, r as f64 + 0.5);
                heights.push((10.0 + 0.1 * x - 0.2 * y) as f32);
            }
        }
        let mut tile = DtmTile {
            file: "dtm.tif".into(),
            transform: t,
            width_px: w,
            height_px: h,
            heights_m: heights,
        };
        let (x, y) = (102.3, 197.1);
        let z = tile.height_at(x, y).unwrap();
        assert!((z - (10.0 + 0.1 * x - 0.2 * y)).abs() < 1e-4, "{z}");
        assert!(
            tile.height_at(100.2, 199.9).is_none(),
            "before the first centre"
        );
        tile.heights_m[2 * w + 2] = f32::NAN;
        assert!(tile.height_at(102.9, 197.1).is_none());
    }
}
