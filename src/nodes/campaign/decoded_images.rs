//! Decoded images shared by the nodes of one process. Many nodes read the same file: a panorama feeds three
//! sparse-cloud triplets and dozens of patch-registration nodes (more in a sweep), an aerial image every
//! recording it overlaps. Each file is decoded once while it stays within a byte budget (least recently used
//! images leave first). Entries are keyed by the file's content hash, which the engine computed for the
//! node's key, so an edited file is never served from memory.

use crate::dag::RawFileValue;
use crate::dag::StageError;
use crate::hashing::ContentHash;
use skytie_stages::imaging::io::load_gray;
use skytie_stages::imaging::GrayImage;
use std::sync::{Arc, Mutex, OnceLock};

/// Largest total size of the decoded images kept, bytes (a `paper` panorama is 46 MB as f32 grey).
const BUDGET_BYTES: usize = 768 << 20;

struct Entry {
    hash: ContentHash,
    image: Arc<GrayImage>,
    last_use: u64,
}

#[derive(Default)]
struct Memory {
    entries: Vec<Entry>,
    bytes: usize,
    clock: u64,
}

fn memory() -> &'static Mutex<Memory> {
    static MEMORY: OnceLock<Mutex<Memory>> = OnceLock::new();
    MEMORY.get_or_init(Default::default)
}

fn size_bytes(img: &GrayImage) -> usize {
    img.data.len() * std::mem::size_of::<f32>()
}

/// The grey image of `file`, decoded at most once per process while it fits the budget. Two nodes asking at
/// the same moment may both decode it; the result is the same either way.
pub fn gray(file: &RawFileValue) -> Result<Arc<GrayImage>, StageError> {
    {
        let mut m = memory().lock().unwrap_or_else(|p| p.into_inner());
        m.clock += 1;
        let now = m.clock;
        if let Some(e) = m.entries.iter_mut().find(|e| e.hash == file.hash) {
            e.last_use = now;
            return Ok(Arc::clone(&e.image));
        }
    }
    let image = Arc::new(load_gray(&file.path).map_err(|e| StageError::new(e.to_string()))?);
    let mut m = memory().lock().unwrap_or_else(|p| p.into_inner());
    if m.entries.iter().any(|e| e.hash == file.hash) {
        return Ok(image);
    }
    m.clock += 1;
    let now = m.clock;
    m.bytes += size_bytes(&image);
    m.entries.push(Entry {
        hash: file.hash,
        image: Arc::clone(&image),
        last_use: now,
    });
    // Evict the least recently used images (never the one just added) until the budget holds.
    while m.bytes > BUDGET_BYTES && m.entries.len() > 1 {
        let oldest = m
            .entries
            .iter()
            .enumerate()
            .filter(|(_, e)| e.hash != file.hash)
            .min_by_key(|(_, e)| e.last_use)
            .map(|(i, _)| i);
        let Some(i) = oldest else { break };
        let e = m.entries.swap_remove(i);
        m.bytes -= size_bytes(&e.image);
    }
    Ok(image)
}
