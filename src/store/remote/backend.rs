//! The remote object store behind the local cache: an `object_store` backend (S3, a folder or in-process
//! memory) with a small tokio current-thread runtime it owns, so the store's API stays synchronous. Every
//! call blocks the calling thread until its request is done; calls from several threads run concurrently.
//!
//! Objects are named by `/`-separated names relative to the URL's prefix (`objects/ab/cdef…`); this module
//! knows nothing of what they hold.

use std::collections::HashMap;
use std::io::{Read, Write};
use std::path::Path;
use std::sync::{Arc, Mutex, OnceLock};

use futures::StreamExt;
use object_store::memory::InMemory;
use object_store::path::{Path as ObjPath, PathPart};
use object_store::{ObjectStore, ObjectStoreExt, PutMode, PutOptions, PutPayload, WriteMultipart};

use super::url::{self, RemoteUrl};
use crate::store::error::StoreError;

/// Objects up to this size are uploaded with one conditional PUT; larger ones in parts (S3 limits a single
/// PUT to 5 GB; parts keep memory bounded).
const SINGLE_PUT_MAX_BYTES: u64 = 64 << 20;
/// Size of one part of a multipart upload.
const PART_BYTES: usize = 16 << 20;
/// Parts in flight at once during a multipart upload.
const PARTS_IN_FLIGHT: usize = 2;

/// In-process stores of `memory://NAME`, shared by every handle of the process with the same name.
fn memory_store(name: &str) -> Arc<InMemory> {
    static STORES: OnceLock<Mutex<HashMap<String, Arc<InMemory>>>> = OnceLock::new();
    let mut stores = STORES
        .get_or_init(|| Mutex::new(HashMap::new()))
        .lock()
        .unwrap_or_else(|p| p.into_inner());
    Arc::clone(
        stores
            .entry(name.to_string())
            .or_insert_with(|| Arc::new(InMemory::new())),
    )
}

/// One object found by [`Remote::list`].
#[derive(Clone, Debug)]
pub(crate) struct RemoteObject {
    /// Name relative to the remote's prefix.
    pub name: String,
    pub bytes: u64,
    /// Last modification, seconds since the Unix epoch.
    pub modified_unix_s: i64,
}

/// Outcome of a conditional upload.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Put {
    Created,
    /// Another writer stored the object first (same name, and for content-addressed names the same bytes).
    AlreadyThere,
}

/// An open remote store (see the module documentation).
pub struct Remote {
    url: String,
    store: Arc<dyn ObjectStore>,
    prefix: Vec<String>,
    runtime: tokio::runtime::Runtime,
}

impl std::fmt::Debug for Remote {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Remote").field("url", &self.url).finish()
    }
}

fn remote_err(
    url: &str,
    action: &'static str,
    name: &str,
    e: impl std::fmt::Display,
) -> StoreError {
    StoreError::Remote {
        action,
        url: url.to_string(),
        name: name.to_string(),
        message: e.to_string(),
    }
}

#[cfg(feature = "s3")]
fn open_s3(raw: &str, bucket: &str) -> Result<Arc<dyn ObjectStore>, StoreError> {
    // TLS through rustls with the ring provider (no C/cmake toolchain needed); installing twice is harmless.
    let _ = rustls::crypto::ring::default_provider().install_default();
    let s3 = object_store::aws::AmazonS3Builder::from_env()
        .with_bucket_name(bucket)
        .build()
        .map_err(|e| StoreError::RemoteUrl(format!(
            "cache remote `{raw}`: cannot set up S3: {e} (set AWS_ACCESS_KEY_ID, AWS_SECRET_ACCESS_KEY, AWS_REGION, and \
             AWS_ENDPOINT with AWS_ALLOW_HTTP=true for a MinIO server without TLS)"
        )))?;
    Ok(Arc::new(s3))
}

#[cfg(not(feature = "s3"))]
fn open_s3(raw: &str, _bucket: &str) -> Result<Arc<dyn ObjectStore>, StoreError> {
    Err(StoreError::RemoteUrl(format!(
        "cache remote `{raw}`: this skytie was built without S3 support (cargo feature `s3`, on by default): \
         rebuild it with default features, or use file:///PATH"
    )))
}

