//! The remote side of the cache: S3-compatible object storage (or a folder, or memory in tests) behind the
//! local cache folder, through the `object_store` crate.
//!
//! The local cache stays the cache in front: a load looks locally first; on a miss it downloads the entry
//! from the remote, verifies it (header, key, blake3 of the payload against the hash the header records) and
//! installs it locally atomically; a save writes locally, then uploads with a conditional PUT
//! (`PutMode::Create`: a second writer of the same key is told the object exists, which is harmless — the name
//! is the key of a deterministic result, so the bytes are the same). Nothing read from the remote is trusted
//! unverified: a damaged remote object is reported, deleted from the remote and recomputed.
//!
//! Remote layout, below the URL's prefix:
//! - `objects/<2 hex>/<62 hex>` — entries, the bytes of the local entry files ([`entries`]);
//! - `dirs/<key>/<path>`, `dirs/<key>.manifest` — generated folders and their manifests ([`dirs`]);
//! - `records/<namespace>/<blake3(name) hex>` — side records (node records, output hashes, failures), the
//!   bytes of the local record files; mutable, last writer wins.
//!
//! Run leases stay local (`<cache>/runs/`): they protect a host's own runs from its own local `gc`; the remote
//! collection ([`gc`]) protects runs on other hosts by a minimum object age instead.

mod backend;
pub mod dirs;
pub mod entries;
pub mod gc;
mod url;
pub mod verify;

pub use backend::Remote;
pub use gc::RemoteGcReport;
pub use url::{parse as parse_url, RemoteUrl, UrlError};
pub use verify::{BadRemoteObject, RemoteVerifyReport};
