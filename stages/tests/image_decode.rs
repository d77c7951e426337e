//! Known-answer tests of the bounded-memory decoders and the tiled TIFF writer: every format and layout is
//! written from known pixels (by the `image`/`tiff` crates or by skytie's writer, cross-checked with the
//! `image` crate's reader) and must decode to the expected grey; bad files fail with their name.

use skytie_stages::imaging::decode::grey::{luma16, luma8};
use skytie_stages::imaging::decode::{decode_grey, probe_file, GreyInfo, GreyRowSink, ImageFormat};
use skytie_stages::imaging::ingest::ingest_with_tiles;
use skytie_stages::imaging::io::load_gray;
use skytie_stages::imaging::pyramid::{read_window, PixelRect, SampleDepth, TiledPyramid};
use skytie_stages::imaging::tiff_write::{TiffCompression, TiledTiffSpec, TiledTiffWriter};
use std::path::Path;

const W: usize = 300;
const H: usize = 170;

fn rgb8(c: usize, r: usize) -> [u8; 3] {
    [
        ((c * 3 + r) % 256) as u8,
        ((c + 5 * r) % 256) as u8,
        ((c * r / 7) % 256) as u8,
    ]
}

fn rgb16(c: usize, r: usize) -> [u16; 3] {
    [
        ((c * 211 + r * 17) % 4096) as u16,
        ((c * 13 + r * 251) % 4096) as u16,
        ((c * r) % 4096) as u16,
    ]
}

fn write_tiled(
    path: &Path,
    channels: usize,
    bytes: usize,
    compression: TiffCompression,
    big: bool,
) {
    let spec = TiledTiffSpec {
        width: W,
        height: H,
        channels,
        bytes_per_sample: bytes,
        tile_side: 64,
        compression,
        big,
    };
    let mut w = TiledTiffWriter::create(path, spec).unwrap();
    for r in 0..H {
        if bytes == 1 {
            w.push_row_u8(&test_row(r, channels, rgb8)).unwrap();
        } else {
            w.push_row_u16(&test_row(r, channels, rgb16)).unwrap();
        }
    }
    w.finish().unwrap();
}

/// The grey the decoders must produce, as 0..1 (16-bit: white 4095, the smallest 2^k − 1 above the data).
fn expected(c: usize, r: usize, channels: usize, bytes: usize) -> f32 {
    match (channels, bytes) {
        (1, 1) => f32::from(rgb8(c, r)[0]) / 255.0,
        (3, 1) => {
            let p = rgb8(c, r);
            f32::from(luma8(p[0], p[1], p[2])) / 255.0
        }
        (1, _) => f32::from(rgb16(c, r)[0]) / 4095.0,
        _ => {
            let p = rgb16(c, r);
            f32::from(luma16(p[0], p[1], p[2])) / 4095.0
        }
    }
}

/// Row `r` of the test pattern `rgb`: its RGB samples, or only their first channel for a grey image.
fn test_row<T: Copy>(r: usize, channels: usize, rgb: impl Fn(usize, usize) -> [T; 3]) -> Vec<T> {
    (0..W)
        .flat_map(|c| {
            let p = rgb(c, r);
            p[..if channels == 3 { 3 } else { 1 }].to_vec()
        })
        .collect()
}

#[test]
fn tiled_tiffs_of_every_compression_depth_and_kind_decode_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (1, 1, TiffCompression::None, false),
        (3, 1, TiffCompression::Lzw, false),
        (3, 1, TiffCompression::Deflate, true),
        (1, 2, TiffCompression::Deflate, false),
        (3, 2, TiffCompression::Lzw, true),
        (3, 2, TiffCompression::None, false),
    ];
    for (i, &(channels, bytes, compression, big)) in cases.iter().enumerate() {
        let path = dir.path().join(format!("t{i}.tif"));
        write_tiled(&path, channels, bytes, compression, big);
        let format = probe_file(&path).unwrap().format;
        assert_eq!(
            format,
            if big {
                ImageFormat::BigTiff
            } else {
                ImageFormat::Tiff
            }
        );
        let img = load_gray(&path).unwrap();
        assert_eq!((img.width, img.height), (W, H));
        for r in 0..H {
            for c in 0..W {
                let e = expected(c, r, channels, bytes);
                assert!(
                    (img.get(c, r) - e).abs() < 1e-6,
                    "case {i} ({c}, {r}): {} vs {e}",
                    img.get(c, r)
                );
            }
        }
        // An independent reader agrees on the raw samples (the writer is valid TIFF). Not for LZW: the `image`
        // crate's TIFF reader fails on LZW tiles narrower than the tile width, which `imaging::decode` reads itself.
        if !big && compression != TiffCompression::Lzw {
            let other = image::open(&path).unwrap();
            assert_eq!((other.width() as usize, other.height() as usize), (W, H));
            if bytes == 1 && channels == 3 {
                let rgb = other.to_rgb8();
                assert_eq!(rgb.get_pixel(123, 77).0, rgb8(123, 77));
            }
        }
    }
}

