//! One-time ingestion of an image file into its tiled pyramid (`imaging::ingest`) against a plain decode of
//! the same file in the same process: the `image` crate's decoder (what a program that "just opens the image"
//! does, no allocation limit); for JPEG files, zune-jpeg decoding the luma plane only (the least work any
//! JPEG reader can do for a grey image); for TIFF files, the `tiff` crate decoding every strip or tile (what
//! the `image` crate does underneath, and the only plain decode of a JPEG-compressed YCbCr TIFF, which the
//! `image` crate refuses) and, for JPEG-compressed TIFFs, zune-jpeg decoding the luma plane of every tile
//! (the least work for a grey image). The plain decodes hold one strip or tile at a time, like ingestion.
//! Plain `fn main`, no harness.
//!
//! Run: `cargo bench -p skytie-stages --bench ingest_decode -- FILE...` (or `SKYTIE_INGEST_FILES` with the
//! paths separated by `:`). Each file is timed `SKYTIE_INGEST_REPS` times (default 1) in alternating order
//! (decode, ingest, decode, …) and the minimum wall time of each is kept; `benches/realsize.sh` runs it on
//! one frame of each kind of the real-size preset. Prints one row per file and decoder:
//! `file  pixels  decoder  decode_s  ingest_s  ingest/decode`.

#[path = "peer_support/mod.rs"]
mod peer_support;

use peer_support::timed;
use skytie_stages::imaging::ingest::ingest;
use std::path::{Path, PathBuf};

/// The `image` crate's decode of `path` with no allocation limit; returns the pixel count.
fn decode_image_crate(path: &Path) -> Result<u64, String> {
    let mut reader = image::ImageReader::open(path)
        .map_err(|e| e.to_string())?
        .with_guessed_format()
        .map_err(|e| e.to_string())?;
    reader.no_limits();
    let img = reader.decode().map_err(|e| e.to_string())?;
    Ok(u64::from(img.width()) * u64::from(img.height()))
}

/// zune-jpeg's decode of `path` to its luma plane; `None` when the file is not a JPEG.
fn decode_zune_luma(path: &Path) -> Option<Result<u64, String>> {
    let bytes = std::fs::read(path).ok()?;
    if !bytes.starts_with(&[0xFF, 0xD8]) {
        return None;
    }
    Some(
        zune_luma(&bytes)
            .map(|plane| plane.len() as u64)
            .map_err(|e| e.to_string()),
    )
}

/// zune-jpeg's decode of the JPEG stream `bytes` to its luma plane.
fn zune_luma(bytes: &[u8]) -> Result<Vec<u8>, zune_jpeg::errors::DecodeErrors> {
    let options = zune_jpeg::zune_core::options::DecoderOptions::default()
        .jpeg_set_out_colorspace(zune_jpeg::zune_core::colorspace::ColorSpace::Luma)
        .set_max_width(1 << 20)
        .set_max_height(1 << 20);
    zune_jpeg::JpegDecoder::new_with_options(
        zune_jpeg::zune_core::bytestream::ZCursor::new(bytes),
        options,
    )
    .decode()
}

/// The `tiff` crate's decode of every strip or tile of the first image of `path`, one at a time; returns the
/// pixel count. `None` when the file is not a TIFF.
fn decode_tiff_chunks(path: &Path) -> Option<Result<u64, String>> {
    let file = std::fs::File::open(path).ok()?;
    let mut dec = tiff::decoder::Decoder::new(std::io::BufReader::new(file))
        .ok()?
        .with_limits(tiff::decoder::Limits::unlimited());
    let mut run = || -> Result<u64, String> {
        let (w, h) = dec.dimensions().map_err(|e| e.to_string())?;
        let (cw, ch) = dec.chunk_dimensions();
        let chunks = match dec.get_chunk_type() {
            tiff::decoder::ChunkType::Tile => w.div_ceil(cw) * h.div_ceil(ch),
            tiff::decoder::ChunkType::Strip => h.div_ceil(ch),
        };
        for i in 0..chunks {
            dec.read_chunk(i).map_err(|e| e.to_string())?;
        }
        Ok(u64::from(w) * u64::from(h))
    };
    Some(run())
}

