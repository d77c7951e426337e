//! Ingestion: an image file decoded once ([`super::decode`]) straight into a pyramid file
//! ([`super::pyramid`]), row by row — the one full pass over an image's pixels the pipeline makes.
//!
//! Decoding and pyramid building overlap: the decoder fills bands of [`BAND_ROWS`] rows and hands each to a
//! second thread that builds the pyramid from it (tiles, hashes, the levels above), through a fixed set of
//! [`BANDS`] band buffers that go back and forth, so memory stays bounded whatever the image's height and the
//! decoder waits when the builder falls behind (`BANDS × BAND_ROWS` rows: 6.8 MB for a 26460 px wide 8-bit
//! frame, less than the builder's own bands of 2 × 256 rows per level). The builder gets the rows in the decoder's order, so the
//! pyramid file is the same byte for byte as a single-threaded build.

use super::decode::{decode_grey, GreyInfo, GreyRowSink};
use super::io_error::ImageIoError;
use super::pyramid::{PyramidBuilder, PyramidSummary, SampleDepth, DEFAULT_TILE_SIDE};
use std::io;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::thread::JoinHandle;

/// Rows per band handed from the decoder to the builder.
pub const BAND_ROWS: usize = 64;
/// Band buffers in circulation: one being filled, the others queued or being built from.
pub const BANDS: usize = 4;

/// What ingesting a file produced.
#[derive(Clone, Debug, PartialEq)]
pub struct Ingested {
    pub info: GreyInfo,
    pub pyramid: PyramidSummary,
}

/// Rows of one band, full image width, at the depth the decoder announced.
enum Rows {
    U8(Vec<u8>),
    U16(Vec<u16>),
}

/// A band of rows on its way to the builder: its samples and how many rows it holds.
struct Band {
    rows: Rows,
    count: usize,
}

/// What the decoder sends the builder.
enum Message {
    Band(Band),
    /// Every row was sent: complete the file.
    Finish,
}

/// The builder thread and the two ends of its band channels.
struct Worker {
    to_builder: Sender<Message>,
    free: Receiver<Band>,
    filling: Option<Band>,
    handle: JoinHandle<io::Result<PyramidSummary>>,
    width: usize,
}

/// Sends decoded rows, a band at a time, to a pyramid builder thread started when the size is known.
struct PyramidSink {
    dest: PathBuf,
    tile_side: usize,
    worker: Option<Worker>,
}

/// The builder thread: builds the pyramid from the bands received until [`Message::Finish`], returning each
/// band's buffer for refilling. A closed channel without `Finish` (the decoder failed) drops the builder,
/// which removes its temporary file, and is an [`io::ErrorKind::Interrupted`] error.
fn build(
    mut builder: PyramidBuilder,
    width: usize,
    bands: Receiver<Message>,
    free: Sender<Band>,
) -> io::Result<PyramidSummary> {
    while let Ok(message) = bands.recv() {
        let band = match message {
            Message::Band(band) => band,
            Message::Finish => return builder.finish(),
        };
        match &band.rows {
            Rows::U8(v) => {
                for row in v.chunks_exact(width).take(band.count) {
                    builder.push_row_u8(row)?;
                }
            }
            Rows::U16(v) => {
                for row in v.chunks_exact(width).take(band.count) {
                    builder.push_row_u16(row)?;
                }
            }
        }
        // The decoder may have stopped already; the buffer is then simply dropped.
        let _ = free.send(band);
    }
    Err(io::Error::new(
        io::ErrorKind::Interrupted,
        "the decoder stopped before the last row",
    ))
}

impl PyramidSink {
    /// Starts the builder thread for an image described by `info`, with its band buffers.
    fn start(&self, info: &GreyInfo) -> io::Result<Worker> {
        let builder = PyramidBuilder::create(
            &self.dest,
            info.width,
            info.height,
            info.depth,
            self.tile_side,
        )?;
        let samples = info.width * BAND_ROWS;
        let (to_builder, bands) = channel();
        let (give_back, free) = channel();
        for _ in 0..BANDS {
            let rows = match info.depth {
                SampleDepth::U8 => Rows::U8(vec![0; samples]),
                SampleDepth::U16 => Rows::U16(vec![0; samples]),
            };
            let _ = give_back.send(Band { rows, count: 0 });
        }
        let width = info.width;
        let handle = std::thread::Builder::new()
            .name("pyramid-builder".into())
            .spawn(move || build(builder, width, bands, give_back))?;
        Ok(Worker {
            to_builder,
            free,
            filling: None,
            handle,
            width,
        })
    }

