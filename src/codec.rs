//! Every byte encoding of cached artifacts and of node parameters lives here, so a change of encoding is a
//! one-file change.
//!
//! An encoded artifact starts with [`FORMAT_VERSION`] (one byte) and a 4-byte kind magic, then the body:
//! - `SERD`: bincode 2 (serde, standard config) of the value — used by [`serde_artifact!`](crate::serde_artifact!) types and the
//!   built-in scalars/vectors;
//! - rasters (kinds chosen by the type, e.g. `GRAY` / `RGB3` for the node layer's images): width and height
//!   (u64 little-endian) followed by the raw `f32` samples as little-endian bytes (memcpy speed; a 4000×3000
//!   grey image is 48 MB) — [`encode_raster`], [`read_raster`];
//! - `BYTE`: length (u64 little-endian) and raw bytes (`Vec<u8>`); `JSON`: JSON text (`serde_json::Value`).
//!
//! Decoding checks version, kind and length and returns a [`CodecError`] that says what is wrong; it never
//! panics and never allocates more than a bounded multiple of the input on garbage.
//!
//! Every artifact can also be written to / read from a stream ([`Artifact::encode_to`],
//! [`Artifact::decode_from`]) with exactly the same bytes; for rasters that is the fast path of the store: the
//! samples go from the image's memory to the entry file in one write and come back with one read straight
//! into the new buffer. The engine knows no image type: the node layer (`nodes::image_artifact`) implements
//! [`Artifact`] for the photogrammetry crate's images with these raster functions.

use serde::de::DeserializeOwned;
use serde::Serialize;
use std::io::{self, Read, Write};

/// Version of the artifact encoding; bump it whenever any encoding below changes.
pub const FORMAT_VERSION: u8 = 1;

const KIND_SERDE: &[u8; 4] = b"SERD";
const KIND_BYTES: &[u8; 4] = b"BYTE";
const KIND_JSON: &[u8; 4] = b"JSON";

/// Advice appended to decoding errors. Payloads reaching the codec from the store have passed its hash
/// check, so a decoding failure means bytes written by an incompatible skytie build, not disk damage.
const INCOMPATIBLE: &str =
    "the cached bytes come from an incompatible skytie build; run `skytie cache gc --max-size 0` (or delete the cache folder)";

/// Bytes before an artifact's body: version byte + kind magic.
const FRAME_LEN: usize = 5;

/// An artifact or parameter value could not be encoded or decoded; the message says what and what to do.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct CodecError(pub String);

impl CodecError {
    fn new(message: impl Into<String>) -> CodecError {
        CodecError(message.into())
    }
}

/// A value that can be cached by the engine.
///
/// `encode`/`decode` work on byte buffers; `encode_to`/`decode_from` produce and consume the same bytes as a
/// stream, which the store uses to write an artifact straight into its entry file and to read it straight out
/// of it. Their defaults go through a buffer; images override them so that their samples move between the
/// file and the image's own `Vec<f32>` with no intermediate copy.
pub trait Artifact: Sized + Send + Sync + 'static {
    /// Appends the encoding of `self` to `out`.
    fn encode(&self, out: &mut Vec<u8>);
    /// Decodes a value encoded by [`Artifact::encode`] (the whole slice).
    fn decode(bytes: &[u8]) -> Result<Self, CodecError>;
    /// Writes exactly the bytes of [`Artifact::encode`] to `sink`.
    fn encode_to(&self, sink: &mut dyn Write) -> io::Result<()> {
        let mut buffer = Vec::new();
        self.encode(&mut buffer);
        sink.write_all(&buffer)
    }
    /// Decodes a value from the next `len` bytes of `source` (all of them are consumed on success). The
    /// caller guarantees that `source` holds `len` bytes (the store checks it against the file size), so
    /// allocations are bounded by `len`.
    fn decode_from(source: &mut dyn Read, len: u64) -> Result<Self, CodecError> {
        let type_name = std::any::type_name::<Self>();
        let len = usize::try_from(len).map_err(|_| too_large(type_name, len))?;
        let mut buffer = vec![0u8; len];
        source
            .read_exact(&mut buffer)
            .map_err(|e| read_failed(type_name, &e))?;
        Self::decode(&buffer)
    }
}

