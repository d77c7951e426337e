//! Reading and writing image files (JPEG, PNG, TIFF via the `image` crate) as [`GrayImage`]/[`RgbImage`].
//!
//! 8-bit files map to 0..1 (value / 255); 16-bit files to 0..1 (value / 65535). Writing clamps to 0..1 and
//! rounds to 8 bits. Writes are atomic (see [`crate::fsutil`]).

use super::huge_pages::collect_f32;
use super::{GrayImage, RgbImage};
use std::path::Path;

/// An image file that could not be read or written; the message names the file and what to do.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {message}")]
pub struct ImageIoError {
    pub path: String,
    pub message: String,
}

fn err(path: &Path, message: impl Into<String>) -> ImageIoError {
    ImageIoError {
        path: path.display().to_string(),
        message: message.into(),
    }
}

/// Decode `path` by its content after [`probe`](super::probe::probe) found it complete: a truncated file (which
/// the decoders would fill with grey) or an absurd header is an error before anything is allocated.
fn open(path: &Path) -> Result<image::DynamicImage, ImageIoError> {
    super::probe::probe(path).map_err(|e| err(path, format!("{e}; {}", e.hint())))?;
    let reader = image::ImageReader::open(path)
        .map_err(|e| {
            err(
                path,
                format!("cannot open ({e}); check that the file exists and is readable"),
            )
        })?
        .with_guessed_format()
        .map_err(|e| err(path, format!("cannot read ({e})")))?;
    reader.decode().map_err(|e| {
        err(
            path,
            format!("does not decode as an image ({e}); is it truncated or not JPEG/PNG/TIFF?"),
        )
    })
}

/// Load any supported image as a single-channel image (luminance for colour files).
pub fn load_gray(path: &Path) -> Result<GrayImage, ImageIoError> {
    let img = open(path)?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    Ok(GrayImage {
        width: w,
        height: h,
        data: grey_values(img),
    })
}

/// The image crate's u8 → f32 channel conversion (`to_rgb32f`) of every byte value, for 8-bit RGB and grey
/// images, read off the crate itself so that a table lookup gives exactly its values.
fn unit_tables() -> &'static ([f32; 256], [f32; 256]) {
    static TABLES: std::sync::OnceLock<([f32; 256], [f32; 256])> = std::sync::OnceLock::new();
    TABLES.get_or_init(|| {
        let bytes: Vec<u8> = (0..=255u8).collect();
        let rgb: Vec<u8> = bytes.iter().flat_map(|&v| [v, v, v]).collect();
        let first_channel = |img: image::DynamicImage| -> [f32; 256] {
            let f = img.to_rgb32f().into_raw();
            std::array::from_fn(|v| f[3 * v])
        };
        (
            first_channel(image::DynamicImage::ImageRgb8(
                image::RgbImage::from_raw(256, 1, rgb).expect("256 × 1 RGB"),
            )),
            first_channel(image::DynamicImage::ImageLuma8(
                image::GrayImage::from_raw(256, 1, bytes).expect("256 × 1 grey"),
            )),
        )
    })
}

/// Luminance `0.2126 R + 0.7152 G + 0.0722 B` of 0..1 channels (16-bit grey: value / 65535). 8-bit grey and RGB
/// are converted straight from their bytes by [`unit_tables`], so the values are exactly those of
/// `to_rgb32f()`, without its 3 × 4-byte-per-pixel intermediate (a 4800 × 2400 panorama: 138 MB and 0.1 s of
/// the 0.2 s `load_gray` took).
fn grey_values(img: image::DynamicImage) -> Vec<f32> {
    let n = img.width() as usize * img.height() as usize;
    let (unit_rgb, unit_grey) = unit_tables();
    let luminance = |r: f32, g: f32, b: f32| 0.2126 * r + 0.7152 * g + 0.0722 * b;
    match img {
        image::DynamicImage::ImageLuma16(b) => {
            collect_f32(n, b.into_raw().into_iter().map(|v| v as f32 / 65535.0))
        }
        image::DynamicImage::ImageLuma8(b) => collect_f32(
            n,
            b.as_raw().iter().map(|&v| {
                let x = unit_grey[v as usize];
                luminance(x, x, x)
            }),
        ),
        image::DynamicImage::ImageRgb8(b) => collect_f32(
            n,
            b.as_raw().chunks_exact(3).map(|p| {
                let c = |k: usize| unit_rgb[p[k] as usize];
                luminance(c(0), c(1), c(2))
            }),
        ),
        other => {
            let rgb = other.to_rgb32f().into_raw();
            collect_f32(n, rgb.chunks_exact(3).map(|p| luminance(p[0], p[1], p[2])))
        }
    }
}

/// Load any supported image as RGB.
pub fn load_rgb(path: &Path) -> Result<RgbImage, ImageIoError> {
    let img = open(path)?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    Ok(RgbImage {
        width: w,
        height: h,
        data: img.to_rgb32f().into_raw(),
    })
}

