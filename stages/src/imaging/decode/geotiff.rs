//! The GeoTIFF georeferencing tags of a TIFF, kept as stored (OGC GeoTIFF 1.1: ModelPixelScale 33550,
//! ModelTiepoint 33922, ModelTransformation 34264, GeoKeyDirectory 34735, GeoDoubleParams 34736,
//! GeoAsciiParams 34737) plus GDAL's no-data tag 42113, so that a georeferenced orthophoto read through the
//! windowed reader keeps where it lies.

use serde::{Deserialize, Serialize};
use std::io::{Read, Seek};
use tiff::decoder::Decoder;
use tiff::tags::Tag;

/// GeoTIFF tags of a TIFF's first image, each as stored (`None` when absent).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GeoTiffTags {
    /// (ScaleX, ScaleY, ScaleZ): model units per pixel.
    pub model_pixel_scale: Option<Vec<f64>>,
    /// Tie points (I, J, K, X, Y, Z)…: raster point (I, J, K) is model point (X, Y, Z).
    pub model_tiepoints: Option<Vec<f64>>,
    /// 4 × 4 raster-to-model matrix, row-major (instead of scale + tie point).
    pub model_transformation: Option<Vec<f64>>,
    /// The GeoKey directory (header and keys) as stored.
    pub geo_key_directory: Option<Vec<u16>>,
    pub geo_double_params: Option<Vec<f64>>,
    pub geo_ascii_params: Option<String>,
    /// GDAL's no-data value, as text.
    pub gdal_nodata: Option<String>,
}

impl GeoTiffTags {
    /// The tags of the decoder's current image; `None` when it has none of them.
    pub fn read<R: Read + Seek>(decoder: &mut Decoder<R>) -> Option<Self> {
        let mut tag = |tag: Tag| decoder.find_tag(tag).ok().flatten();
        let model_pixel_scale = tag(Tag::ModelPixelScaleTag).and_then(|v| v.into_f64_vec().ok());
        let model_tiepoints = tag(Tag::ModelTiepointTag).and_then(|v| v.into_f64_vec().ok());
        let model_transformation =
            tag(Tag::ModelTransformationTag).and_then(|v| v.into_f64_vec().ok());
        let geo_double_params = tag(Tag::GeoDoubleParamsTag).and_then(|v| v.into_f64_vec().ok());
        let geo_key_directory = tag(Tag::GeoKeyDirectoryTag).and_then(|v| v.into_u16_vec().ok());
        let geo_ascii_params = tag(Tag::GeoAsciiParamsTag).and_then(|v| v.into_string().ok());
        let gdal_nodata = tag(Tag::GdalNodata).and_then(|v| v.into_string().ok());
        let tags = Self {
            model_pixel_scale,
            model_tiepoints,
            model_transformation,
            geo_key_directory,
            geo_double_params,
            geo_ascii_params,
            gdal_nodata,
        };
        (tags != Self::default()).then_some(tags)
    }
}