fn too_large(type_name: &str, len: u64) -> CodecError {
    CodecError::new(format!(
        "cached {type_name} of {len} bytes does not fit in this machine's address space"
    ))
}

fn read_failed(type_name: &str, e: &io::Error) -> CodecError {
    CodecError::new(format!("cannot read cached {type_name}: {e}"))
}

fn push_frame(out: &mut Vec<u8>, kind: &[u8; 4]) {
    out.push(FORMAT_VERSION);
    out.extend_from_slice(kind);
}

fn kind_name(kind: &[u8]) -> String {
    match std::str::from_utf8(kind) {
        Ok(s)
            if s.bytes()
                .all(|b| b.is_ascii_uppercase() || b.is_ascii_digit()) =>
        {
            s.to_string()
        }
        _ => format!("{kind:?}"),
    }
}

/// Checks version and kind; returns the body.
fn open_frame<'a>(
    bytes: &'a [u8],
    kind: &[u8; 4],
    type_name: &str,
) -> Result<&'a [u8], CodecError> {
    if bytes.len() < FRAME_LEN {
        return Err(CodecError::new(format!(
            "cached {type_name} is truncated ({} bytes, shorter than its 5-byte header); {INCOMPATIBLE}",
            bytes.len()
        )));
    }
    if bytes[0] != FORMAT_VERSION {
        return Err(CodecError::new(format!(
            "artifact format version {}, this skytie reads {FORMAT_VERSION}: the cache was written by another \
             skytie version; run `skytie cache gc --max-size 0` (or delete the cache folder) and run again",
            bytes[0]
        )));
    }
    if &bytes[1..FRAME_LEN] != kind {
        return Err(CodecError::new(format!(
            "cached artifact is a {} value, not a {type_name} ({}): the cache entry does not belong to this node; \
             {INCOMPATIBLE}",
            kind_name(&bytes[1..FRAME_LEN]),
            kind_name(kind)
        )));
    }
    Ok(&bytes[FRAME_LEN..])
}

fn bincode_config() -> bincode::config::Configuration {
    bincode::config::standard()
}

/// Appends the plain bincode encoding of `value` (no version/kind frame) to `out`.
pub fn encode_serde_into<T: Serialize + ?Sized>(
    value: &T,
    out: &mut Vec<u8>,
) -> Result<(), CodecError> {
    bincode::serde::encode_into_std_write(value, out, bincode_config())
        .map(|_| ())
        .map_err(|e| CodecError::new(format!("cannot encode {}: {e}", std::any::type_name::<T>())))
}

/// Decodes plain bincode produced by [`encode_serde_into`]; every byte must be consumed.
///
/// Garbage can announce huge lengths. bincode's byte limit (which also bounds the memory it reserves for
/// containers: length × element size) is set to the smallest power-of-16 tier of at least 4096 bytes per
/// input byte, capped at 8 GiB, so such input fails instead of allocating without bound. Legitimate values
/// reserve far less than 4096 bytes per encoded byte; values needing more than 8 GiB are not supported.
pub fn decode_serde_exact<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, CodecError> {
    use bincode::config::Config;
    fn run<T: DeserializeOwned, C: Config>(
        bytes: &[u8],
        config: C,
    ) -> Result<(T, usize), bincode::error::DecodeError> {
        bincode::serde::decode_from_slice(bytes, config)
    }
    let claim_bound = (bytes.len() as u64).saturating_mul(4096);
    let base = bincode_config();
    let result = if claim_bound <= 1 << 16 {
        run(bytes, base.with_limit::<{ 1 << 16 }>())
    } else if claim_bound <= 1 << 20 {
        run(bytes, base.with_limit::<{ 1 << 20 }>())
    } else if claim_bound <= 1 << 24 {
        run(bytes, base.with_limit::<{ 1 << 24 }>())
    } else if claim_bound <= 1 << 28 {
        run(bytes, base.with_limit::<{ 1 << 28 }>())
    } else if claim_bound <= 1 << 32 {
        run(bytes, base.with_limit::<{ 1 << 32 }>())
    } else {
        run(bytes, base.with_limit::<{ 1 << 33 }>())
    };
    let type_name = std::any::type_name::<T>();
    match result {
        Ok((value, used)) if used == bytes.len() => Ok(value),
        Ok((_, used)) => Err(CodecError::new(format!(
            "cached {type_name} has {} unexpected trailing bytes after {used}: the entry holds another type; \
             {INCOMPATIBLE}",
            bytes.len() - used
        ))),
        Err(e) => Err(CodecError::new(format!(
            "cannot decode cached {type_name}: {e}; the entry is damaged or holds another type; {INCOMPATIBLE}"
        ))),
    }
}

