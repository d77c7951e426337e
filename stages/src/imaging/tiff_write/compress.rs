//! Compression of one TIFF tile: none, LZW (TIFF 6.0 section 13, with the horizontal-differencing predictor
//! of section 14), Deflate (Adobe, zlib stream, same predictor) or JPEG (TIFF Technote 2: each tile a
//! complete baseline JPEG stream, 4:4:4 YCbCr for colour).

use std::io::{self, Write};

/// How tiles are compressed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TiffCompression {
    None,
    Lzw,
    Deflate,
    /// Baseline JPEG at this quality (1–100); 8-bit samples only.
    Jpeg(u8),
}

impl TiffCompression {
    /// The TIFF `Compression` tag value.
    pub fn tag_value(self) -> u16 {
        match self {
            TiffCompression::None => 1,
            TiffCompression::Lzw => 5,
            TiffCompression::Jpeg(_) => 7,
            TiffCompression::Deflate => 8,
        }
    }

    /// Whether the horizontal-differencing predictor is used.
    pub fn predicts(self) -> bool {
        matches!(self, TiffCompression::Lzw | TiffCompression::Deflate)
    }
}

/// Horizontal differencing in place on `rows` rows of little-endian samples (`bytes_per_sample` 1 or 2),
/// `channels` interleaved samples per pixel.
pub fn predict(tile: &mut [u8], rows: usize, channels: usize, bytes_per_sample: usize) {
    let row_len = tile.len() / rows.max(1);
    for row in tile.chunks_exact_mut(row_len) {
        if bytes_per_sample == 1 {
            for i in (channels..row.len()).rev() {
                row[i] = row[i].wrapping_sub(row[i - channels]);
            }
        } else {
            let n = row.len() / 2;
            for i in (channels..n).rev() {
                let at = |k: usize| u16::from_le_bytes([row[2 * k], row[2 * k + 1]]);
                let d = at(i).wrapping_sub(at(i - channels));
                row[2 * i..2 * i + 2].copy_from_slice(&d.to_le_bytes());
            }
        }
    }
}

/// The compressed bytes of one `side × side` tile of `channels` samples per pixel.
pub fn compress(
    mut tile: Vec<u8>,
    side: usize,
    channels: usize,
    bytes_per_sample: usize,
    compression: TiffCompression,
) -> io::Result<Vec<u8>> {
    if compression.predicts() {
        predict(&mut tile, side, channels, bytes_per_sample);
    }
    match compression {
        TiffCompression::None => Ok(tile),
        TiffCompression::Lzw => {
            // The stream interface, as the `tiff` crate's own writer uses (it always ends with the end code).
            let mut out = Vec::new();
            weezl::encode::Encoder::with_tiff_size_switch(weezl::BitOrder::Msb, 8)
                .into_stream(&mut out)
                .encode_all(&tile[..])
                .status?;
            Ok(out)
        }
        TiffCompression::Deflate => {
            let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
            z.write_all(&tile)?;
            z.finish()
        }
        TiffCompression::Jpeg(quality) => {
            if bytes_per_sample != 1 {
                return Err(io::Error::other("JPEG compression needs 8-bit samples"));
            }
            let colour = if channels == 3 {
                image::ExtendedColorType::Rgb8
            } else {
                image::ExtendedColorType::L8
            };
            let mut out = Vec::new();
            image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, quality)
                .encode(&tile, side as u32, side as u32, colour)
                .map_err(io::Error::other)?;
            Ok(out)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prediction_differences_each_channel() {
        let mut t = vec![10u8, 20, 13, 25, 11, 30];
        predict(&mut t, 1, 2, 1);
        assert_eq!(t, vec![10, 20, 3, 5, 254, 5]);
        let mut t16: Vec<u8> = [1000u16, 1003, 999]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        predict(&mut t16, 1, 1, 2);
        let back: Vec<u16> = t16
            .chunks(2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
            .collect();
        assert_eq!(back, vec![1000, 3, 65532]);
    }
}
