//! Gathering the trajectory map's data from a result folder: recorded and adjusted positions and check
//! points from `trajectory.geojson` (layers `recorded`, `adjusted`, `checkpoints`), else recorded positions
//! from the campaign's `mm/recordings.csv`; true positions from the campaign's `truth/recordings.csv`
//! (evaluation only); error vectors from `checkpoints.csv`; which recordings have nadir / oblique
//! correspondences from `correspondences.csv`.

use super::inputs::{for_each_row, read_csv_opt, CsvTable};
use super::plots::trajectory::{CorrespondenceKind, MapCheckPoint, MapRecording};
use skytie_stages::export::ControlStatus;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Point features of the layers of `trajectory.geojson`: per layer, id property → (x, y).
#[derive(Default)]
struct GeoPoints {
    layers: BTreeMap<String, BTreeMap<String, [f64; 2]>>,
}

/// The parts of a GeoJSON feature the map reads; everything else (other properties, line geometries) is
/// skipped while parsing, so a city campaign's file is never held as a document tree.
#[derive(serde::Deserialize)]
struct Feature {
    #[serde(default)]
    properties: FeatureProps,
    geometry: Option<Geometry>,
}

#[derive(serde::Deserialize, Default)]
struct FeatureProps {
    layer: Option<String>,
    image_id: Option<String>,
    point_id: Option<String>,
}

#[derive(serde::Deserialize)]
struct Geometry {
    #[serde(rename = "type")]
    kind: String,
    coordinates: Coordinates,
}

/// A Point's numbers; any other geometry's nested arrays are skipped (empty).
struct Coordinates(Vec<f64>);

impl<'de> serde::Deserialize<'de> for Coordinates {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visit;
        impl<'de> serde::de::Visitor<'de> for Visit {
            type Value = Coordinates;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("GeoJSON coordinates")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<Coordinates, A::Error> {
                let mut out = Vec::new();
                while let Some(v) = seq.next_element::<NumberOrSkip>()? {
                    if let Some(x) = v.0 {
                        out.push(x);
                    }
                }
                Ok(Coordinates(out))
            }
        }
        d.deserialize_seq(Visit)
    }
}

/// A number, or anything else skipped.
struct NumberOrSkip(Option<f64>);

impl<'de> serde::Deserialize<'de> for NumberOrSkip {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::IgnoredAny;
        struct Visit;
        impl<'de> serde::de::Visitor<'de> for Visit {
            type Value = NumberOrSkip;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or a nested array")
            }
            fn visit_f64<E>(self, v: f64) -> Result<NumberOrSkip, E> {
                Ok(NumberOrSkip(Some(v)))
            }
            fn visit_i64<E>(self, v: i64) -> Result<NumberOrSkip, E> {
                Ok(NumberOrSkip(Some(v as f64)))
            }
            fn visit_u64<E>(self, v: u64) -> Result<NumberOrSkip, E> {
                Ok(NumberOrSkip(Some(v as f64)))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<NumberOrSkip, A::Error> {
                while seq.next_element::<IgnoredAny>()?.is_some() {}
                Ok(NumberOrSkip(None))
            }
            fn visit_unit<E>(self) -> Result<NumberOrSkip, E> {
                Ok(NumberOrSkip(None))
            }
        }
        d.deserialize_any(Visit)
    }
}

#[derive(serde::Deserialize)]
struct FeatureCollection {
    #[serde(default)]
    features: Vec<Feature>,
}

impl GeoPoints {
    /// The point features of a GeoJSON document, by layer and id (`image_id`, else `point_id`).
    fn parse(bytes: &[u8]) -> Result<Self, serde_json::Error> {
        let doc: FeatureCollection = serde_json::from_slice(bytes)?;
        let mut out = Self::default();
        for f in doc.features {
            let (Some(layer), Some(g)) = (f.properties.layer, f.geometry) else {
                continue;
            };
            let Some(id) = f.properties.image_id.or(f.properties.point_id) else {
                continue;
            };
            if g.kind != "Point" || g.coordinates.0.len() < 2 {
                continue;
            }
            let c = &g.coordinates.0;
            out.layers
                .entry(layer)
                .or_default()
                .insert(id, [c[0], c[1]]);
        }
        Ok(out)
    }

    /// One layer's points (empty when absent).
    fn take(&mut self, layer: &str) -> BTreeMap<String, [f64; 2]> {
        self.layers.remove(layer).unwrap_or_default()
    }
}

/// Whether a `correspondences.csv` row's `status` lets its point count as control in the report: a status
/// whose point is delivered as ground control ([`ControlStatus::delivered`]); a file without the column (an
/// empty cell) counts every row.
pub fn counts_as_control(status: &str) -> bool {
    ControlStatus::parse(status).is_none_or(ControlStatus::delivered)
}