/// Full artifact encoding (version, `SERD` kind, bincode) of any serde value.
pub fn encode_serde<T: Serialize + ?Sized>(value: &T) -> Result<Vec<u8>, CodecError> {
    let mut out = Vec::new();
    push_frame(&mut out, KIND_SERDE);
    encode_serde_into(value, &mut out)?;
    Ok(out)
}

/// Decodes an artifact produced by [`encode_serde`] (or by a [`serde_artifact!`](crate::serde_artifact!) type's `encode`).
pub fn decode_serde<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, CodecError> {
    let body = open_frame(bytes, KIND_SERDE, std::any::type_name::<T>())?;
    decode_serde_exact(body)
}

/// Appends the artifact encoding of a serde value; used by [`serde_artifact!`](crate::serde_artifact!).
///
/// # Panics
/// Only if the type itself cannot be represented by bincode (e.g. a serde impl with sequences of unknown
/// length) — a programming error in the type, found the first time any value of it is cached.
pub fn encode_serde_artifact<T: Serialize>(value: &T, out: &mut Vec<u8>) {
    push_frame(out, KIND_SERDE);
    if let Err(e) = encode_serde_into(value, out) {
        panic!("skytie codec: {e} (this type cannot be cached with serde_artifact!; give it a plain serde layout)");
    }
}

/// Canonical bytes of a node's parameters, for its key. Same value ⇒ same bytes (floats by bit pattern).
/// Use `BTreeMap`, not `HashMap`, in parameter types: a hash map's order is not canonical.
pub fn encode_params<P: Serialize>(p: &P) -> Result<Vec<u8>, CodecError> {
    encode_serde(p).map_err(|e| CodecError::new(format!("node parameters: {e}")))
}

/// Implements [`Artifact`](crate::codec::Artifact) for serde types via bincode:
/// `skytie::serde_artifact!(MyResult, Vec<Observation>);`
#[macro_export]
macro_rules! serde_artifact {
    ($($t:ty),* $(,)?) => {
        $(
            impl $crate::codec::Artifact for $t {
                fn encode(&self, out: &mut ::std::vec::Vec<u8>) {
                    $crate::codec::encode_serde_artifact(self, out)
                }
                fn decode(bytes: &[u8]) -> ::std::result::Result<Self, $crate::codec::CodecError> {
                    $crate::codec::decode_serde(bytes)
                }
            }
        )*
    };
}

serde_artifact!((), u64, f64, String, Vec<f64>, Vec<String>);

impl Artifact for Vec<u8> {
    fn encode(&self, out: &mut Vec<u8>) {
        out.reserve(FRAME_LEN + 8 + self.len());
        push_frame(out, KIND_BYTES);
        out.extend_from_slice(&(self.len() as u64).to_le_bytes());
        out.extend_from_slice(self);
    }
    fn decode(bytes: &[u8]) -> Result<Self, CodecError> {
        let body = open_frame(bytes, KIND_BYTES, "byte buffer")?;
        let declared = body
            .get(..8)
            .map(|b| u64::from_le_bytes(b.try_into().expect("8-byte slice")));
        match declared {
            Some(n) if n == (body.len() - 8) as u64 => Ok(body[8..].to_vec()),
            _ => Err(CodecError::new(format!(
                "cached byte buffer is damaged: its length header does not match its {} bytes; {INCOMPATIBLE}",
                body.len()
            ))),
        }
    }
}

