//! Known-answer tests of `imaging::probe`: real JPEG, PNG and TIFF files written by the `image` crate are
//! recognised by content with their size, channels and bit depth; every truncation of them is found without
//! decoding; damaged bytes and absurd headers are named; and nothing panics.

use skytie_stages::imaging::probe::{probe, probe_bytes, ImageFormat, Layout, ProbeError};
use std::io::Cursor;

fn texture(w: u32, h: u32) -> image::RgbImage {
    image::RgbImage::from_fn(w, h, |x, y| {
        image::Rgb([(x * 7 + y * 3) as u8, (x ^ y) as u8, ((x * y) % 251) as u8])
    })
}

fn encode(img: image::DynamicImage, format: image::ImageFormat) -> Vec<u8> {
    let mut out = Cursor::new(Vec::new());
    img.write_to(&mut out, format).unwrap();
    out.into_inner()
}

fn jpeg(w: u32, h: u32) -> Vec<u8> {
    encode(
        image::DynamicImage::ImageRgb8(texture(w, h)),
        image::ImageFormat::Jpeg,
    )
}

fn png(w: u32, h: u32) -> Vec<u8> {
    encode(
        image::DynamicImage::ImageRgb8(texture(w, h)),
        image::ImageFormat::Png,
    )
}

fn tiff16(w: u32, h: u32) -> Vec<u8> {
    let img = image::ImageBuffer::<image::Luma<u16>, _>::from_fn(w, h, |x, y| {
        image::Luma([(x * 300 + y) as u16])
    });
    encode(
        image::DynamicImage::ImageLuma16(img),
        image::ImageFormat::Tiff,
    )
}

#[test]
fn headers_are_read_by_content() {
    let h = probe_bytes(&jpeg(70, 35)).unwrap();
    assert_eq!(
        (h.format, h.width, h.height, h.channels, h.bit_depth),
        (ImageFormat::Jpeg, 70, 35, 3, 8)
    );
    let h = probe_bytes(&png(33, 17)).unwrap();
    assert_eq!(
        (h.format, h.width, h.height, h.channels, h.bit_depth),
        (ImageFormat::Png, 33, 17, 3, 8)
    );
    let h = probe_bytes(&tiff16(40, 30)).unwrap();
    assert_eq!(
        (h.format, h.width, h.height, h.channels, h.bit_depth),
        (ImageFormat::Tiff, 40, 30, 1, 16)
    );
    assert!(matches!(h.layout, Layout::Strips { .. }), "{:?}", h.layout);
    // A PNG named .jpg is what it is.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("pano.jpg");
    std::fs::write(&p, png(8, 4)).unwrap();
    let h = probe(&p).unwrap();
    assert_eq!(h.format, ImageFormat::Png);
    assert!(!h.format.matches_extension(&p));
}

#[test]
fn every_truncation_is_found() {
    for (name, bytes) in [
        ("jpeg", jpeg(64, 32)),
        ("png", png(64, 32)),
        ("tiff", tiff16(64, 32)),
    ] {
        assert!(probe_bytes(&bytes).is_ok(), "{name}");
        for cut in 0..bytes.len() {
            let r = probe_bytes(&bytes[..cut]);
            assert!(
                r.is_err(),
                "{name} cut to {cut} of {} bytes passed",
                bytes.len()
            );
        }
    }
    let bytes = jpeg(200, 100);
    let e = probe_bytes(&bytes[..bytes.len() / 10]).unwrap_err();
    assert!(
        matches!(
            e,
            ProbeError::Truncated {
                format: ImageFormat::Jpeg,
                ..
            }
        ),
        "{e:?}"
    );
    assert!(
        e.to_string().starts_with("is a truncated JPEG file ("),
        "{e}"
    );
    let bytes = png(200, 100);
    let e = probe_bytes(&bytes[..bytes.len() / 2]).unwrap_err();
    assert!(e.to_string().starts_with("is a truncated PNG file"), "{e}");
}

#[test]
fn flipped_png_bytes_fail_the_crc() {
    let mut bytes = png(64, 32);
    let n = bytes.len();
    bytes[n / 2] ^= 0x10;
    let e = probe_bytes(&bytes).unwrap_err();
    assert!(e.to_string().contains("fails its CRC check"), "{e}");
}

#[test]
fn absurd_dimensions_are_rejected_from_the_header() {
    // A PNG whose IHDR claims 100000 × 100000 px in a file of well under 1 KB (valid CRC).
    let mut bytes = png(4, 4);
    bytes[16..20].copy_from_slice(&100_000u32.to_be_bytes());
    bytes[20..24].copy_from_slice(&100_000u32.to_be_bytes());
    let crc = crc(&bytes[12..29]);
    bytes[29..33].copy_from_slice(&crc.to_be_bytes());
    let e = probe_bytes(&bytes).unwrap_err();
    assert!(
        matches!(
            e,
            ProbeError::AbsurdSize {
                width: 100_000,
                height: 100_000,
                ..
            }
        ),
        "{e:?}"
    );
    assert!(e.to_string().contains("100000×100000 px"), "{e}");
    // The same for a JPEG frame header (65000 × 65000).
    let mut bytes = jpeg(16, 16);
    let sof = bytes.windows(2).position(|w| w == [0xFF, 0xC0]).unwrap();
    bytes[sof + 5..sof + 9].copy_from_slice(&[0xFD, 0xE8, 0xFD, 0xE8]);
    assert!(matches!(
        probe_bytes(&bytes),
        Err(ProbeError::AbsurdSize { .. })
    ));
}

fn crc(bytes: &[u8]) -> u32 {
    let mut h = crc32fast::Hasher::new();
    h.update(bytes);
    h.finalize()
}

#[test]
fn tiff_pieces_past_the_end_are_truncation() {
    let bytes = tiff16(64, 64);
    // The image crate writes the directory after the strips: cutting off the tail loses the directory.
    let e = probe_bytes(&bytes[..bytes.len() - 20]).unwrap_err();
    assert!(matches!(e, ProbeError::Truncated { .. }), "{e:?}");
}

#[test]
fn garbage_never_panics() {
    let mut state = 0x1234_5678_9abc_def0u64;
    let seeds = [jpeg(16, 8), png(16, 8), tiff16(16, 8)];
    for round in 0..3000 {
        let mut bytes = seeds[round % 3].clone();
        for _ in 0..4 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let i = (state as usize) % bytes.len();
            bytes[i] = (state >> 32) as u8;
        }
        let _ = probe_bytes(&bytes);
    }
}
