//! The report's interactive map (pan/zoom): recorded and adjusted positions coloured by what supports their
//! correction, correction vectors exaggerated with their own scale bar, verification colours per trajectory
//! segment, aerial control and check points, and the nadir images as background; clicking a recording shows
//! its numbers and registration views. Leaflet (vendored, `assets/vendor/leaflet/`) does the pan/zoom in the
//! campaign's projected metres (CRS.Simple); `assets/map.js` draws all data on one canvas so 10⁴ recordings
//! stay responsive. The data go to `figures/<prefix>map-data.js` as columnar arrays relative to a local origin
//! (world coordinates of ~10⁵ m would cost precision in the browser's pixel arithmetic).

use super::html::{escape, Page};
use super::inputs::{for_each_row, read_csv_opt, CsvTable, ResultSet};
use super::map_background::nadir_background;
use super::map_data::{MapData, AREA_GAP_M};
use super::map_thinning::{kept_position, kept_recordings, status_runs, MAP_DETAIL_LIMIT};
use super::Builder;
use serde_json::{json, Value};
use skytie_stages::campaign::read_campaign;
use skytie_stages::export::Support;
use std::collections::HashMap;
use std::path::Path;

/// The vendored files written to `OUT/report/assets/`.
const ASSETS: [(&str, &[u8]); 4] = [
    (
        "leaflet.js",
        include_bytes!("assets/vendor/leaflet/leaflet.js"),
    ),
    (
        "leaflet.css",
        include_bytes!("assets/vendor/leaflet/leaflet.css"),
    ),
    (
        "leaflet-LICENSE.txt",
        include_bytes!("assets/vendor/leaflet/LICENSE"),
    ),
    ("map.js", include_bytes!("assets/map.js")),
];

/// Folder of the map's script and style files inside `OUT/report/`.
pub const ASSETS_DIR: &str = "assets";

/// Writes the vendored scripts into `report_dir/assets/`.
pub fn write_assets(report_dir: &Path) -> Result<(), String> {
    let dir = report_dir.join(ASSETS_DIR);
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    for (name, bytes) in ASSETS {
        let p = dir.join(name);
        skytie_util::fsutil::atomic_write(&p, bytes)
            .map_err(|e| format!("{}: cannot write: {e}", p.display()))?;
    }
    Ok(())
}

/// The `<head>` lines the map needs.
pub fn head_html() -> String {
    format!(
        "<link rel=\"stylesheet\" href=\"{ASSETS_DIR}/leaflet.css\">\n<script src=\"{ASSETS_DIR}/leaflet.js\"></script>\n\
         <script src=\"{ASSETS_DIR}/map.js\"></script>\n"
    )
}

fn support_code(label: &str) -> u8 {
    match Support::from_label(label) {
        Some(Support::Controlled) => 0,
        Some(Support::Bridged) => 1,
        Some(Support::Extrapolated) => 2,
        _ => 3,
    }
}

/// A round number ≥ 1 so that the 95th-percentile correction is drawn about `target_m` long.
fn exaggeration(corrections_m: &[f64], target_m: f64) -> f64 {
    let mut v: Vec<f64> = corrections_m.iter().copied().filter(|x| *x > 0.0).collect();
    if v.is_empty() {
        return 1.0;
    }
    v.sort_by(f64::total_cmp);
    let p95 = v[((v.len() - 1) as f64 * 0.95) as usize];
    let raw = (target_m / p95).max(1.0);
    let e = 10f64.powf(raw.log10().floor());
    let f = raw / e;
    (if f < 2.0 {
        1.0
    } else if f < 5.0 {
        2.0
    } else {
        5.0
    }) * e
}

