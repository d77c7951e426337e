//! What the sections of one result set read from its folder, read once per report: the recordings' rows of
//! `corrections.csv` (the headline, its verification table and the map all use them), the headline, and the
//! map data (the interactive and the static map). A city campaign's `corrections.csv` and
//! `trajectory.geojson` are tens of megabytes each; reading them once per section tripled the report's time.

use super::headline::{corrections_of_recordings, Headline};
use super::inputs::CsvTable;
use super::map_data::{read_map_data, MapData};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

type Shared<T> = Result<Option<Arc<T>>, String>;

/// Per result folder: the values read so far.
#[derive(Default)]
pub struct SetCache {
    corrections: HashMap<PathBuf, Shared<CsvTable>>,
    headline: HashMap<PathBuf, Result<Arc<Headline>, String>>,
    map: HashMap<(PathBuf, Option<PathBuf>), Shared<MapData>>,
}

impl SetCache {
    /// The recordings' rows of `dir/corrections.csv` (`None` without the file).
    pub fn corrections(&mut self, dir: &Path) -> Shared<CsvTable> {
        self.corrections
            .entry(dir.to_path_buf())
            .or_insert_with(|| corrections_of_recordings(dir).map(|t| t.map(Arc::new)))
            .clone()
    }

    /// [`Headline::from_dir`] of `dir`.
    pub fn headline(&mut self, dir: &Path) -> Result<Arc<Headline>, String> {
        if let Some(h) = self.headline.get(dir) {
            return h.clone();
        }
        let made = self
            .corrections(dir)
            .and_then(|c| Headline::from_dir_with(dir, c.as_deref()).map(Arc::new));
        self.headline.insert(dir.to_path_buf(), made.clone());
        made
    }

    /// [`read_map_data`] of `dir` with `campaign`.
    pub fn map_data(&mut self, dir: &Path, campaign: Option<&Path>) -> Shared<MapData> {
        self.map
            .entry((dir.to_path_buf(), campaign.map(Path::to_path_buf)))
            .or_insert_with(|| read_map_data(dir, campaign).map(|m| m.map(Arc::new)))
            .clone()
    }
}
