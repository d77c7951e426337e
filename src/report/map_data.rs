//! Gathering the trajectory map's data from a result folder: recorded and adjusted positions and check
//! points from `trajectory.geojson` (layers `recorded`, `adjusted`, `checkpoints`), else recorded positions
//! from the campaign's `mm/recordings.csv`; true positions from the campaign's `truth/recordings.csv`
//! (evaluation only); error vectors from `checkpoints.csv`; which recordings have nadir / oblique
//! correspondences from `correspondences.csv`.

use super::inputs::{read_csv_opt, CsvTable};
use super::plots::trajectory::{CorrespondenceKind, MapCheckPoint, MapRecording};
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Point features of one geojson layer: id property → (x, y).
fn geojson_layer(doc: &Value, layer: &str, id_key: &str) -> BTreeMap<String, [f64; 2]> {
    let mut out = BTreeMap::new();
    let Some(features) = doc.get("features").and_then(|f| f.as_array()) else {
        return out;
    };
    for f in features {
        let props = &f["properties"];
        if props["layer"].as_str() != Some(layer) || f["geometry"]["type"].as_str() != Some("Point")
        {
            continue;
        }
        let c = &f["geometry"]["coordinates"];
        let (Some(x), Some(y), Some(id)) = (c[0].as_f64(), c[1].as_f64(), props[id_key].as_str())
        else {
            continue;
        };
        out.insert(id.to_string(), [x, y]);
    }
    out
}

/// Recording image ids with at least one panorama observation of a nadir / oblique control point.
pub fn correspondence_sets(corr: Option<&CsvTable>) -> (BTreeSet<String>, BTreeSet<String>) {
    let (mut nadir, mut oblique) = (BTreeSet::new(), BTreeSet::new());
    if let Some(t) = corr {
        for r in &t.rows {
            if t.text(r, "image_kind") != "panorama" {
                continue;
            }
            let id = t.text(r, "image_id").to_string();
            match t.text(r, "source") {
                "nadir" => {
                    nadir.insert(id);
                }
                "oblique" => {
                    oblique.insert(id);
                }
                _ => {}
            }
        }
    }
    (nadir, oblique)
}

/// Positions by recording id read from a recordings.csv-like file (columns image_id, x, y).
fn positions_csv(path: &Path) -> Result<BTreeMap<String, [f64; 2]>, String> {
    let mut out = BTreeMap::new();
    if let Some(t) = read_csv_opt(path)? {
        for r in &t.rows {
            if let (Some(x), Some(y)) = (t.num(r, "x"), t.num(r, "y")) {
                out.insert(t.text(r, "image_id").to_string(), [x, y]);
            }
        }
    }
    Ok(out)
}

/// Everything the map needs, plus the recording order (ids) for other sections.
pub struct MapData {
    pub ids: Vec<String>,
    pub recordings: Vec<MapRecording>,
    pub checkpoints: Vec<MapCheckPoint>,
    pub has_truth: bool,
}