impl Remote {
    /// Opens the remote store at `raw_url` (see [`super::parse_url`]); a `file://` folder is created if missing.
    pub fn open(raw_url: &str) -> Result<Remote, StoreError> {
        let parsed = url::parse(raw_url).map_err(|e| StoreError::RemoteUrl(e.to_string()))?;
        let (store, prefix): (Arc<dyn ObjectStore>, String) = match &parsed {
            RemoteUrl::S3 { bucket, prefix } => (open_s3(raw_url, bucket)?, prefix.clone()),
            RemoteUrl::File { root } => {
                std::fs::create_dir_all(root)
                    .map_err(StoreError::io("create remote cache folder", root))?;
                let local =
                    object_store::local::LocalFileSystem::new_with_prefix(root).map_err(|e| {
                        StoreError::RemoteUrl(format!(
                            "cache remote `{raw_url}`: cannot use {} as an object store: {e}",
                            root.display()
                        ))
                    })?;
                (Arc::new(local), String::new())
            }
            RemoteUrl::Memory { name } => (memory_store(name), String::new()),
        };
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .map_err(|e| {
                StoreError::RemoteUrl(format!(
                    "cache remote `{raw_url}`: cannot start its I/O runtime: {e}"
                ))
            })?;
        Ok(Remote {
            url: raw_url.trim().to_string(),
            store,
            prefix: prefix
                .split('/')
                .filter(|s| !s.is_empty())
                .map(String::from)
                .collect(),
            runtime,
        })
    }

    /// The URL as given.
    pub fn url(&self) -> &str {
        &self.url
    }

    fn path(&self, name: &str) -> ObjPath {
        self.prefix
            .iter()
            .map(String::as_str)
            .chain(name.split('/').filter(|s| !s.is_empty()))
            .map(PathPart::from)
            .collect()
    }

    fn relative(&self, path: &ObjPath) -> Option<String> {
        let parts: Vec<String> = path.parts().map(|p| p.as_ref().to_string()).collect();
        let rest = parts.strip_prefix(self.prefix.as_slice())?;
        Some(rest.join("/"))
    }

    fn err(&self, action: &'static str, name: &str, e: impl std::fmt::Display) -> StoreError {
        remote_err(&self.url, action, name, e)
    }

    /// Streams object `name` into `sink`; `Ok(false)` when there is no such object.
    pub(crate) fn get_to(&self, name: &str, sink: &mut dyn Write) -> Result<bool, StoreError> {
        let path = self.path(name);
        self.runtime.block_on(async {
            let result = match self.store.get(&path).await {
                Ok(r) => r,
                Err(object_store::Error::NotFound { .. }) => return Ok(false),
                Err(e) => return Err(self.err("download", name, e)),
            };
            let mut stream = result.into_stream();
            while let Some(chunk) = stream.next().await {
                let chunk = chunk.map_err(|e| self.err("download", name, e))?;
                sink.write_all(&chunk)
                    .map_err(|e| self.err("store the download of", name, e))?;
            }
            Ok(true)
        })
    }

    /// Object `name` in memory (for small objects: records, manifests); `None` when there is none.
    pub(crate) fn get_bytes(&self, name: &str) -> Result<Option<Vec<u8>>, StoreError> {
        let mut out = Vec::new();
        Ok(self.get_to(name, &mut out)?.then_some(out))
    }

    /// Uploads `bytes` as `name`: with `create`, only if there is no object of that name yet (a conditional
    /// PUT); otherwise replacing it.
    pub(crate) fn put_bytes(
        &self,
        name: &str,
        bytes: Vec<u8>,
        create: bool,
    ) -> Result<Put, StoreError> {
        let path = self.path(name);
        let mode = if create {
            PutMode::Create
        } else {
            PutMode::Overwrite
        };
        let opts = PutOptions {
            mode,
            ..PutOptions::default()
        };
        self.runtime.block_on(async {
            match self
                .store
                .put_opts(&path, PutPayload::from(bytes), opts)
                .await
            {
                Ok(_) => Ok(Put::Created),
                Err(object_store::Error::AlreadyExists { .. }) => Ok(Put::AlreadyThere),
                Err(e) => Err(self.err("upload", name, e)),
            }
        })
    }

