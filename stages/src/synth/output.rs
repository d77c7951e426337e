//! How the generator writes images at real sensor sizes: each image is rendered at a reduced size (an exact
//! integer fraction of the camera's, so the rendered camera is the real one with its focal length and
//! principal point divided by the same factor) and upsampled bilinearly to the camera's size while it is
//! written — row by row into a tiled TIFF (memory: one band of tiles), or into one buffer for a JPEG. The
//! content then has the rendered resolution; the files, camera tables and everything the pipeline reads
//! have the real ones.

use super::SynthError;
use crate::imaging::tiff_write::{TiffCompression, TiledTiffSpec, TiledTiffWriter};
use crate::imaging::RgbImage;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// File format of the aerial frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AerialFormat {
    /// Baseline JPEG (`.jpg`), 8-bit.
    Jpeg,
    /// Tiled TIFF (`.tif`, 256-px tiles; BigTIFF beyond 4 GiB) with this compression and 8 or 16 bits per
    /// sample (16-bit frames hold 12-bit data, 0..4095, as large-format cameras deliver them).
    TiledTiff {
        compression: TiffCompression,
        bits: u8,
    },
}

impl AerialFormat {
    /// File extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            AerialFormat::Jpeg => "jpg",
            AerialFormat::TiledTiff { .. } => "tif",
        }
    }

    /// Checks the combination (JPEG compression holds 8 bits only).
    pub fn check(self) -> Result<(), String> {
        match self {
            AerialFormat::Jpeg => Ok(()),
            AerialFormat::TiledTiff { compression, bits } => match (compression, bits) {
                (TiffCompression::Jpeg(_), 16) => Err(
                    "JPEG-compressed TIFF holds 8 bits only: use lzw, deflate or none for 16 bits"
                        .into(),
                ),
                (_, 8 | 16) => Ok(()),
                (_, b) => Err(format!("{b} bits per sample; use 8 or 16")),
            },
        }
    }
}

/// `"26460x17004"` (or `×`) as (width, height).
pub fn parse_size_px(text: &str) -> Result<(u32, u32), String> {
    let t = text.trim().replace('×', "x");
    let (w, h) = t
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{text}' is not a size; write WIDTHxHEIGHT, e.g. 26460x17004"))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|_| format!("'{text}' is not a size; write WIDTHxHEIGHT, e.g. 26460x17004"))
    };
    Ok((parse(w)?, parse(h)?))
}

/// The aerial format named by `format` (`jpeg` or `tiff`), with, for TIFF, `compression` (`jpeg`, `lzw`,
/// `deflate` or `none`) and `bits` (8 or 16).
pub fn aerial_format_from(
    format: &str,
    compression: &str,
    bits: u8,
    jpeg_quality: u8,
) -> Result<AerialFormat, String> {
    let f = match format.trim().to_ascii_lowercase().as_str() {
        "jpeg" | "jpg" => AerialFormat::Jpeg,
        "tiff" | "tif" => AerialFormat::TiledTiff {
            compression: match compression.trim().to_ascii_lowercase().as_str() {
                "jpeg" | "jpg" => TiffCompression::Jpeg(jpeg_quality),
                "lzw" => TiffCompression::Lzw,
                "deflate" | "zip" => TiffCompression::Deflate,
                "none" => TiffCompression::None,
                other => {
                    return Err(format!(
                        "unknown TIFF compression '{other}': use jpeg, lzw, deflate or none"
                    ))
                }
            },
            bits,
        },
        other => return Err(format!("unknown aerial format '{other}': use jpeg or tiff")),
    };
    f.check()?;
    Ok(f)
}

/// The integer factor `k` a `width × height` image is rendered at (`width / k × height / k`, then upsampled
/// by `k`): the smallest `k` dividing both sides with `width / k ≤ max_width`, else the largest common divisor
/// (`None` for no limit: k = 1).
pub fn render_factor(width: u32, height: u32, max_width: Option<u32>) -> u32 {
    let Some(cap) = max_width else {
        return 1;
    };
    let g = gcd(width, height).max(1);
    (1..=g)
        .filter(|k| g.is_multiple_of(*k))
        .find(|k| width / k <= cap)
        .unwrap_or(g)
}

fn gcd(a: u32, b: u32) -> u32 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// Source row or column pairs and weights of a bilinear upsampling by `k` (continuous pixel convention: output
/// pixel centre `i + 0.5` is source position `(i + 0.5) / k`).
fn taps(n_out: usize, n_src: usize, k: u32) -> Vec<(usize, usize, f32)> {
    (0..n_out)
        .map(|i| {
            let x = ((i as f64 + 0.5) / f64::from(k) - 0.5).clamp(0.0, (n_src - 1) as f64);
            let x0 = x.floor() as usize;
            let x1 = (x0 + 1).min(n_src - 1);
            (x0, x1, (x - x0 as f64) as f32)
        })
        .collect()
}

/// Calls `row(r, rgb)` for every row of `img` upsampled by `k`, with 0..1 values (RGB interleaved, `f32`).
fn upsampled_rows(
    img: &RgbImage,
    k: u32,
    mut row: impl FnMut(usize, &[f32]) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let (w, h) = (img.width * k as usize, img.height * k as usize);
    let cols = taps(w, img.width, k);
    let rows = taps(h, img.height, k);
    let mut line = vec![0f32; w * 3];
    for (r, &(y0, y1, fy)) in rows.iter().enumerate() {
        for (c, &(x0, x1, fx)) in cols.iter().enumerate() {
            for ch in 0..3 {
                let at = |x: usize, y: usize| img.data[(y * img.width + x) * 3 + ch];
                let top = at(x0, y0) + (at(x1, y0) - at(x0, y0)) * fx;
                let bottom = at(x0, y1) + (at(x1, y1) - at(x0, y1)) * fx;
                line[c * 3 + ch] = top + (bottom - top) * fy;
            }
        }
        row(r, &line)?;
    }
    Ok(())
}

