//! Where a GeoTIFF raster lies (OGC GeoTIFF 1.1): the north-up geotransform pixel ↔ world from its tags
//! (ModelPixelScale + ModelTiepoint, or an axis-aligned ModelTransformation; GTRasterTypeGeoKey decides whether
//! raster (0, 0) is the first pixel's corner or its centre) and the EPSG code of its projected CRS
//! (ProjectedCSTypeGeoKey). Pixels follow the campaign convention: continuous, the top-left corner of the
//! image at (0, 0), the first pixel's centre at (0.5, 0.5).

use crate::imaging::decode::GeoTiffTags;
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::BufReader;
use std::path::Path;
use tiff::decoder::Decoder;

/// GeoKey ids used here.
const GT_RASTER_TYPE: u16 = 1025;
const PROJECTED_CS_TYPE: u16 = 3072;
/// GTRasterTypeGeoKey value "RasterPixelIsPoint".
const PIXEL_IS_POINT: u16 = 2;
/// Relative difference allowed between the two pixel sides of a "square" pixel.
const SQUARE_TOLERANCE: f64 = 1e-6;

/// A north-up raster's placement: world (easting, northing) of continuous pixel (u, v) is
/// `(origin_x_m + u·pixel_m, origin_y_m − v·pixel_m)`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GeoTransform {
    /// World easting of the image's top-left corner, m.
    pub origin_x_m: f64,
    /// World northing of the image's top-left corner, m.
    pub origin_y_m: f64,
    /// Side of a (square) pixel on the ground, m.
    pub pixel_m: f64,
}

impl GeoTransform {
    /// World (easting, northing) of continuous pixel (u, v), m.
    pub fn pixel_to_world(&self, u_px: f64, v_px: f64) -> [f64; 2] {
        [
            self.origin_x_m + u_px * self.pixel_m,
            self.origin_y_m - v_px * self.pixel_m,
        ]
    }

    /// Continuous pixel of world (easting, northing).
    pub fn world_to_pixel(&self, x_m: f64, y_m: f64) -> (f64, f64) {
        (
            (x_m - self.origin_x_m) / self.pixel_m,
            (self.origin_y_m - y_m) / self.pixel_m,
        )
    }
}

/// A georeferenced raster's header: size, placement and CRS code.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RasterHeader {
    pub width_px: u32,
    pub height_px: u32,
    pub transform: GeoTransform,
    /// EPSG code of the projected CRS (`None` when the file names none, or a user-defined one).
    pub epsg: Option<u32>,
}

impl RasterHeader {
    /// World extent (min x, min y, max x, max y), m.
    pub fn extent(&self) -> [f64; 4] {
        let [x0, y1] = self.transform.pixel_to_world(0.0, 0.0);
        let [x1, y0] = self
            .transform
            .pixel_to_world(self.width_px as f64, self.height_px as f64);
        [x0, y0, x1, y1]
    }

    /// Whether world (x, y) lies at least `margin_m` inside the raster.
    pub fn contains(&self, x_m: f64, y_m: f64, margin_m: f64) -> bool {
        let [x0, y0, x1, y1] = self.extent();
        x_m >= x0 + margin_m && x_m <= x1 - margin_m && y_m >= y0 + margin_m && y_m <= y1 - margin_m
    }
}

/// The value of GeoKey `id` when stored inline (location 0) in a GeoKeyDirectory.
fn geo_key(directory: &[u16], id: u16) -> Option<u16> {
    let count = usize::from(*directory.get(3)?);
    directory[4..]
        .chunks_exact(4)
        .take(count)
        .find(|k| k[0] == id && k[1] == 0)
        .map(|k| k[3])
}

/// EPSG code of the projected CRS named by the tags (`None` when absent or user-defined, 32767).
pub fn epsg_code(tags: &GeoTiffTags) -> Option<u32> {
    let dir = tags.geo_key_directory.as_deref()?;
    geo_key(dir, PROJECTED_CS_TYPE)
        .filter(|&c| c != 0 && c != 32767)
        .map(u32::from)
}