    /// Uploads the file `local` as `name` (conditionally with `create`, see [`Remote::put_bytes`]). Files above
    /// 64 MiB go up in parts, streamed from disk: with `create`, one existence check first (a multipart upload
    /// cannot be conditional everywhere; two writers of one content-addressed name upload the same bytes).
    pub(crate) fn put_file(
        &self,
        name: &str,
        local: &Path,
        create: bool,
    ) -> Result<Put, StoreError> {
        let mut file =
            std::fs::File::open(local).map_err(StoreError::io("open for upload", local))?;
        let len = file
            .metadata()
            .map_err(StoreError::io("open for upload", local))?
            .len();
        if len <= SINGLE_PUT_MAX_BYTES {
            let mut bytes = Vec::with_capacity(len as usize);
            file.read_to_end(&mut bytes)
                .map_err(StoreError::io("read for upload", local))?;
            return self.put_bytes(name, bytes, create);
        }
        if create && self.exists(name)? {
            return Ok(Put::AlreadyThere);
        }
        let path = self.path(name);
        self.runtime.block_on(async {
            let upload = self
                .store
                .put_multipart(&path)
                .await
                .map_err(|e| self.err("start the upload of", name, e))?;
            let mut writer = WriteMultipart::new_with_chunk_size(upload, PART_BYTES);
            let mut buf = vec![0u8; PART_BYTES];
            loop {
                let n = match file.read(&mut buf) {
                    Ok(0) => break,
                    Ok(n) => n,
                    Err(e) => {
                        let _ = writer.abort().await;
                        return Err(StoreError::io("read for upload", local)(e));
                    }
                };
                if let Err(e) = writer.wait_for_capacity(PARTS_IN_FLIGHT).await {
                    return Err(self.err("upload", name, e));
                }
                writer.write(&buf[..n]);
            }
            writer
                .finish()
                .await
                .map(|_| Put::Created)
                .map_err(|e| self.err("finish the upload of", name, e))
        })
    }

    /// Whether object `name` exists.
    pub(crate) fn exists(&self, name: &str) -> Result<bool, StoreError> {
        let path = self.path(name);
        self.runtime.block_on(async {
            match self.store.head(&path).await {
                Ok(_) => Ok(true),
                Err(object_store::Error::NotFound { .. }) => Ok(false),
                Err(e) => Err(self.err("look up", name, e)),
            }
        })
    }

    /// Deletes object `name`; `Ok(false)` when there was none.
    pub(crate) fn delete(&self, name: &str) -> Result<bool, StoreError> {
        let path = self.path(name);
        self.runtime.block_on(async {
            match self.store.delete(&path).await {
                Ok(()) => Ok(true),
                Err(object_store::Error::NotFound { .. }) => Ok(false),
                Err(e) => Err(self.err("delete", name, e)),
            }
        })
    }

    /// Every object whose name starts with the folder `dir` (e.g. `objects`), sorted by name.
    pub(crate) fn list(&self, dir: &str) -> Result<Vec<RemoteObject>, StoreError> {
        let path = self.path(dir);
        let mut out = self.runtime.block_on(async {
            let mut stream = self.store.list(Some(&path));
            let mut out = Vec::new();
            while let Some(meta) = stream.next().await {
                let meta = match meta {
                    Ok(m) => m,
                    Err(object_store::Error::NotFound { .. }) => continue,
                    Err(e) => return Err(self.err("list", dir, e)),
                };
                if let Some(name) = self.relative(&meta.location) {
                    out.push(RemoteObject {
                        name,
                        bytes: meta.size,
                        modified_unix_s: meta.last_modified.timestamp(),
                    });
                }
            }
            Ok(out)
        })?;
        out.sort_by(|a, b| a.name.cmp(&b.name));
        Ok(out)
    }
}