impl Artifact for serde_json::Value {
    fn encode(&self, out: &mut Vec<u8>) {
        push_frame(out, KIND_JSON);
        // Writing a `Value` to a Vec cannot fail (its keys are strings, writes to memory are infallible).
        if let Err(e) = serde_json::to_writer(&mut *out, self) {
            panic!("skytie codec: cannot write JSON value: {e}");
        }
    }
    fn decode(bytes: &[u8]) -> Result<Self, CodecError> {
        let body = open_frame(bytes, KIND_JSON, "JSON value")?;
        serde_json::from_slice(body).map_err(|e| {
            CodecError::new(format!(
                "cached JSON value is damaged ({e}); {INCOMPATIBLE}"
            ))
        })
    }
}

// ---- dense f32 rasters ------------------------------------------------------------------------------------
//
// Images are not an engine type: the node layer implements [`Artifact`] for its image types with the functions
// below, which encode any dense `f32` raster (width × height × channels samples) as frame + width + height (u64
// little-endian) + the raw little-endian samples, and read it back straight into a freshly allocated buffer.

/// The in-memory bytes of `samples` (no copy).
fn sample_bytes(samples: &[f32]) -> &[u8] {
    // SAFETY: `f32` has no padding and every bit pattern is a valid `u8` sequence; `u8` needs no alignment;
    // the byte slice covers exactly the samples' memory and borrows `samples`.
    unsafe {
        std::slice::from_raw_parts(
            samples.as_ptr().cast::<u8>(),
            std::mem::size_of_val(samples),
        )
    }
}

/// The in-memory bytes of `samples`, writable (no copy).
fn sample_bytes_mut(samples: &mut [f32]) -> &mut [u8] {
    // SAFETY: as in `sample_bytes`; in addition any 4 bytes written through the view are a valid `f32`, and
    // the view borrows `samples` mutably, so nothing else aliases it.
    unsafe {
        std::slice::from_raw_parts_mut(
            samples.as_mut_ptr().cast::<u8>(),
            std::mem::size_of_val(samples),
        )
    }
}

/// Writes `samples` as little-endian `f32` bytes: on a little-endian target their memory as it is (one
/// write, no copy); elsewhere converted in 64 KiB blocks.
fn write_f32_le(sink: &mut dyn Write, samples: &[f32]) -> io::Result<()> {
    if cfg!(target_endian = "little") {
        return sink.write_all(sample_bytes(samples));
    }
    let mut block = Vec::with_capacity(1 << 16);
    for chunk in samples.chunks(1 << 14) {
        block.clear();
        for v in chunk {
            block.extend_from_slice(&v.to_le_bytes());
        }
        sink.write_all(&block)?;
    }
    Ok(())
}

/// Allocations at least this large ask the OS for transparent huge pages.
const HUGE_PAGE_ADVICE_BYTES: usize = 4 << 20;

/// `count` zero samples for an image about to be filled. The memory comes zeroed from the OS (no memset);
/// on Linux, buffers of 4 MiB or more are advised to use transparent huge pages before they are touched, so
/// filling them costs one page fault per 2 MiB instead of one per 4 KiB (measured: reading a 48 MB image
/// into a fresh buffer takes 19 instead of 33 CPU-ms; `cargo bench --bench store`). The advice changes
/// nothing but the page size and is ignored where unsupported.
fn zeroed_samples(count: usize) -> Vec<f32> {
    let mut samples = vec![0f32; count];
    if std::mem::size_of_val(samples.as_slice()) >= HUGE_PAGE_ADVICE_BYTES {
        advise_huge_pages(sample_bytes_mut(&mut samples));
    }
    samples
}

/// Huge pages for a mapped or allocated buffer (`skytie_util::huge_pages`).
fn advise_huge_pages(memory: &mut [u8]) {
    skytie_util::huge_pages::advise_huge_pages(memory.as_mut_ptr() as usize, memory.len());
}