/// Recording image ids with at least one panorama observation of a nadir / oblique control point that the
/// adjustment did not reject or leave out ([`counts_as_control`]).
pub fn correspondence_sets(corr: Option<&CsvTable>) -> (BTreeSet<String>, BTreeSet<String>) {
    let (mut nadir, mut oblique) = (BTreeSet::new(), BTreeSet::new());
    if let Some(t) = corr {
        for r in &t.rows {
            if !counts_as_control(t.text(r, "status")) {
                continue;
            }
            add_correspondence(
                t.text(r, "image_kind"),
                t.text(r, "source"),
                t.text(r, "image_id"),
                (&mut nadir, &mut oblique),
            );
        }
    }
    (nadir, oblique)
}

fn add_correspondence(
    image_kind: &str,
    source: &str,
    image_id: &str,
    (nadir, oblique): (&mut BTreeSet<String>, &mut BTreeSet<String>),
) {
    if image_kind != "panorama" {
        return;
    }
    let set = match source {
        "nadir" => nadir,
        "oblique" => oblique,
        _ => return,
    };
    if !set.contains(image_id) {
        set.insert(image_id.to_string());
    }
}

/// [`correspondence_sets`] of a `correspondences.csv` file, streamed.
fn correspondence_sets_of(path: &Path) -> Result<(BTreeSet<String>, BTreeSet<String>), String> {
    let (mut nadir, mut oblique) = (BTreeSet::new(), BTreeSet::new());
    let mut cols = None;
    for_each_row(path, |c, r| {
        let [k, s, i, st] = *cols.get_or_insert_with(|| {
            ["image_kind", "source", "image_id", "status"].map(|n| c.col(n).unwrap_or(usize::MAX))
        });
        let cell = |j: usize| r.get(j).unwrap_or("");
        if !counts_as_control(cell(st)) {
            return;
        }
        add_correspondence(cell(k), cell(s), cell(i), (&mut nadir, &mut oblique));
    })?;
    Ok((nadir, oblique))
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
#[derive(Clone)]
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
    let mut geo = if gpath.exists() {
        let bytes =
            std::fs::read(&gpath).map_err(|e| format!("{}: cannot read: {e}", gpath.display()))?;
        GeoPoints::parse(&bytes)
            .map_err(|e| format!("{}: not valid GeoJSON: {e}", gpath.display()))?
    } else {
        GeoPoints::default()
    };
    let mut recorded = geo.take("recorded");
    let mut adjusted = geo.take("adjusted");
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
    let (nadir, oblique) = correspondence_sets_of(&dir.join("correspondences.csv"))?;
    let recordings = ids
        .iter()
        .map(|id| MapRecording {
            recorded: recorded[id],
            adjusted: adjusted.get(id).copied(),
            truth: truth.get(id).copied(),
            kind: CorrespondenceKind::from_flags(nadir.contains(id), oblique.contains(id)),
        })
        .collect();
    let cp_pos = geo.take("checkpoints");
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

/// Pairs of points at most `gap_m` apart that together link every group of [`MapData::areas`] (a spanning set,
/// not every pair): points in one grid cell of side `gap_m / 1.5` are all closer than `gap_m` and are linked to
/// the cell's first point; two cells up to two apart are linked by their first pair within `gap_m`, looked for
/// only while they are not linked yet. Near-linear for trajectories; the groups are those of testing every pair.
fn linked_pairs(points: &[[f64; 2]], gap_m: f64) -> Vec<(usize, usize)> {
    let cell_m = gap_m / 1.5;
    let gap_sq = gap_m * gap_m;
    let mut cells: BTreeMap<(i64, i64), Vec<usize>> = BTreeMap::new();
    let mut loose = Vec::new();
    for (i, p) in points.iter().enumerate() {
        let key = ((p[0] / cell_m).floor(), (p[1] / cell_m).floor());
        if key.0.is_finite() && key.1.is_finite() && cell_m > 0.0 {
            cells
                .entry((key.0 as i64, key.1 as i64))
                .or_default()
                .push(i);
        } else {
            loose.push(i);
        }
    }
    let mut pairs = Vec::new();
    for members in cells.values() {
        pairs.extend(members[1..].iter().map(|&j| (members[0], j)));
    }
    // Cells: union-find over cell indices, to skip the pair search between cells already linked.
    let keys: Vec<(i64, i64)> = cells.keys().copied().collect();
    let mut parent: Vec<usize> = (0..keys.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let close = |i: usize, j: usize| {
        let (dx, dy) = (points[i][0] - points[j][0], points[i][1] - points[j][1]);
        dx * dx + dy * dy <= gap_sq
    };
    for (a, ka) in keys.iter().enumerate() {
        for (dx, dy) in (-2i64..=2).flat_map(|dx| (-2i64..=2).map(move |dy| (dx, dy))) {
            let kb = (ka.0 + dx, ka.1 + dy);
            if kb <= *ka {
                continue;
            }
            let Ok(b) = keys.binary_search(&kb) else {
                continue;
            };
            let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
            if ra == rb {
                continue;
            }
            let found = cells[ka]
                .iter()
                .find_map(|&i| cells[&kb].iter().find(|&&j| close(i, j)).map(|&j| (i, j)));
            if let Some(pair) = found {
                parent[ra.max(rb)] = ra.min(rb);
                pairs.push(pair);
            }
        }
    }
    // Points with non-finite coordinates: tested against every point, as before (none in a valid output).
    for &i in &loose {
        pairs.extend(
            (0..points.len())
                .filter(|&j| j != i && close(i, j))
                .map(|j| (i, j)),
        );
    }
    pairs
}

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
        for (i, j) in linked_pairs(&points, gap_m) {
            let (a, b) = (root(&mut parent, i), root(&mut parent, j));
            if a != b {
                parent[a.max(b)] = a.min(b);
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
    fn areas_from_the_grid_are_those_of_testing_every_pair() {
        let mut rng = skytie_stages::rng::SplitMix64::new(3);
        for round in 0..20 {
            let n = 50 + 20 * round;
            let pts: Vec<[f64; 2]> = (0..n)
                .map(|_| [rng.next_f64() * 3000.0, rng.next_f64() * 3000.0])
                .collect();
            let gap = 100.0 + 10.0 * round as f64;
            let groups = |pairs: Vec<(usize, usize)>| {
                let mut parent: Vec<usize> = (0..n).collect();
                fn root(p: &mut [usize], mut i: usize) -> usize {
                    while p[i] != i {
                        i = p[i];
                    }
                    i
                }
                for (i, j) in pairs {
                    let (a, b) = (root(&mut parent, i), root(&mut parent, j));
                    parent[a.max(b)] = a.min(b);
                }
                (0..n).map(|i| root(&mut parent, i)).collect::<Vec<_>>()
            };
            let mut every = Vec::new();
            for i in 0..n {
                for j in i + 1..n {
                    let (dx, dy) = (pts[i][0] - pts[j][0], pts[i][1] - pts[j][1]);
                    if dx * dx + dy * dy <= gap * gap {
                        every.push((i, j));
                    }
                }
            }
            assert_eq!(
                groups(linked_pairs(&pts, gap)),
                groups(every),
                "round {round}"
            );
        }
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
        // With the adjustment's status: rejected and left-out points are not control.
        let t = CsvTable::from_cells(
            &skytie_stages::export::CORRESPONDENCES_CSV_HEADER,
            &[
                &["nadir", "p1", "panorama", "a", "1", "2", "", "used"],
                &["nadir", "p3", "panorama", "c", "1", "2", "", "rejected"],
                &["oblique", "p2", "panorama", "b", "1", "2", "", "left_out"],
                &[
                    "oblique",
                    "p4",
                    "panorama",
                    "d",
                    "1",
                    "2",
                    "",
                    "not_adjusted",
                ],
            ],
        );
        let (n, o) = correspondence_sets(Some(&t));
        assert_eq!(n.into_iter().collect::<Vec<_>>(), vec!["a"]);
        assert_eq!(o.into_iter().collect::<Vec<_>>(), vec!["d"]);
    }

    #[test]
    fn geojson_points_by_layer() {
        let doc = serde_json::json!({"type": "FeatureCollection", "crs": {"type": "name"}, "features": [
            {"type": "Feature", "geometry": {"type": "Point", "coordinates": [1.0, 2.0, 3.0]},
             "properties": {"layer": "recorded", "image_id": "a", "time": "t", "flags": [1, {"x": 2}]}},
            {"geometry": {"type": "LineString", "coordinates": [[1.0, 2.0], [3, 4]]},
             "properties": {"layer": "recorded"}},
            {"geometry": {"type": "Point", "coordinates": [5, 6]},
             "properties": {"layer": "adjusted", "image_id": "a"}},
            {"geometry": {"type": "Point", "coordinates": [7.5, 8.5]},
             "properties": {"layer": "checkpoints", "point_id": "c1", "improved": null}}]});
        let mut g = GeoPoints::parse(doc.to_string().as_bytes()).unwrap();
        let r = g.take("recorded");
        assert_eq!(r.len(), 1);
        assert_eq!(r["a"], [1.0, 2.0]);
        assert_eq!(g.take("adjusted")["a"], [5.0, 6.0]);
        assert_eq!(g.take("checkpoints")["c1"], [7.5, 8.5]);
        assert!(g.take("missing").is_empty());
    }
}