    fn worker(&mut self) -> io::Result<&mut Worker> {
        self.worker
            .as_mut()
            .ok_or_else(|| io::Error::other("internal: rows before the size"))
    }
}

impl Worker {
    /// The band being filled, taking a free buffer (waiting for the builder) when there is none.
    fn band(&mut self) -> io::Result<&mut Band> {
        if self.filling.is_none() {
            let mut band = self.free.recv().map_err(|_| self.builder_stopped())?;
            band.count = 0;
            self.filling = Some(band);
        }
        Ok(self.filling.as_mut().expect("just filled"))
    }

    /// Copies one decoded row into the band being filled and sends the band when it is full; `samples` picks
    /// the band's buffer of the row's sample depth (`None`: the image was announced with the other depth).
    fn push_row<T: Copy>(
        &mut self,
        row: &[T],
        samples: fn(&mut Rows) -> Option<&mut Vec<T>>,
    ) -> io::Result<()> {
        let width = self.width;
        let band = self.band()?;
        let Some(v) = samples(&mut band.rows) else {
            return Err(io::Error::other(
                "internal: rows of a sample depth the image was not announced with",
            ));
        };
        v[band.count * width..(band.count + 1) * width].copy_from_slice(row);
        band.count += 1;
        self.send_band(false)
    }

    /// Sends the band being filled when it is full (or, with `force`, when it holds any row).
    fn send_band(&mut self, force: bool) -> io::Result<()> {
        let full = self
            .filling
            .as_ref()
            .is_some_and(|b| b.count == BAND_ROWS || (force && b.count > 0));
        if full {
            let band = self.filling.take().expect("checked");
            self.to_builder
                .send(Message::Band(band))
                .map_err(|_| self.builder_stopped())?;
        }
        Ok(())
    }

    /// The builder thread ended early: it failed (the reason comes from [`Worker::join`]).
    fn builder_stopped(&self) -> io::Error {
        io::Error::other("the pyramid builder stopped")
    }

    /// Sends the last rows and [`Message::Finish`], and waits for the finished pyramid.
    fn finish(mut self) -> io::Result<PyramidSummary> {
        let sent = self.send_band(true).and_then(|()| {
            self.to_builder
                .send(Message::Finish)
                .map_err(|_| self.builder_stopped())
        });
        drop(self.to_builder);
        let built = join(self.handle);
        sent.and(built)
    }
}

/// The builder thread's result (a panic in it as an error).
fn join(handle: JoinHandle<io::Result<PyramidSummary>>) -> io::Result<PyramidSummary> {
    handle
        .join()
        .unwrap_or_else(|_| Err(io::Error::other("internal: the pyramid builder panicked")))
}

impl GreyRowSink for PyramidSink {
    fn begin(&mut self, info: &GreyInfo) -> io::Result<()> {
        self.worker = Some(self.start(info)?);
        Ok(())
    }

    fn row_u8(&mut self, row: &[u8]) -> io::Result<()> {
        self.worker()?.push_row(row, |rows| match rows {
            Rows::U8(v) => Some(v),
            Rows::U16(_) => None,
        })
    }

    fn row_u16(&mut self, row: &[u16]) -> io::Result<()> {
        self.worker()?.push_row(row, |rows| match rows {
            Rows::U16(v) => Some(v),
            Rows::U8(_) => None,
        })
    }
}

/// Decodes `source` into the pyramid file `dest` (written atomically; nothing is left at `dest` on error).
pub fn ingest(source: &Path, dest: &Path) -> Result<Ingested, ImageIoError> {
    ingest_with_tiles(source, dest, DEFAULT_TILE_SIDE)
}