/// Per recording index: the status of its verification segment from a verification CSV.
fn segment_status(
    ids: &[String],
    t: Option<&CsvTable>,
) -> (Vec<Value>, Vec<(usize, usize, String)>) {
    let mut status = vec![Value::Null; ids.len()];
    let mut spans = Vec::new();
    let Some(t) = t else {
        return (status, spans);
    };
    let index: HashMap<&str, usize> = ids
        .iter()
        .enumerate()
        .map(|(i, s)| (s.as_str(), i))
        .collect();
    for r in t.rows.iter().filter(|r| t.text(r, "segment") != "all") {
        let (Some(&a), Some(&b)) = (
            index.get(t.text(r, "first_image_id")),
            index.get(t.text(r, "last_image_id")),
        ) else {
            continue;
        };
        let s = t.text(r, "status").to_string();
        for slot in status.iter_mut().take(b + 1).skip(a) {
            *slot = json!(s);
        }
        spans.push((a, b, s));
    }
    (status, spans)
}

/// One recording's row of `corrections.csv` (the columns the map shows).
struct CorrectionRow {
    time: String,
    support: String,
    du_m: Option<f64>,
    dyaw_deg: Option<f64>,
    sigma_enu_m: [Option<f64>; 3],
}

/// The recordings' rows of `corrections.csv` (`t`) by id (the last row of an id wins); `None` without the
/// file.
fn correction_rows(t: Option<&CsvTable>) -> Option<HashMap<String, CorrectionRow>> {
    let t = t?;
    let mut out = HashMap::with_capacity(t.rows.len());
    for r in &t.rows {
        out.insert(
            t.text(r, "image_id").to_string(),
            CorrectionRow {
                time: t.text(r, "time").to_string(),
                support: t.text(r, "support").to_string(),
                du_m: t.num(r, "du_m"),
                dyaw_deg: t.num(r, "dyaw_deg"),
                sigma_enu_m: ["sigma_e_m", "sigma_n_m", "sigma_u_m"].map(|c| t.num(r, c)),
            },
        );
    }
    Some(out)
}

/// Per recording id in `wanted`: the number of distinct control points (source, point id) it observes that the
/// adjustment did not reject or leave out, from `correspondences.csv` (streamed); `None` without the file.
fn control_counts(
    set_dir: &Path,
    wanted: &HashMap<&str, usize>,
) -> Result<Option<Vec<usize>>, String> {
    let mut points: Vec<std::collections::BTreeSet<(String, String)>> =
        vec![Default::default(); wanted.len()];
    let mut cols = None;
    let found = for_each_row(&set_dir.join("correspondences.csv"), |c, r| {
        let [k, i, s, p, st] = *cols.get_or_insert_with(|| {
            ["image_kind", "image_id", "source", "point_id", "status"]
                .map(|n| c.col(n).unwrap_or(usize::MAX))
        });
        let cell = |j: usize| r.get(j).unwrap_or("");
        if cell(k) != "panorama" || !super::map_data::counts_as_control(cell(st)) {
            return;
        }
        if let Some(&slot) = wanted.get(cell(i)) {
            points[slot].insert((cell(s).to_string(), cell(p).to_string()));
        }
    })?;
    Ok(found.map(|_| points.iter().map(|p| p.len()).collect()))
}

/// Status segments of the map in the kept recordings' positions: every segment when nothing was left out,
/// else the runs of equal status (their ends are kept).
fn kept_segments(
    spans: &[(usize, usize, String)],
    kept: &[usize],
    thinned: bool,
) -> Vec<(usize, usize, String)> {
    if !thinned {
        return spans.to_vec();
    }
    status_runs(spans)
        .into_iter()
        .filter_map(|r| {
            let a = kept_position(kept, r.from, true)?;
            let b = kept_position(kept, r.to, false)?;
            (a <= b).then_some((a, b, r.status))
        })
        .collect()
}

