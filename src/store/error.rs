//! Errors of the artifact store: every message names the file and says what to do.

use std::io;
use std::path::{Path, PathBuf};

/// A store operation failed (the cache folder is unusable, or a name is invalid).
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// A file-system operation on the cache failed.
    #[error(
        "cache: cannot {action} {}: {source} (check permissions and free space, or use another cache folder with \
         --cache DIR / SKYTIE_CACHE)",
        path.display()
    )]
    Io {
        action: &'static str,
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    /// A record namespace is not a plain folder name.
    #[error(
        "cache: record namespace `{0}` is invalid: use 1–64 characters from A–Z, a–z, 0–9, '_', '-', '.', not \
         starting with '.'"
    )]
    InvalidNamespace(String),
    /// A request to the remote cache failed.
    #[error(
        "cache remote {url}: cannot {action} {name}: {message} (check the URL, the AWS_* credentials and endpoint, and \
         the network; without --cache-remote and SKYTIE_CACHE_REMOTE the local cache is used alone)"
    )]
    Remote {
        action: &'static str,
        url: String,
        name: String,
        message: String,
    },
    /// The remote cache URL is invalid or the remote cannot be set up (the message says what to do).
    #[error("{0}")]
    RemoteUrl(String),
    /// Entry metadata too large for the entry header.
    #[error("cache: metadata of entry {key} is {len} bytes, more than the {max}-byte limit (shorten the item name)")]
    MetaTooLarge { key: String, len: usize, max: usize },
}

impl StoreError {
    /// Wraps an I/O error with the action and the file it concerns.
    pub(crate) fn io<'a>(
        action: &'static str,
        path: &'a Path,
    ) -> impl FnOnce(io::Error) -> StoreError + 'a {
        move |source| StoreError::Io {
            action,
            path: path.to_path_buf(),
            source,
        }
    }
}
