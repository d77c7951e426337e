//! A render store: the images of a synthetic campaign generation kept outside the (atomically installed)
//! output folder, so a generation that is interrupted — a `paper` campaign renders for hours — resumes where it
//! stopped instead of starting over.
//!
//! Layout: `<store>/manifest.json` says which generation the images belong to (the options and the generator's
//! version); `<store>/<relative path>` is a finished image and `<store>/<relative path>.blake3` its hash. An
//! image is written first, then its hash, each atomically, so an image without a matching hash is never used:
//! it is rendered again. A store whose manifest differs from the current generation's is emptied.
//! Images are byte-identical whatever the thread count, so a resumed campaign equals an uninterrupted one.

use super::SynthError;
use crate::fsutil::atomic_write;
use std::path::{Path, PathBuf};

/// Bump when the rendered bytes of an image for the same options change (renderer, post-processing, encoder).
const STORE_FORMAT: &str = "1";

const MANIFEST: &str = "manifest.json";
const HASH_SUFFIX: &str = ".blake3";

/// Finished images of one generation (see the module doc).
#[derive(Debug)]
pub struct RenderStore {
    dir: PathBuf,
}

impl RenderStore {
    /// Open (or create) the store at `dir` for the generation identified by `identity` (e.g. the options as
    /// JSON); a store left by a different generation is emptied first.
    pub fn open(dir: &Path, identity: &str) -> Result<Self, SynthError> {
        let manifest = format!(
            "{{\"store_format\":\"{STORE_FORMAT}\",\"generator\":\"{}\",\"identity\":{}}}\n",
            env!("CARGO_PKG_VERSION"),
            serde_json::Value::String(identity.to_string())
        );
        let path = dir.join(MANIFEST);
        let same = std::fs::read_to_string(&path).is_ok_and(|m| m == manifest);
        if !same {
            if dir.exists() {
                std::fs::remove_dir_all(dir).map_err(|e| SynthError::io(dir, e))?;
            }
            std::fs::create_dir_all(dir).map_err(|e| SynthError::io(dir, e))?;
            atomic_write(&path, manifest.as_bytes()).map_err(|e| SynthError::io(&path, e))?;
        }
        Ok(Self {
            dir: dir.to_path_buf(),
        })
    }

    /// The folder of the store.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Put the stored image `rel` (relative path with '/') at `dest` when the store has it with a matching
    /// hash; returns whether it did. A stored image whose hash does not match is removed.
    pub fn fetch(&self, rel: &str, dest: &Path) -> Result<bool, SynthError> {
        let (image, hash) = self.paths(rel);
        let (Ok(bytes), Ok(expected)) = (std::fs::read(&image), std::fs::read_to_string(&hash))
        else {
            return Ok(false);
        };
        if blake3::hash(&bytes).to_hex().as_str() != expected.trim() {
            let _ = std::fs::remove_file(&hash);
            let _ = std::fs::remove_file(&image);
            return Ok(false);
        }
        atomic_write(dest, &bytes).map_err(|e| SynthError::io(dest, e))?;
        Ok(true)
    }

    /// Keep a copy of the finished image `src` as `rel`, then its hash.
    pub fn keep(&self, rel: &str, src: &Path) -> Result<(), SynthError> {
        let (image, hash) = self.paths(rel);
        if let Some(parent) = image.parent() {
            std::fs::create_dir_all(parent).map_err(|e| SynthError::io(parent, e))?;
        }
        let bytes = std::fs::read(src).map_err(|e| SynthError::io(src, e))?;
        atomic_write(&image, &bytes).map_err(|e| SynthError::io(&image, e))?;
        let hex = blake3::hash(&bytes).to_hex();
        atomic_write(&hash, format!("{hex}\n").as_bytes()).map_err(|e| SynthError::io(&hash, e))
    }

    /// Delete the store (after the campaign was installed).
    pub fn remove(self) -> Result<(), SynthError> {
        std::fs::remove_dir_all(&self.dir).map_err(|e| SynthError::io(&self.dir, e))
    }

    fn paths(&self, rel: &str) -> (PathBuf, PathBuf) {
        let image = self.dir.join(rel);
        let mut hash = image.clone().into_os_string();
        hash.push(HASH_SUFFIX);
        (image, PathBuf::from(hash))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kept_images_are_fetched_and_corrupt_or_unhashed_ones_are_not() {
        let t = tempfile::tempdir().unwrap();
        let store_dir = t.path().join("store");
        let src = t.path().join("a.jpg");
        std::fs::write(&src, b"image bytes").unwrap();
        let store = RenderStore::open(&store_dir, "options-1").unwrap();
        store.keep("mm/panoramas/a.jpg", &src).unwrap();
        let dest = t.path().join("out.jpg");
        assert!(store.fetch("mm/panoramas/a.jpg", &dest).unwrap());
        assert_eq!(std::fs::read(&dest).unwrap(), b"image bytes");
        assert!(!store.fetch("mm/panoramas/missing.jpg", &dest).unwrap());

        // Reopened for the same generation: still there. Corrupted: not used, and removed.
        let store = RenderStore::open(&store_dir, "options-1").unwrap();
        assert!(store.fetch("mm/panoramas/a.jpg", &dest).unwrap());
        std::fs::write(store_dir.join("mm/panoramas/a.jpg"), b"image bytez").unwrap();
        assert!(!store.fetch("mm/panoramas/a.jpg", &dest).unwrap());
        assert!(!store_dir.join("mm/panoramas/a.jpg").exists());

        // An image whose hash was never written (interrupted between the two writes) is not used.
        store.keep("b.jpg", &src).unwrap();
        std::fs::remove_file(store_dir.join("b.jpg.blake3")).unwrap();
        assert!(!store.fetch("b.jpg", &dest).unwrap());

        // A different generation empties the store.
        store.keep("c.jpg", &src).unwrap();
        let store = RenderStore::open(&store_dir, "options-2").unwrap();
        assert!(!store.fetch("c.jpg", &dest).unwrap());
        store.remove().unwrap();
        assert!(!store_dir.exists());
    }
}