/// The north-up geotransform of the tags; `Err` says what is missing or unsupported and what to do.
pub fn geotransform(tags: &GeoTiffTags) -> Result<GeoTransform, String> {
    let point = tags
        .geo_key_directory
        .as_deref()
        .and_then(|d| geo_key(d, GT_RASTER_TYPE))
        == Some(PIXEL_IS_POINT);
    // Raster coordinates (I, J) are ours minus half a pixel when raster (0, 0) is the first pixel's centre.
    let shift = if point { 0.5 } else { 0.0 };
    let (origin_x, origin_y, sx, sy) = if let Some(m) = &tags.model_transformation {
        if m.len() < 16 {
            return Err("ModelTransformation has fewer than 16 values".into());
        }
        if m[1] != 0.0 || m[4] != 0.0 {
            return Err(
                "the raster is rotated (ModelTransformation with shear terms); warp it north-up \
                        first (e.g. gdalwarp)"
                    .into(),
            );
        }
        (m[3], m[7], m[0], -m[5])
    } else {
        let scale = tags.model_pixel_scale.as_deref().ok_or(
            "no georeference (neither ModelPixelScale + ModelTiepoint nor ModelTransformation); \
             write the file as a GeoTIFF",
        )?;
        let tie = tags
            .model_tiepoints
            .as_deref()
            .filter(|t| t.len() >= 6)
            .ok_or("ModelPixelScale without a ModelTiepoint; write the file as a GeoTIFF")?;
        if scale.len() < 2 {
            return Err("ModelPixelScale has fewer than 2 values".into());
        }
        let (i, j, x, y) = (tie[0], tie[1], tie[3], tie[4]);
        (x - i * scale[0], y + j * scale[1], scale[0], scale[1])
    };
    if !(sx.is_finite() && sy.is_finite() && sx > 0.0 && sy > 0.0) {
        return Err(format!(
            "pixel size {sx} × {sy} is not positive (a south-up or mirrored raster); warp it north-up first"
        ));
    }
    if ((sx - sy) / sx).abs() > SQUARE_TOLERANCE {
        return Err(format!(
            "pixels are not square ({sx} × {sy} m); resample to square pixels first (e.g. gdalwarp -tr)"
        ));
    }
    if !(origin_x.is_finite() && origin_y.is_finite()) {
        return Err("the tie point is not finite".into());
    }
    Ok(GeoTransform {
        origin_x_m: origin_x - shift * sx,
        origin_y_m: origin_y + shift * sx,
        pixel_m: sx,
    })
}

/// Size, geotransform and CRS code of the GeoTIFF at `path`, from its first directory only (no pixels read).
pub fn read_header(path: &Path) -> Result<RasterHeader, String> {
    let file = File::open(path).map_err(|e| format!("cannot be opened ({e})"))?;
    let mut dec =
        Decoder::new(BufReader::new(file)).map_err(|e| format!("is not a readable TIFF ({e})"))?;
    let (w, h) = dec
        .dimensions()
        .map_err(|e| format!("has no readable size ({e})"))?;
    let tags = GeoTiffTags::read(&mut dec)
        .ok_or("has no GeoTIFF tags; write it as a GeoTIFF (georeferenced TIFF)")?;
    Ok(RasterHeader {
        width_px: w,
        height_px: h,
        transform: geotransform(&tags)?,
        epsg: epsg_code(&tags),
    })
}

/// GeoTIFF tags placing a north-up raster by `t` in the projected CRS `EPSG:epsg` (raster type PixelIsArea).
pub fn geotiff_tags(t: &GeoTransform, epsg: u16) -> GeoTiffTags {
    const GT_MODEL_TYPE: u16 = 1024;
    GeoTiffTags {
        model_pixel_scale: Some(vec![t.pixel_m, t.pixel_m, 0.0]),
        model_tiepoints: Some(vec![0.0, 0.0, 0.0, t.origin_x_m, t.origin_y_m, 0.0]),
        geo_key_directory: Some(vec![
            1,
            1,
            0,
            3,
            GT_MODEL_TYPE,
            0,
            1,
            1,
            GT_RASTER_TYPE,
            0,
            1,
            1,
            PROJECTED_CS_TYPE,
            0,
            1,
            epsg,
        ]),
        ..GeoTiffTags::default()
    }
}

