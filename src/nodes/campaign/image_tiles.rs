//! Ingested images as the nodes of one process read them: each pyramid file opened (and its index verified)
//! once, its tiles kept in one least-recently-used cache shared by all images, whose size is a quarter of the
//! memory budget (`skytie_stages::imaging::budget`). Many nodes read the same image — a panorama feeds its
//! orthos, three sparse-cloud triplets and dozens of patch registrations, an aerial frame every recording it
//! overlaps — so a tile is read from disk and hash-checked once while it stays in memory.

use crate::dag::StageError;
use crate::nodes::campaign::ingest::IngestedImage;
use skytie_stages::imaging::budget;
use skytie_stages::imaging::pyramid::{
    PyramidError, PyramidHeader, TileId, TileSource, TiledPyramid,
};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use std::sync::{Arc, Mutex, OnceLock};

/// At most this many pyramid files are kept open.
const MAX_OPEN: usize = 256;

type TileKey = ([u8; 32], TileId);

#[derive(Default)]
struct TileCache {
    tiles: HashMap<TileKey, (Arc<[u8]>, u64)>,
    by_age: BTreeMap<u64, TileKey>,
    bytes: usize,
    clock: u64,
}

impl TileCache {
    fn get(&mut self, key: &TileKey) -> Option<Arc<[u8]>> {
        self.clock += 1;
        let now = self.clock;
        let (tile, last) = self.tiles.get_mut(key)?;
        self.by_age.remove(last);
        *last = now;
        self.by_age.insert(now, *key);
        Some(Arc::clone(tile))
    }

    fn insert(&mut self, key: TileKey, tile: Arc<[u8]>, capacity: usize) {
        if self.tiles.contains_key(&key) {
            return;
        }
        self.clock += 1;
        self.bytes += tile.len();
        self.by_age.insert(self.clock, key);
        self.tiles.insert(key, (tile, self.clock));
        while self.bytes > capacity {
            let Some((_, oldest)) = self.by_age.pop_first() else {
                break;
            };
            if let Some((t, _)) = self.tiles.remove(&oldest) {
                self.bytes -= t.len();
            }
        }
    }
}

fn cache() -> &'static Mutex<TileCache> {
    static CACHE: OnceLock<Mutex<TileCache>> = OnceLock::new();
    CACHE.get_or_init(Default::default)
}

/// Bytes the tile cache may hold: a quarter of the memory budget.
pub fn cache_capacity() -> usize {
    budget::global().total() / 4
}

/// Bytes the tile cache holds now.
pub fn cached_bytes() -> usize {
    cache().lock().unwrap_or_else(|p| p.into_inner()).bytes
}

/// The open pyramid files, least recently used first, each with its index hash.
type OpenFiles = Vec<([u8; 32], Arc<TiledPyramid>)>;

fn open_files() -> &'static Mutex<OpenFiles> {
    static OPEN: OnceLock<Mutex<OpenFiles>> = OnceLock::new();
    OPEN.get_or_init(Default::default)
}

/// An ingested image's tiles through the shared cache.
pub struct CachedPyramid {
    file: Arc<TiledPyramid>,
    key: [u8; 32],
}

impl TileSource for CachedPyramid {
    fn header(&self) -> &PyramidHeader {
        self.file.header()
    }

    fn tile(&self, id: TileId) -> Result<Arc<[u8]>, PyramidError> {
        let key = (self.key, id);
        if let Some(t) = cache().lock().unwrap_or_else(|p| p.into_inner()).get(&key) {
            return Ok(t);
        }
        let tile = self.file.tile(id)?;
        cache().lock().unwrap_or_else(|p| p.into_inner()).insert(
            key,
            Arc::clone(&tile),
            cache_capacity(),
        );
        Ok(tile)
    }
}

/// The pyramid of an ingested image, opened once per process (its index checked against the hash its
/// ingestion recorded).
pub fn open(image: &IngestedImage) -> Result<CachedPyramid, StageError> {
    let key = image.index_hash;
    let mut open = open_files().lock().unwrap_or_else(|p| p.into_inner());
    if let Some(pos) = open.iter().position(|(k, _)| *k == key) {
        let entry = open.remove(pos);
        let file = Arc::clone(&entry.1);
        open.push(entry);
        return Ok(CachedPyramid { file, key });
    }
    let file = Arc::new(
        TiledPyramid::open(Path::new(&image.pyramid_path), &key).map_err(|e| {
            StageError::new(format!(
                "{} (the ingested copy of {}; `skytie cache verify` removes a damaged cache entry)",
                e, image.source
            ))
        })?,
    );
    if open.len() >= MAX_OPEN {
        open.remove(0);
    }
    open.push((key, Arc::clone(&file)));
    Ok(CachedPyramid { file, key })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_least_recently_used_tiles_leave_first() {
        let mut c = TileCache::default();
        let k = |i: usize| ([0u8; 32], (0, i, 0));
        let tile = || -> Arc<[u8]> { vec![0u8; 100].into() };
        c.insert(k(1), tile(), 250);
        c.insert(k(2), tile(), 250);
        assert!(c.get(&k(1)).is_some());
        c.insert(k(3), tile(), 250);
        assert!(c.get(&k(2)).is_none(), "tile 2 was the least recently used");
        assert!(c.get(&k(1)).is_some() && c.get(&k(3)).is_some());
        assert_eq!(c.bytes, 200);
    }
}
