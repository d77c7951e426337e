//! Decoded campaign images shared by all pages of one report: the variants of a sweep show registration views
//! of the same panoramas and aerial images, which are decoded once per report instead of once per variant.

use skytie_stages::imaging::io::load_gray;
use skytie_stages::imaging::GrayImage;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Grey images by path, decoded on first use. Holds only what the pages show (a few images per source).
#[derive(Default)]
pub struct ImageCache {
    images: Mutex<HashMap<PathBuf, Arc<GrayImage>>>,
}

impl ImageCache {
    /// The grey image at `path`, decoded once. Two pages asking at the same moment may both decode it; the
    /// result is the same image either way.
    pub fn gray(&self, path: &Path) -> Result<Arc<GrayImage>, String> {
        let cached = self
            .images
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .get(path)
            .cloned();
        if let Some(img) = cached {
            return Ok(img);
        }
        let img = Arc::new(load_gray(path).map_err(|e| format!("{}: {e}", path.display()))?);
        self.images
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .insert(path.to_path_buf(), Arc::clone(&img));
        Ok(img)
    }
}