/// The EPSG code of the horizontal part of a campaign `crs` (`EPSG:28992+5709` → 28992).
pub fn campaign_epsg(crs: &str) -> Option<u32> {
    let s = crs.trim();
    let rest = s.get(..5)?.eq_ignore_ascii_case("EPSG:").then(|| &s[5..])?;
    rest.split('+').next()?.trim().parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tags(scale: f64, tie: [f64; 2], raster_type: u16) -> GeoTiffTags {
        GeoTiffTags {
            model_pixel_scale: Some(vec![scale, scale, 0.0]),
            model_tiepoints: Some(vec![0.0, 0.0, 0.0, tie[0], tie[1], 0.0]),
            geo_key_directory: Some(vec![
                1,
                1,
                0,
                2,
                GT_RASTER_TYPE,
                0,
                1,
                raster_type,
                PROJECTED_CS_TYPE,
                0,
                1,
                28992,
            ]),
            ..GeoTiffTags::default()
        }
    }

    #[test]
    fn pixel_is_area_puts_the_tie_point_on_the_corner() {
        let t = geotransform(&tags(0.1, [1000.0, 2000.0], 1)).unwrap();
        assert_eq!(t.pixel_to_world(0.0, 0.0), [1000.0, 2000.0]);
        let [x, y] = t.pixel_to_world(0.5, 0.5);
        assert!((x - 1000.05).abs() < 1e-9 && (y - 1999.95).abs() < 1e-9);
        let (u, v) = t.world_to_pixel(x, y);
        assert!((u - 0.5).abs() < 1e-9 && (v - 0.5).abs() < 1e-9);
        assert_eq!(epsg_code(&tags(0.1, [0.0, 0.0], 1)), Some(28992));
    }

    #[test]
    fn pixel_is_point_puts_the_tie_point_on_the_first_centre() {
        let t = geotransform(&tags(0.1, [1000.0, 2000.0], PIXEL_IS_POINT)).unwrap();
        let [x, y] = t.pixel_to_world(0.5, 0.5);
        assert!((x - 1000.0).abs() < 1e-9 && (y - 2000.0).abs() < 1e-9);
    }

    #[test]
    fn rotated_or_non_square_rasters_are_refused_with_a_remedy() {
        let mut t = tags(0.1, [0.0, 0.0], 1);
        t.model_pixel_scale = Some(vec![0.1, 0.2, 0.0]);
        assert!(geotransform(&t).unwrap_err().contains("square"));
        let t = GeoTiffTags {
            model_transformation: Some(vec![
                0.1, 0.01, 0.0, 5.0, 0.01, -0.1, 0.0, 6.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
            ]),
            ..GeoTiffTags::default()
        };
        assert!(geotransform(&t).unwrap_err().contains("north-up"));
        assert!(geotransform(&GeoTiffTags::default())
            .unwrap_err()
            .contains("GeoTIFF"));
    }

    #[test]
    fn written_tags_read_back_to_the_same_transform() {
        let t = GeoTransform {
            origin_x_m: 155_000.25,
            origin_y_m: 463_100.5,
            pixel_m: 0.08,
        };
        let tags = geotiff_tags(&t, 28992);
        assert_eq!(geotransform(&tags).unwrap(), t);
        assert_eq!(epsg_code(&tags), Some(28992));
    }

    #[test]
    fn campaign_crs_codes() {
        assert_eq!(campaign_epsg("EPSG:28992+5709"), Some(28992));
        assert_eq!(campaign_epsg("epsg:25832"), Some(25832));
        assert_eq!(campaign_epsg("WGS84"), None);
    }
}
