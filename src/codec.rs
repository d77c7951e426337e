//! Every byte encoding of cached artifacts and of node parameters lives here, so a change of encoding is a
//! one-file change.
//!
//! An encoded artifact starts with [`FORMAT_VERSION`] (one byte) and a 4-byte kind magic, then the body:
//! - `SERD`: bincode 2 (serde, standard config) of the value — used by [`serde_artifact!`] types and the
//!   built-in scalars/vectors;
//! - `GRAY` / `RGB3`: image width and height (u64 little-endian) followed by the raw `f32` samples as
//!   little-endian bytes (memcpy speed; a 4000×3000 image is 48 MB);
//! - `BYTE`: length (u64 little-endian) and raw bytes (`Vec<u8>`); `JSON`: JSON text (`serde_json::Value`).
//!
//! Decoding checks version, kind and length and returns a [`CodecError`] that says what is wrong; it never
//! panics and never allocates more than a bounded multiple of the input on garbage.

use serde::de::DeserializeOwned;
use serde::Serialize;
use skytie_stages::imaging::{GrayImage, RgbImage};

/// Version of the artifact encoding; bump it whenever any encoding below changes.
pub const FORMAT_VERSION: u8 = 1;

const KIND_SERDE: &[u8; 4] = b"SERD";
const KIND_GRAY: &[u8; 4] = b"GRAY";
const KIND_RGB: &[u8; 4] = b"RGB3";
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
pub trait Artifact: Sized + Send + Sync + 'static {
    /// Appends the encoding of `self` to `out`.
    fn encode(&self, out: &mut Vec<u8>);
    /// Decodes a value encoded by [`Artifact::encode`] (the whole slice).
    fn decode(bytes: &[u8]) -> Result<Self, CodecError>;
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

/// Decodes an artifact produced by [`encode_serde`] (or by a [`serde_artifact!`] type's `encode`).
pub fn decode_serde<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, CodecError> {
    let body = open_frame(bytes, KIND_SERDE, std::any::type_name::<T>())?;
    decode_serde_exact(body)
}

/// Appends the artifact encoding of a serde value; used by [`serde_artifact!`].
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

/// Appends `samples` as little-endian `f32` bytes.
#[cfg(target_endian = "little")]
fn put_f32_le(out: &mut Vec<u8>, samples: &[f32]) {
    // SAFETY: `f32` has no padding and every bit pattern is a valid `u8` sequence; `u8` needs no alignment;
    // the byte slice covers exactly the samples' memory and lives as long as `samples`. On a little-endian
    // target the in-memory bytes of an `f32` are its little-endian encoding, so this is a plain memcpy.
    let raw = unsafe {
        std::slice::from_raw_parts(
            samples.as_ptr().cast::<u8>(),
            std::mem::size_of_val(samples),
        )
    };
    out.extend_from_slice(raw);
}

/// Appends `samples` as little-endian `f32` bytes (portable path for big-endian targets).
#[cfg(not(target_endian = "little"))]
fn put_f32_le(out: &mut Vec<u8>, samples: &[f32]) {
    let start = out.len();
    out.resize(start + samples.len() * 4, 0);
    for (dst, v) in out[start..].chunks_exact_mut(4).zip(samples) {
        dst.copy_from_slice(&v.to_le_bytes());
    }
}

/// Reads little-endian `f32` samples (`bytes.len()` is a multiple of 4, checked by the caller).
#[cfg(target_endian = "little")]
fn get_f32_le(bytes: &[u8]) -> Vec<f32> {
    let n = bytes.len() / 4;
    let mut samples: Vec<f32> = Vec::with_capacity(n);
    // SAFETY: the destination has capacity for `n` f32 = `4 n` bytes and does not overlap `bytes`; any 4 bytes
    // are a valid `f32`; on a little-endian target the little-endian encoding is the in-memory layout. The
    // length is set only after all `n` samples are initialised.
    unsafe {
        std::ptr::copy_nonoverlapping(bytes.as_ptr(), samples.as_mut_ptr().cast::<u8>(), n * 4);
        samples.set_len(n);
    }
    samples
}

/// Reads little-endian `f32` samples (portable path for big-endian targets).
#[cfg(not(target_endian = "little"))]
fn get_f32_le(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

fn encode_image(out: &mut Vec<u8>, kind: &[u8; 4], width: usize, height: usize, samples: &[f32]) {
    out.reserve(FRAME_LEN + 16 + samples.len() * 4);
    push_frame(out, kind);
    out.extend_from_slice(&(width as u64).to_le_bytes());
    out.extend_from_slice(&(height as u64).to_le_bytes());
    put_f32_le(out, samples);
}

/// Decodes an image body; `channels` samples per pixel. Returns (width, height, samples).
fn decode_image(
    bytes: &[u8],
    kind: &[u8; 4],
    type_name: &str,
    channels: usize,
) -> Result<(usize, usize, Vec<f32>), CodecError> {
    let body = open_frame(bytes, kind, type_name)?;
    if body.len() < 16 {
        return Err(CodecError::new(format!(
            "cached {type_name} is truncated: its size header needs 16 bytes, found {}; {INCOMPATIBLE}",
            body.len()
        )));
    }
    let width = u64::from_le_bytes(body[0..8].try_into().expect("8-byte slice"));
    let height = u64::from_le_bytes(body[8..16].try_into().expect("8-byte slice"));
    let samples = &body[16..];
    let expected = width
        .checked_mul(height)
        .and_then(|n| n.checked_mul(channels as u64 * 4))
        .filter(|&n| n == samples.len() as u64);
    let (Some(_), Ok(width), Ok(height)) =
        (expected, usize::try_from(width), usize::try_from(height))
    else {
        return Err(CodecError::new(format!(
            "cached {type_name} of {width}×{height} px should hold {width}×{height}×{channels} f32 samples but has \
             {} bytes of samples: the entry is damaged; {INCOMPATIBLE}",
            samples.len()
        )));
    };
    Ok((width, height, get_f32_le(samples)))
}

impl Artifact for GrayImage {
    fn encode(&self, out: &mut Vec<u8>) {
        encode_image(out, KIND_GRAY, self.width, self.height, &self.data);
    }
    fn decode(bytes: &[u8]) -> Result<Self, CodecError> {
        let (width, height, data) = decode_image(bytes, KIND_GRAY, "gray image", 1)?;
        Ok(GrayImage {
            width,
            height,
            data,
        })
    }
}

impl Artifact for RgbImage {
    fn encode(&self, out: &mut Vec<u8>) {
        encode_image(out, KIND_RGB, self.width, self.height, &self.data);
    }
    fn decode(bytes: &[u8]) -> Result<Self, CodecError> {
        let (width, height, data) = decode_image(bytes, KIND_RGB, "RGB image", 3)?;
        Ok(RgbImage {
            width,
            height,
            data,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;
    use std::collections::BTreeMap;

    fn round_trip<T: Artifact + PartialEq + std::fmt::Debug>(value: T) {
        let mut bytes = Vec::new();
        value.encode(&mut bytes);
        assert_eq!(bytes[0], FORMAT_VERSION);
        assert_eq!(T::decode(&bytes).unwrap(), value);
        // Every truncation fails cleanly.
        for cut in 0..bytes.len() {
            assert!(
                T::decode(&bytes[..cut]).is_err(),
                "decoding {cut} of {} bytes succeeded",
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