/// Turns samples whose memory holds little-endian `f32` bytes into native values (a no-op on little-endian
/// targets).
fn samples_from_le(samples: &mut [f32]) {
    if cfg!(target_endian = "big") {
        for v in samples {
            *v = f32::from_bits(u32::from_le(v.to_bits()));
        }
    }
}

/// Bytes of an image artifact before its samples: frame + width and height (u64 each).
const IMAGE_HEAD_LEN: usize = FRAME_LEN + 16;

fn image_head(kind: &[u8; 4], width: usize, height: usize) -> [u8; IMAGE_HEAD_LEN] {
    let mut head = [0u8; IMAGE_HEAD_LEN];
    head[0] = FORMAT_VERSION;
    head[1..FRAME_LEN].copy_from_slice(kind);
    head[FRAME_LEN..FRAME_LEN + 8].copy_from_slice(&(width as u64).to_le_bytes());
    head[FRAME_LEN + 8..].copy_from_slice(&(height as u64).to_le_bytes());
    head
}

pub fn encode_raster(
    out: &mut Vec<u8>,
    kind: &[u8; 4],
    width: usize,
    height: usize,
    samples: &[f32],
) {
    out.reserve(IMAGE_HEAD_LEN + samples.len() * 4);
    out.extend_from_slice(&image_head(kind, width, height));
    if cfg!(target_endian = "little") {
        out.extend_from_slice(sample_bytes(samples));
    } else {
        for v in samples {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
}

pub fn encode_raster_to(
    sink: &mut dyn Write,
    kind: &[u8; 4],
    width: usize,
    height: usize,
    samples: &[f32],
) -> io::Result<()> {
    sink.write_all(&image_head(kind, width, height))?;
    write_f32_le(sink, samples)
}

/// Checks an image artifact's head (its first up to [`IMAGE_HEAD_LEN`] bytes) against the number of sample
/// bytes that follow it; returns (width, height).
fn image_shape(
    head: &[u8],
    sample_len: u64,
    kind: &[u8; 4],
    type_name: &str,
    channels: usize,
) -> Result<(usize, usize), CodecError> {
    let body = open_frame(head, kind, type_name)?;
    if body.len() < 16 {
        return Err(CodecError::new(format!(
            "cached {type_name} is truncated: its size header needs 16 bytes, found {}; {INCOMPATIBLE}",
            body.len()
        )));
    }
    let width = u64::from_le_bytes(body[0..8].try_into().expect("8-byte slice"));
    let height = u64::from_le_bytes(body[8..16].try_into().expect("8-byte slice"));
    let expected = width
        .checked_mul(height)
        .and_then(|n| n.checked_mul(channels as u64 * 4))
        .filter(|&n| n == sample_len);
    match (expected, usize::try_from(width), usize::try_from(height)) {
        (Some(_), Ok(width), Ok(height)) => Ok((width, height)),
        _ => Err(CodecError::new(format!(
            "cached {type_name} of {width}×{height} px should hold {width}×{height}×{channels} f32 samples but has \
             {sample_len} bytes of samples: the entry is damaged; {INCOMPATIBLE}"
        ))),
    }
}

/// Decodes an image body; `channels` samples per pixel. Returns (width, height, samples).
pub fn decode_raster(
    bytes: &[u8],
    kind: &[u8; 4],
    type_name: &str,
    channels: usize,
) -> Result<(usize, usize, Vec<f32>), CodecError> {
    let head_len = bytes.len().min(IMAGE_HEAD_LEN);
    let sample_len = (bytes.len() - head_len) as u64;
    let (width, height) = image_shape(&bytes[..head_len], sample_len, kind, type_name, channels)?;
    let raw = &bytes[head_len..];
    let mut samples = zeroed_samples(raw.len() / 4);
    sample_bytes_mut(&mut samples).copy_from_slice(raw);
    samples_from_le(&mut samples);
    Ok((width, height, samples))
}

/// Reads an image of `len` bytes from `source`: the head, then the samples with one `read_exact` straight
/// into the image's buffer (allocated once, zeroed lazily by the OS).
pub fn read_raster(
    source: &mut dyn Read,
    len: u64,
    kind: &[u8; 4],
    type_name: &str,
    channels: usize,
) -> Result<(usize, usize, Vec<f32>), CodecError> {
    let mut head = [0u8; IMAGE_HEAD_LEN];
    let head_len = len.min(IMAGE_HEAD_LEN as u64) as usize;
    source
        .read_exact(&mut head[..head_len])
        .map_err(|e| read_failed(type_name, &e))?;
    let sample_len = len - head_len as u64;
    let (width, height) = image_shape(&head[..head_len], sample_len, kind, type_name, channels)?;
    // `sample_len` = width × height × channels × 4 was checked without overflow, and the caller guarantees
    // that `source` holds it, so the allocation is bounded by the entry's size.
    let count = usize::try_from(sample_len / 4).map_err(|_| too_large(type_name, len))?;
    let mut samples = zeroed_samples(count);
    source
        .read_exact(sample_bytes_mut(&mut samples))
        .map_err(|e| read_failed(type_name, &e))?;
    samples_from_le(&mut samples);
    Ok((width, height, samples))
}

/// Implements [`Artifact`](crate::codec::Artifact) for a dense `f32` raster type with public fields `width`,
/// `height` (usize) and `data` (`Vec<f32>`, `channels` samples per pixel, row-major) through the raster
/// encoding: `skytie::raster_artifact!(GrayImage, b"GRAY", "gray image", 1);`
#[macro_export]
macro_rules! raster_artifact {
    ($t:ty, $kind:expr, $name:expr, $channels:expr) => {
        impl $crate::codec::Artifact for $t {
            fn encode(&self, out: &mut ::std::vec::Vec<u8>) {
                $crate::codec::encode_raster(out, $kind, self.width, self.height, &self.data);
            }
            fn decode(bytes: &[u8]) -> ::std::result::Result<Self, $crate::codec::CodecError> {
                let (width, height, data) =
                    $crate::codec::decode_raster(bytes, $kind, $name, $channels)?;
                Ok(Self {
                    width,
                    height,
                    data,
                })
            }
            fn encode_to(&self, sink: &mut dyn ::std::io::Write) -> ::std::io::Result<()> {
                $crate::codec::encode_raster_to(sink, $kind, self.width, self.height, &self.data)
            }
            fn decode_from(
                source: &mut dyn ::std::io::Read,
                len: u64,
            ) -> ::std::result::Result<Self, $crate::codec::CodecError> {
                let (width, height, data) =
                    $crate::codec::read_raster(source, len, $kind, $name, $channels)?;
                Ok(Self {
                    width,
                    height,
                    data,
                })
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;
    use std::collections::BTreeMap;

    /// Fields grouped into a nested struct encode as if they were the outer struct's own, in order: an
    /// artifact can group its counters (e.g. the nadir refinement's misses) without invalidating the cache.
    #[test]
    fn a_nested_struct_encodes_as_its_fields_in_sequence() {
        #[derive(Serialize, Deserialize, Debug, PartialEq)]
        struct Flat {
            id: String,
            a: usize,
            b: usize,
            c: Vec<u8>,
        }
        #[derive(Serialize, Deserialize, Debug, PartialEq)]
        struct Counts {
            a: usize,
            #[serde(default)]
            b: usize,
        }
        #[derive(Serialize, Deserialize, Debug, PartialEq)]
        struct Nested {
            id: String,
            counts: Counts,
            c: Vec<u8>,
        }
        let flat = Flat {
            id: "r".into(),
            a: 3,
            b: 70_000,
            c: vec![1, 2],
        };
        let bytes = encode_serde(&flat).unwrap();
        let nested: Nested = decode_serde(&bytes).unwrap();
        assert_eq!(nested.counts, Counts { a: 3, b: 70_000 });
        assert_eq!(encode_serde(&nested).unwrap(), bytes);
    }

    /// One- and three-channel rasters shaped like the node layer's images.
    #[derive(Debug, PartialEq)]
    struct GrayImage {
        width: usize,
        height: usize,
        data: Vec<f32>,
    }
    #[derive(Debug, PartialEq)]
    struct RgbImage {
        width: usize,
        height: usize,
        data: Vec<f32>,
    }
    raster_artifact!(GrayImage, b"GRAY", "gray image", 1);
    raster_artifact!(RgbImage, b"RGB3", "RGB image", 3);
    impl GrayImage {
        fn from_vec(width: usize, height: usize, data: Vec<f32>) -> Option<Self> {
            (data.len() == width * height).then_some(GrayImage {
                width,
                height,
                data,
            })
        }
        fn filled(width: usize, height: usize, v: f32) -> Self {
            GrayImage {
                width,
                height,
                data: vec![v; width * height],
            }
        }
    }
    impl RgbImage {
        fn filled(width: usize, height: usize, v: [f32; 3]) -> Self {
            RgbImage {
                width,
                height,
                data: v.repeat(width * height),
            }
        }
    }

    fn round_trip<T: Artifact + PartialEq + std::fmt::Debug>(value: T) {
        let mut bytes = Vec::new();
        value.encode(&mut bytes);
        assert_eq!(bytes[0], FORMAT_VERSION);
        assert_eq!(T::decode(&bytes).unwrap(), value);
        // The streaming forms produce and accept exactly the same bytes.
        let mut streamed = Vec::new();
        value.encode_to(&mut streamed).unwrap();
        assert_eq!(streamed, bytes);
        let mut source = bytes.as_slice();
        assert_eq!(
            T::decode_from(&mut source, bytes.len() as u64).unwrap(),
            value
        );
        assert!(source.is_empty(), "decode_from left bytes unread");
        // Every truncation fails cleanly, in both forms.
        for cut in 0..bytes.len() {
            assert!(
                T::decode(&bytes[..cut]).is_err(),
                "decoding {cut} of {} bytes succeeded",
                bytes.len()
            );
            assert!(
                T::decode_from(&mut &bytes[..cut], cut as u64).is_err(),
                "stream-decoding {cut} of {} bytes succeeded",
                bytes.len()
            );
        }
    }

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    struct Sample {
        name: String,
        values: Vec<f64>,
        table: BTreeMap<String, u32>,
        flag: Option<bool>,
    }
    serde_artifact!(Sample);

    #[test]
    fn builtin_and_serde_types_round_trip() {
        round_trip(());
        round_trip(42u64);
        round_trip(-0.0f64);
        round_trip(String::from("ortho[rec 0012]"));
        round_trip(vec![1u8, 2, 3, 255]);
        round_trip(vec![1.5f64, f64::MAX, -1e-300]);
        round_trip(vec!["a".to_string(), String::new()]);
        round_trip(serde_json::json!({"b": [1, 2.5, null], "a": "x"}));
        round_trip(Sample {
            name: "n".into(),
            values: vec![0.1, 0.2],
            table: [("k".to_string(), 7)].into_iter().collect(),
            flag: Some(true),
        });
    }

    #[test]
    fn images_round_trip_bit_exactly() {
        let data: Vec<f32> = (0..12)
            .map(|i| i as f32 * 0.37 - 1.0)
            .chain([f32::NAN, -0.0, f32::INFINITY])
            .collect();
        let gray = GrayImage::from_vec(5, 3, data.clone()).unwrap();
        let mut bytes = Vec::new();
        gray.encode(&mut bytes);
        assert_eq!(bytes.len(), 5 + 16 + 15 * 4);
        // Header then raw little-endian samples.
        assert_eq!(&bytes[1..5], b"GRAY");
        assert_eq!(u64::from_le_bytes(bytes[5..13].try_into().unwrap()), 5);
        assert_eq!(u64::from_le_bytes(bytes[13..21].try_into().unwrap()), 3);
        assert_eq!(&bytes[21..25], &data[0].to_le_bytes());
        let back = GrayImage::decode(&bytes).unwrap();
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!((back.width, back.height), (5, 3));
        assert_eq!(bits(&back.data), bits(&data));
        let mut streamed = Vec::new();
        gray.encode_to(&mut streamed).unwrap();
        assert_eq!(streamed, bytes);
        let back = GrayImage::decode_from(&mut bytes.as_slice(), bytes.len() as u64).unwrap();
        assert_eq!(bits(&back.data), bits(&data));
        // A source shorter than the announced length (a file truncated meanwhile) is an error, not a panic.
        let err = GrayImage::decode_from(&mut &bytes[..40], bytes.len() as u64).unwrap_err();
        assert!(err.0.contains("cannot read cached gray image"), "{}", err.0);
        round_trip(RgbImage::filled(4, 2, [0.25, 0.5, 1.0]));
    }

    #[test]
    fn wrong_version_kind_and_size_are_explained() {
        let mut bytes = Vec::new();
        GrayImage::filled(2, 2, 1.0).encode(&mut bytes);
        let mut old = bytes.clone();
        old[0] = FORMAT_VERSION + 2;
        let msg = GrayImage::decode(&old).unwrap_err().0;
        assert!(
            msg.contains(&format!("format version {}", FORMAT_VERSION + 2))
                && msg.contains("cache gc"),
            "{msg}"
        );
        let msg = RgbImage::decode(&bytes).unwrap_err().0;
        assert!(msg.contains("GRAY") && msg.contains("RGB3"), "{msg}");
        let mut lying = bytes.clone();
        lying[5..13].copy_from_slice(&u64::MAX.to_le_bytes());
        let msg = GrayImage::decode(&lying).unwrap_err().0;
        assert!(msg.contains("should hold"), "{msg}");
        // A lying size header is caught before the stream decoder allocates anything.
        let msg = GrayImage::decode_from(&mut lying.as_slice(), lying.len() as u64)
            .unwrap_err()
            .0;
        assert!(msg.contains("should hold"), "{msg}");
        let msg = RgbImage::decode_from(&mut bytes.as_slice(), bytes.len() as u64)
            .unwrap_err()
            .0;
        assert!(msg.contains("GRAY") && msg.contains("RGB3"), "{msg}");
        let msg = u64::decode(&bytes).unwrap_err().0;
        assert!(msg.contains("not a u64"), "{msg}");
    }

    #[test]
    fn garbage_with_huge_lengths_fails_without_allocating() {
        // A varint length prefix of ~2^64 followed by nothing.
        let mut bytes = vec![FORMAT_VERSION];
        bytes.extend_from_slice(KIND_SERDE);
        bytes.extend_from_slice(&[253, 255, 255, 255, 255, 255, 255, 255, 127]);
        assert!(String::decode(&bytes).is_err());
        assert!(Vec::<String>::decode(&bytes).is_err());
        assert!(Vec::<f64>::decode(&bytes).is_err());
        // Trailing bytes are rejected.
        let mut two = Vec::new();
        7u64.encode(&mut two);
        two.push(0);
        assert!(u64::decode(&two).unwrap_err().0.contains("trailing"));
    }

    #[test]
    fn sparse_values_of_large_types_decode_despite_the_garbage_limit() {
        // 50 000 `None`s of a 520-byte type encode in ~50 kB but reserve 26 MB while decoding (more than a
        // 256-bytes-per-input-byte bound would allow).
        let sparse: Vec<Option<[[f64; 32]; 2]>> = vec![None; 50_000];
        let bytes = encode_serde(&sparse).unwrap();
        assert!(bytes.len() < 50_100);
        assert_eq!(
            decode_serde::<Vec<Option<[[f64; 32]; 2]>>>(&bytes)
                .unwrap()
                .len(),
            50_000
        );
    }

    #[test]
    fn params_are_canonical_and_distinguish_values() {
        #[derive(Serialize)]
        struct P {
            radius_m: f64,
            levels: u32,
        }
        let a = encode_params(&P {
            radius_m: 1.5,
            levels: 3,
        })
        .unwrap();
        assert_eq!(
            a,
            encode_params(&P {
                radius_m: 1.5,
                levels: 3
            })
            .unwrap()
        );
        assert_ne!(
            a,
            encode_params(&P {
                radius_m: 1.5000001,
                levels: 3
            })
            .unwrap()
        );
        assert_ne!(
            a,
            encode_params(&P {
                radius_m: 1.5,
                levels: 4
            })
            .unwrap()
        );
        assert_eq!(a[0], FORMAT_VERSION);
    }
}