#[test]
fn jpeg_compressed_tiled_tiff_keeps_its_luma() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("j.tif");
    write_tiled(&path, 3, 1, TiffCompression::Jpeg(95), false);
    let img = load_gray(&path).unwrap();
    let mut worst = 0.0f32;
    for r in 0..H {
        for c in 0..W {
            worst = worst.max((img.get(c, r) - expected(c, r, 3, 1)).abs());
        }
    }
    // JPEG is lossy: the pattern has sharp steps, quality 95 keeps them within a few grey levels.
    assert!(worst < 24.0 / 255.0, "worst error {worst}");
}

/// Keeps every 8-bit row a decoder delivers.
#[derive(Default)]
struct Rows8(Vec<u8>);

impl GreyRowSink for Rows8 {
    fn begin(&mut self, _: &GreyInfo) -> std::io::Result<()> {
        Ok(())
    }
    fn row_u8(&mut self, row: &[u8]) -> std::io::Result<()> {
        self.0.extend_from_slice(row);
        Ok(())
    }
    fn row_u16(&mut self, _: &[u16]) -> std::io::Result<()> {
        Err(std::io::Error::other("16-bit rows from an 8-bit image"))
    }
}

/// The grey of the `tiff` crate's own decode of every tile (all components, the first one taken), as skytie
/// read JPEG-compressed TIFFs before it decoded their luma plane alone.
fn tiff_crate_grey(path: &Path) -> Vec<u8> {
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let mut dec = tiff::decoder::Decoder::new(file).unwrap();
    let (w, h) = dec.dimensions().unwrap();
    let (w, h) = (w as usize, h as usize);
    let n = match dec.colortype().unwrap() {
        tiff::ColorType::Gray(8) => 1,
        _ => 3,
    };
    let mut grey = vec![0u8; w * h];
    let across = w.div_ceil(64);
    for t in 0..across * h.div_ceil(64) {
        let (dw, dh) = dec.chunk_data_dimensions(t as u32);
        let tiff::decoder::DecodingResult::U8(v) = dec.read_chunk(t as u32).unwrap() else {
            panic!("8-bit samples expected");
        };
        let (x0, y0) = ((t % across) * 64, (t / across) * 64);
        for r in 0..dh as usize {
            for c in 0..dw as usize {
                grey[(y0 + r) * w + x0 + c] = v[(r * dw as usize + c) * n];
            }
        }
    }
    grey
}

#[test]
fn jpeg_tiff_tiles_decode_to_the_luma_the_tiff_crate_decodes() {
    let dir = tempfile::tempdir().unwrap();
    for channels in [3, 1] {
        let path = dir.path().join(format!("j{channels}.tif"));
        write_tiled(&path, channels, 1, TiffCompression::Jpeg(90), false);
        let mut rows = Rows8::default();
        decode_grey(&path, &mut rows).unwrap();
        assert_eq!(rows.0.len(), W * H);
        assert!(
            rows.0 == tiff_crate_grey(&path),
            "{channels} channels: the luma-only decode differs from the tiff crate's"
        );
    }
}

