//! `ingest`: one image file (panorama, nadir or oblique frame) decoded once into a tiled, multi-resolution grey
//! pyramid in the node's cache folder (`skytie_stages::imaging::ingest`), which every later stage reads window
//! by window at the resolution it works at. The output records where the pyramid lies and the hash that
//! authenticates its index (and through it every tile); a pyramid file that went missing, changed size or whose
//! index no longer matches that hash is rebuilt. A file that does not decode fails this node only, with the file and the decoder's reason; its
//! dependents are skipped and counted.

use crate::dag::{
    BuildError, DagBuilder, Handle, InputsOf, NodeCtx, RawFile, RunResult, Stage, StageError,
};
use crate::workflow::{ParamError, StageParams};
use serde::{Deserialize, Serialize};
use skytie_stages::imaging::decode::{GeoTiffTags, ImageFormat};
use skytie_stages::imaging::ingest::ingest_with_tiles;
use skytie_stages::imaging::pyramid::{SampleDepth, TiledPyramid, DEFAULT_TILE_SIDE};
use std::path::Path;

/// File name of the pyramid in the node's folder.
const PYRAMID_FILE: &str = "image.pyr";

/// Parameters of ingestion.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IngestParams {
    /// Side of the square tiles, pixels (a multiple of 16 in [64, 2048]; default 256).
    pub tile_side_px: usize,
}

impl Default for IngestParams {
    fn default() -> Self {
        Self {
            tile_side_px: DEFAULT_TILE_SIDE,
        }
    }
}

impl StageParams for IngestParams {
    fn validate(&self) -> Result<(), Vec<ParamError>> {
        let t = self.tile_side_px;
        if (64..=2048).contains(&t) && t.is_multiple_of(16) {
            Ok(())
        } else {
            Err(vec![ParamError::new(
                "tile_side_px",
                format!("must be a multiple of 16 in [64, 2048] px, got {t}"),
            )])
        }
    }
}

/// An ingested image: its source, size and sample depth, and the pyramid file that holds it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IngestedImage {
    /// The source file (for messages).
    pub source: String,
    pub format: ImageFormat,
    pub width: u64,
    pub height: u64,
    pub depth: SampleDepth,
    /// The sample value that maps to grey 1.0.
    pub white: u16,
    pub levels: u32,
    /// The finest level holding detail of its own (`PyramidLayout::detail_level`; 0 unless the image was
    /// enlarged by pixel repetition).
    #[serde(default)]
    pub detail_level: u32,
    /// Absolute path of the pyramid file in the cache.
    pub pyramid_path: String,
    /// blake3 of the pyramid's header and tile hashes.
    pub index_hash: [u8; 32],
    pub file_len: u64,
    /// GeoTIFF tags of the source, when it has them.
    pub geotiff: Option<GeoTiffTags>,
}
crate::serde_artifact!(IngestedImage);

/// The ingestion node.
pub struct Ingest;

impl Stage for Ingest {
    crate::nodes::stage_types!(named "ingest" version "2", IngestParams => IngestedImage, inputs: RawFile);

    fn run(&self, p: &IngestParams, file: InputsOf<Self>, ctx: &NodeCtx) -> RunResult<Self> {
        let tmp = ctx.output_dir_tmp()?;
        let done = ingest_with_tiles(&file.path, &tmp.join(PYRAMID_FILE), p.tile_side_px)
            .map_err(|e| StageError::new(e.to_string()))?;
        let layout = &done.pyramid.layout;
        Ok(IngestedImage {
            source: file.path.display().to_string(),
            format: done.info.format,
            width: layout.width as u64,
            height: layout.height as u64,
            depth: layout.depth,
            white: done.pyramid.white,
            levels: layout.levels() as u32,
            detail_level: layout.detail_level as u32,
            pyramid_path: ctx
                .output_dir()
                .join(PYRAMID_FILE)
                .to_string_lossy()
                .into_owned(),
            index_hash: done.pyramid.index_hash,
            file_len: done.pyramid.file_len,
            geotiff: done.info.geotiff,
        })
    }

    /// A cached pyramid is used only when its length and its index (header and tile hash table, a few kB)
    /// match what was recorded: a file cut short or left with unwritten pages by a crash is built again.
    /// Each tile is checked against the index when it is read.
    fn cached_output_ok(&self, out: &IngestedImage, _ctx: &NodeCtx) -> bool {
        pyramid_intact(Path::new(&out.pyramid_path), out.file_len, &out.index_hash)
    }
}

/// True when the pyramid file at `path` has `file_len` bytes and its index hashes to `index_hash`.
fn pyramid_intact(path: &Path, file_len: u64, index_hash: &[u8; 32]) -> bool {
    std::fs::metadata(path).is_ok_and(|m| m.len() == file_len)
        && TiledPyramid::open(path, index_hash).is_ok()
}

/// Adds the ingestion of `path` (item label `label`); equal files share one node.
pub fn ingest_file(
    b: &mut DagBuilder,
    label: &str,
    path: std::path::PathBuf,
) -> Result<Handle<IngestedImage>, BuildError> {
    b.add(Ingest, label, IngestParams::default(), RawFile(path))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::fs::FileExt;

    /// A pyramid whose index was changed on disk, or which was cut short, is not reused from the cache.
    #[test]
    fn a_pyramid_with_a_changed_index_or_length_is_not_reused() {
        let dir = tempfile::tempdir().unwrap();
        let src = dir.path().join("frame.png");
        image::GrayImage::from_fn(300, 200, |x, y| {
            image::Luma([((x * 7 + y * 3) % 251) as u8])
        })
        .save(&src)
        .unwrap();
        let pyr = dir.path().join(PYRAMID_FILE);
        let done = ingest_with_tiles(&src, &pyr, 64).unwrap();
        let (len, hash) = (done.pyramid.file_len, done.pyramid.index_hash);
        assert!(pyramid_intact(&pyr, len, &hash));
        let at = done.pyramid.layout.hash_table_offset();
        let file = std::fs::OpenOptions::new().write(true).open(&pyr).unwrap();
        let mut byte = [0u8; 1];
        std::fs::File::open(&pyr)
            .unwrap()
            .read_exact_at(&mut byte, at)
            .unwrap();
        file.write_all_at(&[byte[0] ^ 0xFF], at).unwrap();
        assert!(!pyramid_intact(&pyr, len, &hash), "a changed tile hash");
        file.write_all_at(&byte, at).unwrap();
        assert!(pyramid_intact(&pyr, len, &hash));
        file.set_len(len - 1).unwrap();
        assert!(!pyramid_intact(&pyr, len, &hash), "a file cut short");
    }
}
