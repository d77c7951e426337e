//! Geometry and header of a tiled pyramid file: how many levels, how many tiles per level, where each tile
//! lies in the file, and the fixed-size header that records it.
//!
//! File layout (little-endian): a [`HEADER_LEN`]-byte header, then every tile of level 0 row by row, then those
//! of level 1, …, then one [`TILE_HASH_LEN`]-byte blake3 hash per tile in the same order. Tiles are
//! `tile_side × tile_side` samples (1 byte for 8-bit images, 2 for 16-bit); a tile that reaches past the
//! level's right or bottom edge repeats the edge pixel, so every tile has the same size and its offset follows
//! from its index. Level `l + 1` halves level `l` (rounding up): level-`l` pixel `(c, r)` covers level-0 pixels
//! `[c·2^l, (c + 1)·2^l) × [r·2^l, (r + 1)·2^l)`, so continuous coordinates scale exactly by `2^l`.
//!
//! The header also records the image's **detail level** ([`PyramidLayout::detail_level`]): the finest level
//! that holds detail of its own. It is 0 for a photograph; for an image enlarged by pixel repetition (every
//! pixel of level `l` repeated 2^l × 2^l times) it is `l`, because the levels below it only repeat its pixels.
//! Stages never sample an image finer than its detail level, so such an image is read exactly like the one
//! it was enlarged from.

use std::fmt;

/// Bytes of the header at the start of a pyramid file.
pub const HEADER_LEN: usize = 64;
/// Bytes of one tile's hash (blake3) in the hash table.
pub const TILE_HASH_LEN: usize = 32;
/// The file magic (last byte: layout version).
pub const MAGIC: [u8; 8] = *b"SKYPYR\x00\x01";
/// Default tile side, pixels.
pub const DEFAULT_TILE_SIDE: usize = 256;
/// Levels stop once the longer side of a level is at most this many pixels (so a stage can always reduce an
/// image until a whole frame fits a few dozen pixels), or at [`MAX_LEVELS`].
pub const TOP_LEVEL_SIDE: usize = 32;
/// At most this many levels.
pub const MAX_LEVELS: usize = 24;

/// How a sample is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum SampleDepth {
    /// One byte per sample, 0..=255.
    U8,
    /// Two bytes per sample (little-endian), 0..=65535.
    U16,
}

impl SampleDepth {
    /// Bytes per sample.
    pub fn bytes(self) -> usize {
        match self {
            SampleDepth::U8 => 1,
            SampleDepth::U16 => 2,
        }
    }

    /// Bits per sample.
    pub fn bits(self) -> u32 {
        8 * self.bytes() as u32
    }

    fn code(self) -> u8 {
        self.bytes() as u8
    }

    fn from_code(code: u8) -> Option<Self> {
        match code {
            1 => Some(SampleDepth::U8),
            2 => Some(SampleDepth::U16),
            _ => None,
        }
    }
}

impl fmt::Display for SampleDepth {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}-bit", self.bits())
    }
}

/// Level sizes and tile grid of a pyramid.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PyramidLayout {
    pub width: usize,
    pub height: usize,
    pub depth: SampleDepth,
    pub tile_side: usize,
    /// (width, height) of every level, level 0 first.
    pub level_sizes: Vec<(usize, usize)>,
    /// The finest level holding detail of its own (module documentation): each level below it is its pixels
    /// repeated 2 × 2 times. 0 unless the builder found such repetition.
    pub detail_level: usize,
    /// Index of the first tile of every level, and the total tile count last.
    first_tile: Vec<usize>,
}

impl PyramidLayout {
    /// The layout of a `width × height` image; `None` for an empty image or a tile side outside 16..=4096.
    pub fn new(width: usize, height: usize, depth: SampleDepth, tile_side: usize) -> Option<Self> {
        if width == 0 || height == 0 || !(16..=4096).contains(&tile_side) {
            return None;
        }
        let mut level_sizes = vec![(width, height)];
        while level_sizes.len() < MAX_LEVELS {
            let (w, h) = *level_sizes.last().expect("level 0 exists");
            if w.max(h) <= TOP_LEVEL_SIDE {
                break;
            }
            level_sizes.push((w.div_ceil(2), h.div_ceil(2)));
        }
        let mut first_tile = Vec::with_capacity(level_sizes.len() + 1);
        let mut count = 0usize;
        for &(w, h) in &level_sizes {
            first_tile.push(count);
            count = count.checked_add(w.div_ceil(tile_side).checked_mul(h.div_ceil(tile_side))?)?;
        }
        first_tile.push(count);
        let layout = Self {
            width,
            height,
            depth,
            tile_side,
            level_sizes,
            detail_level: 0,
            first_tile,
        };
        // Every offset must fit a u64 (and this machine's file offsets).
        layout.file_len_checked()?;
        Some(layout)
    }