#[test]
fn jpeg_png_and_striped_tiff_from_the_image_crate() {
    let dir = tempfile::tempdir().unwrap();
    let rgb = image::RgbImage::from_fn(W as u32, H as u32, |c, r| {
        image::Rgb(rgb8(c as usize, r as usize))
    });
    for name in ["a.png", "a.tif"] {
        let p = dir.path().join(name);
        rgb.save(&p).unwrap();
        let img = load_gray(&p).unwrap();
        for (c, r) in [(0, 0), (299, 169), (150, 80)] {
            assert_eq!(img.get(c, r), expected(c, r, 3, 1), "{name} ({c}, {r})");
        }
    }
    let grey16 =
        image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_fn(W as u32, H as u32, |c, r| {
            image::Luma([rgb16(c as usize, r as usize)[0]])
        });
    let p = dir.path().join("g16.png");
    grey16.save(&p).unwrap();
    let img = load_gray(&p).unwrap();
    assert_eq!(img.get(17, 9), expected(17, 9, 1, 2));
    // JPEG: the decoder's Y plane equals the luma of the image crate's RGB decode within rounding.
    let smooth = image::RgbImage::from_fn(W as u32, H as u32, |c, r| {
        image::Rgb([(c / 2) as u8, (r + 40) as u8, ((c + r) / 3) as u8])
    });
    let p = dir.path().join("a.jpg");
    smooth.save(&p).unwrap();
    let grey = load_gray(&p).unwrap();
    let decoded = image::open(&p).unwrap().to_rgb8();
    for (c, r) in [(5, 5), (100, 60), (290, 160)] {
        let q = decoded.get_pixel(c, r).0;
        let y = f32::from(luma8(q[0], q[1], q[2])) / 255.0;
        assert!(
            (grey.get(c as usize, r as usize) - y).abs() <= 2.0 / 255.0,
            "({c}, {r})"
        );
    }
}

#[test]
fn sixteen_bit_lzw_strips_and_bigtiff_from_the_tiff_crate() {
    use tiff::encoder::{colortype, TiffEncoder};
    let dir = tempfile::tempdir().unwrap();
    let data: Vec<u16> = (0..W * H).map(|i| rgb16(i % W, i / W)[0] * 16).collect();
    let p = dir.path().join("s.tif");
    let mut enc = TiffEncoder::new(std::fs::File::create(&p).unwrap())
        .unwrap()
        .with_compression(tiff::encoder::Compression::Lzw);
    enc.write_image::<colortype::Gray16>(W as u32, H as u32, &data)
        .unwrap();
    let img = load_gray(&p).unwrap();
    // Largest value 4095 · 16 = 65520: white 65535.
    assert_eq!(img.get(10, 20), f32::from(data[20 * W + 10]) / 65535.0);
    let p = dir.path().join("b.tif");
    let mut enc = TiffEncoder::new_big(std::fs::File::create(&p).unwrap()).unwrap();
    enc.write_image::<colortype::Gray16>(W as u32, H as u32, &data)
        .unwrap();
    assert_eq!(probe_file(&p).unwrap().format, ImageFormat::BigTiff);
    assert_eq!(
        load_gray(&p).unwrap().get(299, 169),
        f32::from(data[169 * W + 299]) / 65535.0
    );
}

#[test]
fn geotiff_tags_are_kept() {
    use tiff::encoder::{colortype, TiffEncoder};
    use tiff::tags::Tag;
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("geo.tif");
    let mut enc = TiffEncoder::new(std::fs::File::create(&p).unwrap()).unwrap();
    let mut image = enc.new_image::<colortype::Gray8>(64, 32).unwrap();
    image
        .encoder()
        .write_tag(Tag::ModelPixelScaleTag, &[0.1f64, 0.1, 0.0][..])
        .unwrap();
    image
        .encoder()
        .write_tag(
            Tag::ModelTiepointTag,
            &[0.0f64, 0.0, 0.0, 155000.0, 463000.0, 0.0][..],
        )
        .unwrap();
    image
        .encoder()
        .write_tag(
            Tag::GeoKeyDirectoryTag,
            &[1u16, 1, 0, 1, 3072, 0, 1, 28992][..],
        )
        .unwrap();
    image.write_data(&vec![7u8; 64 * 32]).unwrap();
    let mut sink = skytie_stages::imaging::decode::collect::GreyCollector::new(&p);
    let info = decode_grey(&p, &mut sink).unwrap();
    let geo = info.geotiff.expect("GeoTIFF tags");
    assert_eq!(geo.model_pixel_scale, Some(vec![0.1, 0.1, 0.0]));
    assert_eq!(geo.model_tiepoints.unwrap()[3], 155000.0);
    assert_eq!(geo.geo_key_directory.unwrap()[7], 28992);
}