/// Only the dimensions (width, height) of an image file, without decoding the pixels.
pub fn dimensions(path: &Path) -> Result<(u32, u32), ImageIoError> {
    image::image_dimensions(path).map_err(|e| err(path, format!("cannot read image header ({e})")))
}

#[inline]
fn to_u8(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

fn format_for(path: &Path) -> Result<image::ImageFormat, ImageIoError> {
    image::ImageFormat::from_path(path)
        .map_err(|_| err(path, "unknown image extension; use .png, .jpg or .tif"))
}

fn save_dynamic(
    path: &Path,
    img: image::DynamicImage,
    jpeg_quality: u8,
) -> Result<(), ImageIoError> {
    let format = format_for(path)?;
    crate::fsutil::atomic_write_with(path, |w| {
        let res = if format == image::ImageFormat::Jpeg {
            let enc = image::codecs::jpeg::JpegEncoder::new_with_quality(w, jpeg_quality);
            img.write_with_encoder(enc)
        } else {
            let mut buf = std::io::Cursor::new(Vec::new());
            img.write_to(&mut buf, format).map(|_| {
                use std::io::Write;
                let _ = w.write_all(buf.get_ref());
            })
        };
        res.map_err(std::io::Error::other)
    })
    .map_err(|e| err(path, format!("cannot write ({e})")))
}

/// Save as 8-bit RGB (format from the extension; JPEG at `jpeg_quality`).
pub fn save_rgb(path: &Path, img: &RgbImage, jpeg_quality: u8) -> Result<(), ImageIoError> {
    let raw: Vec<u8> = img.data.iter().map(|&v| to_u8(v)).collect();
    let buf =
        image::RgbImage::from_raw(img.width as u32, img.height as u32, raw).ok_or_else(|| {
            err(
                path,
                "internal: RGB buffer size does not match its dimensions",
            )
        })?;
    save_dynamic(path, image::DynamicImage::ImageRgb8(buf), jpeg_quality)
}

/// Save as 8-bit grey (format from the extension; JPEG at quality 95).
pub fn save_gray(path: &Path, img: &GrayImage) -> Result<(), ImageIoError> {
    let raw: Vec<u8> = img.data.iter().map(|&v| to_u8(v)).collect();
    let buf =
        image::GrayImage::from_raw(img.width as u32, img.height as u32, raw).ok_or_else(|| {
            err(
                path,
                "internal: grey buffer size does not match its dimensions",
            )
        })?;
    save_dynamic(path, image::DynamicImage::ImageLuma8(buf), 95)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grey_from_bytes_equals_the_image_crate_float_conversion() {
        // Every byte value in every channel position, for RGB and grey 8-bit images.
        let (w, h) = (256, 3);
        let rgb: Vec<u8> = (0..w * h * 3)
            .map(|i| ((i * 7 + i / 3) % 256) as u8)
            .collect();
        let grey: Vec<u8> = (0..w * h).map(|i| (i % 256) as u8).collect();
        let images = [
            image::DynamicImage::ImageRgb8(
                image::RgbImage::from_raw(w as u32, h as u32, rgb).unwrap(),
            ),
            image::DynamicImage::ImageLuma8(
                image::GrayImage::from_raw(w as u32, h as u32, grey).unwrap(),
            ),
        ];
        for img in images {
            let reference: Vec<f32> = img
                .to_rgb32f()
                .into_raw()
                .chunks_exact(3)
                .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
                .collect();
            let got = grey_values(img);
            assert_eq!(got.len(), reference.len());
            for (a, b) in got.iter().zip(&reference) {
                assert_eq!(a.to_bits(), b.to_bits());
            }
        }
    }

    #[test]
    fn png_round_trip_is_exact_at_8_bits() {
        let dir = tempfile::tempdir().unwrap();
        let mut img = RgbImage::filled(4, 3, [0.0, 0.5, 1.0]);
        img.set(1, 2, [1.0, 0.0, 0.2]);
        let p = dir.path().join("a.png");
        save_rgb(&p, &img, 95).unwrap();
        let back = load_rgb(&p).unwrap();
        assert_eq!((back.width, back.height), (4, 3));
        for (a, b) in img.data.iter().zip(&back.data) {
            assert!((a - b).abs() <= 0.5 / 255.0 + 1e-6);
        }
        assert_eq!(dimensions(&p).unwrap(), (4, 3));
    }

    #[test]
    fn truncated_file_is_an_error_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.jpg");
        save_rgb(&p, &RgbImage::filled(64, 64, [0.3, 0.4, 0.5]), 90).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        std::fs::write(&p, &bytes[..bytes.len() / 3]).unwrap();
        let e = load_gray(&p).unwrap_err();
        assert!(e.to_string().contains("t.jpg"), "{e}");
    }
}