/// Writes `img` (rendered at the camera's size / `k`) upsampled by `k` to `path` as `format`.
pub fn write_aerial_image(
    img: &RgbImage,
    k: u32,
    path: &Path,
    format: AerialFormat,
    jpeg_quality: u8,
) -> Result<(), SynthError> {
    let io = |e: std::io::Error| SynthError::io(path, e);
    match format {
        AerialFormat::Jpeg => write_jpeg(img, k, path, jpeg_quality),
        AerialFormat::TiledTiff { compression, bits } => {
            let (w, h) = (img.width * k as usize, img.height * k as usize);
            let bytes_per_sample = usize::from(bits / 8);
            let spec = TiledTiffSpec {
                width: w,
                height: h,
                channels: 3,
                bytes_per_sample,
                tile_side: 256,
                compression,
                big: (w * h * 3 * bytes_per_sample) as u64 > (3u64 << 30),
            };
            let mut writer = TiledTiffWriter::create(path, spec).map_err(io)?;
            upsampled_rows(img, k, |_, line| {
                if bits == 16 {
                    let row: Vec<u16> = line
                        .iter()
                        .map(|v| (v.clamp(0.0, 1.0) * 4095.0).round() as u16)
                        .collect();
                    writer.push_row_u16(&row)
                } else {
                    let row: Vec<u8> = line
                        .iter()
                        .map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8)
                        .collect();
                    writer.push_row_u8(&row)
                }
            })
            .map_err(io)?;
            writer.finish().map_err(io)
        }
    }
}

/// Writes `img` upsampled by `k` as a JPEG (the whole 8-bit RGB image is held for the encoder).
pub fn write_jpeg(img: &RgbImage, k: u32, path: &Path, jpeg_quality: u8) -> Result<(), SynthError> {
    if k == 1 {
        return crate::imaging::io::save_rgb(path, img, jpeg_quality)
            .map_err(|e| SynthError::io(path, e));
    }
    let (w, h) = (img.width * k as usize, img.height * k as usize);
    let mut rgb = Vec::with_capacity(w * h * 3);
    upsampled_rows(img, k, |_, line| {
        rgb.extend(line.iter().map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8));
        Ok(())
    })
    .map_err(|e| SynthError::io(path, e))?;
    let buf = image::RgbImage::from_raw(w as u32, h as u32, rgb)
        .ok_or_else(|| SynthError::io(path, std::io::Error::other("internal: RGB buffer size")))?;
    crate::fsutil::atomic_write_with(path, |out| {
        image::codecs::jpeg::JpegEncoder::new_with_quality(out, jpeg_quality)
            .encode_image(&buf)
            .map_err(std::io::Error::other)
    })
    .map_err(|e| SynthError::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn render_factors_divide_both_sides() {
        assert_eq!(render_factor(26460, 17004, Some(2400)), 12);
        assert_eq!(render_factor(14192, 10640, Some(2400)), 8); // 1774 × 1330
        assert_eq!(render_factor(14192, 10640, Some(1000)), 16); // 887 × 665
        assert_eq!(render_factor(8192, 4096, Some(2048)), 4);
        assert_eq!(render_factor(1600, 800, Some(2048)), 1);
        assert_eq!(render_factor(1600, 800, None), 1);
        assert_eq!(render_factor(1601, 800, Some(100)), 1); // coprime sides: no reduction
    }

    #[test]
    fn flags_parse() {
        assert_eq!(parse_size_px("26460x17004").unwrap(), (26460, 17004));
        assert_eq!(parse_size_px(" 800 × 600 ").unwrap(), (800, 600));
        assert!(parse_size_px("800").is_err());
        assert_eq!(
            aerial_format_from("tiff", "lzw", 16, 92).unwrap(),
            AerialFormat::TiledTiff {
                compression: TiffCompression::Lzw,
                bits: 16
            }
        );
        assert!(aerial_format_from("tiff", "jpeg", 16, 92).is_err());
        assert!(aerial_format_from("png", "none", 8, 92).is_err());
        assert_eq!(
            aerial_format_from("JPEG", "", 8, 92).unwrap(),
            AerialFormat::Jpeg
        );
    }

    #[test]
    fn upsampling_keeps_pixel_centres_and_averages() {
        let mut img = RgbImage::filled(2, 1, [0.0, 0.0, 0.0]);
        img.set(1, 0, [1.0, 0.5, 0.25]);
        let mut rows = Vec::new();
        upsampled_rows(&img, 4, |_, line| {
            rows.push(line.to_vec());
            Ok(())
        })
        .unwrap();
        assert_eq!(rows.len(), 4);
        let r = &rows[0];
        assert_eq!(r.len(), 8 * 3);
        // Output pixels 0, 1 lie left of source pixel 0's centre (clamped), 6, 7 right of pixel 1's.
        assert_eq!(r[0], 0.0);
        assert_eq!(r[7 * 3], 1.0);
        // Output pixel 4 (centre 4.5 → source 1.125, 0.625 past pixel 0's centre).
        assert!((r[4 * 3] - 0.625).abs() < 1e-6);
    }
}