/// The map's data document: every recording of a campaign within [`MAP_DETAIL_LIMIT`], else the thinned set
/// of [`super::map_thinning`].
fn map_json(
    data: &MapData,
    set_dir: &Path,
    corrections: Option<&CsvTable>,
    views: &HashMap<String, Vec<(String, String)>>,
) -> Result<Value, String> {
    let corrections = correction_rows(corrections);
    let row = |id: &str| corrections.as_ref().and_then(|c| c.get(id));
    let (ox, oy) = {
        let r0 = data.recordings.first().map_or([0.0, 0.0], |r| r.recorded);
        (
            (r0[0] / 100.0).round() * 100.0,
            (r0[1] / 100.0).round() * 100.0,
        )
    };
    let round = |v: f64| (v * 1e4).round() / 1e4;
    let ids = &data.ids;
    let n = ids.len();
    let before = read_csv_opt(&set_dir.join("verification.csv"))?;
    let after = read_csv_opt(&set_dir.join("verification_adjusted.csv"))?;
    let (status_before, spans_before) = segment_status(ids, before.as_ref());
    let (status_after, spans_after) = segment_status(ids, after.as_ref());
    let support_of = |id: &str| support_code(row(id).map_or("", |r| r.support.as_str()));
    // Flagged: not corrected (when there is a correction file), or in a failed segment of the adjusted
    // trajectory's verification (else the recorded one's).
    let shown_status = if after.is_some() {
        &status_after
    } else {
        &status_before
    };
    let flagged: Vec<bool> = (0..n)
        .map(|i| {
            (corrections.is_some() && support_of(&ids[i]) == 3)
                || shown_status[i].as_str() == Some("fail")
        })
        .collect();
    let run_ends: Vec<usize> = status_runs(&spans_before)
        .iter()
        .chain(&status_runs(&spans_after))
        .flat_map(|r| [r.from, r.to])
        .collect();
    let kept = kept_recordings(n, &flagged, &run_ends, MAP_DETAIL_LIMIT);
    let thinned = kept.len() < n;
    let (mut rx, mut ry, mut ax, mut ay) = (vec![], vec![], vec![], vec![]);
    let (mut dz, mut dyaw, mut sx, mut sy, mut sz, mut support, mut time) =
        (vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
    let (mut kept_ids, mut before_k, mut after_k) = (vec![], vec![], vec![]);
    let mut moved = Vec::new();
    for &i in &kept {
        let (id, r) = (&ids[i], &data.recordings[i]);
        let adjusted = r.adjusted.unwrap_or(r.recorded);
        rx.push(round(r.recorded[0] - ox));
        ry.push(round(r.recorded[1] - oy));
        ax.push(round(adjusted[0] - ox));
        ay.push(round(adjusted[1] - oy));
        moved.push((adjusted[0] - r.recorded[0]).hypot(adjusted[1] - r.recorded[1]));
        let c = row(id);
        dz.push(c.and_then(|c| c.du_m));
        dyaw.push(c.and_then(|c| c.dyaw_deg));
        sx.push(c.and_then(|c| c.sigma_enu_m[0]));
        sy.push(c.and_then(|c| c.sigma_enu_m[1]));
        sz.push(c.and_then(|c| c.sigma_enu_m[2]));
        support.push(support_of(id));
        time.push(c.map_or(Value::Null, |c| json!(c.time)));
        kept_ids.push(id.clone());
        before_k.push(status_before[i].clone());
        after_k.push(status_after[i].clone());
    }
    let position: HashMap<&str, usize> = kept_ids
        .iter()
        .enumerate()
        .map(|(k, s)| (s.as_str(), k))
        .collect();
    let control: Vec<Value> = match control_counts(set_dir, &position)? {
        Some(counts) => counts.into_iter().map(|c| json!(c)).collect(),
        None => vec![Value::Null; kept_ids.len()],
    };
    let segments: Vec<Value> = kept_segments(&spans_before, &kept, thinned)
        .iter()
        .map(|s| ("recorded", s))
        .chain(
            kept_segments(&spans_after, &kept, thinned)
                .iter()
                .map(|s| ("adjusted", s)),
        )
        .map(|(t, (a, b, s))| json!({"trajectory": t, "from": a, "to": b, "status": s}))
        .collect();
    let cps = &data.checkpoints;
    let err = |e: Option<[f64; 2]>, k: usize| e.map(|v| round(v[k]));
    let views: HashMap<&String, &Vec<(String, String)>> = views
        .iter()
        .filter(|(id, _)| position.contains_key(id.as_str()))
        .collect();
    let mut doc = json!({
        "origin": [ox, oy],
        "exaggeration": exaggeration(&moved, 25.0),
        "recordings": {
            "id": kept_ids, "time": time, "rx": rx, "ry": ry, "ax": ax, "ay": ay, "dz": dz, "dyaw": dyaw,
            "sx": sx, "sy": sy, "sz": sz, "support": support, "control": control,
            "before": before_k, "after": after_k,
        },
        "checkpoints": {
            "id": (0..cps.len()).collect::<Vec<_>>(),
            "x": cps.iter().map(|c| round(c.position[0] - ox)).collect::<Vec<_>>(),
            "y": cps.iter().map(|c| round(c.position[1] - oy)).collect::<Vec<_>>(),
            "bx": cps.iter().map(|c| err(c.error_before, 0)).collect::<Vec<_>>(),
            "by": cps.iter().map(|c| err(c.error_before, 1)).collect::<Vec<_>>(),
            "ax": cps.iter().map(|c| err(c.error_after, 0)).collect::<Vec<_>>(),
            "ay": cps.iter().map(|c| err(c.error_after, 1)).collect::<Vec<_>>(),
        },
        "segments": segments,
        "views": views,
        "backgrounds": [],
    });
    if thinned {
        doc["thinned"] = json!({
            "recordings": n,
            "shown": kept.len(),
            "flagged": flagged.iter().filter(|f| **f).count(),
        });
    }
    Ok(doc)
}

/// Backgrounds per area of the map (nadir images resampled onto the ground), as `{href, x0, y0, x1, y1}`
/// relative to the map origin.
fn backgrounds(b: &mut Builder, data: &MapData, prefix: &str, origin: [f64; 2]) -> Vec<Value> {
    let Some(root) = b.campaign.clone() else {
        return Vec::new();
    };
    let campaign = match read_campaign(&root) {
        Ok((c, _)) => c,
        Err(e) => {
            b.notes
                .push(format!("map background: cannot read the campaign: {e}"));
            return Vec::new();
        }
    };
    if campaign.nadir.is_empty() {
        return Vec::new();
    }
    let ground: HashMap<&str, f64> = campaign
        .recordings
        .iter()
        .map(|r| (r.image_id.as_str(), r.z - r.camera_height_m))
        .collect();
    let mut out = Vec::new();
    let ids = &data.ids;
    for (k, area) in data.clone().areas(AREA_GAP_M).into_iter().enumerate() {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for r in &area.recordings {
            for d in 0..2 {
                lo[d] = lo[d].min(r.recorded[d]);
                hi[d] = hi[d].max(r.recorded[d]);
            }
        }
        if !lo[0].is_finite() {
            continue;
        }
        let mut heights: Vec<f64> = area
            .ids
            .iter()
            .filter_map(|id| ground.get(id.as_str()).copied())
            .collect();
        if heights.is_empty() {
            heights = ids
                .iter()
                .filter_map(|id| ground.get(id.as_str()).copied())
                .collect();
        }
        heights.sort_by(f64::total_cmp);
        let Some(&z) = heights.get(heights.len() / 2) else {
            continue;
        };
        let margin = 40.0;
        let bounds = [
            lo[0] - margin,
            lo[1] - margin,
            hi[0] + margin,
            hi[1] + margin,
        ];
        let name = format!("{prefix}map-background-{}.png", k + 1);
        let (path, href) = b.figure_path(&name);
        match nadir_background(&campaign, &b.images, bounds, z, &path) {
            Ok(Some(bg)) => {
                b.wrote_figure(path);
                let [x0, y0, x1, y1] = bg.bounds_world;
                out.push(
                    json!({"href": href, "x0": x0 - origin[0], "y0": y0 - origin[1],
                                "x1": x1 - origin[0], "y1": y1 - origin[1]}),
                );
            }
            Ok(None) => {}
            Err(e) => b
                .notes
                .push(format!("map background of area {}: {e}", k + 1)),
        }
    }
    out
}

/// Appends the interactive map of `set` to `page` (heading included). `views` maps recording ids to their
/// registration views (href, caption).
pub fn map_section(
    b: &mut Builder,
    page: &mut Page,
    set: &ResultSet,
    prefix: &str,
    views: &HashMap<String, Vec<(String, String)>>,
) -> Result<(), String> {
    page.heading(&format!("{prefix}map"), "Map");
    let campaign = b.campaign.clone();
    let Some(data) = b.cache.map_data(&set.dir, campaign.as_deref())? else {
        b.note(
            page,
            format!("{}: no recorded positions found: no map", set.dir.display()),
        );
        return Ok(());
    };
    let corrections = b.cache.corrections(&set.dir)?;
    let doc = map_json(&data, &set.dir, corrections.as_deref(), views)?;
    let origin = [
        doc["origin"][0].as_f64().unwrap_or(0.0),
        doc["origin"][1].as_f64().unwrap_or(0.0),
    ];
    let mut doc = doc;
    doc["backgrounds"] = Value::Array(backgrounds(b, &data, prefix, origin));
    let id = if prefix.is_empty() {
        "run".to_string()
    } else {
        prefix.trim_end_matches('-').to_string()
    };
    let file = format!("{prefix}map-data.js");
    let (path, href) = b.figure_path(&file);
    let text = format!(
        "window.SKYTIE_MAPS = window.SKYTIE_MAPS || {{}};\nwindow.SKYTIE_MAPS[{}] = {};\n",
        serde_json::to_string(&id).map_err(|e| e.to_string())?,
        serde_json::to_string(&doc).map_err(|e| e.to_string())?
    );
    skytie_util::fsutil::atomic_write(&path, text.as_bytes())
        .map_err(|e| format!("{}: cannot write: {e}", path.display()))?;
    b.wrote_figure(path);
    page.head(&head_html());
    if let Some(t) = doc.get("thinned") {
        page.raw(&format!(
            "<p class=\"note\">The map carries {} of the {} recordings: every flagged one ({} not corrected or \
             in a failed verification segment), the ends of every stretch of equal verification status, and \
             recordings at an even spacing along the trajectory; every recording is in trajectory_adjusted.csv \
             and corrections.csv.</p>\n",
            t["shown"], t["recordings"], t["flagged"]
        ));
    }
    let e = doc["exaggeration"].as_f64().unwrap_or(1.0);
    page.raw(&format!(
        "<p class=\"note\">Drag to pan, scroll to zoom, click a recording for its numbers and registration views. \
         Coordinates in the campaign CRS, metres (origin {} E, {} N). Filled dots: adjusted positions coloured by \
         what supports the correction (blue: own aerial control, green: bridged between controlled neighbours, \
         orange: extrapolated, red: not corrected); grey rings: recorded positions; black lines: correction \
         vectors (adjusted − recorded) drawn {}× longer than they are; broad bands: verification per segment \
         (green pass, red fail, grey insufficient: too few points, a stretch without any, or after adjustment a stated σ too large for the tolerance); purple: aerial \
         control points; black squares: check points with their errors before (grey) and after (red), drawn {}× \
         longer.</p>\n\
         <div class=\"mapwrap\"><div id=\"map-{}\" class=\"skymap\"></div><div id=\"panel-{}\" class=\"mappanel\">\
         <p>Click a recording on the map.</p></div></div>\n<script src=\"{}\"></script>\n",
        origin[0],
        origin[1],
        e,
        e,
        escape(&id),
        escape(&id),
        escape(&href)
    ));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exaggeration_is_a_round_number_at_least_one() {
        assert_eq!(exaggeration(&[0.5; 10], 25.0), 50.0);
        assert_eq!(exaggeration(&[0.8; 10], 25.0), 20.0);
        assert_eq!(exaggeration(&[100.0], 25.0), 1.0);
        assert_eq!(exaggeration(&[], 25.0), 1.0);
    }
}