/// Reads the map data of one result folder. `campaign` is the campaign folder (for recorded positions
/// without geojson and for `truth/`). Ok(None) when no positions are available at all.
pub fn read_map_data(dir: &Path, campaign: Option<&Path>) -> Result<Option<MapData>, String> {
    let gpath = dir.join("trajectory.geojson");
    let geo = if gpath.exists() {
        let bytes =
            std::fs::read(&gpath).map_err(|e| format!("{}: cannot read: {e}", gpath.display()))?;
        Some(
            serde_json::from_slice::<Value>(&bytes)
                .map_err(|e| format!("{}: not valid GeoJSON: {e}", gpath.display()))?,
        )
    } else {
        None
    };
    let mut recorded = geo
        .as_ref()
        .map(|g| geojson_layer(g, "recorded", "image_id"))
        .unwrap_or_default();
    let mut adjusted = geo
        .as_ref()
        .map(|g| geojson_layer(g, "adjusted", "image_id"))
        .unwrap_or_default();
    if adjusted.is_empty() {
        adjusted = positions_csv(&dir.join("trajectory_adjusted.csv"))?;
    }
    // Order: the campaign's recordings.csv order when available, else sorted ids.
    let mut ids: Vec<String> = Vec::new();
    if let Some(c) = campaign {
        let p = c.join("mm/recordings.csv");
        if let Some(t) = read_csv_opt(&p)? {
            for r in &t.rows {
                let id = t.text(r, "image_id").to_string();
                if let (Some(x), Some(y)) = (t.num(r, "x"), t.num(r, "y")) {
                    recorded.entry(id.clone()).or_insert([x, y]);
                }
                ids.push(id);
            }
        }
    }
    if ids.is_empty() {
        ids = recorded.keys().cloned().collect();
    }
    ids.retain(|id| recorded.contains_key(id));
    if ids.is_empty() {
        return Ok(None);
    }
    let truth = match campaign {
        Some(c) => positions_csv(&c.join("truth/recordings.csv"))?,
        None => BTreeMap::new(),
    };
    let corr = read_csv_opt(&dir.join("correspondences.csv"))?;
    let (nadir, oblique) = correspondence_sets(corr.as_ref());
    let recordings = ids
        .iter()
        .map(|id| MapRecording {
            recorded: recorded[id],
            adjusted: adjusted.get(id).copied(),
            truth: truth.get(id).copied(),
            kind: CorrespondenceKind::from_flags(nadir.contains(id), oblique.contains(id)),
        })
        .collect();
    let cp_pos = geo
        .as_ref()
        .map(|g| geojson_layer(g, "checkpoints", "point_id"))
        .unwrap_or_default();
    let mut checkpoints = Vec::new();
    if let Some(t) = read_csv_opt(&dir.join("checkpoints.csv"))? {
        for r in &t.rows {
            let id = t.text(r, "point_id");
            let Some(&position) = cp_pos.get(id) else {
                continue;
            };
            let vec2 = |p: &str| Some([t.num(r, &format!("{p}_x"))?, t.num(r, &format!("{p}_y"))?]);
            checkpoints.push(MapCheckPoint {
                position,
                error_before: vec2("before"),
                error_after: vec2("after"),
            });
        }
    }
    Ok(Some(MapData {
        ids,
        recordings,
        checkpoints,
        has_truth: !truth.is_empty(),
    }))
}

/// Recordings and check points further apart than this (m) from every other one of a group belong to separate
/// areas, each drawn as its own map (a campaign of several areas kilometres apart would otherwise shrink every
/// street to a few pixels). Consecutive recordings are ~5 m apart, so one street of any length stays one area.
pub const AREA_GAP_M: f64 = 250.0;

