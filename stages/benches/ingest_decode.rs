//! One-time ingestion of an image file into its tiled pyramid (`imaging::ingest`) against a plain decode of
//! the same file in the same process: the `image` crate's decoder (what a program that "just opens the image"
//! does, no allocation limit) and, for JPEG files, zune-jpeg decoding the luma plane only (the least work any
//! JPEG reader can do for a grey image). Plain `fn main`, no harness.
//!
//! Run: `cargo bench -p skytie-stages --bench ingest_decode -- FILE...` (or `SKYTIE_INGEST_FILES` with the
//! paths separated by `:`). Each file is timed `SKYTIE_INGEST_REPS` times (default 1) in alternating order
//! (decode, ingest, decode, …) and the minimum wall time of each is kept; `benches/realsize.sh` runs it on
//! one frame of each kind of the real-size preset. Prints one row per file and decoder:
//! `file  pixels  decoder  decode_s  ingest_s  ingest/decode`.

use skytie_stages::imaging::ingest::ingest;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Wall seconds of `f`, and its result.
fn timed<T>(f: impl FnOnce() -> T) -> (f64, T) {
    let s = Instant::now();
    let r = f();
    (s.elapsed().as_secs_f64(), r)
}

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
    let options = zune_jpeg::zune_core::options::DecoderOptions::default()
        .jpeg_set_out_colorspace(zune_jpeg::zune_core::colorspace::ColorSpace::Luma)
        .set_max_width(1 << 20)
        .set_max_height(1 << 20);
    let mut decoder = zune_jpeg::JpegDecoder::new_with_options(
        zune_jpeg::zune_core::bytestream::ZCursor::new(&bytes),
        options,
    );
    Some(
        decoder
            .decode()
            .map(|plane| plane.len() as u64)
            .map_err(|e| e.to_string()),
    )
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
    let decoders: [(&str, Box<Decoder>); 2] = [
        ("image", Box::new(|| Some(decode_image_crate(path)))),
        ("zune-jpeg luma", Box::new(|| decode_zune_luma(path))),
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