    /// Number of levels (level 0 = full resolution).
    pub fn levels(&self) -> usize {
        self.level_sizes.len()
    }

    /// Tiles across and down at `level`.
    pub fn tiles(&self, level: usize) -> (usize, usize) {
        let (w, h) = self.level_sizes[level];
        (w.div_ceil(self.tile_side), h.div_ceil(self.tile_side))
    }

    /// Total number of tiles over all levels.
    pub fn tile_count(&self) -> usize {
        *self.first_tile.last().expect("sentinel")
    }

    /// Bytes of one tile.
    pub fn tile_bytes(&self) -> usize {
        self.tile_side * self.tile_side * self.depth.bytes()
    }

    /// Index of tile (`level`, `tx`, `ty`) in file order, or `None` when the pyramid has no such tile.
    pub fn existing_tile_index(&self, (level, tx, ty): (usize, usize, usize)) -> Option<usize> {
        let (across, down) = self.tiles(level.min(self.levels() - 1));
        (level < self.levels() && tx < across && ty < down).then(|| self.tile_index(level, tx, ty))
    }

    /// Index of tile (`tx`, `ty`) of `level` in file order.
    pub fn tile_index(&self, level: usize, tx: usize, ty: usize) -> usize {
        let (across, _) = self.tiles(level);
        self.first_tile[level] + ty * across + tx
    }

    /// Byte offset of tile number `index` in the file.
    pub fn tile_offset(&self, index: usize) -> u64 {
        HEADER_LEN as u64 + index as u64 * self.tile_bytes() as u64
    }

    /// Byte offset of the hash table.
    pub fn hash_table_offset(&self) -> u64 {
        self.tile_offset(self.tile_count())
    }

    /// Bytes of the hash table.
    pub fn hash_table_len(&self) -> usize {
        self.tile_count() * TILE_HASH_LEN
    }

    /// Length of the whole file.
    pub fn file_len(&self) -> u64 {
        self.hash_table_offset() + self.hash_table_len() as u64
    }

    fn file_len_checked(&self) -> Option<u64> {
        let tiles = u64::try_from(self.tile_count()).ok()?;
        let body = tiles.checked_mul(self.tile_bytes() as u64 + TILE_HASH_LEN as u64)?;
        let total = body.checked_add(HEADER_LEN as u64)?;
        (total < i64::MAX as u64).then_some(total)
    }

    /// The header bytes for this layout with `white` (the sample value that maps to 1.0).
    pub fn encode_header(&self, white: u16) -> [u8; HEADER_LEN] {
        let mut h = [0u8; HEADER_LEN];
        h[..8].copy_from_slice(&MAGIC);
        h[8..16].copy_from_slice(&(self.width as u64).to_le_bytes());
        h[16..24].copy_from_slice(&(self.height as u64).to_le_bytes());
        h[24] = self.depth.code();
        h[25..29].copy_from_slice(&(self.tile_side as u32).to_le_bytes());
        h[29..31].copy_from_slice(&white.to_le_bytes());
        h[31] = self.levels() as u8;
        h[32] = self.detail_level as u8;
        h
    }

    /// The layout and white value a header describes; `Err` says what is wrong with it.
    pub fn decode_header(h: &[u8]) -> Result<(Self, u16), String> {
        if h.len() < HEADER_LEN || h[..8] != MAGIC {
            return Err("not a skytie tiled pyramid of this layout version (wrong magic)".into());
        }
        let u64_at = |i: usize| u64::from_le_bytes(h[i..i + 8].try_into().expect("8 bytes"));
        let width = usize::try_from(u64_at(8)).map_err(|_| "width does not fit".to_string())?;
        let height = usize::try_from(u64_at(16)).map_err(|_| "height does not fit".to_string())?;
        let depth = SampleDepth::from_code(h[24]).ok_or("unknown sample depth")?;
        let tile_side = u32::from_le_bytes(h[25..29].try_into().expect("4 bytes")) as usize;
        let white = u16::from_le_bytes([h[29], h[30]]);
        let layout = Self::new(width, height, depth, tile_side)
            .ok_or_else(|| format!("impossible size {width} × {height} / tile {tile_side}"))?;
        if usize::from(h[31]) != layout.levels() {
            return Err(format!(
                "header says {} levels, the size implies {}",
                h[31],
                layout.levels()
            ));
        }
        if white == 0 {
            return Err("white level 0".into());
        }
        let detail_level = usize::from(h[32]);
        if detail_level >= layout.levels() {
            return Err(format!(
                "header says detail level {detail_level} of {} levels",
                layout.levels()
            ));
        }
        Ok((
            Self {
                detail_level,
                ..layout
            },
            white,
        ))
    }
}

/// A pixel rectangle of one level: top-left corner (may lie outside the level) and size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelRect {
    pub x0: i64,
    pub y0: i64,
    pub width: usize,
    pub height: usize,
}

