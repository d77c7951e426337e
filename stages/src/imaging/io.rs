//! Reading whole image files as [`GrayImage`] (through [`super::decode`], the decoders of the pipeline's
//! pyramids: JPEG luma, 8-bit files / 255, 16-bit files / their white level) or [`RgbImage`] (the `image`
//! crate, for the tools), and writing them. Writing clamps to 0..1 and rounds to 8 bits. Writes are atomic
//! (see [`crate::fsutil`]). Reading a whole image reserves its buffer from the memory budget
//! ([`super::budget`]); the pipeline reads windows of pyramids instead ([`super::pyramid`]).

use super::decode::collect::GreyCollector;
use super::decode::limits::reserve;
use super::{GrayImage, RgbImage};
use std::path::Path;

pub use super::io_error::ImageIoError;

fn err(path: &Path, message: impl Into<String>) -> ImageIoError {
    ImageIoError::new(path, message)
}

/// Decodes `path` with the `image` crate after [`probe`](super::probe::probe) found it complete (a truncated
/// file, which the decoders would fill with grey, or an absurd header is an error before anything is
/// allocated), its allocation limit replaced by the memory budget (the crate's default of 512 MiB refuses
/// valid large frames).
fn open(path: &Path) -> Result<image::DynamicImage, ImageIoError> {
    let header = super::probe::probe(path).map_err(|e| err(path, format!("{e}; {}", e.hint())))?;
    let (w, h) = (header.width as usize, header.height as usize);
    // The decoded RGB(A) image at up to 16 bits, and its 32-bit float RGB copy.
    let _reservation = reserve(
        path,
        header.format.name(),
        w,
        h,
        w * h * (8 + 12),
        "its decoded colour image",
    )?;
    let mut reader = image::ImageReader::open(path)
        .map_err(|e| {
            err(
                path,
                format!("cannot open ({e}); check that the file exists and is readable"),
            )
        })?
        .with_guessed_format()
        .map_err(|e| err(path, format!("cannot read ({e})")))?;
    reader.no_limits();
    reader.decode().map_err(|e| {
        err(
            path,
            format!("does not decode as an image ({e}); is it truncated or not JPEG/PNG/TIFF?"),
        )
    })
}

/// Load any supported image as a single-channel image: the grey of [`super::decode`] (JPEG/JFIF luma for
/// colour files), 8-bit samples / 255, 16-bit samples / the image's white level.
pub fn load_gray(path: &Path) -> Result<GrayImage, ImageIoError> {
    let mut collector = GreyCollector::new(path);
    super::decode::decode_grey(path, &mut collector)?;
    Ok(collector.finish())
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
    let buf = quantised(path, img.width, img.height, &img.data, "RGB")?;
    save_dynamic(path, image::DynamicImage::ImageRgb8(buf), jpeg_quality)
}

/// Save as 8-bit grey (format from the extension; JPEG at quality 95).
pub fn save_gray(path: &Path, img: &GrayImage) -> Result<(), ImageIoError> {
    let buf = quantised(path, img.width, img.height, &img.data, "grey")?;
    save_dynamic(path, image::DynamicImage::ImageLuma8(buf), 95)
}

/// `data` (row-major samples of a `width × height` image of pixel type `P`) quantised to 8 bits for writing
/// to `path`; `what` names the pixel type in the error.
fn quantised<P: image::Pixel<Subpixel = u8>>(
    path: &Path,
    width: usize,
    height: usize,
    data: &[f32],
    what: &str,
) -> Result<image::ImageBuffer<P, Vec<u8>>, ImageIoError> {
    let raw: Vec<u8> = data.iter().map(|&v| to_u8(v)).collect();
    image::ImageBuffer::from_raw(width as u32, height as u32, raw).ok_or_else(|| {
        err(
            path,
            format!("internal: {what} buffer size does not match its dimensions"),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

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