/// zune-jpeg's decode of the luma plane of every tile or strip of a JPEG-compressed TIFF (its `JPEGTables`
/// prepended), one at a time; returns the pixel count. `None` when the file is not a JPEG-compressed TIFF.
fn decode_tiff_zune_luma(path: &Path) -> Option<Result<u64, String>> {
    use std::os::unix::fs::FileExt;
    use tiff::tags::Tag;
    let file = std::fs::File::open(path).ok()?;
    let raw = file.try_clone().ok()?;
    let mut dec = tiff::decoder::Decoder::new(std::io::BufReader::new(file)).ok()?;
    if dec.find_tag_unsigned::<u16>(Tag::Compression).ok()?? != 7 {
        return None;
    }
    let tiled = matches!(dec.get_chunk_type(), tiff::decoder::ChunkType::Tile);
    let (offsets, counts) = if tiled {
        (Tag::TileOffsets, Tag::TileByteCounts)
    } else {
        (Tag::StripOffsets, Tag::StripByteCounts)
    };
    let offsets = dec.get_tag_u64_vec(offsets).ok()?;
    let counts = dec.get_tag_u64_vec(counts).ok()?;
    let tables = dec.get_tag_u8_vec(Tag::JPEGTables).ok();
    let mut run = || -> Result<u64, String> {
        let mut chunk = Vec::new();
        for (&offset, &count) in offsets.iter().zip(&counts) {
            chunk.resize(count as usize, 0);
            raw.read_exact_at(&mut chunk, offset)
                .map_err(|e| e.to_string())?;
            let stream = match &tables {
                Some(t) if t.len() >= 4 => [&t[..t.len() - 2], &chunk[2..]].concat(),
                _ => chunk.clone(),
            };
            zune_luma(&stream).map_err(|e| format!("{e:?}"))?;
        }
        let (w, h) = dec.dimensions().map_err(|e| e.to_string())?;
        Ok(u64::from(w) * u64::from(h))
    };
    Some(run())
}

/// Minimum over `reps` of the wall time of ingesting `path` into a fresh pyramid in `dir`.
fn time_ingest(path: &Path, dir: &Path, reps: usize) -> Result<f64, String> {
    let dest = dir.join("bench.pyr");
    let mut best = f64::INFINITY;
    for _ in 0..reps {
        let (t, r) = timed(|| ingest(path, &dest));
        r.map_err(|e| e.to_string())?;
        let _ = std::fs::remove_file(&dest);
        best = best.min(t);
    }
    Ok(best)
}

/// Minimum over `reps` of the wall time of `decode`, and the pixel count it reported.
fn time_decode(
    reps: usize,
    decode: impl Fn() -> Option<Result<u64, String>>,
) -> Option<Result<(f64, u64), String>> {
    let mut best = (f64::INFINITY, 0);
    for _ in 0..reps {
        let (t, r) = timed(&decode);
        match r? {
            Ok(px) => best = (best.0.min(t), px),
            Err(e) => return Some(Err(e)),
        }
    }
    Some(Ok(best))
}

/// A plain decode of one file: the pixel count it decoded, `None` when it does not apply to the file.
type Decoder<'a> = dyn Fn() -> Option<Result<u64, String>> + 'a;

fn bench_file(path: &Path, dir: &Path, reps: usize) {
    let name = path.display();
    let decoders: [(&str, Box<Decoder>); 4] = [
        ("image", Box::new(|| Some(decode_image_crate(path)))),
        ("zune-jpeg luma", Box::new(|| decode_zune_luma(path))),
        ("tiff chunks", Box::new(|| decode_tiff_chunks(path))),
        (
            "zune-jpeg luma per tile",
            Box::new(|| decode_tiff_zune_luma(path)),
        ),
    ];
    let ingest_s = match time_ingest(path, dir, reps) {
        Ok(t) => t,
        Err(e) => {
            println!("{name}: ingestion failed: {e}");
            return;
        }
    };
    println!("{name}  ingest {ingest_s:.2} s");
    for (label, decode) in &decoders {
        match time_decode(reps, decode) {
            None => {}
            Some(Err(e)) => println!("{name}  {label}: decode failed: {e}"),
            Some(Ok((decode_s, px))) => println!(
                "{name}  {:.1} MP  {label}  decode {decode_s:.2} s  ingest {ingest_s:.2} s  ingest/decode {:.2}",
                px as f64 / 1e6,
                ingest_s / decode_s
            ),
        }
    }
}

fn main() {
    let mut files: Vec<PathBuf> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .map(PathBuf::from)
        .collect();
    if let Ok(list) = std::env::var("SKYTIE_INGEST_FILES") {
        files.extend(list.split(':').filter(|s| !s.is_empty()).map(PathBuf::from));
    }
    if files.is_empty() {
        println!("ingest_decode: no files given (pass paths after `--` or in SKYTIE_INGEST_FILES); nothing timed");
        return;
    }
    let reps = std::env::var("SKYTIE_INGEST_REPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1usize)
        .max(1);
    let dir = std::env::temp_dir().join(format!("skytie_ingest_bench_{}", std::process::id()));
    if let Err(e) = std::fs::create_dir_all(&dir) {
        println!("ingest_decode: cannot create {}: {e}", dir.display());
        return;
    }
    for f in &files {
        bench_file(f, &dir, reps);
    }
    let _ = std::fs::remove_dir_all(&dir);
}