/// [`ingest`] with a chosen tile side (pixels).
pub fn ingest_with_tiles(
    source: &Path,
    dest: &Path,
    tile_side: usize,
) -> Result<Ingested, ImageIoError> {
    let mut sink = PyramidSink {
        dest: dest.to_path_buf(),
        tile_side,
        worker: None,
    };
    let decoded = decode_grey(source, &mut sink);
    let worker = sink.worker.take();
    let incomplete = |e: io::Error| {
        ImageIoError::new(
            source,
            format!("cannot complete its pyramid in {} ({e})", dest.display()),
        )
    };
    let (e, worker) = match (decoded, worker) {
        (Ok(info), Some(worker)) => {
            let pyramid = worker.finish().map_err(incomplete)?;
            return Ok(Ingested { info, pyramid });
        }
        (Ok(_), None) => {
            return Err(ImageIoError::new(
                source,
                "internal: the decoder produced no image",
            ))
        }
        (Err(e), worker) => (e, worker),
    };
    // The decoder failed: stop the builder (its temporary file goes) and report why. When the builder had
    // failed on its own first (e.g. a full disk), its reason is the one to report.
    if let Some(w) = worker {
        drop(w.to_builder);
        match join(w.handle) {
            Err(built) if built.kind() != io::ErrorKind::Interrupted => {
                return Err(incomplete(built))
            }
            _ => {}
        }
    }
    Err(e)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imaging::tiff_write::{TiffCompression, TiledTiffSpec, TiledTiffWriter};

    /// Feeds decoded rows straight into a builder on this thread: the single-threaded reference.
    struct Direct {
        dest: PathBuf,
        builder: Option<PyramidBuilder>,
    }

    impl GreyRowSink for Direct {
        fn begin(&mut self, info: &GreyInfo) -> io::Result<()> {
            let b = PyramidBuilder::create(&self.dest, info.width, info.height, info.depth, 64)?;
            self.builder = Some(b);
            Ok(())
        }
        fn row_u8(&mut self, row: &[u8]) -> io::Result<()> {
            self.builder.as_mut().unwrap().push_row_u8(row)
        }
        fn row_u16(&mut self, row: &[u16]) -> io::Result<()> {
            self.builder.as_mut().unwrap().push_row_u16(row)
        }
    }

    /// A `w × h` tiled TIFF (64-px tiles) of `bytes` bytes per grey sample, compressed as `compression`.
    fn write(path: &Path, (w, h): (usize, usize), bytes: usize, compression: TiffCompression) {
        let spec = TiledTiffSpec {
            width: w,
            height: h,
            channels: 1,
            bytes_per_sample: bytes,
            tile_side: 64,
            compression,
            big: false,
        };
        let mut out = TiledTiffWriter::create(path, spec).unwrap();
        for r in 0..h {
            let value = |c: usize| (c * 31 + r * 17 + (c * r) % 101) % 4096;
            if bytes == 1 {
                let row: Vec<u8> = (0..w).map(|c| value(c) as u8).collect();
                out.push_row_u8(&row).unwrap();
            } else {
                let row: Vec<u16> = (0..w).map(|c| value(c) as u16).collect();
                out.push_row_u16(&row).unwrap();
            }
        }
        out.finish().unwrap();
    }

    #[test]
    fn the_pyramid_built_beside_the_decoder_is_the_single_threaded_one_byte_for_byte() {
        let dir = tempfile::tempdir().unwrap();
        // Taller than all band buffers together, so every buffer goes round several times.
        let size = (333, BANDS * BAND_ROWS * 3 + 37);
        for (i, (bytes, compression)) in [
            (1, TiffCompression::Jpeg(90)),
            (2, TiffCompression::Deflate),
        ]
        .into_iter()
        .enumerate()
        {
            let src = dir.path().join(format!("s{i}.tif"));
            write(&src, size, bytes, compression);
            let threaded = dir.path().join(format!("t{i}.pyr"));
            let done = ingest_with_tiles(&src, &threaded, 64).unwrap();
            let mut direct = Direct {
                dest: dir.path().join(format!("d{i}.pyr")),
                builder: None,
            };
            decode_grey(&src, &mut direct).unwrap();
            let reference = direct.builder.take().unwrap().finish().unwrap();
            assert_eq!(done.pyramid, reference);
            assert!(
                std::fs::read(&threaded).unwrap() == std::fs::read(&direct.dest).unwrap(),
                "case {i}: the files differ"
            );
        }
    }

    #[test]
    fn a_decoder_failing_midway_leaves_no_pyramid_and_names_the_file() {
        use std::os::unix::fs::FileExt;
        let dir = tempfile::tempdir().unwrap();
        let src = dir.path().join("bad.tif");
        write(&src, (200, 900), 1, TiffCompression::Deflate);
        // Spoil the compressed data of the last tile: rows before it decode, then the decoder fails.
        let mut dec = tiff::decoder::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(&src).unwrap(),
        ))
        .unwrap();
        let offsets = dec.get_tag_u64_vec(tiff::tags::Tag::TileOffsets).unwrap();
        let file = std::fs::OpenOptions::new().write(true).open(&src).unwrap();
        file.write_all_at(&[0xFF; 8], *offsets.last().unwrap())
            .unwrap();
        let out = dir.path().join("out");
        let e = ingest_with_tiles(&src, &out.join("p.pyr"), 64).unwrap_err();
        assert!(e.to_string().contains("bad.tif"), "{e}");
        let left: Vec<_> = std::fs::read_dir(&out).unwrap().collect();
        assert!(left.is_empty(), "left behind: {left:?}");
    }
}