impl MapData {
    /// Splits the map into areas: groups of recordings and check points linked by distances ≤ `gap_m`
    /// (single linkage, by recorded position). Areas are ordered by their first recording (in `ids` order);
    /// one area is the whole map. An area of check points without recordings follows the others.
    pub fn areas(self, gap_m: f64) -> Vec<MapData> {
        let n_rec = self.recordings.len();
        let points: Vec<[f64; 2]> = self
            .recordings
            .iter()
            .map(|r| r.recorded)
            .chain(self.checkpoints.iter().map(|c| c.position))
            .collect();
        let mut parent: Vec<usize> = (0..points.len()).collect();
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        let gap_sq = gap_m * gap_m;
        for i in 0..points.len() {
            for j in i + 1..points.len() {
                let (dx, dy) = (points[i][0] - points[j][0], points[i][1] - points[j][1]);
                if dx * dx + dy * dy <= gap_sq {
                    let (a, b) = (root(&mut parent, i), root(&mut parent, j));
                    if a != b {
                        parent[a.max(b)] = a.min(b);
                    }
                }
            }
        }
        // Area index by root, in order of first appearance (recordings first).
        let mut area_of_root: BTreeMap<usize, usize> = BTreeMap::new();
        let mut area: Vec<usize> = Vec::with_capacity(points.len());
        for i in 0..points.len() {
            let r = root(&mut parent, i);
            let next = area_of_root.len();
            area.push(*area_of_root.entry(r).or_insert(next));
        }
        let mut out: Vec<MapData> = (0..area_of_root.len())
            .map(|_| MapData {
                ids: Vec::new(),
                recordings: Vec::new(),
                checkpoints: Vec::new(),
                has_truth: self.has_truth,
            })
            .collect();
        for (k, (id, rec)) in self.ids.into_iter().zip(self.recordings).enumerate() {
            out[area[k]].ids.push(id);
            out[area[k]].recordings.push(rec);
        }
        for (k, c) in self.checkpoints.into_iter().enumerate() {
            out[area[n_rec + k]].checkpoints.push(c);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn areas_are_groups_further_apart_than_the_gap() {
        let rec = |x: f64, y: f64| MapRecording {
            recorded: [x, y],
            adjusted: None,
            truth: None,
            kind: CorrespondenceKind::None,
        };
        // A 1 km street of 5-m steps (one area), a second street 3 km east, a check point near the second.
        let mut ids = Vec::new();
        let mut recordings = Vec::new();
        for i in 0..200 {
            ids.push(format!("a{i:03}"));
            recordings.push(rec(92_000.0 + 5.0 * i as f64, 437_000.0));
        }
        for i in 0..10 {
            ids.push(format!("b{i:03}"));
            recordings.push(rec(95_000.0, 437_000.0 + 5.0 * i as f64));
        }
        let checkpoints = vec![MapCheckPoint {
            position: [95_010.0, 437_020.0],
            error_before: None,
            error_after: None,
        }];
        let data = MapData {
            ids,
            recordings,
            checkpoints,
            has_truth: false,
        };
        let areas = data.areas(AREA_GAP_M);
        assert_eq!(areas.len(), 2);
        assert_eq!(
            (areas[0].recordings.len(), areas[0].checkpoints.len()),
            (200, 0)
        );
        assert_eq!(
            (areas[1].recordings.len(), areas[1].checkpoints.len()),
            (10, 1)
        );
        assert_eq!(areas[1].ids[0], "b000");
    }

    #[test]
    fn correspondence_kinds_per_recording() {
        let t = CsvTable::from_cells(
            &skytie_stages::export::CORRESPONDENCES_CSV_HEADER,
            &[
                &["nadir", "p1", "panorama", "a", "1", "2", ""],
                &["nadir", "p1", "nadir", "n1", "1", "2", "0.9"],
                &["oblique", "p2", "panorama", "a", "1", "2", ""],
                &["oblique", "p2", "panorama", "b", "1", "2", ""],
            ],
        );
        let (n, o) = correspondence_sets(Some(&t));
        assert_eq!(n.into_iter().collect::<Vec<_>>(), vec!["a"]);
        assert_eq!(o.into_iter().collect::<Vec<_>>(), vec!["a", "b"]);
    }

    #[test]
    fn geojson_points_by_layer() {
        let doc = serde_json::json!({"features": [
            {"geometry": {"type": "Point", "coordinates": [1.0, 2.0, 3.0]},
             "properties": {"layer": "recorded", "image_id": "a"}},
            {"geometry": {"type": "LineString", "coordinates": [[1.0, 2.0]]},
             "properties": {"layer": "recorded"}},
            {"geometry": {"type": "Point", "coordinates": [5.0, 6.0]},
             "properties": {"layer": "adjusted", "image_id": "a"}}]});
        let r = geojson_layer(&doc, "recorded", "image_id");
        assert_eq!(r.len(), 1);
        assert_eq!(r["a"], [1.0, 2.0]);
    }
}