impl PixelRect {
    pub fn new(x0: i64, y0: i64, width: usize, height: usize) -> Self {
        Self {
            x0,
            y0,
            width,
            height,
        }
    }

    /// The smallest rectangle of whole pixels containing the continuous box [u0, u1) × [v0, v1); `None` for
    /// non-finite or empty boxes.
    pub fn covering(u0: f64, v0: f64, u1: f64, v1: f64) -> Option<Self> {
        let (c0, r0, c1, r1) = (u0.floor(), v0.floor(), u1.ceil(), v1.ceil());
        let ok = [c0, r0, c1, r1]
            .iter()
            .all(|v| v.is_finite() && v.abs() < 1e15);
        (ok && c1 > c0 && r1 > r0)
            .then(|| Self::new(c0 as i64, r0 as i64, (c1 - c0) as usize, (r1 - r0) as usize))
    }

    /// This rectangle clipped to `[0, w) × [0, h)`; `None` when nothing is left.
    pub fn clipped(&self, w: usize, h: usize) -> Option<Self> {
        let x0 = self.x0.max(0);
        let y0 = self.y0.max(0);
        let x1 = (self.x0 + self.width as i64).min(w as i64);
        let y1 = (self.y0 + self.height as i64).min(h as i64);
        (x1 > x0 && y1 > y0).then(|| Self::new(x0, y0, (x1 - x0) as usize, (y1 - y0) as usize))
    }

    pub fn area(&self) -> usize {
        self.width * self.height
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_halve_rounding_up_until_one_tile() {
        let l = PyramidLayout::new(26460, 17004, SampleDepth::U8, 256).unwrap();
        assert_eq!(l.level_sizes[0], (26460, 17004));
        assert_eq!(l.level_sizes[1], (13230, 8502));
        assert_eq!(l.level_sizes[2], (6615, 4251));
        assert_eq!(l.level_sizes[3], (3308, 2126));
        let last = *l.level_sizes.last().unwrap();
        assert!(last.0 <= 32 && last.1 <= 32);
        assert_eq!(l.levels(), 11);
        assert_eq!(l.tiles(0), (104, 67));
        // 1-px images have one level of one tile.
        let one = PyramidLayout::new(1, 1, SampleDepth::U16, 256).unwrap();
        assert_eq!((one.levels(), one.tile_count()), (1, 1));
        assert_eq!(one.tile_bytes(), 256 * 256 * 2);
    }

    #[test]
    fn offsets_are_contiguous_and_the_header_round_trips() {
        let l = PyramidLayout::new(1000, 600, SampleDepth::U16, 128).unwrap();
        assert_eq!(l.tile_index(0, 0, 0), 0);
        assert_eq!(l.tile_index(1, 0, 0), 8 * 5);
        assert_eq!(l.levels(), 6); // 1000 → 500 → 250 → 125 → 63 → 32
        assert_eq!(l.tile_offset(1) - l.tile_offset(0), 128 * 128 * 2);
        assert_eq!(
            l.file_len(),
            64 + l.tile_count() as u64 * (128 * 128 * 2 + 32)
        );
        let (back, white) = PyramidLayout::decode_header(&l.encode_header(4095)).unwrap();
        assert_eq!((back, white), (l.clone(), 4095));
        let detailed = PyramidLayout {
            detail_level: 2,
            ..l.clone()
        };
        let (back, _) = PyramidLayout::decode_header(&detailed.encode_header(255)).unwrap();
        assert_eq!(back.detail_level, 2);
        let mut bad = l.encode_header(1);
        bad[31] = 9;
        assert!(PyramidLayout::decode_header(&bad).is_err());
        let mut bad = l.encode_header(1);
        bad[32] = 6;
        assert!(PyramidLayout::decode_header(&bad).is_err());
        assert!(PyramidLayout::decode_header(&[0u8; 64]).is_err());
    }

    #[test]
    fn absurd_sizes_have_no_layout() {
        assert!(PyramidLayout::new(0, 10, SampleDepth::U8, 256).is_none());
        assert!(PyramidLayout::new(usize::MAX / 2, usize::MAX / 2, SampleDepth::U8, 256).is_none());
    }

    #[test]
    fn covering_and_clipping() {
        let r = PixelRect::covering(-1.5, 2.2, 10.1, 3.0).unwrap();
        assert_eq!(r, PixelRect::new(-2, 2, 13, 1));
        assert_eq!(r.clipped(5, 5), Some(PixelRect::new(0, 2, 5, 1)));
        assert!(PixelRect::covering(1.0, 1.0, 1.0, 2.0).is_none());
        assert!(PixelRect::covering(f64::NAN, 0.0, 1.0, 1.0).is_none());
        assert!(r.clipped(0, 5).is_none());
    }
}
