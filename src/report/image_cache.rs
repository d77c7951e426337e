//! Windows of campaign images shared by all pages of one report: the variants of a sweep draw the same map
//! backgrounds and registration views, whose image windows are decoded once per report instead of once per
//! variant. A window is read at the pyramid level its figure needs
//! (`skytie_stages::imaging::partial::PartialPyramid`: the file decoded once, only the tiles under the
//! window kept), so memory follows the figures' sizes, not the images'. The cache holds at most a quarter of
//! the memory budget (`skytie_stages::imaging::budget`); the least recently used windows leave first.

use skytie_stages::imaging::budget;
use skytie_stages::imaging::partial::{PartialPyramid, Region};
use skytie_stages::imaging::pyramid::ScaledWindow;
use std::collections::{HashMap, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// A window request: file, level, box (f64 bits, so equal requests compare equal).
type Key = (PathBuf, usize, [u64; 4]);

#[derive(Default)]
struct Windows {
    windows: HashMap<Key, Arc<ScaledWindow>>,
    /// Keys from least to most recently used.
    order: VecDeque<Key>,
    bytes: usize,
}

impl Windows {
    fn get(&mut self, key: &Key) -> Option<Arc<ScaledWindow>> {
        let w = Arc::clone(self.windows.get(key)?);
        if let Some(pos) = self.order.iter().position(|k| k == key) {
            let k = self.order.remove(pos).expect("position is in range");
            self.order.push_back(k);
        }
        Some(w)
    }

    fn insert(&mut self, key: Key, window: Arc<ScaledWindow>, capacity: usize) {
        let size = window_bytes(&window);
        if size > capacity || self.windows.contains_key(&key) {
            return;
        }
        while self.bytes + size > capacity {
            let Some(oldest) = self.order.pop_front() else {
                break;
            };
            if let Some(w) = self.windows.remove(&oldest) {
                self.bytes -= window_bytes(&w);
            }
        }
        self.bytes += size;
        self.order.push_back(key.clone());
        self.windows.insert(key, window);
    }
}

fn window_bytes(w: &ScaledWindow) -> usize {
    w.image.data.len() * std::mem::size_of::<f32>()
}

/// Image windows by request, decoded on first use; see the module documentation.
#[derive(Default)]
pub struct ImageCache {
    windows: Mutex<Windows>,
}

impl ImageCache {
    /// The window of pyramid `level` of the image at `path` covering the continuous full-resolution box
    /// `[u0, v0, u1, v1)` (clipped to the image; `None` when it misses it), decoded once. Two pages asking at
    /// the same moment may both decode it; the result is the same window either way.
    pub fn window(
        &self,
        path: &Path,
        level: usize,
        box_full_px: [f64; 4],
    ) -> Result<Option<Arc<ScaledWindow>>, String> {
        let key: Key = (path.to_path_buf(), level, box_full_px.map(f64::to_bits));
        if let Some(w) = self.lock().get(&key) {
            return Ok(Some(w));
        }
        let pyramid = PartialPyramid::decode(path, |_| vec![Region::window(level, box_full_px)])
            .map_err(|e| e.to_string())?;
        let Some(window) = ScaledWindow::read(&pyramid, level, box_full_px)
            .map_err(|e| format!("{}: {e}", path.display()))?
        else {
            return Ok(None);
        };
        drop(pyramid);
        let window = Arc::new(window);
        self.lock()
            .insert(key, Arc::clone(&window), budget::global().total() / 4);
        Ok(Some(window))
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Windows> {
        self.windows
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use skytie_stages::imaging::pyramid::PixelRect;
    use skytie_stages::imaging::GrayImage;

    fn window(side: usize) -> Arc<ScaledWindow> {
        Arc::new(ScaledWindow {
            image: GrayImage::filled(side, side, 0.0),
            level: 0,
            rect: PixelRect::new(0, 0, side, side),
            level_size: (side, side),
            full_size: (side, side),
        })
    }

    #[test]
    fn the_least_recently_used_windows_leave_first_and_the_bytes_stay_bounded() {
        let key = |i: u64| (PathBuf::from("a.png"), 0, [i, 0, 0, 0]);
        let mut w = Windows::default();
        let capacity = 2 * 10 * 10 * 4;
        w.insert(key(1), window(10), capacity);
        w.insert(key(2), window(10), capacity);
        assert!(w.get(&key(1)).is_some());
        w.insert(key(3), window(10), capacity);
        assert!(
            w.get(&key(2)).is_none(),
            "window 2 was the least recently used"
        );
        assert!(w.get(&key(1)).is_some() && w.get(&key(3)).is_some());
        assert_eq!(w.bytes, capacity);
        w.insert(key(4), window(100), capacity);
        assert!(w.get(&key(4)).is_none(), "larger than the whole cache");
        assert_eq!(w.bytes, capacity);
    }
}