#[test]
fn truncated_and_absurd_files_fail_with_their_name() {
    let dir = tempfile::tempdir().unwrap();
    let rgb = image::RgbImage::from_fn(256, 256, |c, r| image::Rgb(rgb8(c as usize, r as usize)));
    let jpg = dir.path().join("cut.jpg");
    rgb.save(&jpg).unwrap();
    let bytes = std::fs::read(&jpg).unwrap();
    std::fs::write(&jpg, &bytes[..bytes.len() / 2]).unwrap();
    let e = load_gray(&jpg).unwrap_err().to_string();
    assert!(e.contains("cut.jpg") && e.contains("truncated"), "{e}");
    // A tiled TIFF cut in the middle of its tiles.
    let tif = dir.path().join("cut.tif");
    write_tiled(&tif, 3, 1, TiffCompression::Deflate, false);
    let bytes = std::fs::read(&tif).unwrap();
    std::fs::write(&tif, &bytes[..bytes.len() / 2]).unwrap();
    let e = load_gray(&tif).unwrap_err().to_string();
    assert!(e.contains("cut.tif"), "{e}");
    // A PNG header claiming 100000 × 100000 px in a few hundred bytes: refused before decoding.
    let png = dir.path().join("huge.png");
    image::GrayImage::new(8, 8).save(&png).unwrap();
    let mut b = std::fs::read(&png).unwrap();
    b[16..20].copy_from_slice(&100_000u32.to_be_bytes());
    b[20..24].copy_from_slice(&100_000u32.to_be_bytes());
    let crc = crc32(&b[12..29]);
    b[29..33].copy_from_slice(&crc.to_be_bytes());
    std::fs::write(&png, &b).unwrap();
    let e = load_gray(&png).unwrap_err().to_string();
    assert!(e.contains("huge.png") && e.contains("100000×100000"), "{e}");
    // A JPEG whose frame header claims 60000 × 60000 px.
    let big = dir.path().join("huge.jpg");
    image::GrayImage::new(16, 16).save(&big).unwrap();
    let mut b = std::fs::read(&big).unwrap();
    let sof = b.windows(2).position(|w| w == [0xFF, 0xC0]).unwrap();
    b[sof + 5..sof + 7].copy_from_slice(&60_000u16.to_be_bytes());
    b[sof + 7..sof + 9].copy_from_slice(&60_000u16.to_be_bytes());
    std::fs::write(&big, &b).unwrap();
    let e = load_gray(&big).unwrap_err().to_string();
    assert!(e.contains("huge.jpg") && e.contains("60000×60000"), "{e}");
    // Not an image at all.
    let txt = dir.path().join("notes.jpg");
    std::fs::write(&txt, b"hello").unwrap();
    let e = load_gray(&txt).unwrap_err().to_string();
    assert!(
        e.contains("notes.jpg") && e.contains("not a JPEG, PNG or TIFF"),
        "{e}"
    );
}

#[test]
fn ingestion_gives_the_same_grey_as_a_whole_decode() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("src.tif");
    write_tiled(&src, 3, 2, TiffCompression::Deflate, false);
    let whole = load_gray(&src).unwrap();
    let ing = ingest_with_tiles(&src, &dir.path().join("p.pyr"), 64).unwrap();
    assert_eq!(ing.pyramid.layout.depth, SampleDepth::U16);
    assert_eq!(ing.pyramid.white, 4095);
    let p = TiledPyramid::open(&dir.path().join("p.pyr"), &ing.pyramid.index_hash).unwrap();
    let win = read_window(&p, 0, PixelRect::new(0, 0, W, H)).unwrap();
    assert_eq!(win.data, whole.data);
}

/// CRC-32 (ISO 3309, as PNG chunks use).
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 == 1 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}
